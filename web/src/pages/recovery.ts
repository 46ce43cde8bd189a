// The recovery page, for phones in the field: where to go (predicted, or once landed, actual
// landing point), how far and which way from the phone, and links to open the point in the
// phone's map app. It polls /api/state (simpler than a socket over a flaky mobile link) and keeps
// the last state in localStorage, so it still shows the last known point with no network.
// Without the phone's position (permission refused, or plain HTTP, where browsers give none) the
// page stays useful: the point to copy or open, why there is no position, and a field to type or
// paste one.

import "../styles/common.css";
import "../styles/recovery.css";
import { Api } from "../lib/api";
import { bearingDeg, distanceM } from "../lib/geo";
import { cardinal, fmtDir, fmtDistance, fmtDuration, fmtLatLon, fmtWallUtc, wrap360 } from "../lib/format";
import { isObj, parseSession, parseState, parseStation } from "../lib/parse";
import { parsePosition, positionUnavailable } from "../lib/position";
import { landedText, recoveryPoint } from "../lib/recovery";
import { resolveToken, searchWithoutToken } from "../lib/token";
import type { LatLon, State, Station } from "../lib/types";
import { ChaseCarShare } from "../ui/chaseCarShare";
import { h, setText } from "../ui/dom";
import { RecoveryMap } from "../ui/recoveryMap";

const POLL_MS = 2000;
/** A point older than this is flagged: the vehicle may have moved a long way since. */
const STALE_AFTER_S = 10;
const CACHE_KEY = "stx.recovery.last";
/** The station's map settings, kept so the map (and a cached tile pack) shows with no network. */
const STATION_KEY = "stx.recovery.station";

const token = resolveToken(location.search, sessionStorage);
if (new URLSearchParams(location.search).has("token")) history.replaceState(null, "", `${location.pathname}${searchWithoutToken(location.search)}`);
const api = new Api(token);

let state: State | null = null;
let stateAtMs: number | null = null; // page clock when fetched
let fromCache = false;
let phone: (LatLon & { accuracy_m: number }) | null = null;
/** A position typed or pasted by hand: used instead of the browser's while set. */
let manual: LatLon | null = null;
let geoErrorCode: number | null = null;
let deviceHeading: number | null = null;
let fetchError = "";
/** Made once the station's map settings are known (from the session, or the saved copy). */
let map: RecoveryMap | null = null;

/** The opt-in to show this phone on SondeHub as a chase car. */
const chaseShare = new ChaseCarShare(api);

const el = {
  kind: h("div", { class: "kind", "data-testid": "rec-kind" }),
  arrow: h("div", { class: "arrow", "data-testid": "rec-arrow", "aria-hidden": "true" }, "⬆"),
  arrowNote: h("div", { class: "muted", "data-testid": "rec-arrow-note" }),
  distance: h("div", { class: "big", "data-testid": "rec-distance" }),
  bearing: h("div", { class: "mid", "data-testid": "rec-bearing" }),
  point: h("div", { class: "mid", "data-testid": "rec-point" }),
  ttl: h("div", { "data-testid": "rec-ttl" }),
  geo: h("a", { class: "btn", "data-testid": "rec-geo-link" }, "Open in map app"),
  osm: h("a", { class: "btn", "data-testid": "rec-osm-link", target: "_blank", rel: "noopener" }, "OpenStreetMap"),
  updated: h("div", { "data-testid": "rec-updated" }),
  stale: h("div", { class: "stale-flag", role: "alert", "data-testid": "rec-stale" }),
  phone: h("div", { class: "muted", "data-testid": "rec-phone" }),
  why: h("div", { class: "why", role: "status", "data-testid": "rec-phone-why" }),
  decimal: h("div", { class: "mid mono", "data-testid": "rec-point-decimal" }),
  copy: h("button", { type: "button", class: "btn", "data-testid": "rec-copy" }, "Copy coordinates"),
  copyStatus: h("div", { class: "small", "data-testid": "rec-copy-status", role: "status" }),
  phoneInput: h("input", { type: "text", inputmode: "text", autocomplete: "off", placeholder: "e.g. 38.5333, -7.8889 or a geo:/map link", "data-testid": "rec-phone-input", "aria-label": "your position: latitude, longitude" }),
  phoneSet: h("button", { type: "button", class: "btn", "data-testid": "rec-phone-set" }, "Use"),
  phoneClear: h("button", { type: "button", class: "btn", "data-testid": "rec-phone-clear", hidden: true }, "Forget"),
  phoneErr: h("div", { class: "form-error", role: "alert", "data-testid": "rec-phone-error" }),
  manualBox: h("details", { class: "manual", "data-testid": "rec-manual" }),
  mapBox: h("div", { class: "rec-map-slot" }),
};
el.manualBox.append(
  h("summary", {}, "Enter your position by hand"),
  h("div", { class: "manual-row" }, el.phoneInput, el.phoneSet, el.phoneClear),
  el.phoneErr,
);

