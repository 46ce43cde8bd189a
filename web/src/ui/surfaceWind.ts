// The surface wind in the Wind panel (lib/surfaceWind.ts says what it shows): the wind in force
// at the target and where it comes from, the drone's copy, the anemometer when one is
// configured; and for operators a form to type one (Set) or withdraw theirs (Clear).
//
// The left column must hold every panel down to Link at 1440×900 with a few pixels to spare, so
// the readout is a few short lines in the small type of the learned polar's table, and the form
// stays folded behind a button in the panel's heading until the operator opens it: typing a wind
// is done once or twice a flight, reading it all the time.

import { ApiError } from "../lib/api";
import { surfaceWindBody, surfaceWindShown, type ShownLine, type SurfaceWind } from "../lib/surfaceWind";
import type { SurfaceWindBody } from "../generated/api";
import { h, setAttr, setText } from "./dom";

/** What the form does with the station: each resolves to the station's new view, or throws. */
export interface SurfaceWindActions {
  set(body: SurfaceWindBody): Promise<SurfaceWind | null>;
  clear(): Promise<SurfaceWind | null>;
}

interface Line {
  root: HTMLElement;
  value: HTMLElement;
  main: HTMLElement;
  detail: HTMLElement;
}

function line(label: string, testid: string): Line {
  const main = h("b", {});
  const detail = h("span", { class: "sw-detail" });
  const value = h("span", { class: "ro-val sw-val", "data-testid": testid }, main, detail);
  return { root: h("div", { class: "sw-row" }, h("span", { class: "sw-lbl" }, label), value), value, main, detail };
}

function show(l: Line, shown: ShownLine): void {
  setText(l.main, shown.text);
  setText(l.detail, shown.detail === "" ? "" : ` ${shown.detail}`);
  setAttr(l.value, "title", shown.title);
  l.value.classList.toggle("warn", shown.warn);
}

export class SurfaceWindBlock {
  readonly root: HTMLElement;
  /** The heading's button that opens the form (operators only). */
  readonly toggle: HTMLButtonElement;
  private readonly wind = line("Surface", "ro-surface-wind");
  private readonly drone = line("Drone", "ro-surface-drone");
  private readonly mast = line("Anemom.", "ro-surface-anemometer");
  private readonly form: HTMLElement;
  private readonly speed: HTMLInputElement;
  private readonly from: HTMLInputElement;
  private readonly err = h("div", { class: "form-error", role: "alert", "data-testid": "surface-wind-error" });
  private latest: SurfaceWind | null = null;
  private busy = false;
  /** States shown from the stream, counted: an answer to a request must not hide a newer one. */
  private updates = 0;

  constructor(private readonly actions: SurfaceWindActions | null) {
    const input = (testid: string, aria: string, placeholder: string): HTMLInputElement =>
      h("input", { type: "text", inputmode: "decimal", "data-testid": testid, "data-command": true, "aria-label": aria, placeholder });
    this.speed = input("surface-wind-speed", "surface wind speed, m/s", "m/s");
    this.from = input("surface-wind-from", "surface wind from, degrees true", "from °");
    const cmd = (text: string, testid: string, title: string, cls = "small"): HTMLButtonElement =>
      h("button", { type: "button", class: cls, "data-testid": testid, "data-command": true, title }, text);
    const set = cmd("Set", "surface-wind-set", "send this surface wind to the drone (it replaces any you set before)", "small primary");
    const clear = cmd("Clear", "surface-wind-clear", "withdraw the surface wind you set (an anemometer's, if heard, stays)");
    set.addEventListener("click", () => void this.send("set"));
    clear.addEventListener("click", () => void this.send("clear"));
    for (const i of [this.speed, this.from]) i.addEventListener("keydown", (e) => {
      if (e.key === "Enter") void this.send("set");
    });
    this.form = h("div", { class: "sw-form", "data-testid": "surface-wind-form", hidden: true },
      h("div", { class: "sw-inputs" }, this.speed, h("span", {}, "m/s from"), this.from, h("span", {}, "°"), set, clear), this.err);
    this.toggle = cmd("Set surface wind…", "surface-wind-toggle", "type the surface wind at the target (a hand-held anemometer, a windsock)", "sw-toggle");
    this.toggle.setAttribute("aria-expanded", "false");
    this.toggle.addEventListener("click", () => this.open(this.form.hidden));
    this.root = h("div", { class: "sw", "data-testid": "surface-wind" }, this.wind.root, this.drone.root, this.mast.root, this.form);
    this.show(null);
    if (actions === null) this.toggle.hidden = true;
  }

  update(sw: SurfaceWind | null): void {
    this.updates += 1;
    this.show(sw);
  }

  private show(sw: SurfaceWind | null): void {
    this.latest = sw;
    const shown = surfaceWindShown(sw);
    show(this.wind, shown.wind);
    show(this.drone, shown.drone);
    this.mast.root.hidden = shown.anemometer === null;
    if (shown.anemometer !== null) show(this.mast, shown.anemometer);
    this.root.dataset.source = sw?.wind?.source ?? "none";
    this.root.dataset.drone = sw?.drone ?? "unknown";
  }

  private open(on: boolean): void {
    this.form.hidden = !on;
    this.toggle.setAttribute("aria-expanded", String(on));
    this.toggle.classList.toggle("on", on);
    if (!on) return;
    setText(this.err, "");
    // Editing starts from the operator's own value, else from the wind in force.
    const r = this.latest?.operator ?? this.latest?.wind ?? null;
    if (r !== null && this.speed.value === "" && this.from.value === "") {
      this.speed.value = r.speed_mps.toFixed(1);
      this.from.value = r.from_deg.toFixed(0);
    }
    this.speed.focus();
  }

  private async send(what: "set" | "clear"): Promise<void> {
    const actions = this.actions;
    if (actions === null || this.busy) return;
    let request: () => Promise<SurfaceWind | null>;
    if (what === "set") {
      const b = surfaceWindBody(this.speed.value, this.from.value);
      if (!b.ok) {
        setText(this.err, b.error);
        return;
      }
      request = () => actions.set(b.body);
    } else {
      request = () => actions.clear();
    }
    // One request at a time: a double click must not send the wind twice.
    this.busy = true;
    const updatesBefore = this.updates;
    try {
      const view = await request();
      setText(this.err, "");
      // The answer is the station's view when it took the request. A state streamed since is
      // newer (in a rehearsal the drone can accept before the answer arrives): keep that.
      if (view !== null && this.updates === updatesBefore) this.show(view);
      if (what === "clear") this.speed.value = this.from.value = "";
      this.open(false);
    } catch (e) {
      // The station's own reason (a value out of range, the operator role, a replay) as it said it.
      setText(this.err, `${what === "set" ? "not set" : "not cleared"}: ${e instanceof ApiError ? e.reason : e instanceof Error ? e.message : String(e)}`);
    } finally {
      this.busy = false;
    }
  }
}
