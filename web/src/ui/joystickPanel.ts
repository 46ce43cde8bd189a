// Manual mode with the browser Gamepad API, or without a gamepad the on-screen stick (pointer or
// keyboard, lib/screenStick.ts). The page polls `navigator.getGamepads()` (a test can replace
// it), shows the sticks live, and streams `manual` messages at 10 Hz only while the dead-man is
// held — gamepad button 0, the on-screen hold button, Space, or the pointer on the stick — and the
// page is focused and visible (lib/manualSender.ts decides; this module gathers the facts and
// shows them). A gamepad, when there is one, is the only source of sticks.

import { h, panel, s, setAttr, setText } from "./dom";
import { firstPad, manualMessage, readSticks, type PadLike, type Sticks } from "../lib/joystick";
import { ManualSender, MANUAL_RATE_HZ, type ManualGate } from "../lib/manualSender";
import { ScreenStick } from "../lib/screenStick";
import type { ManualMsg, ManualReleaseMsg } from "../lib/types";

const POLL_MS = 20;

export class JoystickPanel {
  readonly root: HTMLElement;
  readonly sender: ManualSender;
  private readonly status: HTMLElement;
  private readonly deadmanEl: HTMLElement;
  private readonly sendingEl: HTMLElement;
  private readonly rateEl: HTMLElement;
  private readonly valuesEl: HTMLElement;
  private readonly modeWarn: HTMLElement;
  private readonly dot: SVGCircleElement;
  private readonly hold: HTMLButtonElement;
  private screenHold = false;
  private readonly screen = new ScreenStick();
  private operator = false;
  private socketOpen = false;
  /** False between a window blur and the next focus. */
  private focused = true;
  private visible = document.visibilityState === "visible";
  private sticks: Sticks | null = null;
  private padId = "";
  private lastPaint = 0;

  constructor(send: (m: ManualMsg | ManualReleaseMsg) => boolean) {
    this.sender = new ManualSender({ send, sample: () => this.sample() });
    this.status = h("span", { "data-testid": "joystick-status" });
    this.deadmanEl = h("span", { class: "deadman", "data-testid": "joystick-deadman" });
    this.sendingEl = h("span", { class: "sending", "data-testid": "joystick-sending" });
    this.rateEl = h("span", { class: "muted", "data-testid": "joystick-rate" });
    this.valuesEl = h("span", { "data-testid": "joystick-values" });
    this.modeWarn = h("div", { class: "form-error", "data-testid": "joystick-mode-warning" });
    this.dot = s("circle", { cx: 50, cy: 50, r: 7, fill: "#ffd400", stroke: "#000", "stroke-width": 2 });
    const stick = s("svg", { viewBox: "0 0 100 100", class: "stick", role: "application", tabindex: 0, "data-command": "",
      "aria-label": "on-screen stick: press and drag, or Space held with the arrow keys (C centres); x main line, y brake", "data-testid": "joystick-stick" },
      s("rect", { x: 1, y: 1, width: 98, height: 98, fill: "#fff", stroke: "#000", "stroke-width": 2 }),
      s("line", { x1: 50, y1: 0, x2: 50, y2: 100, stroke: "#999" }),
      s("text", { x: 3, y: 10, "font-size": 9 }, "brake 0"),
      s("text", { x: 3, y: 96, "font-size": 9 }, "brake 1"),
      s("text", { x: 97, y: 52, "font-size": 9, "text-anchor": "end" }, "ML +1"),
      this.dot);
    this.hold = h("button", { type: "button", class: "hold", "data-testid": "joystick-hold", "data-command": true, "aria-label": "dead-man: hold to send stick commands" }, "HOLD to fly");
    const press = (e: Event): void => {
      e.preventDefault();
      this.screenHold = true;
      this.hold.setPointerCapture?.((e as PointerEvent).pointerId);
      this.evaluate();
    };
    const release = (): void => {
      this.screenHold = false;
      this.evaluate();
    };
    this.hold.addEventListener("pointerdown", press);
    for (const ev of ["pointerup", "pointercancel", "lostpointercapture"]) this.hold.addEventListener(ev, release);
    this.hold.addEventListener("keydown", (e) => {
      if ((e.key === " " || e.key === "Enter") && !e.repeat) press(e);
    });
    this.hold.addEventListener("keyup", release);
    this.hold.addEventListener("blur", release);
    this.hold.addEventListener("contextmenu", (e) => e.preventDefault());
    this.bindScreenStick(stick);

    // Stop at once when the page loses focus or visibility, or the gamepad goes.
    window.addEventListener("blur", () => {
      this.focused = false;
      this.screenHold = false;
      this.screen.release();
      this.evaluate();
    });
    window.addEventListener("focus", () => {
      this.focused = true;
      this.evaluate();
    });
    document.addEventListener("visibilitychange", () => {
      this.visible = document.visibilityState === "visible";
      if (!this.visible) {
        this.screenHold = false;
        this.screen.release();
      }
      this.evaluate();
    });
    window.addEventListener("gamepaddisconnected", () => this.evaluate());
    window.addEventListener("gamepadconnected", () => this.evaluate());
    setInterval(() => this.evaluate(), POLL_MS);

    this.root = panel("Manual (joystick)", "panel-joystick",
      h("div", { class: "joy" }, stick as unknown as Node,
        h("div", { class: "joy-info" },
          h("div", { class: "pad-id" }, "Gamepad: ", this.status),
          h("div", {}, this.valuesEl),
          h("div", {}, "Dead-man: ", this.deadmanEl),
          h("div", {}, this.sendingEl),
          h("div", {}, this.rateEl),
          this.hold)),
      this.modeWarn);
    this.paint(true);
  }

