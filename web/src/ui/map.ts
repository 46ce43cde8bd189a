// The map: track, vehicle (oriented by heading), target, planned pattern and final approach,
// predicted landing points with their 1-σ ellipses, wind arrow, and drafts being edited. Tiles
// come from the station's `tile_url`; a metric grid around the session origin and a scale bar
// are always drawn, so positions stay readable when no tile loads (offline field, no cache).
// While "follow" is on, the view frames the vehicle, target, pattern and predictions
// (lib/framing.ts); a drag or zoom by the operator turns it off. Text about the geometry lives in
// the badge strip along the top, never on the map, so no label hides the target or the pattern;
// what each symbol means is in the legend under the map, which lists those drawn now.

import L from "leaflet";
import "leaflet/dist/leaflet.css";
import { h, setText } from "./dom";
import { stationTileLayer } from "./tileLayer";
import { FlightPathLayer } from "./flightPathLayer";
import { MapLegend } from "./mapLegend";
import { DRAFT_LOCALIZER, DRAFT_PLAN, ELLIPSE_PLANNED, ELLIPSE_UNCONTROLLED, FINAL, LIVE_LEGEND, PATTERN, REACH_50, REACH_95, STALE_COLOR, TRACK, dotIcon, targetIcon, vehicleIcon } from "./mapSymbols";
import { MetricGrid } from "./metricGrid";
import { ellipsePoints, fromLocal, toLocal } from "../lib/geo";
import { fmt, fmtDir } from "../lib/format";
import { boxAround, keyPoints, needsFraming, shareOfView, type Box } from "../lib/framing";
import { isLanded, landedText } from "../lib/recovery";
import { trackPositions, vehiclePosition } from "../lib/fix";
import { packNote, tilesBadge } from "../lib/tiles";
import { ZoneEditor } from "./zoneEditor";
import type { Footprint, KeepOutAlarm, KeepOutMsg, LandingPrediction, LatLon, Ring, State, Station, TrackPoint } from "../lib/types";

const ll = (p: LatLon): L.LatLngExpression => [p.lat_deg, p.lon_deg];
/** Whether a layer's points (flat, rings, or polygons of rings) are two or more, without copying a long track. */
const twoPoints = (latlngs: unknown[]): boolean => {
  let n = 0;
  for (const x of latlngs) if ((n += Array.isArray(x) ? (twoPoints(x) ? 2 : x.length) : 1) >= 2) return true;
  return false;
};
const MAX_TRACK = 20_000;
/** Half the largest marker drawn on key geometry (the vehicle's 40 px icon), px. */
const MARKER_HALF_PX = 20;
/** Failed tiles (and none loaded) after which the tile layer is dropped for the grid alone. */
const GIVE_UP_AFTER_FAILED_TILES = 6;

export type Picker = ((p: LatLon) => void) | null;

