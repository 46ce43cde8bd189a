// The Plan page's map: launch, burst, deploy and landing points with their 1-σ ellipses, the
// unsteered landing samples, the region steering likely reaches (green) and the target, on the
// station's tiles (the field laptop's offline pack) or, without tiles, over nothing but the
// scale. It frames every one of them, the whole sample cloud included, and its legend names
// each symbol from the same styles the map draws with.

import L from "leaflet";
import "leaflet/dist/leaflet.css";
import type * as Wire from "../generated/api";
import { ellipsePolygon } from "../lib/preflight";
import type { Station } from "../lib/types";
import { h } from "./dom";
import { MapLegend, type LegendEntry } from "./mapLegend";
import { ringedDot } from "./mapSymbols";
import { stationTileLayer } from "./tileLayer";

const dot = (color: string, label: string, testid?: string): HTMLElement => ringedDot(color, 14, label, testid);
const dotIcon = (color: string, testid: string, label: string): L.DivIcon => L.divIcon({ className: "plan-mk", html: dot(color, label, testid), iconSize: [18, 18], iconAnchor: [9, 9] });

const LAUNCH = "#fff";
const TARGET = "#000";
/** Each planned point: its field in the plan, colour, test id and name. */
const POINTS: [keyof Pick<Wire.PreflightReport, "burst" | "deploy" | "landing_unsteered">, string, string, string][] = [
  ["burst", "#b00000", "burst", "burst"],
  ["deploy", "#7a4b00", "deploy", "parafoil deploy"],
  ["landing_unsteered", "#0b2f8a", "landing", "unsteered landing"],
];
const SAMPLE: L.CircleMarkerOptions = { radius: 2, color: "#0b2f8a", weight: 1, fillOpacity: 0.6, className: "plan-sample", interactive: false };
const REGION: L.PolylineOptions = { color: "#007a00", weight: 2, fillColor: "#00a000", fillOpacity: 0.25, className: "plan-region", interactive: false };

const LEGEND: LegendEntry[] = [
  { key: "launch", label: "launch site", swatch: { kind: "element", make: () => dot(LAUNCH, "launch site") } },
  ...POINTS.map(([, color, id, name]): LegendEntry => ({ key: id, label: `${name}; ring: its 1-σ ellipse`, swatch: { kind: "element", make: () => dot(color, name) } })),
  { key: "sample", label: "one sample's unsteered landing", swatch: { kind: "dot", style: SAMPLE } },
  { key: "region", label: "region steering reaches", swatch: { kind: "area", style: REGION } },
  { key: "target", label: "target", swatch: { kind: "element", make: () => dot(TARGET, "target") } },
];

export class PreflightMap {
  readonly root: HTMLElement;
  private readonly map: L.Map;
  private readonly layers = L.layerGroup();
  private readonly legend = new MapLegend(LEGEND, "plan-legend");

  constructor(station: Station, tileToken: string | null) {
    const el = h("div", { class: "plan-map", "data-testid": "plan-map", role: "application", "aria-label": "map of the plan" });
    this.map = L.map(el, { zoomControl: true, attributionControl: true }).setView([station.origin.lat_deg, station.origin.lon_deg], 10);
    stationTileLayer(station, tileToken)?.addTo(this.map);
    L.control.scale({ metric: true, imperial: false, maxWidth: 160 }).addTo(this.map);
    this.layers.addTo(this.map);
    this.root = h("div", { class: "plan-map-box" }, el, this.legend.root);
  }

  /** Draws `plan` and frames it. */
  show(plan: Wire.PreflightReport): void {
    this.map.invalidateSize();
    this.layers.clearLayers();
    const r = plan.request;
    const launch: L.LatLngTuple = [r.launch_lat_deg, r.launch_lon_deg];
    const bounds = L.latLngBounds([launch, launch]);
    const drawn = new Set(["launch", ...POINTS.map(([, , id]) => id)]);
    if (plan.steered_region_lat_lon_deg.length > 0) {
      const region = L.polygon(plan.steered_region_lat_lon_deg, REGION).addTo(this.layers);
      bounds.extend(region.getBounds());
      drawn.add("region");
      this.legend.setLabel("region", `region steering reaches in ≥ ${(100 * plan.steered_region_probability).toFixed(0)} % of the samples`);
    }
    for (const [lat, lon] of plan.landing_samples_lat_lon_deg) {
      L.circleMarker([lat, lon], SAMPLE).addTo(this.layers);
      // The whole cloud in view: its spread is the plan's point.
      bounds.extend([lat, lon]);
      drawn.add("sample");
    }
    L.marker(launch, { icon: dotIcon(LAUNCH, "plan-mk-launch", "launch"), interactive: false }).addTo(this.layers);
    for (const [key, color, id] of POINTS) {
      const p = plan[key];
      const ring = ellipsePolygon([p.lat_deg, p.lon_deg], p.ellipse);
      L.polygon(ring, { color, weight: 2, fill: false, className: `plan-ellipse plan-ellipse-${id}`, interactive: false }).addTo(this.layers);
      L.marker([p.lat_deg, p.lon_deg], { icon: dotIcon(color, `plan-mk-${id}`, id), interactive: false }).addTo(this.layers);
      bounds.extend([p.lat_deg, p.lon_deg]);
      for (const q of ring) bounds.extend(q);
    }
    if (plan.target) {
      L.marker([plan.target.lat_deg, plan.target.lon_deg], { icon: dotIcon(TARGET, "plan-mk-target", "target"), interactive: false }).addTo(this.layers);
      bounds.extend([plan.target.lat_deg, plan.target.lon_deg]);
      drawn.add("target");
    }
    this.legend.show(drawn);
    // At once, not animated: a new plan is a new picture, and the page reads as it is drawn.
    this.map.fitBounds(bounds, { padding: [24, 24], animate: false });
  }
}
