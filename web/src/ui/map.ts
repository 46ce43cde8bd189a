// The map: track, vehicle (oriented by heading), target, planned pattern and final approach,
// predicted landing points with their 1-σ ellipses, wind arrow, and drafts being edited. Tiles
// come from the station's `tile_url`; a metric grid around the session origin and a scale bar
// are always drawn, so positions stay readable when no tile loads (offline field, no cache).
// While "follow" is on, the view frames the vehicle, target, pattern and predictions
// (lib/framing.ts); a drag or zoom by the operator turns it off. Text about the geometry lives in
// the badge strip along the top, never on the map, so no label hides the target or the pattern.

import L from "leaflet";
import "leaflet/dist/leaflet.css";
import { h, setText } from "./dom";
import { stationTileLayer } from "./tileLayer";
import { FlightPathLayer } from "./flightPathLayer";
import { distanceM, ellipsePoints, fromLocal, gridValues, niceStep, toLocal } from "../lib/geo";
import { fmt, fmtDir, fmtDistance } from "../lib/format";
import { boxAround, keyPoints, needsFraming, type Box } from "../lib/framing";
import { isLanded, landedText } from "../lib/recovery";
import { trackPositions, vehiclePosition } from "../lib/fix";
import { packNote, tilesBadge } from "../lib/tiles";
import { ZoneEditor } from "./zoneEditor";
import type { Footprint, KeepOutAlarm, KeepOutMsg, LandingPrediction, LatLon, Ring, State, Station, TrackPoint } from "../lib/types";

const ll = (p: LatLon): L.LatLngExpression => [p.lat_deg, p.lon_deg];
const MAX_TRACK = 20_000;
/** Failed tiles (and none loaded) after which the tile layer is dropped for the grid alone. */
const GIVE_UP_AFTER_FAILED_TILES = 6;

export type Picker = ((p: LatLon) => void) | null;

export class MapView {
  readonly root: HTMLElement;
  private readonly map: L.Map;
  private origin: LatLon;
  private readonly grid = L.layerGroup();
  private readonly track = L.polyline([], { color: "#0b2f8a", weight: 3 });
  private readonly pattern = L.polygon([], { color: "#c000c0", weight: 2, dashArray: "6 5", fill: false, className: "map-pattern" });
  private readonly final = L.polyline([], { color: "#c000c0", weight: 4, className: "map-final-line" });
  /** The reachable footprint: at least 95 % (light) and 50 % (darker) of the draws reach it. */
  private readonly reach95 = L.polygon([], { color: "#2a7ab0", weight: 1, fillColor: "#2a7ab0", fillOpacity: 0.1, interactive: false, className: "map-footprint-95" });
  private readonly reach50 = L.polygon([], { color: "#2a7ab0", weight: 2, fillColor: "#2a7ab0", fillOpacity: 0.22, interactive: false, className: "map-footprint-50" });
  private readonly reachText: HTMLElement;
  /** Keep-out zones, drawn under everything else, each named on hover; edited by operators. */
  private readonly zones: ZoneEditor;
  private readonly alarmText: HTMLElement;
  private readonly flightPath: FlightPathLayer;
  private readonly ellPlanned = L.polygon([], { color: "#006400", weight: 2, fillOpacity: 0.12 });
  private readonly ellUncontrolled = L.polygon([], { color: "#c05800", weight: 2, fillOpacity: 0.08, dashArray: "4 4" });
  private readonly planned: L.Marker;
  private readonly uncontrolled: L.Marker;
  private readonly target: L.Marker;
  private readonly vehicle: L.Marker;
  private readonly draftTarget: L.Marker;
  private readonly draftPlan = L.polyline([], { color: "#000", weight: 2, dashArray: "2 6" });
  private readonly draftLocalizer = L.polyline([], { color: "#006b8f", weight: 3, dashArray: "10 6" });
  private readonly tilesStatus: HTMLElement;
  private readonly windText: HTMLElement;
  private readonly windArrow: HTMLElement;
  private readonly finalText: HTMLElement;
  private readonly landedText: HTMLElement;
  private readonly followBtn: HTMLButtonElement;
  private readonly overlay: HTMLElement;
  private picker: Picker = null;
  private follow = true;
  /** True while the page itself moves the view, so its events are not taken for the operator's. */
  private framing = false;
  /** The box of the key points at the last state (lib/framing.ts). */
  private lastWant: Box | null = null;
  private tilesLoaded = 0;
  private tilesFailed = 0;
  private lastTrackKey = "";