export class MapView {
  readonly root: HTMLElement;
  /** What each symbol drawn now means: under the map, never over it. */
  readonly legend = new MapLegend(LIVE_LEGEND, "map-legend");
  private readonly map: L.Map;
  private origin: LatLon;
  private readonly grid: MetricGrid;
  private readonly track = L.polyline([], TRACK);
  private readonly pattern = L.polygon([], PATTERN);
  private readonly final = L.polyline([], FINAL);
  private readonly reach95 = L.polygon([], REACH_95);
  private readonly reach50 = L.polygon([], REACH_50);
  private readonly reachText: HTMLElement;
  /** Keep-out zones, drawn under everything else, each named on hover; edited by operators. */
  private readonly zones: ZoneEditor;
  private readonly alarmText: HTMLElement;
  private readonly flightPath: FlightPathLayer;
  private readonly ellPlanned = L.polygon([], ELLIPSE_PLANNED);
  private readonly ellUncontrolled = L.polygon([], ELLIPSE_UNCONTROLLED);
  private readonly planned: L.Marker;
  private readonly uncontrolled: L.Marker;
  private readonly target: L.Marker;
  private readonly vehicle: L.Marker;
  private readonly draftTarget: L.Marker;
  private readonly draftPlan = L.polyline([], DRAFT_PLAN);
  private readonly draftLocalizer = L.polyline([], DRAFT_LOCALIZER);
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
    this.grid = new MetricGrid(this.map, this.origin, { labelLines: true, onStep: (step) => this.legend.setLabel("grid", `grid ${step} m`) });
    const icon = (cls: string, svg: SVGSVGElement, size: number, testid: string): L.DivIcon =>
      L.divIcon({ className: `mk ${cls}`, html: h("div", { "data-testid": testid }, svg), iconSize: [size, size], iconAnchor: [size / 2, size / 2] });
    this.target = L.marker(ll(this.origin), { icon: icon("mk-target", targetIcon(), 34, "map-target"), keyboard: false, interactive: false });
    this.planned = L.marker(ll(this.origin), { icon: icon("mk-planned", dotIcon(ELLIPSE_PLANNED.color!), 18, "map-pred-planned"), interactive: false });
    this.uncontrolled = L.marker(ll(this.origin), { icon: icon("mk-uncontrolled", dotIcon(ELLIPSE_UNCONTROLLED.color!), 18, "map-pred-uncontrolled"), interactive: false });
    this.vehicle = L.marker(ll(this.origin), { icon: icon("mk-vehicle", vehicleIcon(), 2 * MARKER_HALF_PX, "map-vehicle"), zIndexOffset: 1000, interactive: false });
    this.draftTarget = L.marker(ll(this.origin), { icon: icon("mk-draft", targetIcon(), 34, "map-draft-target"), interactive: false, opacity: 0.6 });
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
    // The legend under the map grows and shrinks as symbols come and go, and the map with it:
    // Leaflet must measure its box again, or it frames and clips to the old one.
    new ResizeObserver(() => this.invalidate()).observe(el);
    // A badge that appears or wraps to a new row deepens the strip between two states.
    new ResizeObserver(() => this.keepInView()).observe(overlay);

    this.map.on("moveend zoomend", () => this.noteView());
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

  /**
   * Where the badge strip ends, px from the map's top. The strip sits 8 px below the edge
   * (live.css), so its height alone would leave the geometry just under its last row.
   */
  private badgesBottom(): number {
    return this.overlay.offsetTop + this.overlay.offsetHeight;
  }

  private frame(want: Box): void {
    const size = this.map.getSize();
    if (size.x === 0 || size.y === 0) return; // not laid out yet: Leaflet would zoom to the limit
    this.framing = true;
    try {
      // The badges run along the top edge: keep the key geometry, markers and all, below them.
      const top = this.badgesBottom() + MARKER_HALF_PX + 8;
      const side = MARKER_HALF_PX + 16;
      this.map.fitBounds([[want.south, want.west], [want.north, want.east]], { paddingTopLeft: [side, top], paddingBottomRight: [side, side], maxZoom: 18, animate: false });
    } finally {
      this.framing = false;
    }
  }

  /**
   * The part of the view where a key point's marker is whole and clear of the badge strip: the
   * strip and half the largest marker are cut off each edge. Framing again is decided on this box
   * (lib/framing.ts), so a vehicle flying towards the badges is re-framed before they cover it.
   */
  private viewBox(): Box {
    const size = this.map.getSize();
    const top = Math.min(size.y - 1, this.badgesBottom() + MARKER_HALF_PX);
    const bottom = Math.max(top + 1, size.y - MARKER_HALF_PX);
    const left = Math.min(MARKER_HALF_PX, size.x / 2 - 1);
    const right = Math.max(left + 1, size.x - MARKER_HALF_PX);
    const nw = this.map.containerPointToLatLng([left, top]);
    const se = this.map.containerPointToLatLng([right, bottom]);
    return { south: se.lat, west: nw.lng, north: nw.lat, east: se.lng };
  }

  /** Frames the key points again if following and they are at an edge, under the badges or out of view. */
  private keepInView(): void {
    if (this.follow && this.lastWant && this.map.getSize().x > 0 && needsFraming(this.viewBox(), this.lastWant)) this.frame(this.lastWant);
    this.noteView();
  }

  /** Leaflet measures its container: call once the element is in the document and when it resizes. */
  invalidate(): void {
    this.framing = true;
    try {
      this.map.invalidateSize();
    } finally {
      this.framing = false;
    }
    this.grid.draw();
    this.keepInView();
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
    this.showLegend();
  }