document.getElementById("app")!.replaceChildren(
  h("header", {}, h("strong", {}, "STRAPLEX recovery"), h("a", { href: "index.html", class: "muted small" }, "live page")),
  el.stale,
  h("main", {}, el.kind, el.arrow, el.arrowNote, el.distance, el.bearing, el.point, el.decimal, el.ttl,
    h("div", { class: "links" }, el.geo, el.osm, el.copy), el.copyStatus, el.mapBox, el.updated, el.phone, el.why, el.manualBox, chaseShare.root),
);

el.copy.addEventListener("click", () => void copyPoint());
const usePhoneInput = (): void => {
  const r = parsePosition(el.phoneInput.value);
  if (!r.ok) {
    setText(el.phoneErr, r.error);
    return;
  }
  manual = r.value;
  setText(el.phoneErr, "");
  render();
};
el.phoneSet.addEventListener("click", usePhoneInput);
el.phoneInput.addEventListener("keydown", (e) => {
  if (e.key === "Enter") usePhoneInput();
});
el.phoneClear.addEventListener("click", () => {
  manual = null;
  el.phoneInput.value = "";
  render();
});

loadCache();
render();
void poll();
setInterval(() => void poll(), POLL_MS);
setInterval(render, 1000);
setInterval(() => void chaseShare.tick(), 1000);
void chaseShare.probe();
watchPhone();
watchHeading();
if ("serviceWorker" in navigator && window.isSecureContext) {
  // Lets the page itself open with no network (sw.js caches the page's files, never the API).
  navigator.serviceWorker.register("sw.js").catch(() => {});
}

async function poll(): Promise<void> {
  if (map === null) await loadStation();
  try {
    const raw = await api.get("/api/state");
    const p = isObj(raw) ? parseState(raw) : null;
    if (!p?.ok) throw new Error(p ? p.error : "not a state");
    state = p.value;
    stateAtMs = Date.now();
    fromCache = false;
    fetchError = "";
    try {
      localStorage.setItem(CACHE_KEY, JSON.stringify({ at: stateAtMs, state: raw }));
    } catch {
      // storage full or forbidden: the page still works, only without the offline copy
    }
  } catch (e) {
    fetchError = e instanceof Error ? e.message : String(e);
  }
  render();
}

/** The station's map settings from the session (saved for offline use), else the saved copy. */
async function loadStation(): Promise<void> {
  let station: Station | null = null;
  try {
    const p = parseSession(await api.get("/api/session"));
    if (p.ok) {
      station = p.value.station;
      try {
        localStorage.setItem(STATION_KEY, JSON.stringify(station));
      } catch {
        // storage full or forbidden: the map only needs the network next time
      }
    }
  } catch {
    // no network: the saved copy below
  }
  if (station === null) {
    try {
      const saved: unknown = JSON.parse(localStorage.getItem(STATION_KEY) ?? "null");
      station = isObj(saved) ? parseStation(saved) : null;
    } catch {
      station = null; // a corrupt copy is ignored
    }
  }
  if (station === null) return;
  map = new RecoveryMap(station, token);
  el.mapBox.replaceChildren(map.root);
}