  private tiles: L.TileLayer | null = null;
  /** Why the station's tile pack gives no map, as it said. */
  private readonly packError: string | null;

  /** `saveZones`: sends an operator's edit of the keep-out zones (`PUT /api/keep-out`). */
  constructor(station: Station, tileToken: string | null, saveZones: (collection: unknown) => Promise<unknown>) {
    this.origin = station.origin;
    const el = h("div", { class: "map", "data-testid": "map", role: "application", "aria-label": "map" });
    this.root = el;
    this.map = L.map(el, { zoomControl: true, attributionControl: true, preferCanvas: false }).setView(ll(this.origin), 15);
    this.tiles = stationTileLayer(station, tileToken);
    if (this.tiles) {
      this.tiles.on("tileload", () => this.onTile(true));
      this.tiles.on("tileerror", () => this.onTile(false));
      this.tiles.addTo(this.map);
    }
    L.control.scale({ metric: true, imperial: false, maxWidth: 160 }).addTo(this.map);
    this.grid.addTo(this.map);
    const icon = (cls: string, html: string, size: number, testid: string): L.DivIcon =>
      L.divIcon({ className: `mk ${cls}`, html: `<div data-testid="${testid}">${html}</div>`, iconSize: [size, size], iconAnchor: [size / 2, size / 2] });
    this.target = L.marker(ll(this.origin), { icon: icon("mk-target", TARGET_SVG, 34, "map-target"), keyboard: false, interactive: false });
    this.planned = L.marker(ll(this.origin), { icon: icon("mk-planned", DOT_SVG("#006400"), 18, "map-pred-planned"), interactive: false });
    this.uncontrolled = L.marker(ll(this.origin), { icon: icon("mk-uncontrolled", DOT_SVG("#c05800"), 18, "map-pred-uncontrolled"), interactive: false });
    this.vehicle = L.marker(ll(this.origin), { icon: icon("mk-vehicle", VEHICLE_SVG, 40, "map-vehicle"), zIndexOffset: 1000, interactive: false });
    this.draftTarget = L.marker(ll(this.origin), { icon: icon("mk-draft", TARGET_SVG, 34, "map-draft-target"), interactive: false, opacity: 0.6 });
    this.zones = new ZoneEditor(this.map, { save: saveZones, onEditing: (on) => on && this.setFollow(false) });
    this.flightPath = new FlightPathLayer(this.map);
    for (const layer of [this.reach95, this.reach50, this.pattern, this.final, this.ellUncontrolled, this.ellPlanned, this.track, this.draftPlan, this.draftLocalizer]) layer.addTo(this.map);

    // Badges drawn on top of the map: tiles status, wind, final approach, landing, follow toggle.
    this.packError = station.offline_tiles_error;
    const tb = tilesBadge(this.tiles !== null, 0, 0, this.packError);
    this.tilesStatus = h("div", { class: "map-badge", "data-testid": "map-tiles-status", "data-state": tb.state }, tb.text);
    const note = packNote(this.packError);
    const packNoteEl = h("div", { class: "map-badge pack-error", "data-testid": "map-tiles-error", role: "status", hidden: note === null }, note ?? "");
    this.windArrow = h("div", { class: "wind-arrow", "aria-hidden": "true" }, "➜");
    this.windText = h("span", { "data-testid": "map-wind" }, "wind —");
    this.finalText = h("div", { class: "map-badge final", "data-testid": "map-final", hidden: true });
    this.landedText = h("div", { class: "map-badge landed", "data-testid": "map-landed", hidden: true });
    this.alarmText = h("div", { class: "map-badge alarm", role: "alert", "data-testid": "map-keep-out-alarm", hidden: true });
    this.reachText = h("div", { class: "map-badge reach", "data-testid": "map-footprint", hidden: true, title: "ground the stack can still reach: darker in at least half of the dispersed draws, lighter in 95 %" });
    this.followBtn = h("button", { type: "button", class: "small on", "data-testid": "map-follow", "aria-pressed": "true", title: "keep the vehicle, target, pattern and predicted landings in view (off when you drag or zoom)" }, "Follow");
    this.followBtn.addEventListener("click", () => this.setFollow(!this.follow));
    const overlay = h("div", { class: "map-overlay", "data-testid": "map-overlay" }, this.tilesStatus, packNoteEl, h("div", { class: "map-badge wind" }, this.windArrow, this.windText), this.alarmText, this.finalText, this.reachText, this.flightPath.badge, this.landedText, this.followBtn);
    L.DomEvent.disableClickPropagation(overlay);
    L.DomEvent.disableScrollPropagation(overlay);
    el.append(overlay, this.zones.root);
    this.overlay = overlay;

    this.map.on("moveend zoomend", () => this.drawGrid());
    this.map.on("click", (e: L.LeafletMouseEvent) => {
      if (this.picker) this.picker({ lat_deg: e.latlng.lat, lon_deg: e.latlng.lng });
    });
    // A drag or a zoom by the operator means they want to look elsewhere: stop following until
    // asked again. The page's own framing raises the same events, hence the flag.
    this.map.on("dragstart zoomstart", () => {
      if (!this.framing) this.setFollow(false);
    });
  }

