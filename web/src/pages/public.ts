// The public page a relay serves (`stx relay`): where the payload is, how high and fast, its
// stage, the predicted landing and the target, on a map with its track. No token, no controls:
// it reads the relay's WebSocket (`public_history`, then `public_state`s) and says plainly how
// late and how rounded what it shows is, and when nothing new comes.

import "../styles/common.css";
import "../styles/public.css";
import L from "leaflet";
import "leaflet/dist/leaflet.css";
import { fmt, fmtDir, fmtLatLon, fmtMissionTime } from "../lib/format";
import { caveat, freshness, parsePublicHistory, parsePublicState, type PublicStateMsg, type PublicTrackPoint } from "../lib/publicState";
import { h, setText } from "../ui/dom";
import { MapLegend, type LegendEntry } from "../ui/mapLegend";
import { GRID, TRACK, ringedDot } from "../ui/mapSymbols";
import { MetricGrid } from "../ui/metricGrid";

const PAYLOAD = "#0b2f8a";
const LANDING = "#006400";
const TARGET = "#c00000";
const dot = (color: string, title: string, testid: string): L.DivIcon =>
  L.divIcon({ className: "pub-mk", html: ringedDot(color, 16, title, testid), iconSize: [20, 20], iconAnchor: [10, 10] });
const LEGEND: LegendEntry[] = [
  { key: "payload", label: "the payload", swatch: { kind: "element", make: () => ringedDot(PAYLOAD, 14, "the payload") } },
  { key: "track", label: "its track", swatch: { kind: "line", style: TRACK } },
  { key: "landing", label: "predicted landing", swatch: { kind: "element", make: () => ringedDot(LANDING, 14, "predicted landing") } },
  { key: "target", label: "landing target", swatch: { kind: "element", make: () => ringedDot(TARGET, 14, "landing target") } },
  { key: "grid", label: "grid", swatch: { kind: "line", style: GRID } },
];

const field = (testid: string): HTMLElement => h("span", { "data-testid": testid }, "—");
const el = {
  stage: field("pub-stage"), time: field("pub-time"), alt: field("pub-alt"), climb: field("pub-climb"),
  speed: field("pub-speed"), where: field("pub-where"), landing: field("pub-landing"),
  fresh: h("div", { class: "pub-fresh", "data-testid": "pub-fresh" }, "connecting…"),
  caveat: h("div", { class: "pub-caveat", "data-testid": "pub-caveat" }),
  viewers: h("span", { "data-testid": "pub-viewers" }),
};
const mapEl = h("div", { class: "pub-map", "data-testid": "pub-map", role: "application", "aria-label": "map of the flight" });
const legend = new MapLegend(LEGEND, "pub-legend");
const row = (label: string, value: HTMLElement): HTMLElement => h("div", { class: "pub-row" }, h("span", { class: "muted" }, label), value);
document.getElementById("app")?.replaceChildren(
  h("header", {}, h("strong", {}, "Follow the flight"), h("span", { class: "muted" }, " · ", el.viewers, " · ", h("a", { href: "/kml" }, "Google Earth"))),
  el.fresh,
  el.caveat,
  h("main", {}, h("div", { class: "pub-figures" },
    row("stage", el.stage), row("mission time", el.time), row("altitude", el.alt), row("climb", el.climb),
    row("ground speed", el.speed), row("position", el.where), row("predicted landing", el.landing)),
    h("div", { class: "pub-map-box" }, mapEl, legend.root)),
);

const map = L.map(mapEl, { zoomControl: true, attributionControl: false }).setView([0, 0], 2);
L.control.scale({ metric: true, imperial: false, maxWidth: 120 }).addTo(map);
let grid: MetricGrid | null = null;
const track = L.polyline([], TRACK).addTo(map);
const payload = L.marker([0, 0], { icon: dot(PAYLOAD, "the payload", "pub-map-payload"), interactive: false });
const landing = L.marker([0, 0], { icon: dot(LANDING, "predicted landing", "pub-map-landing"), interactive: false });
const target = L.marker([0, 0], { icon: dot(TARGET, "landing target", "pub-map-target"), interactive: false });
let latest: PublicStateMsg | null = null;
let points: PublicTrackPoint[] = [];
let framed = false;

