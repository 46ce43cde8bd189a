/**
 * The unsteered flight path on the live map during the ascent and under the round chute: the
 * burst, the deploy point, where the parafoil lands unsteered and where the round chute alone
 * would, joined by a dashed line from the vehicle, the disc steering could reach from the
 * deploy point, and a badge saying when each comes and which winds the path flew in.
 */
import L from "leaflet";
import { h, setText } from "./dom";
import { PATH_LINE, PATH_REACH, pathGlyph, type PathMark } from "./mapSymbols";
import { flightPathSummary, type FlightPath } from "../lib/flightPath";
import type { LatLon } from "../lib/types";

const ll = (p: LatLon): L.LatLngExpression => [p.lat_deg, p.lon_deg];

const MARK = (mark: PathMark, testid: string): L.DivIcon => L.divIcon({ className: "mk mk-path", html: pathGlyph(mark, testid), iconSize: [20, 20], iconAnchor: [10, 10] });

export class FlightPathLayer {
  readonly badge: HTMLElement;
  private readonly group = L.layerGroup();
  /** The legend's keys of what is drawn now (mapSymbols.ts). */
  readonly drawn = new Set<string>();
  private readonly line = L.polyline([], PATH_LINE);
  private readonly reach = L.circle([0, 0], { ...PATH_REACH, radius: 1 });
  private readonly burst = L.marker([0, 0], { icon: MARK("burst", "map-burst"), interactive: false });
  private readonly deploy = L.marker([0, 0], { icon: MARK("deploy", "map-deploy"), interactive: false });
  private readonly landing = L.marker([0, 0], { icon: MARK("landing", "map-unsteered-landing"), interactive: false });
  private readonly chute = L.marker([0, 0], { icon: MARK("chute", "map-chute-landing"), interactive: false });

  constructor(map: L.Map) {
    this.badge = h("div", { class: "map-badge path", "data-testid": "map-flight-path", hidden: true });
    this.group.addTo(map);
  }

  /** Draws `p` from the vehicle at `from`; null clears it (under the parafoil, on the ground). */
  update(p: FlightPath | null, from: LatLon | null, stale: boolean, mission_time_s: number | null = null): void {
    this.group.clearLayers();
    this.drawn.clear();
    this.badge.hidden = p === null;
    if (p === null) return;
    for (const key of ["path", "path-reach", "deploy", "unsteered", "chute", ...(p.burst ? ["burst"] : [])]) this.drawn.add(key);
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