  private setFollow(on: boolean): void {
    this.follow = on;
    this.followBtn.classList.toggle("on", on);
    this.followBtn.setAttribute("aria-pressed", String(on));
    if (on && this.lastWant) this.frame(this.lastWant);
  }

  private frame(want: Box): void {
    const size = this.map.getSize();
    if (size.x === 0 || size.y === 0) return; // not laid out yet: Leaflet would zoom to the limit
    this.framing = true;
    try {
      // The badges run along the top edge: keep the key geometry below them.
      const top = this.overlay.offsetHeight + 24;
      this.map.fitBounds([[want.south, want.west], [want.north, want.east]], { paddingTopLeft: [36, top], paddingBottomRight: [36, 36], maxZoom: 18, animate: false });
    } finally {
      this.framing = false;
    }
  }

  /** The part of the view below the badge strip, where key geometry must stay. */
  private viewBox(): Box {
    const size = this.map.getSize();
    const nw = this.map.containerPointToLatLng([0, Math.min(size.y - 1, this.overlay.offsetHeight + 8)]);
    const se = this.map.containerPointToLatLng([size.x, size.y]);
    return { south: se.lat, west: nw.lng, north: nw.lat, east: se.lng };
  }

  /** Leaflet measures its container: call once the element is in the document and when it resizes. */
  invalidate(): void {
    this.framing = true;
    try {
      this.map.invalidateSize();
    } finally {
      this.framing = false;
    }
    this.drawGrid();
  }

  setPicker(p: Picker): void {
    this.picker = p;
    this.root.classList.toggle("picking", p !== null);
  }

  setTrack(points: readonly TrackPoint[]): void {
    const last = points[points.length - 1];
    const key = `${points.length}:${last?.time_s ?? ""}`;
    if (key === this.lastTrackKey) return;
    this.lastTrackKey = key;
    // What the track holds, for the end-to-end test (a replay's seek cuts it at that moment).
    this.root.dataset.trackPoints = String(points.length);
    this.root.dataset.trackLastS = last === undefined ? "" : String(last.time_s);
    this.track.setLatLngs(trackPositions(points.slice(-MAX_TRACK)).map((p) => [p.lat_deg, p.lon_deg] as L.LatLngTuple));
  }