function loadCache(): void {
  try {
    const c: unknown = JSON.parse(localStorage.getItem(CACHE_KEY) ?? "null");
    if (isObj(c) && typeof c.at === "number" && isObj(c.state)) {
      const p = parseState(c.state);
      if (p.ok) {
        state = p.value;
        stateAtMs = c.at;
        fromCache = true;
      }
    }
  } catch {
    // a corrupt cache is ignored
  }
}

function watchPhone(): void {
  if (!window.isSecureContext || !("geolocation" in navigator)) return; // render() says why
  navigator.geolocation.watchPosition(
    (p) => {
      phone = { lat_deg: p.coords.latitude, lon_deg: p.coords.longitude, accuracy_m: p.coords.accuracy };
      chaseShare.setPosition(phone);
      geoErrorCode = null;
      render();
    },
    (e) => {
      // A watch keeps trying after a timeout or a lost fix; the last position stays shown until
      // a refusal, which is final.
      geoErrorCode = e.code;
      if (e.code === 1) phone = null;
      chaseShare.setPosition(phone);
      render();
    },
    { enableHighAccuracy: true, maximumAge: 5000, timeout: 30000 },
  );
}

/** The point as "lat, lon" in decimal degrees: what map apps and messengers accept. */
function decimal(p: LatLon): string {
  return `${p.lat_deg.toFixed(6)}, ${p.lon_deg.toFixed(6)}`;
}

async function copyPoint(): Promise<void> {
  const pt = state ? recoveryPoint(state) : null;
  if (pt === null) return;
  const text = decimal(pt);
  try {
    // The async clipboard needs a secure page; plain HTTP gets the old selection copy.
    if (navigator.clipboard && window.isSecureContext) await navigator.clipboard.writeText(text);
    else legacyCopy(text);
    setText(el.copyStatus, `copied: ${text}`);
  } catch {
    setText(el.copyStatus, `could not copy — select it by hand: ${text}`);
  }
}

function legacyCopy(text: string): void {
  const ta = h("textarea", { readonly: true, style: "position:fixed;top:-100px;opacity:0" });
  ta.value = text;
  document.body.append(ta);
  ta.select();
  const ok = document.execCommand("copy");
  ta.remove();
  if (!ok) throw new Error("copy refused");
}

/** Compass heading of the phone, where the browser gives an absolute one; else the arrow is north-up. */
function watchHeading(): void {
  const onOrient = (e: DeviceOrientationEvent): void => {
    const webkit = (e as DeviceOrientationEvent & { webkitCompassHeading?: number }).webkitCompassHeading;
    if (typeof webkit === "number") deviceHeading = webkit;
    else if (e.absolute && e.alpha !== null) deviceHeading = wrap360(360 - e.alpha);
  };
  window.addEventListener("deviceorientationabsolute", onOrient as EventListener);
  window.addEventListener("deviceorientation", onOrient);
}