function place(m: L.Marker, p: { lat_deg: number; lon_deg: number } | null): void {
  if (p === null) m.remove();
  else m.setLatLng([p.lat_deg, p.lon_deg]).addTo(map);
}

function show(s: PublicStateMsg): void {
  latest = s;
  const p = s.position;
  setText(el.stage, s.stage?.replace(/_/g, " ") ?? "—");
  setText(el.time, fmtMissionTime(s.mission_time_s));
  setText(el.alt, fmt(p?.alt_msl_m, "m MSL", 0));
  setText(el.climb, fmt(p?.climb_mps, "m/s", 1));
  setText(el.speed, p ? `${fmt(p.ground_speed_mps, "m/s", 1)} toward ${fmtDir(p.course_deg)}` : "—");
  setText(el.where, p ? fmtLatLon(p.lat_deg, p.lon_deg) : "—");
  setText(el.landing, s.landing ? fmtLatLon(s.landing.lat_deg, s.landing.lon_deg) : "—");
  setText(el.caveat, caveat(s));
  el.caveat.hidden = el.caveat.textContent === "";
  place(payload, p);
  place(landing, s.landing);
  place(target, s.target);
  if (p) {
    const t = s.mission_time_s;
    const last = points[points.length - 1];
    if (t !== null && (last === undefined || t - last.mission_time_s >= 1)) {
      points.push({ mission_time_s: t, lat_deg: p.lat_deg, lon_deg: p.lon_deg, alt_msl_m: p.alt_msl_m });
      drawTrack();
    }
    if (!framed) {
      framed = true;
      map.setView([p.lat_deg, p.lon_deg], 13);
      grid = new MetricGrid(map, p, { labelLines: false });
    }
    mapEl.dataset.missionTimeS = String(s.mission_time_s);
    mapEl.dataset.lat = String(p.lat_deg);
    mapEl.dataset.lon = String(p.lon_deg);
  }
  refresh();
}

function drawTrack(): void {
  if (points.length > 20_000) points = points.slice(-18_000);
  track.setLatLngs(points.map((q) => [q.lat_deg, q.lon_deg]));
  mapEl.dataset.trackPoints = String(points.length);
}

function refresh(): void {
  if (latest === null) return;
  const f = freshness(latest, Date.now());
  setText(el.fresh, f.text);
  document.body.dataset.freshness = f.stale ? "stale" : "fresh";
  grid?.draw();
}

function connect(): void {
  const socket = new WebSocket(`${location.protocol === "https:" ? "wss:" : "ws:"}//${location.host}/api/ws`);
  socket.onmessage = (e) => {
    let m: unknown;
    try {
      m = JSON.parse(String(e.data));
    } catch {
      return;
    }
    const history = parsePublicHistory(m);
    if (history !== null) {
      points = history;
      drawTrack();
      return;
    }
    const s = parsePublicState(m);
    if (s !== null) show(s);
  };
  socket.onclose = () => {
    setText(el.fresh, "connection to the relay lost: reconnecting…");
    document.body.dataset.freshness = "stale";
    setTimeout(connect, 2000);
  };
}

async function viewers(): Promise<void> {
  try {
    const r = await fetch("/api/relay");
    const b: unknown = await r.json();
    // The pages watching through this relay, those of relays below it included.
    const n = typeof b === "object" && b !== null && "audience" in b ? Number(b.audience) : NaN;
    setText(el.viewers, Number.isFinite(n) ? `${n} watching` : "");
  } catch {
    setText(el.viewers, "");
  }
}

connect();
void viewers();
setInterval(() => void viewers(), 10_000);
setInterval(refresh, 1000);
