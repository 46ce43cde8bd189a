// When a reported position is one: the station's rule (stx_link::telemetry::has_position_fix) on
// the page's side. A GPS without a fix reports zeros for its coordinates (ArduPilot's, and our
// simulated drone's during an outage); drawn, they would put the vehicle at 0° N 0° E, in the
// Gulf of Guinea, and the map would fly there. The station sends the drone's GPS as received,
// with its fix type, so every part of the page that places the vehicle asks here first.

import type { Gps, GpsFix, LatLon, State, TrackPoint } from "./types";

/** Fix types that place the receiver (GPS_FIX_TYPE ≥ 2). */
const WITH_POSITION: ReadonlySet<GpsFix> = new Set<GpsFix>(["fix2d", "fix3d", "dgps", "rtk_float", "rtk_fixed", "static", "ppp"]);

/** Coordinates that can be a vehicle's: finite, in range, and not exactly 0°, 0°. */
export function isPosition(lat: number | null | undefined, lon: number | null | undefined): boolean {
  if (lat == null || lon == null || !Number.isFinite(lat) || !Number.isFinite(lon)) return false;
  return Math.abs(lat) <= 90 && Math.abs(lon) <= 180 && !(lat === 0 && lon === 0);
}

/** A position with the altitude that came with it, if any. */
export type Placed = LatLon & { alt_msl_m: number | null };

/** The drone's GPS as a position: only with a fix (2-D or better) and not at 0°, 0°. */
export function gpsPosition(g: Gps | null | undefined): Placed | null {
  if (!g || g.fix === null || !WITH_POSITION.has(g.fix) || !isPosition(g.lat_deg, g.lon_deg)) return null;
  return { lat_deg: g.lat_deg!, lon_deg: g.lon_deg!, alt_msl_m: g.alt_msl_m };
}

/** Where the vehicle is: the station's estimate, else the drone's GPS when it has a fix. */
export function vehiclePosition(s: State): Placed | null {
  const e = s.estimate;
  if (e && isPosition(e.lat_deg, e.lon_deg)) return { lat_deg: e.lat_deg!, lon_deg: e.lon_deg!, alt_msl_m: e.alt_msl_m };
  return gpsPosition(s.vehicle?.gps);
}

/** A track's points that are positions (the station sends none at 0°, 0°; an older recording may). */
export function trackPositions(points: readonly TrackPoint[]): TrackPoint[] {
  return points.filter((p) => isPosition(p.lat_deg, p.lon_deg));
}
