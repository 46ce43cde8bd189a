// The cutdown control: hold 2 s (progress ring) to arm and confirm; releasing early cancels. The
// state machine is lib/cutdown.ts; this module turns pointer and key events into press/release.

import { h, s, setAttr, setText } from "./dom";
import { CutdownHold, type CutdownDeps, type CutdownPhase } from "../lib/cutdown";
import { fmtMissionTime } from "../lib/format";

const R = 26;
const CIRC = 2 * Math.PI * R;

export class CutdownButton {
  readonly root: HTMLElement;
  private readonly hold: CutdownHold;
  private readonly ring: SVGCircleElement;
  private readonly status: HTMLElement;
  private readonly armed: HTMLElement;
  private readonly button: HTMLButtonElement;
  private raf = 0;

  constructor(deps: Omit<CutdownDeps, "onChange">) {
    this.ring = s("circle", { cx: 30, cy: 30, r: R, fill: "none", stroke: "#d00000", "stroke-width": 6, "stroke-dasharray": CIRC.toFixed(1), "stroke-dashoffset": CIRC.toFixed(1), transform: "rotate(-90 30 30)" });
    const svg = s("svg", { viewBox: "0 0 60 60", class: "ring", "aria-hidden": "true" }, s("circle", { cx: 30, cy: 30, r: R, fill: "none", stroke: "#ddd", "stroke-width": 6 }), this.ring);
    this.button = h("button", { type: "button", class: "cutdown", "data-testid": "cutdown-button", "data-command": true, "aria-label": "cutdown: press and hold for 2 seconds" }, svg as unknown as Node, h("span", {}, "CUTDOWN", h("small", {}, "hold 2 s")));
    this.status = h("div", { class: "cutdown-status", "data-testid": "cutdown-status", role: "status" }, "idle — a click does nothing; hold to cut down");
    this.armed = h("div", { class: "form-error", "data-testid": "cutdown-armed" });
    this.hold = new CutdownHold({ ...deps, onChange: (p) => this.onPhase(p) });
    const press = (e: Event): void => {
      e.preventDefault();
      if (this.button.disabled) return;
      this.hold.press();
      this.animate();
    };
    const release = (): void => this.hold.release();
    this.button.addEventListener("pointerdown", (e) => {
      if (e.button === 0) press(e);
    });
    for (const ev of ["pointerup", "pointerleave", "pointercancel"]) this.button.addEventListener(ev, release);
    this.button.addEventListener("keydown", (e) => {
      if ((e.key === " " || e.key === "Enter") && !e.repeat) press(e);
    });
    this.button.addEventListener("keyup", release);
    this.button.addEventListener("blur", release);
    this.button.addEventListener("contextmenu", (e) => e.preventDefault());
    // A click (keyboard Enter included) must never be the gesture: swallow it.
    this.button.addEventListener("click", (e) => e.preventDefault());
    window.addEventListener("blur", release);
    this.root = h("section", { class: "panel danger", "data-testid": "panel-cutdown", "aria-label": "cutdown" }, h("h2", {}, "Flight termination"), h("div", { class: "cutdown-row" }, this.button, h("div", {}, this.status, this.armed)));
  }

  /** Shows when the station reports cutdown armed (possibly by another operator). */
  update(armedUntil: number | null, now_s: number): void {
    setText(this.armed, armedUntil !== null && armedUntil > now_s ? `ARMED until ${fmtMissionTime(armedUntil)}` : "");
  }

  private animate(): void {
    cancelAnimationFrame(this.raf);
    const step = (): void => {
      setAttr(this.ring, "stroke-dashoffset", (CIRC * (1 - this.hold.progress())).toFixed(1));
      if (this.hold.phase.kind === "holding") this.raf = requestAnimationFrame(step);
    };
    step();
  }

  private onPhase(p: CutdownPhase): void {
    this.button.dataset.phase = p.kind;
    const text: Record<CutdownPhase["kind"], string> = {
      idle: "idle — a click does nothing; hold to cut down",
      holding: "holding… release to cancel",
      arming: "arming…",
      confirming: "armed — confirming…",
      sent: "CUTDOWN SENT — see command outcomes",
      failed: `FAILED: ${p.kind === "failed" ? p.reason : ""}`,
      cancelled: "cancelled (released before 2 s) — nothing sent",
    };
    setText(this.status, text[p.kind]);
    if (p.kind !== "holding") setAttr(this.ring, "stroke-dashoffset", (CIRC * (1 - this.hold.progress())).toFixed(1));
  }
}
