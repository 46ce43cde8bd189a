// Wind: the onboard estimate (speed, from-direction, σ) against the forecast profile, drawn as
// speed versus altitude with the estimate marked at the current altitude.

import { h, panel, readout, s, setText } from "./dom";
import { fmt, fmtDir } from "../lib/format";
import { forecastAt } from "../lib/wind";
import type { ForecastWind, State } from "../lib/types";

const W = 240;
const H = 130;
const PAD = { l: 40, r: 8, t: 8, b: 24 };

export class WindPanel {
  readonly root: HTMLElement;
  private readonly est: HTMLElement;
  private readonly fc: HTMLElement;
  private readonly svg: SVGSVGElement;
  private lastProfileKey = "";

  constructor() {
    const a = readout("Estimate", "ro-wind");
    const b = readout("Forecast here", "ro-wind-forecast");
    this.est = a.value;
    this.fc = b.value;
    this.svg = s("svg", { viewBox: `0 0 ${W} ${H}`, class: "wind-chart", role: "img", "aria-label": "wind speed against altitude: forecast line, estimate dot", "data-testid": "wind-chart" });
    this.root = panel("Wind", "panel-wind", h("div", { class: "ro-grid" }, a.root, b.root), this.svg as unknown as Node);
  }

  update(st: State): void {
    const e = st.estimate;
    setText(this.est, e ? `${fmt(e.wind_speed_mps, "m/s")} from ${fmtDir(e.wind_from_deg)} ±${fmt(e.wind_sigma_mps, "m/s", 2)}` : "—");
    const alt = e?.alt_msl_m ?? null;
    const f = alt === null ? null : forecastAt(st.forecast_wind, alt);
    setText(this.fc, f ? `${fmt(f.speed_mps, "m/s")} from ${fmtDir(f.from_deg)}` : "—");
    this.draw(st.forecast_wind, alt, e?.wind_speed_mps ?? null, e?.wind_sigma_mps ?? null);
  }

  private draw(p: readonly ForecastWind[], alt: number | null, speed: number | null, sigma: number | null): void {
    const key = `${p.map((x) => `${x.alt_msl_m}:${x.speed_mps}`).join(",")}|${alt?.toFixed(0)}|${speed?.toFixed(2)}|${sigma?.toFixed(2)}`;
    if (key === this.lastProfileKey) return;
    this.lastProfileKey = key;
    this.svg.replaceChildren();
    if (p.length === 0) {
      this.svg.append(s("text", { x: W / 2, y: H / 2, "text-anchor": "middle", "font-size": 12 }, "no forecast"));
      return;
    }
    const alts = p.map((x) => x.alt_msl_m).concat(alt === null ? [] : [alt]);
    const aMin = Math.min(...alts);
    const aMax = Math.max(...alts, aMin + 1);
    const vMax = Math.max(1, ...p.map((x) => x.speed_mps), (speed ?? 0) + (sigma ?? 0)) * 1.1;
    const X = (v: number): number => PAD.l + (v / vMax) * (W - PAD.l - PAD.r);
    const Y = (a: number): number => H - PAD.b - ((a - aMin) / (aMax - aMin)) * (H - PAD.t - PAD.b);
    const axis = s("g", { stroke: "#000", "stroke-width": 1 },
      s("line", { x1: PAD.l, y1: PAD.t, x2: PAD.l, y2: H - PAD.b }),
      s("line", { x1: PAD.l, y1: H - PAD.b, x2: W - PAD.r, y2: H - PAD.b }));
    const labels = s("g", { "font-size": 10, fill: "#000" },
      s("text", { x: PAD.l - 3, y: Y(aMax) + 8, "text-anchor": "end" }, `${aMax.toFixed(0)}`),
      s("text", { x: PAD.l - 3, y: Y(aMin), "text-anchor": "end" }, `${aMin.toFixed(0)}`),
      s("text", { x: 2, y: H / 2 - 4 }, "alt"),
      s("text", { x: 2, y: H / 2 + 8 }, "m MSL"),
      s("text", { x: X(0), y: H - 8, "text-anchor": "start" }, "0"),
      s("text", { x: X(vMax / 1.1), y: H - 8, "text-anchor": "middle" }, `${(vMax / 1.1).toFixed(1)}`),
      s("text", { x: W - PAD.r, y: H - 1, "text-anchor": "end" }, "speed m/s"));
    const line = s("polyline", { points: p.map((x) => `${X(x.speed_mps).toFixed(1)},${Y(x.alt_msl_m).toFixed(1)}`).join(" "), fill: "none", stroke: "#555", "stroke-width": 2, "stroke-dasharray": "5 3" });
    this.svg.append(axis, labels, line);
    if (alt !== null) {
      this.svg.append(s("line", { x1: PAD.l, x2: W - PAD.r, y1: Y(alt), y2: Y(alt), stroke: "#999", "stroke-width": 1 }));
      if (speed !== null) {
        const sg = sigma ?? 0;
        this.svg.append(
          s("line", { x1: X(Math.max(0, speed - sg)), x2: X(speed + sg), y1: Y(alt), y2: Y(alt), stroke: "#006b8f", "stroke-width": 4 }),
          s("circle", { cx: X(speed), cy: Y(alt), r: 5, fill: "#006b8f", stroke: "#000" }),
        );
      }
    }
  }
}
