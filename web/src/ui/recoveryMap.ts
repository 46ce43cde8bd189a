// The recovery page's map: the point to drive to and the phone, on the station's tiles (the
// offline pack of the field laptop, where there is no internet), with the line between them, and
// a metric grid whose spacing the legend gives, so distances read off the map with no tiles. A
// phone in a field has a small screen and little patience: the map frames both points by itself
// until the person moves it, names its dots in the legend, and says plainly when there are no
// tiles (the arrow still guides).

import L from "leaflet";
import "leaflet/dist/leaflet.css";
import { h, setText } from "./dom";
import { packNote, tilesBadge } from "../lib/tiles";
import type { LatLon, Station } from "../lib/types";
import { MapLegend, type LegendEntry } from "./mapLegend";
import { GRID, ringedDot } from "./mapSymbols";
import { MetricGrid } from "./metricGrid";
import { stationTileLayer } from "./tileLayer";

const ll = (p: LatLon): L.LatLngExpression => [p.lat_deg, p.lon_deg];
const dotEl = (color: string, title: string, testid?: string): HTMLElement => ringedDot(color, 16, title, testid);
const dot = (color: string, title: string, testid: string): L.DivIcon => L.divIcon({ className: "rec-mk", html: dotEl(color, title, testid), iconSize: [20, 20], iconAnchor: [10, 10] });

const POINT = "#006400";
const PHONE = "#0b2f8a";
const LINE: L.PolylineOptions = { color: PHONE, weight: 3, dashArray: "6 6", interactive: false, className: "rec-line" };
const LEGEND: LegendEntry[] = [
  { key: "point", label: "the point to go to", swatch: { kind: "element", make: () => dotEl(POINT, "the point to go to") } },
  { key: "phone", label: "you (this phone, or the position typed)", swatch: { kind: "element", make: () => dotEl(PHONE, "you") } },
  { key: "line", label: "the way there", swatch: { kind: "line", style: LINE } },
  { key: "grid", label: "grid", swatch: { kind: "line", style: GRID } },
];

export class RecoveryMap {
  readonly root: HTMLElement;
  private readonly map: L.Map;
  private readonly point = L.marker([0, 0], { icon: dot(POINT, "the point to go to", "rec-map-point"), interactive: false });
  private readonly phone = L.marker([0, 0], { icon: dot(PHONE, "you", "rec-map-phone"), interactive: false });
  private readonly line = L.polyline([], LINE);
  private readonly legend = new MapLegend(LEGEND, "rec-legend");
  private readonly badge: HTMLElement;
  private readonly packError: string | null;
  private readonly hasTiles: boolean;
  private loaded = 0;
  private failed = 0;
  /** Frames the points by itself until the person drags or zooms. */
  private follow = true;
  private framing = false;

  constructor(station: Station, tileToken: string | null) {
    const el = h("div", { class: "rec-map", "data-testid": "rec-map", role: "application", "aria-label": "map of the landing point and the phone" });
    this.map = L.map(el, { zoomControl: true, attributionControl: true }).setView(ll(station.origin), 14);
    const tiles = stationTileLayer(station, tileToken);
    this.hasTiles = tiles !== null;
    this.packError = station.offline_tiles_error;
    if (tiles) {
      tiles.on("tileload", () => this.onTile(true));
      tiles.on("tileerror", () => this.onTile(false));
      tiles.addTo(this.map);
    }
    L.control.scale({ metric: true, imperial: false, maxWidth: 120 }).addTo(this.map);
    // Lines every so many metres from the launch site; a phone has no room for their labels.
    new MetricGrid(this.map, station.origin, { labelLines: false, onStep: (step) => this.legend.setLabel("grid", `grid squares of ${step} m`) });
    this.line.addTo(this.map);
    const b = tilesBadge(this.hasTiles, 0, 0, this.packError);
    this.badge = h("div", { class: "small muted", "data-testid": "rec-map-tiles", "data-state": b.state }, this.badgeText(b.text));
    const note = packNote(this.packError);
    this.root = h("div", { class: "rec-map-box" }, el, this.legend.root, this.badge, h("div", { class: "small form-error", "data-testid": "rec-map-pack-error", hidden: note === null }, note ?? ""));
    this.map.on("dragstart zoomstart", () => {
      if (!this.framing) this.follow = false;
    });
  }

  private badgeText(text: string): string {
    // Without tiles the map still places the two points against each other and the scale.
    return this.hasTiles ? text : `${text}: the map shows the points and the scale only`;
  }

  private onTile(ok: boolean): void {
    if (ok) this.loaded += 1;
    else this.failed += 1;
    const b = tilesBadge(true, this.loaded, this.failed, this.packError);
    this.badge.dataset.state = b.state;
    setText(this.badge, this.badgeText(b.text));
  }

  /** Shows the point to drive to and, when known, the phone; frames them while following. */
  update(point: LatLon | null, from: LatLon | null): void {
    // The page is laid out after the map is made: Leaflet must measure its box again.
    this.map.invalidateSize();
    const show = (m: L.Marker, p: LatLon | null): void => {
      if (p === null) m.remove();
      else m.setLatLng(ll(p)).addTo(this.map);
    };
    show(this.point, point);
    show(this.phone, from);
    this.line.setLatLngs(point && from ? [ll(from), ll(point)] : []);
    this.legend.show(new Set(["grid", ...(point ? ["point"] : []), ...(from ? ["phone"] : []), ...(point && from ? ["line"] : [])]));
    if (!this.follow || point === null) return;
    this.framing = true;
    try {
      if (from) this.map.fitBounds(L.latLngBounds([ll(point), ll(from)]), { padding: [30, 30], maxZoom: 17, animate: false });
      else this.map.setView(ll(point), Math.max(this.map.getZoom(), 15), { animate: false });
    } finally {
      this.framing = false;
    }
  }
}
