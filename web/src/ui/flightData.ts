// Key flight data: speeds, sink, glide, altitudes, position, GPS, power, and what guidance has
// learned of the canopy beside them; and the actuators as bars.

import { h, panel, readout, setStyle, setText } from "./dom";
import { vehiclePosition } from "../lib/fix";
import { fmt, fmtLatLon, label } from "../lib/format";
import { learnedTable, type LearnedCell } from "../lib/learned";
import type { Learned, N, State } from "../lib/types";

/** "2.04 : 1", or a bare dash when there is no glide (on the ground, under the balloon). */
const glide = (v: N | undefined): string => (v === null || v === undefined ? "—" : fmt(v, ": 1", 2));

type Row = { value: HTMLElement; get: (s: State) => string };

export class FlightData {
  readonly root: HTMLElement;
  private readonly rows: Row[] = [];
  private readonly learned = new LearnedPolar();

  constructor() {
    // Numbers in three columns, the longer texts (position, GPS, air, battery) as one line each
    // below: the left column must hold every panel down to the link without scrolling.
    const grid = h("div", { class: "ro-grid three" });
    const list = h("div", { class: "ro-list" });
    let into = grid;
    const add = (lbl: string, id: string, get: (s: State) => string, title?: string): void => {
      const r = readout(lbl, id, title);
      into.append(r.root);
      this.rows.push({ value: r.value, get });
    };
    add("Airspeed", "ro-airspeed", (s) => fmt(s.estimate?.airspeed_mps ?? s.vehicle?.air?.airspeed_mps, "m/s"));
    add("Ground speed", "ro-groundspeed", (s) => fmt(s.estimate?.ground_speed_mps, "m/s"));
    add("Sink rate", "ro-sink", (s) => fmt(s.estimate?.sink_rate_mps, "m/s"), "positive down");
    add("Heading rate", "ro-heading-rate", (s) => fmt(s.estimate?.heading_rate_dps, "°/s"));
    add("Glide air", "ro-glide-air", (s) => glide(s.estimate?.glide_ratio_air), "horizontal air distance per metre of height");
    add("Glide gnd", "ro-glide-ground", (s) => glide(s.estimate?.glide_ratio_ground), "horizontal ground distance per metre of height");
    add("Altitude MSL", "ro-alt-msl", (s) => fmt(vehiclePosition(s)?.alt_msl_m, "m", 0));
    // Once landed, the height above the origin's ground is the field's elevation difference
    // plus noise ("−4 m"): the stack is on the ground, and that is what to read.
    add("Height AGL", "ro-height", (s) => (s.vehicle?.stage === "landed" ? "landed" : fmt(s.estimate?.height_m, "m", 0)), "height above the ground at the station origin");
    add("Position σ", "ro-pos-sigma", (s) => fmt(s.estimate?.position_sigma_m, "m"));
    into = list;
    add("Position", "ro-position", (s) => {
      const at = vehiclePosition(s);
      return fmtLatLon(at?.lat_deg, at?.lon_deg);
    });
    add("GPS", "ro-gps", (s) => {
      const g = s.vehicle?.gps;
      return g ? `${label(g.fix)} · ${fmt(g.satellites, "sats", 0)} · ±${fmt(g.h_acc_m, "m")}` : "—";
    });
    add("Air", "ro-air", (s) => {
      const a = s.vehicle?.air;
      return a ? `${fmt(a.static_pressure_pa, "Pa", 0)} · q ${fmt(a.differential_pressure_pa, "Pa")} · ${fmt(a.temperature_c, "°C")}` : "—";
    });
    add("Battery", "ro-battery", (s) => {
      const p = s.vehicle?.power;
      return p ? `${fmt(p.voltage_v, "V", 2)} · ${fmt(p.current_a, "A", 2)} · ${fmt(p.remaining_percent, "%", 0)}` : "—";
    });
    this.root = panel("Flight data", "panel-flight", grid, list, this.learned.root);
  }

