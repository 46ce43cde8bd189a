// The phone's position on the recovery page when the browser will not give it: why not (said in
// words the recovery team can act on), and a position typed or pasted by hand in the forms people
// actually have at hand — decimal degrees, our own "38.53000° N, 7.89310° W", a geo: URI, or a
// map link with the coordinates in it.

import type { Checked } from "./inputs";
import type { LatLon } from "./types";

const NUM = String.raw`[-+−]?\d+(?:[.,]\d+)?`;
/** One coordinate: a number, optional degree sign, optional hemisphere letter after it. */
const COORD = new RegExp(String.raw`^\s*(${NUM})\s*°?\s*([NSEWnsew])?\s*$`);

function coord(text: string, kind: "lat" | "lon"): number | null {
  const m = COORD.exec(text);
  if (!m) return null;
  let v = Number(m[1]!.replace("−", "-").replace(",", "."));
  const hemi = m[2]?.toUpperCase();
  if (hemi !== undefined) {
    if (kind === "lat" ? !"NS".includes(hemi) : !"EW".includes(hemi)) return null;
    if (v < 0) return null; // "-38 N" is a contradiction, not a position
    if (hemi === "S" || hemi === "W") v = -v;
  }
  return Number.isFinite(v) ? v : null;
}

/**
 * Splits two coordinates. The separator is the strongest one present — ";", then a comma next to
 * a space, then spaces, then a bare comma — so decimal commas survive ("38,5 -7,8").
 */
function split(t: string): [string, string] | null {
  const two = (parts: string[]): [string, string] | null => (parts.length === 2 ? [parts[0]!, parts[1]!] : null);
  if (t.includes(";")) return two(t.split(/\s*;\s*/));
  if (/,\s|\s,/.test(t)) return two(t.split(/\s*,\s+|\s+,\s*/));
  const words = t.split(/\s+/);
  // "38.5° N 7.8° W": each number with its hemisphere letter.
  if (words.length === 4 && /^[NSns]$/.test(words[1]!) && /^[EWew]$/.test(words[3]!)) return [`${words[0]} ${words[1]}`, `${words[2]} ${words[3]}`];
  if (words.length > 1) return two(words);
  return two(t.split(","));
}

/** A position typed or pasted by a person; the error says what form is expected. */
export function parsePosition(text: string): Checked<LatLon> {
  let t = text.trim();
  if (t === "") return { ok: false, error: "type or paste a position, e.g. 38.5333, -7.8889" };
  const geo = /^geo:([^;?]+)/i.exec(t);
  if (geo) t = geo[1]!;
  else {
    // A map link: "…@38.53,-7.88,17z", "…?q=38.53,-7.88", "…mlat=38.53&mlon=-7.88", "#map=17/38.53/-7.88".
    const at = new RegExp(String.raw`@(${NUM}),(${NUM})`).exec(t) ?? new RegExp(String.raw`[?&](?:q|ll|query)=(${NUM}),\s*(${NUM})`).exec(t);
    const osm = new RegExp(String.raw`mlat=(${NUM}).*mlon=(${NUM})`).exec(t) ?? new RegExp(String.raw`map=\d+/(${NUM})/(${NUM})`).exec(t);
    const m = at ?? osm;
    if (m) t = `${m[1]}, ${m[2]}`;
    else if (/^https?:/i.test(t)) return { ok: false, error: "this link has no coordinates in it: paste the coordinates themselves" };
  }
  const parts = split(t);
  if (!parts) return { ok: false, error: "expected two coordinates: latitude, longitude (e.g. 38.5333, -7.8889)" };
  const lat = coord(parts[0], "lat");
  const lon = coord(parts[1], "lon");
  if (lat === null) return { ok: false, error: `latitude "${parts[0]}" not understood (e.g. 38.5333 or 38.5333° N)` };
  if (lon === null) return { ok: false, error: `longitude "${parts[1]}" not understood (e.g. -7.8889 or 7.8889° W)` };
  if (lat < -90 || lat > 90) return { ok: false, error: "latitude must be within −90…90°" };
  if (lon < -180 || lon > 180) return { ok: false, error: "longitude must be within −180…180°" };
  return { ok: true, value: { lat_deg: lat, lon_deg: lon } };
}

/** Why the browser cannot give the phone's position, or null if it may. */
export interface GeoContext {
  secure: boolean;
  hasGeolocation: boolean;
  /** GeolocationPositionError code after a request failed: 1 denied, 2 unavailable, 3 timeout. */
  errorCode: number | null;
  /** `location.origin`, to name the address to open instead. */
  origin: string;
}

export function positionUnavailable(g: GeoContext): string | null {
  if (!g.secure) {
    const https = g.origin.replace(/^http:/, "https:");
    return `The phone's position needs a secure page: this one was opened over plain HTTP (${g.origin}). Open ${https}/recovery.html if the station serves HTTPS, or enter your position below.`;
  }
  if (!g.hasGeolocation) return "This browser gives no position (no geolocation). Enter your position below.";
  switch (g.errorCode) {
    case null:
      return null;
    case 1:
      return "Location permission is denied for this page: allow location for this site in the browser's settings and reload, or enter your position below.";
    case 2:
      return "The phone cannot find its position now (no GPS fix, location off?). Enter your position below, or wait.";
    case 3:
      return "The phone took too long to find its position. Enter your position below, or wait.";
    default:
      return "The phone's position is unavailable. Enter your position below.";
  }
}