function render(): void {
  const now = Date.now();
  const pt = state ? recoveryPoint(state) : null;
  const ageS = stateAtMs === null ? null : (now - stateAtMs) / 1000;
  const stale = state === null || fromCache || (ageS !== null && ageS > STALE_AFTER_S) || state.link.stale;
  const why = state === null ? "no data yet" : fromCache ? "offline — showing the last saved point" : state.link.stale ? "the station has lost the drone's link" : ageS !== null && ageS > STALE_AFTER_S ? `no update for ${fmtDuration(ageS)}` : "";
  setText(el.stale, stale ? `STALE: ${why}${fetchError ? ` (${fetchError})` : ""}` : "");
  el.stale.hidden = !stale;
  document.body.classList.toggle("stale", stale);
  if (pt === null) {
    setText(el.kind, state === null ? "Waiting for data…" : "No landing point yet");
    setText(el.distance, "— m");
    setText(el.bearing, "bearing —°");
    setText(el.point, "");
    setText(el.decimal, "");
    setText(el.ttl, "");
    el.arrow.hidden = true;
    el.copy.disabled = true;
  } else {
    el.copy.disabled = false;
    setText(el.kind, pt.kind === "actual" && state ? landedText(state) : pt.kind === "planned" ? "Predicted landing (guided)" : "Predicted landing (uncontrolled)");
    el.kind.dataset.kind = pt.kind;
    setText(el.point, fmtLatLon(pt.lat_deg, pt.lon_deg));
    setText(el.decimal, decimal(pt));
    el.point.dataset.lat = pt.lat_deg.toFixed(7);
    el.point.dataset.lon = pt.lon_deg.toFixed(7);
    setText(el.ttl, pt.kind === "actual" ? "" : `lands in ${fmtDuration(pt.time_to_land_s)}${pt.semi_major_m !== null ? ` · ±${Math.round(pt.semi_major_m)} m (1σ)` : ""}`);
    el.geo.setAttribute("href", `geo:${pt.lat_deg.toFixed(6)},${pt.lon_deg.toFixed(6)}`);
    el.osm.setAttribute("href", `https://www.openstreetmap.org/?mlat=${pt.lat_deg.toFixed(6)}&mlon=${pt.lon_deg.toFixed(6)}#map=17/${pt.lat_deg.toFixed(6)}/${pt.lon_deg.toFixed(6)}`);
    const from = manual ?? phone;
    if (from) {
      const d = distanceM(from, pt);
      const b = bearingDeg(from, pt);
      setText(el.distance, fmtDistance(d));
      setText(el.bearing, `bearing ${fmtDir(b)} (${cardinal(b)})`);
      el.arrow.hidden = false;
      el.arrow.style.transform = `rotate(${(deviceHeading === null ? b : wrap360(b - deviceHeading)).toFixed(0)}deg)`;
      setText(el.arrowNote, deviceHeading === null ? "arrow: north is up (no compass)" : "arrow: relative to where the phone points");
    } else {
      setText(el.distance, "— m");
      setText(el.bearing, "bearing —° (phone position unknown)");
      el.arrow.hidden = true;
      setText(el.arrowNote, "");
    }
  }
  map?.update(pt, manual ?? phone);
  setText(el.updated, state ? `last update ${fmtWallUtc(state.wall_ms ?? stateAtMs)} · ${ageS === null ? "" : `${fmtDuration(ageS)} ago`}` : "");
  const noPos = positionUnavailable({ secure: window.isSecureContext, hasGeolocation: "geolocation" in navigator, errorCode: geoErrorCode, origin: location.origin });
  const phoneText = manual
    ? `from your position entered by hand: ${fmtLatLon(manual.lat_deg, manual.lon_deg)}`
    : phone
      ? `phone ${fmtLatLon(phone.lat_deg, phone.lon_deg)} ±${Math.round(phone.accuracy_m)} m`
      : noPos
        ? "phone position unavailable"
        : "locating the phone…";
  setText(el.phone, phoneText);
  // Once a position is typed the page has what it needed: why the phone gave none is no news.
  const known = phone !== null || manual !== null;
  setText(el.why, known ? "" : (noPos ?? ""));
  el.why.hidden = known || noPos === null;
  el.phone.dataset.source = manual ? "manual" : phone ? "gps" : noPos ? "unavailable" : "locating";
  el.phoneClear.hidden = manual === null;
  // Without the phone's own position, typing one is the way to get distance and bearing.
  if (!phone && noPos && !el.manualBox.dataset.opened) {
    el.manualBox.open = true;
    el.manualBox.dataset.opened = "1";
  }
}