  /** The keep-out zones in force (drawn at once unless an operator is editing them). */
  setZones(k: KeepOutMsg): void {
    this.zones.show(k);
    this.root.dataset.keepOutAreas = String(k.areas.length);
  }

  private showAlarms(alarms: KeepOutAlarm[]): void {
    this.alarmText.hidden = alarms.length === 0;
    setText(this.alarmText, alarms.map((a) => `${a.prediction} landing in keep-out zone "${a.zone}"`).join(" · "));
  }

  private showFootprint(f: Footprint | null, stale: boolean): void {
    const level = (p: number): Ring[][] => f?.contours.find((c) => Math.abs(c.level - p) < 1e-6)?.polygons ?? [];
    this.reach95.setLatLngs(level(0.95));
    this.reach50.setLatLngs(level(0.5));
    const old = stale || (f?.stale ?? false);
    for (const layer of [this.reach95, this.reach50]) layer.setStyle({ color: old ? "#888" : "#2a7ab0", fillColor: old ? "#888" : "#2a7ab0" });
    this.reachText.hidden = f === null;
    if (f !== null) {
      this.reachText.dataset.computed = f.computed_s.toFixed(1);
      this.reachText.classList.toggle("stale", old);
      const hits = f.zone_hits.map((z) => `${z.zone} (${Math.round(z.level * 100)} %)`).join(", ");
      setText(this.reachText, `reach 50 % / 95 % from ${fmt(f.height_m, "m", 0)} · ${fmt(f.age_s, "s", 0)} ago${hits ? ` · keep-out within reach: ${hits}` : ""}`);
    }
  }

  update(s: State, stale: boolean): void {
    const e = s.estimate;
    const landed = isLanded(s);
    // Never a GPS without a fix: its zeros would put the vehicle in the Gulf of Guinea.
    const at = vehiclePosition(s);
    if (at !== null) {
      this.vehicle.setLatLng([at.lat_deg, at.lon_deg]);
      if (!this.map.hasLayer(this.vehicle)) this.vehicle.addTo(this.map);
      const hd = e?.heading_deg ?? s.vehicle?.attitude?.yaw_deg ?? 0;
      const el = this.vehicle.getElement()?.querySelector<HTMLElement>("[data-testid=map-vehicle]");
      if (el) {
        el.style.transform = `rotate(${hd.toFixed(1)}deg)`;
        el.classList.toggle("stale", stale);
        el.classList.toggle("landed", landed);
        el.dataset.heading = hd.toFixed(1);
      }
    }
    const g = s.guidance;
    this.show(this.target, g?.target ?? null);
    const tEl = this.target.getElement()?.querySelector<HTMLElement>("[data-testid=map-target]");
    if (tEl && g?.target) {
      // Where the page drew the target, for tests and for people reading the DOM.
      tEl.dataset.lat = g.target.lat_deg.toFixed(7);
      tEl.dataset.lon = g.target.lon_deg.toFixed(7);
    }
    // After touchdown the pattern and the predictions are over: the map shows where it is.
    const pat = landed ? null : (g?.pattern ?? null);
    // The wire's `[lat, lon]` pairs are Leaflet's own.
    this.pattern.setLatLngs(pat ? pat.corners : []);
    if (pat?.final_entry && g?.target) {
      this.final.setLatLngs([pat.final_entry, ll(g.target)]);
      setText(this.finalText, `final ${fmtDir(pat.final_course_deg)} from ${fmt(pat.final_approach_height_m, "m", 0)}${pat.target_reachable === false ? " · target NOT reachable" : ""}`);
      this.finalText.hidden = false;
    } else {
      this.final.setLatLngs([]);
      this.finalText.hidden = true;
    }
    const pred = landed ? null : s.prediction;
    this.showFootprint(landed ? null : s.footprint, stale);
    this.flightPath.update(landed ? null : s.flight_path, at, stale, s.mission_time_s);
    this.showAlarms(landed ? [] : s.keep_out_alarms);
    this.showPrediction(this.planned, this.ellPlanned, pred?.planned ?? null, "planned", stale);
    this.showPrediction(this.uncontrolled, this.ellUncontrolled, pred?.uncontrolled ?? null, "uncontrolled", stale);
    for (const [layer, color] of [[this.pattern, "#c000c0"], [this.final, "#c000c0"]] as const) layer.setStyle({ color: stale ? "#888" : color });
    this.landedText.hidden = !landed;
    // The station's figure, measured once: the same in the header, the log and the recordings.
    if (landed) setText(this.landedText, landedText(s));
    if (e?.wind_from_deg != null) {
      this.windArrow.style.transform = `rotate(${(e.wind_from_deg + 90).toFixed(0)}deg)`;
      setText(this.windText, `wind ${fmt(e.wind_speed_mps, "m/s")} from ${fmtDir(e.wind_from_deg)}`);
    } else setText(this.windText, "wind —");
    this.lastWant = boxAround(keyPoints(s));
    if (this.follow && this.lastWant && needsFraming(this.viewBox(), this.lastWant)) this.frame(this.lastWant);
  }

