// The live map's symbols in one place: each layer's style and each marker's look, which the map
// draws with and its legend draws its swatches from, so the legend cannot drift from the map it
// explains; and the ringed dot the Plan and recovery maps mark their points with. Markers are
// made as elements (a fresh one per call: an element lives in one place), not as HTML text, and
// their style goes through the CSSOM, which the station's Content-Security-Policy allows.

import type L from "leaflet";
import { h, s } from "./dom";
import type { LegendEntry } from "./mapLegend";

/** Layers of stale data are drawn in this grey, whatever their colour. */
export const STALE_COLOR = "#888";

export const TRACK: L.PolylineOptions = { color: "#0b2f8a", weight: 3, className: "map-track" };
export const PATTERN: L.PolylineOptions = { color: "#c000c0", weight: 2, dashArray: "6 5", fill: false, className: "map-pattern" };
export const FINAL: L.PolylineOptions = { color: "#c000c0", weight: 4, className: "map-final-line" };
/** The reachable footprint: at least 95 % (light) and 50 % (darker) of the draws reach it. */
export const REACH_95: L.PolylineOptions = { color: "#2a7ab0", weight: 1, fillColor: "#2a7ab0", fillOpacity: 0.1, interactive: false, className: "map-footprint-95" };
export const REACH_50: L.PolylineOptions = { color: "#2a7ab0", weight: 2, fillColor: "#2a7ab0", fillOpacity: 0.22, interactive: false, className: "map-footprint-50" };
export const ELLIPSE_PLANNED: L.PolylineOptions = { color: "#006400", weight: 2, fillOpacity: 0.12, className: "map-ellipse-planned" };
export const ELLIPSE_UNCONTROLLED: L.PolylineOptions = { color: "#c05800", weight: 2, fillOpacity: 0.08, dashArray: "4 4", className: "map-ellipse-uncontrolled" };
export const DRAFT_PLAN: L.PolylineOptions = { color: "#000", weight: 2, dashArray: "2 6", className: "map-draft-plan" };
export const DRAFT_LOCALIZER: L.PolylineOptions = { color: "#006b8f", weight: 3, dashArray: "10 6", className: "map-draft-localizer" };
export const KEEP_OUT: L.PolylineOptions = { color: "#b00020", weight: 2, fillColor: "#b00020", fillOpacity: 0.18, dashArray: "4 3", className: "map-keep-out" };
/** The unsteered flight path from the vehicle, and the disc steering could reach from deployment. */
export const PATH_LINE: L.PolylineOptions = { color: "#7a4a00", weight: 2, dashArray: "3 6", interactive: false, className: "map-flight-path" };
export const PATH_REACH: L.PolylineOptions = { color: "#7a4a00", weight: 1, fillOpacity: 0.05, interactive: false, className: "map-path-reach" };

/** The flight path's points: glyph, colour, and what they mean. */
export const PATH_MARKS = {
  burst: { glyph: "✷", color: "#b00000", title: "predicted burst" },
  deploy: { glyph: "◆", color: "#7a4a00", title: "predicted parafoil deployment" },
  landing: { glyph: "✕", color: "#7a4a00", title: "unsteered parafoil landing" },
  chute: { glyph: "○", color: "#555", title: "landing under the round chute alone" },
} as const;
export type PathMark = keyof typeof PATH_MARKS;

/** A flight-path point as drawn: the glyph in its colour. */
export function pathGlyph(mark: PathMark, testid?: string): HTMLElement {
  const m = PATH_MARKS[mark];
  return h("div", { "data-testid": testid ?? null, "data-sw": "", title: m.title, style: `color:${m.color};font:bold 18px/20px sans-serif;text-align:center` }, m.glyph);
}

/** A point: a disc of `size_px` in its colour, ringed white and black to stand out on any tile. */
export function ringedDot(color: string, size_px: number, title: string, testid?: string): HTMLElement {
  return h("div", { "data-testid": testid ?? null, "data-sw": "", title, style: `width:${size_px}px;height:${size_px}px;border-radius:50%;background:${color};border:2px solid #fff;box-shadow:0 0 0 1px #000` });
}

export const TARGET_RED = "#d00000";
/** The target: a red ring with a dot, haloed in white to stand out on any tile. */
export function targetIcon(): SVGSVGElement {
  return s("svg", { viewBox: "-17 -17 34 34", width: 34, height: 34 },
    s("circle", { r: 13, fill: "none", stroke: "#fff", "stroke-width": 6 }),
    s("circle", { r: 13, fill: "none", stroke: TARGET_RED, "stroke-width": 3, "data-sw": "" }),
    s("circle", { r: 5, fill: TARGET_RED, stroke: "#fff", "stroke-width": 1.5 }));
}

