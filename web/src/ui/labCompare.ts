// The Lab's comparison of a recording with the model, drawn: a line saying what was compared,
// the error table (model − recorded, with units) and one small uPlot per channel with the
// recorded and the modelled series over each other, the plots side by side in a grid.

import uPlot from "uplot";
import { COMPARE_CHANNELS, comparedPart, compareRows, type CompareResult } from "../lib/lab";
import { h } from "./dom";

const RECORDED = "#0b2f8a";
const MODEL = "#c05800";

function channelPlot(r: CompareResult, c: CompareResult["channels"][number], width: number): HTMLElement {
  const title = `${COMPARE_CHANNELS[c.name] ?? c.name} (${c.unit})`;
  const box = h("div", { "data-testid": `compare-plot-${c.name}` }, h("h3", {}, title));
  const opts: uPlot.Options = {
    width,
    height: 160,
    scales: { x: { time: false } },
    // One legend for the grid: nine per-plot legends of "t s: -- recorded: -- model: --" wrapped
    // into each other at narrow widths.
    legend: { show: false },
    series: [{ label: "t s" }, { label: "recorded", stroke: RECORDED, spanGaps: false }, { label: "model", stroke: MODEL, dash: [6, 3] }],
  };
  new uPlot(opts, [r.time_s, c.recorded, c.model], box);
  return box;
}

/** The parts of the Lab's results for a comparison, plots `width` pixels wide. */
export function compareView(r: CompareResult, width: number): HTMLElement[] {
  const vehicle = r.vehicle_changes.length === 0 ? "the seed's vehicle" : `the vehicle with ${r.vehicle_changes.join(", ")}`;
  const head = h("h2", { "data-testid": "compare-summary" }, `${r.recording} (${comparedPart(r)}): ${r.samples} samples over ${r.duration_s.toFixed(1)} s, flown by ${vehicle}`);
  const header = h("tr", {}, ...["channel", "unit", "RMS", "largest |error|", "bias", "samples"].map((t) => h("th", {}, t)));
  const rows = compareRows(r).map((cells) => h("tr", {}, ...cells.map((t) => h("td", {}, t))));
  const table = h("table", { "data-testid": "compare-errors" }, h("caption", {}, "model − recorded, over every recorded sample"), header, ...rows);
  const swatch = (colour: string, dashed: boolean): Node => {
    const line = h("span", { class: "swatch" });
    line.style.borderTop = `2px ${dashed ? "dashed" : "solid"} ${colour}`;
    return line;
  };
  const legend = h("div", { class: "compare-legend", "data-testid": "compare-legend" },
    h("span", {}, swatch(RECORDED, false), " recorded"), h("span", {}, swatch(MODEL, true), " model"), h("span", { class: "note" }, "against t, s from the compared part's start"));
  const grid = h("div", { class: "compare-grid" }, ...r.channels.map((c) => channelPlot(r, c, width)));
  return [h("div", { "data-testid": "compare-result" }, head, table), legend, grid];
}