  showDraftTarget(p: LatLon | null): void {
    this.show(this.draftTarget, p);
  }

  showDraftPlan(points: readonly LatLon[]): void {
    this.draftPlan.setLatLngs(points.map(ll));
  }

  /** The localizer line: a point and a course, drawn 2 km each way. */
  showDraftLocalizer(p: LatLon | null, course_deg: number | null): void {
    if (p === null || course_deg === null) {
      this.draftLocalizer.setLatLngs([]);
      return;
    }
    const o = toLocal(this.origin, p);
    const c = (course_deg * Math.PI) / 180;
    const at = (d: number): L.LatLngExpression => ll(fromLocal(this.origin, { east_m: o.east_m + d * Math.sin(c), north_m: o.north_m + d * Math.cos(c) }));
    this.draftLocalizer.setLatLngs([at(-2000), at(2000)]);
  }

  private show(m: L.Marker, p: LatLon | null): void {
    if (p === null) {
      m.remove();
      return;
    }
    m.setLatLng(ll(p));
    if (!this.map.hasLayer(m)) m.addTo(this.map);
  }

  private showPrediction(m: L.Marker, ell: L.Polygon, p: LandingPrediction | null, name: string, stale: boolean): void {
    this.show(m, p);
    m.getElement()?.classList.toggle("stale", stale);
    const dot = m.getElement()?.querySelector<HTMLElement>("[data-testid]");
    if (dot && p) {
      // Where the page drew the prediction, for tests and for people reading the DOM.
      dot.dataset.lat = p.lat_deg.toFixed(7);
      dot.dataset.lon = p.lon_deg.toFixed(7);
    }
    if (p === null || p.semi_major_m === null || p.semi_minor_m === null) {
      ell.setLatLngs([]);
      return;
    }
    ell.setStyle({ color: stale ? "#888" : name === "planned" ? "#006400" : "#c05800" });
    ell.setLatLngs(ellipsePoints(p, p.semi_major_m, p.semi_minor_m, p.major_axis_deg ?? 0).map(ll));
    const tip = `predicted landing (${name}) · 1σ ${fmt(p.semi_major_m, "m", 0)} × ${fmt(p.semi_minor_m, "m", 0)} · in ${fmt(p.time_to_land_s, "s", 0)}`;
    if (!ell.getTooltip()) ell.bindTooltip(tip, { sticky: true });
    else ell.setTooltipContent(tip);
  }