/** A predicted landing: a dot in the colour of its ellipse. */
export function dotIcon(color: string): SVGSVGElement {
  return s("svg", { viewBox: "-9 -9 18 18", width: 18, height: 18 }, s("circle", { r: 7, fill: color, stroke: "#fff", "stroke-width": 2.5, "data-sw": "" }));
}

export const VEHICLE_YELLOW = "#ffd400";
/** The vehicle: an arrow pointing north at rotation 0, turned by the heading. */
export function vehicleIcon(): SVGSVGElement {
  return s("svg", { viewBox: "-20 -20 40 40", width: 40, height: 40 },
    s("path", { d: "M0 -18 L11 14 L0 7 L-11 14 Z", fill: VEHICLE_YELLOW, stroke: "#000", "stroke-width": 2.5, "stroke-linejoin": "round", "data-sw": "" }));
}

/** The metric grid's lines. */
export const GRID: L.PolylineOptions = { color: "#000", weight: 1, opacity: 0.35, interactive: false, className: "map-grid" };

/** Every symbol the live map may draw, in the legend's order: a short name, and what it means in full. */
export const LIVE_LEGEND: readonly LegendEntry[] = [
  { key: "vehicle", label: "drone", title: "the drone, pointing along its heading", swatch: { kind: "icon", make: vehicleIcon } },
  { key: "track", label: "track", title: "the track flown", swatch: { kind: "line", style: TRACK } },
  { key: "target", label: "target", title: "the landing target", swatch: { kind: "icon", make: targetIcon } },
  { key: "pattern", label: "pattern", title: "the landing pattern guidance flies", swatch: { kind: "line", style: PATTERN } },
  { key: "final", label: "final", title: "the final approach to the target", swatch: { kind: "line", style: FINAL } },
  { key: "planned", label: "landing, guided", title: "predicted landing under guidance", swatch: { kind: "icon", make: () => dotIcon(ELLIPSE_PLANNED.color!) } },
  { key: "ellipse-planned", label: "guided, 1 σ", title: "1-σ ellipse of the guided landing", swatch: { kind: "ellipse", style: ELLIPSE_PLANNED } },
  { key: "uncontrolled", label: "landing, uncontrolled", title: "predicted landing with the servos neutral", swatch: { kind: "icon", make: () => dotIcon(ELLIPSE_UNCONTROLLED.color!) } },
  { key: "ellipse-uncontrolled", label: "uncontrolled, 1 σ", title: "1-σ ellipse of the uncontrolled landing", swatch: { kind: "ellipse", style: ELLIPSE_UNCONTROLLED } },
  { key: "reach-50", label: "reach ≥ 50 %", title: "ground the stack can still reach in at least half of the dispersed draws", swatch: { kind: "area", style: REACH_50 } },
  { key: "reach-95", label: "reach ≥ 95 %", title: "ground the stack can still reach in at least 95 % of the dispersed draws", swatch: { kind: "area", style: REACH_95 } },
  { key: "path", label: "path, unsteered", title: "the predicted unsteered path from the drone", swatch: { kind: "line", style: PATH_LINE } },
  { key: "burst", label: "burst", title: PATH_MARKS.burst.title, swatch: { kind: "element", make: () => pathGlyph("burst") } },
  { key: "deploy", label: "parafoil deploys", title: PATH_MARKS.deploy.title, swatch: { kind: "element", make: () => pathGlyph("deploy") } },
  { key: "unsteered", label: "lands unsteered", title: PATH_MARKS.landing.title, swatch: { kind: "element", make: () => pathGlyph("landing") } },
  { key: "chute", label: "lands on round chute", title: PATH_MARKS.chute.title, swatch: { kind: "element", make: () => pathGlyph("chute") } },
  { key: "path-reach", label: "reach from deploy", title: "where steering could land it from the deploy point", swatch: { kind: "ellipse", style: PATH_REACH } },
  { key: "keep-out", label: "keep-out", title: "keep-out zone: no target inside, a landing predicted inside raises the alarm", swatch: { kind: "area", style: KEEP_OUT } },
  { key: "draft-target", label: "target draft", title: "target being edited, not sent", swatch: { kind: "icon", make: targetIcon, opacity: 0.6 } },
  { key: "draft-plan", label: "plan draft", title: "plan being edited, not sent", swatch: { kind: "line", style: DRAFT_PLAN } },
  { key: "draft-localizer", label: "localizer draft", title: "localizer being edited, not sent", swatch: { kind: "line", style: DRAFT_LOCALIZER } },
  { key: "grid", label: "grid", title: "metric grid east and north of the launch site", swatch: { kind: "line", style: GRID } },
];
