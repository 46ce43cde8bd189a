// Wind: the onboard estimate (speed, from-direction, σ) against the forecast profile and the
// wind the station measured from the balloon's drift during the ascent, drawn as profiles
// against altitude side by side — speed on the left, direction (from, 0…360°) on the right —
// with the forecast dashed, the ascent's bands as diamonds with their ±2σ bars (and the
// altitudes each band spans), the wind measured so far on the way down solid, and the current
// estimate as a dot (with its σ on the speed side). Under the readouts, the surface wind at the
// target and the drone's copy of it (ui/surfaceWind.ts); on the charts, at the ground, its point.

import { h, panel, readout, s, setText } from "./dom";
import { fmt, fmtDir } from "../lib/format";
import { linkStale } from "../lib/staleness";
import { SurfaceWindBlock, type SurfaceWindActions } from "./surfaceWind";
import { ascentBandAt, ascentPoint, directionPieces, directionSpans, forecastAt, MeasuredProfile, type AscentPoint } from "../lib/wind";
import type { AscentWindMsg, ForecastWind, N, State, SurfaceWindReading } from "../lib/types";

// Short: the left column holds every panel down to Link at 1440×900, the surface wind's lines
// included. Each axis's title shares its ticks' row ("0 speed m/s 3.4", "from N E S W N").
const W = 280;
const H = 100;
/** Top margin: the legend's row. */
const T = 14;
/** Bottom margin: the ticks' row. */
const B = 14;
/** Speed chart x range and direction chart x range, in SVG units. */
const SP = { l: 34, r: 138 };
const DR = { l: 172, r: 274 };
const FORECAST = { stroke: "#555", "stroke-width": 2, "stroke-dasharray": "5 3", fill: "none" };
const MEASURED = { stroke: "#006b8f", "stroke-width": 2, fill: "none" };
const ASCENT = "#b34700";
const ASCENT_BAR = { stroke: ASCENT, "stroke-width": 1.5 };
const SURFACE = "#2e7d32";
/** The smallest altitude band drawn, m. */
const MIN_BAND_M = 300;

/** The forecast between two altitudes: its levels inside, and interpolated values at both ends. */
function forecastIn(p: readonly ForecastWind[], lo: number, hi: number): ForecastWind[] {
  if (p.length === 0) return [];
  const end = (a: number): ForecastWind[] => {
    const f = forecastAt(p, a);
    return f ? [{ alt_msl_m: a, speed_mps: f.speed_mps, from_deg: f.from_deg }] : [];
  };
  return [...end(lo), ...p.filter((x) => x.alt_msl_m > lo && x.alt_msl_m < hi), ...end(hi)];
}

/** "2.0 ±0.2 m/s": the unit once, so that speed, spread and direction fit the sidebar's line. */
function speedWithin(speed: N | undefined, spread: N | undefined): string {
  return `${fmt(speed, "")} ±${fmt(spread, "m/s")}`;
}

/** Stages whose wind the estimate measures on the way down. */
const DESCENT_STAGES: ReadonlySet<string> = new Set(["round_chute", "parafoil_deploy", "parafoil"]);

export class WindPanel {
  readonly root: HTMLElement;
  private readonly est: HTMLElement;
  private readonly fc: HTMLElement;
  private readonly asc: HTMLElement;
  private readonly svg: SVGSVGElement;
  private readonly surface: SurfaceWindBlock;
  private readonly measured = new MeasuredProfile();
  private ascent: AscentPoint[] = [];
  private ascentOver = false;
  private last: { profile: readonly ForecastWind[]; alt: number | null; speed: number | null; sigma: number | null; from: number | null; surface: SurfaceWindReading | null } = { profile: [], alt: null, speed: null, sigma: null, from: null, surface: null };
  private lastKey = "";
  private lastTime = -Infinity;

  /**
   * @param groundMslM the ground at the station's origin, m MSL: the chart's axis stops there.
   * @param surfaceWind what the surface wind's form does; null: no form.
   */
  constructor(private readonly groundMslM: N = null, surfaceWind: SurfaceWindActions | null = null) {
    const a = readout("Estimate", "ro-wind");
    const b = readout("Forecast", "ro-wind-forecast", "the forecast profile at the current altitude");
    const c = readout("Ascent", "ro-wind-ascent", "the wind measured from the balloon's drift during the ascent: the band at the current altitude (±2σ of the speed), or the bands measured");
    this.est = a.value;
    this.fc = b.value;
    this.asc = c.value;
    this.svg = s("svg", { viewBox: `0 0 ${W} ${H}`, class: "wind-chart", role: "img", "aria-label": "wind against altitude: speed (left) and direction it blows from (right); forecast dashed, ascent bands diamonds with ±2σ bars, descent measured solid, estimate dot, surface wind squares at the ground", "data-testid": "wind-chart" });
    this.surface = new SurfaceWindBlock(surfaceWind);
    this.root = panel("Wind", "panel-wind", h("div", { class: "ro-list" }, a.root, b.root, c.root), this.surface.root, this.svg as unknown as Node);
    // The form's button sits in the heading's row, which has room to spare: no line of its own.
    this.root.querySelector("h2")?.append(this.surface.toggle);
  }