  private onTile(ok: boolean): void {
    if (ok) this.tilesLoaded += 1;
    else this.tilesFailed += 1;
    const b = tilesBadge(true, this.tilesLoaded, this.tilesFailed, this.packError);
    const offline = b.state === "offline";
    // A tile source that answers nothing (offline field, no cache): stop asking, so the browser
    // does not log a failed request for every pan; the grid carries the map. A reload tries again.
    if (offline && this.tilesFailed >= GIVE_UP_AFTER_FAILED_TILES && this.tiles) {
      this.tiles.remove();
      this.tiles = null;
    }
    this.root.classList.toggle("tiles-offline", offline);
    setText(this.tilesStatus, b.text);
    this.tilesStatus.dataset.state = b.state;
  }

  /** Grid lines every 1/2/5×10^k m east and north of the origin, labelled in metres. */
  private drawGrid(): void {
    this.grid.clearLayers();
    // The view, for tests and for people reading the DOM: with the container's size it gives
    // every pixel's position (Web Mercator), as where a zone's corner was clicked.
    const c = this.map.getCenter();
    this.root.dataset.center = `${c.lat.toFixed(7)},${c.lng.toFixed(7)}`;
    this.root.dataset.zoom = String(this.map.getZoom());
    const b = this.map.getBounds();
    const sw = toLocal(this.origin, { lat_deg: b.getSouth(), lon_deg: b.getWest() });
    const ne = toLocal(this.origin, { lat_deg: b.getNorth(), lon_deg: b.getEast() });
    const step = niceStep(Math.max(ne.east_m - sw.east_m, ne.north_m - sw.north_m), 8);
    const style: L.PolylineOptions = { color: "#000", weight: 1, opacity: 0.35, interactive: false };
    const pt = (east_m: number, north_m: number): L.LatLngExpression => ll(fromLocal(this.origin, { east_m, north_m }));
    // Leaflet positions the icon element with its own transform: offsets go on the inner span.
    const label = (text: string, at: L.LatLngExpression, cls: string): L.Marker =>
      L.marker(at, { icon: L.divIcon({ className: "grid-label", html: `<span class="${cls}">${text}</span>`, iconSize: [0, 0] }), interactive: false, keyboard: false });
    for (const x of gridValues(sw.east_m, ne.east_m, step)) {
      this.grid.addLayer(L.polyline([pt(x, sw.north_m), pt(x, ne.north_m)], { ...style, weight: x === 0 ? 2 : 1 }));
      this.grid.addLayer(label(`${x >= 0 ? "E" : "W"} ${Math.abs(x)} m`, pt(x, sw.north_m), "bottom"));
    }
    for (const y of gridValues(sw.north_m, ne.north_m, step)) {
      this.grid.addLayer(L.polyline([pt(sw.east_m, y), pt(ne.east_m, y)], { ...style, weight: y === 0 ? 2 : 1 }));
      this.grid.addLayer(label(`${y >= 0 ? "N" : "S"} ${Math.abs(y)} m`, pt(sw.east_m, y), "left"));
    }
  }
}

const TARGET_SVG = `<svg viewBox="-17 -17 34 34" width="34" height="34"><circle r="13" fill="none" stroke="#fff" stroke-width="6"/><circle r="13" fill="none" stroke="#d00000" stroke-width="3"/><circle r="5" fill="#d00000" stroke="#fff" stroke-width="1.5"/></svg>`;
const DOT_SVG = (c: string): string => `<svg viewBox="-9 -9 18 18" width="18" height="18"><circle r="7" fill="${c}" stroke="#fff" stroke-width="2.5"/></svg>`;
// Points up (north) at rotation 0; rotated by the heading.
const VEHICLE_SVG = `<svg viewBox="-20 -20 40 40" width="40" height="40"><path d="M0 -18 L11 14 L0 7 L-11 14 Z" fill="#ffd400" stroke="#000" stroke-width="2.5" stroke-linejoin="round"/></svg>`;