  setRole(operator: boolean): void {
    this.operator = operator;
    this.evaluate();
  }

  setSocketOpen(open: boolean): void {
    this.socketOpen = open;
    this.evaluate();
  }

  setVehicleMode(mode: string | null): void {
    setText(this.modeWarn, this.sender.sending && mode !== "manual" ? `vehicle is in ${mode ?? "unknown"} mode: the drone ignores the sticks until mode is manual` : "");
  }

  /** The on-screen stick: the pointer on it, or the keys while it or the HOLD button has focus. */
  private bindScreenStick(stick: SVGSVGElement): void {
    const at = (e: PointerEvent): void => {
      const r = stick.getBoundingClientRect();
      this.screen.point(((e.clientX - r.left) / r.width) * 100, ((e.clientY - r.top) / r.height) * 100);
      this.evaluate();
    };
    stick.addEventListener("pointerdown", (e) => {
      if (!this.operator) return;
      e.preventDefault();
      stick.setPointerCapture?.(e.pointerId);
      stick.focus();
      at(e);
    });
    stick.addEventListener("pointermove", (e) => {
      if (stick.hasPointerCapture?.(e.pointerId)) at(e);
    });
    const letGo = (): void => {
      this.screen.release();
      this.evaluate();
    };
    for (const ev of ["pointerup", "pointercancel", "lostpointercapture", "blur"]) stick.addEventListener(ev, letGo);
    const keys = (down: boolean) => (e: KeyboardEvent): void => {
      if (!this.operator || (down && e.repeat && e.key === " ")) return;
      if (this.screen.key(e.key, down)) {
        e.preventDefault();
        this.evaluate();
      }
    };
    stick.addEventListener("keydown", keys(true));
    stick.addEventListener("keyup", keys(false));
    // On the HOLD button Space is its own dead-man; the arrows still move the stick.
    this.hold.addEventListener("keydown", (e) => {
      if (e.key !== " " && e.key !== "Enter" && this.operator && this.screen.key(e.key, true)) {
        e.preventDefault();
        this.evaluate();
      }
    });
  }

  private readPad(): PadLike | null {
    let pads: readonly (Gamepad | null)[] | null = null;
    try {
      pads = typeof navigator.getGamepads === "function" ? navigator.getGamepads() : null;
    } catch {
      pads = null; // a permissions policy can forbid the Gamepad API
    }
    const p = firstPad(pads);
    this.padId = p && "id" in p ? String((p as Gamepad).id) : "";
    return p;
  }

  private sample(): ManualMsg | null {
    const p = this.readPad();
    return manualMessage(p === null ? this.screen.sticks() : readSticks(p));
  }

  private evaluate(): void {
    const pad = this.readPad();
    this.sticks = pad ? readSticks(pad) : this.screen.sticks();
    const gate: ManualGate = {
      operator: this.operator,
      socketOpen: this.socketOpen,
      // The blur/focus events react at once; hasFocus() covers the initial state.
      focused: this.focused && document.hasFocus(),
      visible: this.visible,
      // Without a gamepad the on-screen stick is always there to read.
      sticksConnected: true,
      deadman: (this.sticks?.deadman ?? false) || this.screenHold,
    };
    this.sender.update(gate);
    this.paint(false);
  }

  private paint(force: boolean): void {
    const now = performance.now();
    if (!force && now - this.lastPaint < 100) return;
    this.lastPaint = now;
    const st = this.sticks;
    setText(this.status, this.padId || "none: the on-screen stick (drag it, or Space + arrows)");
    setAttr(this.dot, "cx", String(50 + 46 * (st?.mainLine ?? 0)));
    setAttr(this.dot, "cy", String(4 + 92 * (st?.brake ?? 0)));
    setText(this.valuesEl, st ? `main line ${st.mainLine >= 0 ? "+" : ""}${st.mainLine.toFixed(2)} · brake ${st.brake.toFixed(2)}` : "main line — · brake —");
    const held = (st?.deadman ?? false) || this.screenHold;
    setText(this.deadmanEl, held ? "HELD" : "released");
    this.deadmanEl.dataset.held = String(held);
    const sending = this.sender.sending;
    setText(this.sendingEl, sending ? `SENDING at ${MANUAL_RATE_HZ} Hz` : `not sending: ${this.sender.blocked ?? "—"}`);
    this.sendingEl.dataset.sending = String(sending);
    const last = this.sender.lastSentMs;
    setText(this.rateEl, `${this.sender.rateHz().toFixed(0)} of ${MANUAL_RATE_HZ} Hz · last ${last === null ? "never" : `${((Date.now() - last) / 1000).toFixed(1)} s ago`} · ${this.sender.sent} sent · ${this.sender.releases} released`);
    this.hold.classList.toggle("on", this.screenHold);
  }
}