  /** The ascent's bands (an `ascent_wind` message, or `GET /api/ascent_wind`). */
  setAscent(msg: AscentWindMsg): void {
    this.ascent = msg.bands.map(ascentPoint);
    this.ascentOver = msg.ascent_over;
    this.showAscentReadout();
    this.draw();
  }

  private showAscentReadout(): void {
    const alt = this.last.alt;
    const here = alt === null ? null : ascentBandAt(this.ascent, alt);
    let text = "—";
    if (here) {
      text = `${speedWithin(here.speed_mps, (here.speed_hi_mps - here.speed_lo_mps) / 2)} from ${here.dir_half_deg === null ? "—" : fmtDir(here.from_deg)}`;
    } else if (this.ascent.length > 0) {
      const lo = Math.min(...this.ascent.map((p) => p.alt_min_msl_m));
      const hi = Math.max(...this.ascent.map((p) => p.alt_max_msl_m));
      text = `${this.ascent.length} band${this.ascent.length === 1 ? "" : "s"}, ${lo.toFixed(0)}–${hi.toFixed(0)} m${this.ascentOver ? "" : " so far"}`;
    }
    setText(this.asc, text);
  }

  update(st: State): void {
    this.surface.update(st.surface_wind);
    const e = st.estimate;
    setText(this.est, e ? `${speedWithin(e.wind_speed_mps, e.wind_sigma_mps)} from ${fmtDir(e.wind_from_deg)}` : "—");
    const alt = e?.alt_msl_m ?? null;
    const f = alt === null ? null : forecastAt(st.forecast_wind, alt);
    setText(this.fc, f ? `${fmt(f.speed_mps, "m/s")} from ${fmtDir(f.from_deg)}` : "—");
    // A new mission clock (station restart) is a new descent: the old profile does not belong.
    if (st.time_s < this.lastTime) this.measured.clear();
    this.lastTime = st.time_s;
    // The solid profile is the descent's: under the balloon the estimator's wind is not one (the
    // ascent's own measurement is the diamonds).
    const descending = st.vehicle?.stage != null && DESCENT_STAGES.has(st.vehicle.stage);
    if (descending && !linkStale(st.link) && alt !== null && e?.wind_speed_mps != null && e.wind_from_deg != null) this.measured.add(alt, e.wind_speed_mps, e.wind_from_deg);
    this.last = { profile: st.forecast_wind, alt, speed: e?.wind_speed_mps ?? null, sigma: e?.wind_sigma_mps ?? null, from: e?.wind_from_deg ?? null, surface: st.surface_wind?.wind ?? null };
    this.showAscentReadout();
    this.draw();
  }

