/**
 * The unsteered flight path on the live map during the ascent and under the round chute: the
 * burst, the deploy point, where the parafoil lands unsteered and where the round chute alone
 * would, joined by a dashed line from the vehicle, the disc steering could reach from the
 * deploy point, and a badge saying when each comes and which winds the path flew in.
 */
import L from "leaflet";
import { h, setText } from "./dom";
import { flightPathSummary, type FlightPath } from "../lib/flightPath";
import type { LatLon } from "../lib/types";

const ll = (p: LatLon): L.LatLngExpression => [p.lat_deg, p.lon_deg];

const MARK = (testid: string, glyph: string, title: string, colour: string): L.DivIcon =>
  L.divIcon({
    className: "mk mk-path",
    // An element, not HTML text: its style goes through the CSSOM, which the CSP allows.
    html: h("div", { "data-testid": testid, title, style: `color:${colour};font:bold 18px/20px sans-serif;text-align:center` }, glyph),
    iconSize: [20, 20],
    iconAnchor: [10, 10],
  });

export class FlightPathLayer {
  readonly badge: HTMLElement;
  private readonly group = L.layerGroup();
  private readonly line = L.polyline([], { color: "#7a4a00", weight: 2, dashArray: "3 6", interactive: false, className: "map-flight-path" });
  private readonly reach = L.circle([0, 0], { radius: 1, color: "#7a4a00", weight: 1, fillOpacity: 0.05, interactive: false, className: "map-path-reach" });
  private readonly burst = L.marker([0, 0], { icon: MARK("map-burst", "✷", "predicted burst", "#b00000"), interactive: false });
  private readonly deploy = L.marker([0, 0], { icon: MARK("map-deploy", "◆", "predicted parafoil deployment", "#7a4a00"), interactive: false });
  private readonly landing = L.marker([0, 0], { icon: MARK("map-unsteered-landing", "✕", "unsteered parafoil landing", "#7a4a00"), interactive: false });
  private readonly chute = L.marker([0, 0], { icon: MARK("map-chute-landing", "○", "landing under the round chute alone", "#555"), interactive: false });

  constructor(map: L.Map) {
    this.badge = h("div", { class: "map-badge path", "data-testid": "map-flight-path", hidden: true });
    this.group.addTo(map);
  }

  /** Draws `p` from the vehicle at `from`; null clears it (under the parafoil, on the ground). */
  update(p: FlightPath | null, from: LatLon | null, stale: boolean, mission_time_s: number | null = null): void {
    this.group.clearLayers();
    this.badge.hidden = p === null;
    if (p === null) return;
    const points = [from, p.burst, p.deploy, p.landing].filter((x): x is LatLon => x !== null);
    this.line.setLatLngs(points.map(ll));
    this.reach.setLatLng(ll(p.reach_centre)).setRadius(p.reach_radius_m);
    this.group.addLayer(this.reach).addLayer(this.line);
    if (p.burst) this.group.addLayer(this.burst.setLatLng(ll(p.burst)));
    this.group.addLayer(this.deploy.setLatLng(ll(p.deploy)));
    this.group.addLayer(this.landing.setLatLng(ll(p.landing)));
    this.group.addLayer(this.chute.setLatLng(ll(p.round_chute_landing)));
    for (const [m, pt] of [[this.burst, p.burst], [this.deploy, p.deploy], [this.landing, p.landing], [this.chute, p.round_chute_landing]] as const) {
      const el = m.getElement()?.querySelector<HTMLElement>("[data-testid]");
      if (el && pt) {
        // Where the page drew it, for tests and for people reading the DOM.
        el.dataset.lat = pt.lat_deg.toFixed(6);
        el.dataset.lon = pt.lon_deg.toFixed(6);
        el.dataset.alt = pt.alt_msl_m.toFixed(0);
      }
    }
    setText(this.badge, flightPathSummary(p, mission_time_s));
    this.badge.classList.toggle("stale", stale);
  }
}
