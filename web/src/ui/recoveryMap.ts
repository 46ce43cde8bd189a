// The recovery page's map: the point to drive to and the phone, on the station's tiles (the
// offline pack of the field laptop, where there is no internet), with the line between them. A
// phone in a field has a small screen and little patience: the map frames both points by itself
// until the person moves it, and says plainly when there are no tiles (the arrow still guides).

import L from "leaflet";
import "leaflet/dist/leaflet.css";
import { h, setText } from "./dom";
import { packNote, tilesBadge } from "../lib/tiles";
import type { LatLon, Station } from "../lib/types";
import { stationTileLayer } from "./tileLayer";

const ll = (p: LatLon): L.LatLngExpression => [p.lat_deg, p.lon_deg];
const dot = (color: string, testid: string): L.DivIcon =>
  // An element, not HTML text: its style goes through the CSSOM, which the CSP allows.
  L.divIcon({ className: "rec-mk", html: h("div", { "data-testid": testid, style: `width:16px;height:16px;border-radius:50%;background:${color};border:2px solid #fff;box-shadow:0 0 0 1px #000` }), iconSize: [20, 20], iconAnchor: [10, 10] });

export class RecoveryMap {
  readonly root: HTMLElement;
  private readonly map: L.Map;
  private readonly point = L.marker([0, 0], { icon: dot("#006400", "rec-map-point"), interactive: false });
  private readonly phone = L.marker([0, 0], { icon: dot("#0b2f8a", "rec-map-phone"), interactive: false });
  private readonly line = L.polyline([], { color: "#0b2f8a", weight: 3, dashArray: "6 6", interactive: false });
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
    this.line.addTo(this.map);
    const b = tilesBadge(this.hasTiles, 0, 0, this.packError);
    this.badge = h("div", { class: "small muted", "data-testid": "rec-map-tiles", "data-state": b.state }, this.badgeText(b.text));
    const note = packNote(this.packError);
    this.root = h("div", { class: "rec-map-box" }, el, this.badge, h("div", { class: "small form-error", "data-testid": "rec-map-pack-error", hidden: note === null }, note ?? ""));
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