  /** The keep-out zones in force (drawn at once unless an operator is editing them). */
  setZones(k: KeepOutMsg): void {
    this.zones.show(k);
    this.root.dataset.keepOutAreas = String(k.areas.length);
    this.showLegend();
  }

  /** Lists in the legend the symbols drawn now. */
  private showLegend(): void {
    const on = new Set<string>(["grid", ...this.flightPath.drawn]);
    const markers = { vehicle: this.vehicle, target: this.target, planned: this.planned, uncontrolled: this.uncontrolled, "draft-target": this.draftTarget };
    const paths = {
      track: this.track, pattern: this.pattern, final: this.final, "ellipse-planned": this.ellPlanned, "ellipse-uncontrolled": this.ellUncontrolled,
      "reach-50": this.reach50, "reach-95": this.reach95, "draft-plan": this.draftPlan, "draft-localizer": this.draftLocalizer,
    };
    for (const [key, m] of Object.entries(markers)) if (this.map.hasLayer(m)) on.add(key);
    // An emptied layer stays on the map with no points, and a line of one point (a plan of its
    // land item alone) shows nothing: a path is drawn from two points on, however close.
    for (const [key, p] of Object.entries(paths)) if (twoPoints(p.getLatLngs())) on.add(key);
    if (this.zones.drawn > 0) on.add("keep-out");
    this.legend.show(on);
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
    for (const [layer, style] of [[this.reach95, REACH_95], [this.reach50, REACH_50]] as const) layer.setStyle({ color: old ? STALE_COLOR : style.color, fillColor: old ? STALE_COLOR : style.fillColor });
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
    for (const [layer, style] of [[this.pattern, PATTERN], [this.final, FINAL]] as const) layer.setStyle({ color: stale ? STALE_COLOR : style.color });
    this.landedText.hidden = !landed;
    // The station's figure, measured once: the same in the header, the log and the recordings.
    if (landed) setText(this.landedText, landedText(s));
    if (e?.wind_from_deg != null) {
      this.windArrow.style.transform = `rotate(${(e.wind_from_deg + 90).toFixed(0)}deg)`;
      setText(this.windText, `wind ${fmt(e.wind_speed_mps, "m/s")} from ${fmtDir(e.wind_from_deg)}`);
    } else setText(this.windText, "wind —");
    this.lastWant = boxAround(keyPoints(s));
    this.keepInView();
    this.showLegend();
  }

  showDraftTarget(p: LatLon | null): void {
    this.show(this.draftTarget, p);
    this.showLegend();
  }

  showDraftPlan(points: readonly LatLon[]): void {
    this.draftPlan.setLatLngs(points.map(ll));
    this.showLegend();
  }

  /** The localizer line: a point and a course, drawn 2 km each way. */
  showDraftLocalizer(p: LatLon | null, course_deg: number | null): void {
    if (p === null || course_deg === null) {
      this.draftLocalizer.setLatLngs([]);
      this.showLegend();
      return;
    }
    const o = toLocal(this.origin, p);
    const c = (course_deg * Math.PI) / 180;
    const at = (d: number): L.LatLngExpression => ll(fromLocal(this.origin, { east_m: o.east_m + d * Math.sin(c), north_m: o.north_m + d * Math.cos(c) }));
    this.draftLocalizer.setLatLngs([at(-2000), at(2000)]);
    this.showLegend();
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
    ell.setStyle({ color: stale ? STALE_COLOR : (name === "planned" ? ELLIPSE_PLANNED : ELLIPSE_UNCONTROLLED).color });
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

  /**
   * The view, for tests and for people reading the DOM: with the container's size it gives every
   * pixel's position (Web Mercator), as where a zone's corner was clicked.
   */
  private noteView(): void {
    const c = this.map.getCenter();
    this.root.dataset.center = `${c.lat.toFixed(7)},${c.lng.toFixed(7)}`;
    this.root.dataset.zoom = String(this.map.getZoom());
    // How much of the view the key geometry's box spans, as the page frames it (for the tests:
    // the markers alone understate it, the box holds the ellipses and the smallest span too).
    this.root.dataset.keyShare = this.lastWant && this.map.getSize().x > 0 ? shareOfView(this.viewBox(), this.lastWant).toFixed(3) : "";
  }
}
