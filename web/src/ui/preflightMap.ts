// The Plan page's map: launch, burst, deploy and landing points with their 1-σ ellipses, the
// unsteered landing samples, the region steering likely reaches and the target, on the station's
// tiles (the field laptop's offline pack) or, without tiles, over nothing but the scale.

import L from "leaflet";
import "leaflet/dist/leaflet.css";
import type * as Wire from "../generated/api";
import { ellipsePolygon } from "../lib/preflight";
import type { Station } from "../lib/types";
import { h } from "./dom";
import { stationTileLayer } from "./tileLayer";

const dot = (color: string, testid: string, label: string): L.DivIcon =>
  // An element, not HTML text: its style goes through the CSSOM, which the CSP allows.
  L.divIcon({ className: "plan-mk", html: h("div", { "data-testid": testid, title: label, style: `width:14px;height:14px;border-radius:50%;background:${color};border:2px solid #fff;box-shadow:0 0 0 1px #000` }), iconSize: [18, 18], iconAnchor: [9, 9] });

/** Each planned point: its name on the page, colour and test id. */
const POINTS: [keyof Pick<Wire.PreflightReport, "burst" | "deploy" | "landing_unsteered">, string, string][] = [
  ["burst", "#b00000", "burst"],
  ["deploy", "#7a4b00", "deploy"],
  ["landing_unsteered", "#0b2f8a", "landing"],
];

export class PreflightMap {
  readonly root: HTMLElement;
  private readonly map: L.Map;
  private readonly layers = L.layerGroup();

  constructor(station: Station, tileToken: string | null) {
    const el = h("div", { class: "plan-map", "data-testid": "plan-map", role: "application", "aria-label": "map of the plan" });
    this.map = L.map(el, { zoomControl: true, attributionControl: true }).setView([station.origin.lat_deg, station.origin.lon_deg], 10);
    stationTileLayer(station, tileToken)?.addTo(this.map);
    L.control.scale({ metric: true, imperial: false, maxWidth: 160 }).addTo(this.map);
    this.layers.addTo(this.map);
    this.root = h("div", { class: "plan-map-box" }, el,
      h("div", { class: "small muted" }, "red: burst · brown: parafoil deploy · blue: unsteered landing (with samples) · green: region steering reaches · black: target; rings are 1-σ"));
  }

  /** Draws `plan` and frames it. */
  show(plan: Wire.PreflightReport): void {
    this.map.invalidateSize();
    this.layers.clearLayers();
    const r = plan.request;
    const launch: L.LatLngTuple = [r.launch_lat_deg, r.launch_lon_deg];
    const region = L.polygon(plan.steered_region_lat_lon_deg, { color: "#005a00", weight: 2, fillOpacity: 0.12, className: "plan-region", interactive: false });
    region.addTo(this.layers);
    for (const [lat, lon] of plan.landing_samples_lat_lon_deg) {
      L.circleMarker([lat, lon], { radius: 2, color: "#0b2f8a", weight: 1, fillOpacity: 0.6, className: "plan-sample", interactive: false }).addTo(this.layers);
    }
    const bounds = L.latLngBounds([launch, launch]).extend(region.getBounds());
    L.marker(launch, { icon: dot("#fff", "plan-mk-launch", "launch"), interactive: false }).addTo(this.layers);
    for (const [key, color, id] of POINTS) {
      const p = plan[key];
      const ring = ellipsePolygon([p.lat_deg, p.lon_deg], p.ellipse);
      L.polygon(ring, { color, weight: 2, fill: false, className: `plan-ellipse plan-ellipse-${id}`, interactive: false }).addTo(this.layers);
      L.marker([p.lat_deg, p.lon_deg], { icon: dot(color, `plan-mk-${id}`, id), interactive: false }).addTo(this.layers);
      bounds.extend([p.lat_deg, p.lon_deg]);
      for (const q of ring) bounds.extend(q);
    }
    if (plan.target) {
      L.marker([plan.target.lat_deg, plan.target.lon_deg], { icon: dot("#000", "plan-mk-target", "target"), interactive: false }).addTo(this.layers);
      bounds.extend([plan.target.lat_deg, plan.target.lon_deg]);
    }
    this.map.fitBounds(bounds.pad(0.1));
  }
}
