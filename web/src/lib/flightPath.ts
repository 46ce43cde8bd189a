/**
 * The unsteered flight path the station predicts while the balloon rises and the round chute
 * falls (`state.flight_path`): its parsing, lenient like the rest of the state (a point that
 * does not parse leaves the whole path out rather than drawing it wrong), and the one-line
 * summary the map's badge shows, the burst with where its altitude comes from (the drone's
 * parameters or the station config).
 */
import { fmt, fmtDuration } from "./format";
// The path's types live with the rest of the state's (types.ts); this file reads and summarises it.
import type { FlightPath, PathPoint } from "./types";

export type { FlightPath, PathPoint };

/** How the badge names a source of the launch profile. */
const SOURCES: Record<string, string> = { drone: "drone", station_config: "station config" };

type Obj = Record<string, unknown>;
const isObj = (v: unknown): v is Obj => typeof v === "object" && v !== null && !Array.isArray(v);
const finite = (v: unknown): v is number => typeof v === "number" && Number.isFinite(v);

function point(v: unknown): PathPoint | null {
  if (!isObj(v)) return null;
  const { lat_deg, lon_deg, alt_msl_m, in_s } = v;
  if (!finite(lat_deg) || !finite(lon_deg) || !finite(alt_msl_m) || !finite(in_s)) return null;
  if (Math.abs(lat_deg) > 90 || Math.abs(lon_deg) > 180) return null;
  return { lat_deg, lon_deg, alt_msl_m, in_s };
}

/** `state.flight_path`, or null when absent or malformed. */
export function parseFlightPath(o: Obj): FlightPath | null {
  const deploy = point(o.deploy);
  const landing = point(o.landing);
  const round_chute_landing = point(o.round_chute_landing);
  const burst = o.burst === null || o.burst === undefined ? null : point(o.burst);
  const centre = o.reach_centre_lat_lon_deg;
  if (!deploy || !landing || !round_chute_landing || (o.burst != null && burst === null)) return null;
  if (!Array.isArray(centre) || !finite(centre[0]) || !finite(centre[1]) || !finite(o.reach_radius_m)) return null;
  return {
    stage: typeof o.stage === "string" ? o.stage : "ascent",
    burst,
    deploy,
    landing,
    round_chute_landing,
    reach_centre: { lat_deg: centre[0], lon_deg: centre[1] },
    reach_radius_m: o.reach_radius_m,
    measured_bands: finite(o.measured_bands) ? o.measured_bands : 0,
    measured_to_msl_m: finite(o.measured_to_msl_m) ? o.measured_to_msl_m : null,
    burst_source: typeof o.burst_source === "string" ? o.burst_source : null,
    computed_mission_s: finite(o.computed_mission_s) ? o.computed_mission_s : null,
  };
}

/**
 * The badge: when and how high the burst and the deployment come, and which winds say so. The
 * times count down on the mission clock `mission_time_s` (the drone's) from when the path was
 * computed, at any rehearsal speed.
 */
export function flightPathSummary(p: FlightPath, mission_time_s: number | null = null): string {
  const elapsed = mission_time_s !== null && p.computed_mission_s !== null ? Math.max(0, mission_time_s - p.computed_mission_s) : 0;
  const left = (pt: PathPoint): number => Math.max(0, pt.in_s - elapsed);
  const parts: string[] = [];
  if (p.burst) {
    // Never a number without its origin: a station that is not told cannot tell.
    const source = p.burst_source === null ? "source not given" : (SOURCES[p.burst_source] ?? p.burst_source);
    parts.push(`burst in ${fmtDuration(left(p.burst))} at ${fmt(p.burst.alt_msl_m / 1000, "km")} (${source})`);
  }
  parts.push(`deploy in ${fmtDuration(left(p.deploy))} at ${fmt(p.deploy.alt_msl_m, "m", 0)}`);
  parts.push(`unsteered landing in ${fmtDuration(left(p.landing))}`);
  parts.push(
    p.measured_bands > 0 && p.measured_to_msl_m !== null
      ? `winds: ${p.measured_bands} measured bands to ${fmt(p.measured_to_msl_m / 1000, "km")}, forecast above`
      : "winds: forecast only",
  );
  return parts.join(" · ");
}