  update(s: State): void {
    for (const r of this.rows) setText(r.value, r.get(s));
    this.learned.update(s.guidance?.learned ?? null);
  }
}

/**
 * The replica's learned polar (lib/learned.ts) as a table under the readouts. Drawn before the
 * first state, so the column's layout is settled from the start; rebuilt only when its text
 * changes (the scales move slowly, the state comes at 4 Hz).
 */
class LearnedPolar {
  readonly root = h("table", { class: "learned", "data-testid": "learned-polar" });
  private drawn: string | null = null;

  constructor() {
    this.update(null);
  }

  update(l: Learned | null): void {
    const t = learnedTable(l);
    const key = JSON.stringify(t);
    if (key === this.drawn) return;
    this.drawn = key;
    const cell = (tag: "th" | "td", c: LearnedCell, scope?: string): HTMLElement =>
      h(tag, { colspan: c.cols ?? null, rowspan: c.rows ?? null, class: c.off ? "warn off" : null, title: c.title ?? null, scope: scope ?? null }, c.text);
    this.root.replaceChildren(
      h("thead", {}, h("tr", {}, ...t.head.map((c) => cell("th", c, "col")))),
      h("tbody", {}, ...t.rows.map((r) => h("tr", {}, ...r.map((c, i) => (i === 0 ? cell("th", c, "row") : cell("td", c)))))),
    );
  }
}

/** One actuator bar. Bipolar bars (main line −1…1) grow from the centre. */
class Bar {
  readonly root: HTMLElement;
  private readonly fill: HTMLElement;
  private readonly cmd: HTMLElement;
  private readonly text: HTMLElement;

  constructor(name: string, testid: string, private readonly bipolar: boolean) {
    this.fill = h("div", { class: "bar-fill" });
    this.cmd = h("div", { class: "bar-cmd", title: "commanded by guidance" });
    this.text = h("span", { class: "bar-val", "data-testid": testid });
    const track = h("div", { class: `bar-track${bipolar ? " bipolar" : ""}`, role: "meter", "aria-label": name, "aria-valuemin": bipolar ? -1 : 0, "aria-valuemax": 1 }, this.fill, this.cmd);
    this.root = h("div", { class: "bar" }, h("span", { class: "bar-lbl" }, name), track, this.text);
  }

  update(v: N, commanded: N): void {
    const x = v === null ? 0 : Math.max(this.bipolar ? -1 : 0, Math.min(1, v));
    const [left, width] = this.bipolar ? [50 + Math.min(0, x) * 50, Math.abs(x) * 50] : [0, x * 100];
    setStyle(this.fill, `left:${left.toFixed(1)}%;width:${width.toFixed(1)}%`);
    if (commanded === null) setStyle(this.cmd, "display:none");
    else {
      const c = Math.max(this.bipolar ? -1 : 0, Math.min(1, commanded));
      setStyle(this.cmd, `left:${(this.bipolar ? 50 + c * 50 : c * 100).toFixed(1)}%`);
    }
    setText(this.text, v === null ? "—" : `${v >= 0 && this.bipolar ? "+" : ""}${v.toFixed(2)}`);
  }
}

export class Actuators {
  readonly root: HTMLElement;
  private readonly main = new Bar("Main line", "act-main-line", true);
  private readonly left = new Bar("Brake L", "act-brake-left", false);
  private readonly right = new Bar("Brake R", "act-brake-right", false);

  constructor() {
    this.root = panel("Actuators", "panel-actuators", this.main.root, this.left.root, this.right.root);
    this.root.title = "main line −1…1 (bar from the centre), brakes 0…1; the magenta tick is what guidance commands";
  }

  update(s: State): void {
    const sv = s.vehicle?.servos ?? null;
    const c = s.guidance?.commands ?? null;
    this.main.update(sv?.main_line ?? null, c?.main_line ?? null);
    this.left.update(sv?.brake_left ?? null, c?.brake ?? null);
    this.right.update(sv?.brake_right ?? null, c?.brake ?? null);
  }
}