  private draw(): void {
    const { profile, alt, speed, sigma, from, surface } = this.last;
    let p = profile;
    const m = this.measured.points();
    const asc = this.ascent;
    const ascKey = asc.map((x) => `${x.alt_msl_m.toFixed(0)}:${x.speed_mps.toFixed(2)}:${x.from_deg.toFixed(0)}:${x.speed_hi_mps.toFixed(2)}`).join(",");
    const key = `${p.map((x) => `${x.alt_msl_m}:${x.speed_mps}:${x.from_deg}`).join(",")}|${m.length}|${ascKey}|${alt?.toFixed(0)}|${speed?.toFixed(2)}|${sigma?.toFixed(2)}|${from?.toFixed(0)}|${surface?.speed_mps.toFixed(1)}:${surface?.from_deg.toFixed(0)}`;
    if (key === this.lastKey) return;
    this.lastKey = key;
    this.svg.replaceChildren();
    if (p.length === 0 && m.length === 0 && asc.length === 0) {
      this.svg.append(s("text", { x: W / 2, y: H / 2, "text-anchor": "middle", "font-size": 12 }, "no forecast, no measurement yet"));
      return;
    }
    // The altitude band flown so far (plus some room), not the whole forecast up to 12 km, where
    // a descent from 1 km would be a smear at the bottom; the forecast is sampled inside it.
    const flown = m.map((x) => x.alt_msl_m).concat(alt === null ? [] : [alt], asc.map((x) => x.alt_min_msl_m), asc.map((x) => x.alt_max_msl_m));
    let aMin: number;
    let aMax: number;
    if (flown.length > 0) {
      const lo = Math.min(...flown);
      const hi = Math.max(...flown);
      const pad = Math.max(50, (hi - lo) * 0.1, (MIN_BAND_M - (hi - lo)) / 2);
      // Not below the ground: only data measured below it (a lower field) may take the axis there.
      aMin = this.groundMslM === null ? lo - pad : Math.max(lo - pad, Math.min(this.groundMslM, lo));
      aMax = Math.max(hi + pad, aMin + MIN_BAND_M);
    } else {
      aMin = Math.min(...p.map((x) => x.alt_msl_m));
      aMax = Math.max(...p.map((x) => x.alt_msl_m), aMin + 1);
    }
    p = forecastIn(p, aMin, aMax);
    // The surface wind at the ground, once the axis reaches down to it (the last hundred metres
    // or so, where guidance uses it).
    const ground = this.groundMslM;
    const atGround = surface !== null && ground !== null && ground >= aMin && ground <= aMax ? { ...surface, alt_msl_m: ground } : null;
    const vTop = Math.max(1, ...p.map((x) => x.speed_mps), ...m.map((x) => x.speed_mps), ...asc.map((x) => x.speed_hi_mps), (speed ?? 0) + (sigma ?? 0), atGround?.speed_mps ?? 0) * 1.1;
    const Y = (a: number): number => H - B - ((a - aMin) / (aMax - aMin)) * (H - T - B);
    const XS = (v: number): number => SP.l + (v / vTop) * (SP.r - SP.l);
    const XD = (d: number): number => DR.l + (d / 360) * (DR.r - DR.l);
    const line = (pts: string[], style: Record<string, string | number>, testid: string): SVGElement => s("polyline", { points: pts.join(" "), ...style, "data-testid": testid });
    const at = (x: number, y: number): string => `${x.toFixed(1)},${y.toFixed(1)}`;

    const frame = s("g", { stroke: "#000", "stroke-width": 1, fill: "none" },
      s("rect", { x: SP.l, y: T, width: SP.r - SP.l, height: H - T - B }),
      s("rect", { x: DR.l, y: T, width: DR.r - DR.l, height: H - T - B }));
    const grid = s("g", { stroke: "#ccc", "stroke-width": 1 }, ...[90, 180, 270].map((d) => s("line", { x1: XD(d), x2: XD(d), y1: T, y2: H - B })));
    const labels = s("g", { "font-size": 9, fill: "#000" },
      s("text", { x: SP.l - 2, y: T + 8, "text-anchor": "end" }, `${aMax.toFixed(0)}`),
      s("text", { x: SP.l - 2, y: H - B, "text-anchor": "end", "data-testid": "wind-axis-min" }, `${aMin.toFixed(0)}`),
      s("text", { x: 1, y: (H - B) / 2 + 2 }, "m MSL"),
      s("text", { x: SP.l, y: H - B + 10, "text-anchor": "start" }, "0"),
      s("text", { x: SP.r, y: H - B + 10, "text-anchor": "end" }, `${(vTop / 1.1).toFixed(1)}`),
      s("text", { x: (SP.l + SP.r) / 2, y: H - B + 10, "text-anchor": "middle", "font-weight": 700 }, "speed m/s"),
      ...[0, 90, 180, 270, 360].map((d) => s("text", { x: XD(d), y: H - B + 10, "text-anchor": d === 0 ? "start" : d === 360 ? "end" : "middle" }, d === 0 ? "N" : d === 90 ? "E" : d === 180 ? "S" : d === 270 ? "W" : "N")),
      s("text", { x: DR.l - 3, y: H - B + 10, "text-anchor": "end", "font-weight": 700 }, "from"));
    this.svg.append(grid, frame, labels, this.legend({ forecast: p.length > 0, ascent: asc.length > 0, descent: m.length > 1, estimate: alt !== null && speed !== null, surface: atGround !== null }));

    // Speed profiles.
    if (p.length > 0) this.svg.append(line(p.map((x) => at(XS(x.speed_mps), Y(x.alt_msl_m))), FORECAST, "wind-forecast-speed"));
    if (m.length > 1) this.svg.append(line(m.map((x) => at(XS(x.speed_mps), Y(x.alt_msl_m))), MEASURED, "wind-measured-speed"));
    // Direction profiles, cut where they cross north.
    for (const piece of directionPieces(p)) this.svg.append(line(piece.map((x) => at(XD(x.from_deg), Y(x.alt_msl_m))), FORECAST, "wind-forecast-dir"));
    for (const piece of directionPieces(m)) if (piece.length > 1) this.svg.append(line(piece.map((x) => at(XD(x.from_deg), Y(x.alt_msl_m))), MEASURED, "wind-measured-dir"));

    // The ascent's bands: the altitudes each spans, its ±2σ, and a diamond at its wind.
    const diamond = (x: number, y: number, testid: string): SVGElement =>
      s("path", { d: `M${x.toFixed(1)},${(y - 4).toFixed(1)} l4,4 l-4,4 l-4,-4 z`, fill: ASCENT, stroke: "#000", "stroke-width": 0.5, "data-testid": testid });
    for (const b of asc) {
      const y = Y(b.alt_msl_m);
      const extent = (x: number): SVGElement => s("line", { x1: x, x2: x, y1: Y(b.alt_min_msl_m), y2: Y(b.alt_max_msl_m), stroke: ASCENT, "stroke-width": 1, "stroke-opacity": 0.5 });
      this.svg.append(
        extent(XS(b.speed_mps)),
        s("line", { x1: XS(b.speed_lo_mps), x2: XS(b.speed_hi_mps), y1: y, y2: y, ...ASCENT_BAR, "data-testid": "wind-ascent-speed-bar" }),
        diamond(XS(b.speed_mps), y, "wind-ascent-speed"),
      );
      for (const [lo, hi] of directionSpans(b.from_deg, b.dir_half_deg)) {
        this.svg.append(s("line", { x1: XD(lo), x2: XD(hi), y1: y, y2: y, ...ASCENT_BAR, "stroke-dasharray": b.dir_half_deg === null ? "2 2" : "none", "data-testid": "wind-ascent-dir-bar" }));
      }
      if (b.dir_half_deg !== null) this.svg.append(extent(XD(b.from_deg)), diamond(XD(b.from_deg), y, "wind-ascent-dir"));
    }

    if (alt !== null) {
      this.svg.append(
        s("line", { x1: SP.l, x2: SP.r, y1: Y(alt), y2: Y(alt), stroke: "#999", "stroke-width": 1 }),
        s("line", { x1: DR.l, x2: DR.r, y1: Y(alt), y2: Y(alt), stroke: "#999", "stroke-width": 1 }));
      if (speed !== null) {
        const sg = sigma ?? 0;
        this.svg.append(
          s("line", { x1: XS(Math.max(0, speed - sg)), x2: XS(speed + sg), y1: Y(alt), y2: Y(alt), stroke: "#006b8f", "stroke-width": 4 }),
          s("circle", { cx: XS(speed), cy: Y(alt), r: 4.5, fill: "#006b8f", stroke: "#000", "data-testid": "wind-est-speed" }));
      }
      if (from !== null) {
        const d = ((from % 360) + 360) % 360;
        this.svg.append(s("circle", { cx: XD(d), cy: Y(alt), r: 4.5, fill: "#006b8f", stroke: "#000", "data-testid": "wind-est-dir" }));
      }
    }
    if (atGround !== null) {
      const square = (x: number, testid: string): SVGElement => s("rect", { x: x - 4, y: Y(atGround.alt_msl_m) - 4, width: 8, height: 8, fill: SURFACE, stroke: "#000", "data-testid": testid });
      this.svg.append(square(XS(atGround.speed_mps), "wind-surface-speed"), square(XD(((atGround.from_deg % 360) + 360) % 360), "wind-surface-dir"));
    }
  }

