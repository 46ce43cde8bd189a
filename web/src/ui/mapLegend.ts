// A map's legend: one row per symbol the map draws now, each with a swatch drawn from the very
// style or marker the map uses (the caller passes them, never copies of their colours) and what
// it means. Symbols not on the map are not listed, so the legend stays short and says only what
// is there to see. It folds away (a `details` element) on a small screen.

import type L from "leaflet";
import { h, s, setText } from "./dom";

/** How a symbol looks: a line, an area or an ellipse in a Leaflet path style, or a marker's own element. */
export type Swatch =
  | { kind: "line" | "area" | "ellipse"; style: L.PathOptions }
  | { kind: "dot"; style: L.PathOptions }
  | { kind: "icon"; make: () => SVGSVGElement; opacity?: number }
  | { kind: "element"; make: () => HTMLElement };

export interface LegendEntry {
  /** Names the symbol for the page (`data-legend`) and the tests. */
  key: string;
  label: string;
  /** What the symbol means in full (the row's tooltip), where the label is short. */
  title?: string;
  swatch: Swatch;
}

const W = 28;
const H = 16;

/** The swatch as an element; the shape carrying the symbol's colour is marked `data-sw`. */
function swatchOf(sw: Swatch): Element {
  if (sw.kind === "icon") {
    const icon = sw.make();
    icon.setAttribute("width", String(H + 2));
    icon.setAttribute("height", String(H + 2));
    if (sw.opacity !== undefined) icon.setAttribute("opacity", String(sw.opacity));
    return icon;
  }
  if (sw.kind === "element") return sw.make();
  const st = sw.style;
  const color = st.color ?? "#3388ff";
  // Leaflet's own defaults where the style leaves them out (a polygon fills in its stroke colour).
  const paint: Record<string, string | number> = {
    "data-sw": "",
    stroke: st.stroke === false ? "none" : color,
    "stroke-width": Math.min(st.weight ?? 3, 5),
    "stroke-opacity": st.opacity ?? 1,
    fill: sw.kind === "line" || st.fill === false ? "none" : (st.fillColor ?? color),
    "fill-opacity": st.fillOpacity ?? 0.2,
  };
  if (st.dashArray) paint["stroke-dasharray"] = String(st.dashArray);
  const shape =
    sw.kind === "line"
      ? s("line", { ...paint, x1: 2, y1: H / 2, x2: W - 2, y2: H / 2 })
      : sw.kind === "area"
        ? s("rect", { ...paint, x: 2, y: 2, width: W - 4, height: H - 4 })
        : sw.kind === "ellipse"
          ? s("ellipse", { ...paint, cx: W / 2, cy: H / 2, rx: W / 2 - 2, ry: H / 2 - 2 })
          : s("circle", { ...paint, cx: W / 2, cy: H / 2, r: 3 });
  return s("svg", { viewBox: `0 0 ${W} ${H}`, width: W, height: H, "aria-hidden": "true" }, shape);
}

export class MapLegend {
  readonly root: HTMLDetailsElement;
  private readonly rows = new Map<string, { row: HTMLElement; label: HTMLElement }>();

  /** `testid` names the legend; its rows are `${testid}-${key}`. */
  constructor(entries: readonly LegendEntry[], testid: string) {
    const list = h("ul", { class: "map-legend-list" });
    for (const e of entries) {
      const label = h("span", { class: "map-legend-label" }, e.label);
      const row = h("li", { "data-legend": e.key, "data-testid": `${testid}-${e.key}`, title: e.title ?? null, hidden: true }, h("span", { class: "map-legend-swatch" }, swatchOf(e.swatch)), label);
      this.rows.set(e.key, { row, label });
      list.append(row);
    }
    this.root = h("details", { class: "map-legend", "data-testid": testid, open: true }, h("summary", {}, "Legend"), list);
  }

  /** Lists the symbols in `drawn` (keys of the entries), and hides the others. */
  show(drawn: ReadonlySet<string>): void {
    for (const [key, { row }] of this.rows) {
      const hidden = !drawn.has(key);
      if (row.hidden !== hidden) row.hidden = hidden;
    }
  }

  /** Changes what an entry says (a grid's spacing, which follows the zoom). */
  setLabel(key: string, text: string): void {
    const r = this.rows.get(key);
    if (r) setText(r.label, text);
  }
}
