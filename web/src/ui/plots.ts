// Plots over time (uPlot): altitude; airspeed and sink rate; heading and course; main line and
// brakes. Fed by `history.states`, then by live states; 10 minutes kept (series.ts). Redrawn at
// most once a second: the data come at 4 Hz but the eye does not need it, and the cores are shared.
// Time without current data (stale link, silent station) is a gap in the lines under a grey
// hatched band labelled "stale", never a line drawn on as if live.

import uPlot from "uplot";
import "uplot/dist/uPlot.min.css";
import { h } from "./dom";
import { breakWraps, Series, staleSpans } from "../lib/series";
import { linkStale } from "../lib/staleness";
import { wrap360 } from "../lib/format";
import type { State } from "../lib/types";

interface ChartDef {
  id: string;
  title: string;
  unit: string;
  series: { label: string; color: string; dash?: number[] }[];
  pick: (s: State) => (number | null)[];
  angles?: boolean;
  range?: [number, number];
}

const DEFS: ChartDef[] = [
  { id: "plot-altitude", title: "Altitude", unit: "m MSL", series: [{ label: "altitude m", color: "#0b2f8a" }], pick: (s) => [s.estimate?.alt_msl_m ?? null] },
  {
    id: "plot-speeds", title: "Airspeed, sink rate", unit: "m/s",
    series: [{ label: "airspeed m/s", color: "#0b2f8a" }, { label: "sink m/s", color: "#c05800" }],
    pick: (s) => [s.estimate?.airspeed_mps ?? null, s.estimate?.sink_rate_mps ?? null],
  },
  {
    id: "plot-heading", title: "Heading, course", unit: "°", angles: true, range: [0, 360],
    series: [{ label: "heading °", color: "#0b2f8a" }, { label: "course °", color: "#c000c0" }],
    pick: (s) => [s.estimate?.heading_deg == null ? null : wrap360(s.estimate.heading_deg), s.estimate?.course_deg == null ? null : wrap360(s.estimate.course_deg)],
  },
  {
    id: "plot-actuators", title: "Main line, brakes", unit: "−1…1", range: [-1, 1],
    series: [{ label: "main line", color: "#0b2f8a" }, { label: "brake L", color: "#006400" }, { label: "brake R", color: "#c05800", dash: [6, 4] }],
    pick: (s) => [s.vehicle?.servos?.main_line ?? null, s.vehicle?.servos?.brake_left ?? null, s.vehicle?.servos?.brake_right ?? null],
  },
];

export class Plots {
  readonly root: HTMLElement;
  private readonly charts: { def: ChartDef; data: Series; plot: uPlot | null; box: HTMLElement }[];
  private dirty = false;
  private timer: ReturnType<typeof setInterval> | null = null;

  constructor() {
    this.root = h("div", { class: "plots", "data-testid": "plots" });
    this.charts = DEFS.map((def) => {
      const box = h("div", { class: "plot", "data-testid": def.id });
      this.root.append(box);
      return { def, data: new Series(def.series.map((x) => x.label)), plot: null, box };
    });
  }

  /** Creates the charts once the container has a size; safe to call again on resize or tab show. */
  layout(): void {
    for (const c of this.charts) {
      const w = Math.max(200, c.box.clientWidth);
      const hgt = Math.max(120, c.box.clientHeight - 4);
      if (c.box.clientWidth === 0) continue; // hidden tab: try again when shown
      if (c.plot === null) {
        c.plot = new uPlot(this.options(c.def, w, hgt, c.data), this.columns(c), c.box);
        // What the chart draws, for the end-to-end test (it reads the data, not the pixels).
        (c.box as HTMLElement & { uplot?: uPlot }).uplot = c.plot;
      } else c.plot.setSize({ width: w, height: hgt });
    }
    if (this.timer === null) this.timer = setInterval(() => this.redraw(), 1000);
  }

  /**
   * Starts over from `history.states`. The server sends the latest state before the history, so
   * history cannot simply be appended (it would be older than what is already there).
   */
  reset(states: readonly State[], latest: State | null): void {
    for (const c of this.charts) c.data.clear();
    for (const s of states) this.push(s);
    if (latest !== null) this.push(latest);
    this.dirty = true;
  }

  push(s: State): void {
    const stale = linkStale(s.link);
    // On the mission clock (the drone's), as the T+ clock: at 20× a minute of flight is a
    // minute on the axis. The station's clock only before the drone is heard.
    const t = s.mission_time_s ?? s.time_s;
    for (const c of this.charts) if (c.data.push(t, c.def.pick(s), stale)) this.dirty = true;
  }

  private redraw(): void {
    if (!this.dirty) return;
    this.dirty = false;
    for (const c of this.charts) c.plot?.setData(this.columns(c));
  }

  private columns(c: { def: ChartDef; data: Series }): uPlot.AlignedData {
    const cols = c.data.cols.map((col) => (c.def.angles ? breakWraps(col) : col));
    return [c.data.t.slice(), ...cols.map((x) => x.slice())] as uPlot.AlignedData;
  }

  private options(def: ChartDef, width: number, height: number, data: Series): uPlot.Options {
    return {
      width,
      height,
      hooks: { drawClear: [(u: uPlot) => drawStaleBands(u, data)] },
      title: `${def.title} (${def.unit})`,
      legend: { show: true, live: true },
      cursor: { drag: { x: false, y: false } },
      scales: { x: { time: false }, y: def.range ? { range: def.range } : { auto: true } },
      axes: [
        { label: "mission time, s", stroke: "#000", grid: { stroke: "#ccc" }, size: 34, labelSize: 14 },
        { stroke: "#000", grid: { stroke: "#ccc" }, size: 48, ...(def.angles ? { splits: () => [0, 90, 180, 270, 360] } : {}) },
      ],
      series: [{ label: "T s" }, ...def.series.map((x) => ({ label: x.label, stroke: x.color, width: 2, spanGaps: false, ...(x.dash ? { dash: x.dash } : {}) }))],
    };
  }
}

/** Grey hatched bands over the stretches without current data, under the lines. */
function drawStaleBands(u: uPlot, data: Series): void {
  const spans = staleSpans(data.t, data.kinds);
  if (spans.length === 0) return;
  const ctx = u.ctx;
  const { top, height, left, width } = u.bbox;
  for (const [a, b] of spans) {
    const x0 = Math.max(left, u.valToPos(a, "x", true));
    const x1 = Math.min(left + width, u.valToPos(b, "x", true));
    if (!Number.isFinite(x0) || !Number.isFinite(x1) || x1 <= x0) continue;
    ctx.save();
    ctx.beginPath();
    ctx.rect(x0, top, x1 - x0, height);
    ctx.clip();
    ctx.fillStyle = "rgba(120, 120, 120, 0.22)";
    ctx.fillRect(x0, top, x1 - x0, height);
    ctx.strokeStyle = "rgba(80, 80, 80, 0.35)";
    ctx.lineWidth = 1;
    ctx.beginPath();
    for (let x = x0 - height; x < x1; x += 10 * devicePixelRatio) {
      ctx.moveTo(x, top + height);
      ctx.lineTo(x + height, top);
    }
    ctx.stroke();
    if (x1 - x0 > 40 * devicePixelRatio) {
      ctx.fillStyle = "#000";
      // uPlot leaves the context as its axes last set it (right-aligned labels).
      ctx.textAlign = "left";
      ctx.textBaseline = "alphabetic";
      ctx.font = `bold ${11 * devicePixelRatio}px sans-serif`;
      ctx.fillText("stale", x0 + 4 * devicePixelRatio, top + 14 * devicePixelRatio);
    }
    ctx.restore();
  }
}