  /** What each mark drawn is, in a row above the charts: nothing that is not on them. */
  private legend(shown: { forecast: boolean; ascent: boolean; descent: boolean; estimate: boolean; surface: boolean }): SVGElement {
    const y = 8;
    const items: [boolean, number, (x: number) => SVGElement, string][] = [
      [shown.forecast, 56, (x) => s("line", { x1: x, x2: x + 12, y1: y, y2: y, ...FORECAST }), "forecast"],
      [shown.ascent, 68, (x) => s("path", { d: `M${x + 6},${y - 4} l4,4 l-4,4 l-4,-4 z`, fill: ASCENT }), "ascent ±2σ"],
      [shown.descent, 52, (x) => s("line", { x1: x, x2: x + 12, y1: y, y2: y, ...MEASURED }), "descent"],
      [shown.estimate, 50, (x) => s("circle", { cx: x + 6, cy: y, r: 3.5, fill: "#006b8f", stroke: "#000" }), "estimate"],
      [shown.surface, 48, (x) => s("rect", { x: x + 2.5, y: y - 3.5, width: 7, height: 7, fill: SURFACE, stroke: "#000" }), "surface"],
    ];
    const g = s("g", { "data-testid": "wind-legend" });
    let x = 4;
    for (const [on, width, mark, label] of items) {
      if (!on) continue;
      g.append(mark(x), s("text", { x: x + 14, y: y + 3, "font-size": 8, "data-testid": "wind-legend-item" }, label));
      x += width;
    }
    return g;
  }
}
