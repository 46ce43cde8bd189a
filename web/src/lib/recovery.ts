// Which point the recovery team should drive to: once landed, where the station measured the
// touchdown; before, the landing predicted for the way it is flying (guided modes → planned;
// uncontrolled → uncontrolled). And the header's landing badge: the countdown only while a landing
// is predicted (under the round chute, the map's unsteered landing; under the parafoil, the flown
// prediction), on the mission's clock; once landed, the station's one miss figure.

import { vehiclePosition } from "./fix";
import { fmtDistance, fmtDuration } from "./format";
import type { LatLon, N, State } from "./types";

export type RecoveryKind = "actual" | "planned" | "uncontrolled";

export interface RecoveryPoint extends LatLon {
  kind: RecoveryKind;
  time_to_land_s: N;
  semi_major_m: N;
}

/** On the ground: the mission's stage (else the drone's) is `landed`. */
export function isLanded(s: State): boolean {
  return (s.mission.stage ?? s.vehicle?.stage ?? null) === "landed";
}

export function recoveryPoint(s: State): RecoveryPoint | null {
  if (isLanded(s)) {
    const l = s.mission.landing;
    if (l !== null) return { kind: "actual", lat_deg: l.position.lat_deg, lon_deg: l.position.lon_deg, time_to_land_s: 0, semi_major_m: s.estimate?.position_sigma_m ?? null };
    const at = vehiclePosition(s);
    if (at !== null) return { kind: "actual", lat_deg: at.lat_deg, lon_deg: at.lon_deg, time_to_land_s: 0, semi_major_m: s.estimate?.position_sigma_m ?? null };
  }
  const p = s.prediction;
  if (p === null) return null;
  const mode = s.guidance?.mode ?? s.vehicle?.mode ?? null;
  const unguided = mode === "uncontrolled" || mode === "manual";
  const order = unguided ? [["uncontrolled", p.uncontrolled], ["planned", p.planned]] as const : [["planned", p.planned], ["uncontrolled", p.uncontrolled]] as const;
  for (const [kind, lp] of order) {
    if (lp !== null) return { kind, lat_deg: lp.lat_deg, lon_deg: lp.lon_deg, time_to_land_s: lp.time_to_land_s, semi_major_m: lp.semi_major_m };
  }
  return null;
}

/** The header's landing badge: live countdown, the same marked stale, or where it landed. */
export interface LandingBadge {
  state: "none" | "live" | "stale" | "landed";
  text: string;
}

/** When the stack is predicted to land, in mission seconds from now, and by which prediction. */
export interface LandingCountdown {
  in_s: number;
  kind: "planned" | "uncontrolled" | "unsteered";
}

const PARAFOIL_STAGES: readonly string[] = ["parafoil_deploy", "parafoil"];

/**
 * The landing the map shows, as a countdown: under the parafoil the prediction flown (planned in
 * guided modes, else uncontrolled); under the round chute the flight path's unsteered landing,
 * counted down on the mission clock from when it was computed; before (pad, balloon) none — a
 * "landing in" during the climb counted the balloon's descent it had not begun.
 */
export function landingCountdown(s: State): LandingCountdown | null {
  const stage = s.mission.stage ?? s.vehicle?.stage ?? null;
  if (stage !== null && PARAFOIL_STAGES.includes(stage)) {
    const pt = recoveryPoint(s);
    if (pt === null || pt.kind === "actual" || pt.time_to_land_s === null) return null;
    return { in_s: pt.time_to_land_s, kind: pt.kind };
  }
  const p = s.flight_path;
  if (stage === "round_chute" && p !== null) {
    const elapsed = s.mission_time_s !== null && p.computed_mission_s !== null ? Math.max(0, s.mission_time_s - p.computed_mission_s) : 0;
    return { in_s: Math.max(0, p.landing.in_s - elapsed), kind: "unsteered" };
  }
  return null;
}

/** The landing figure as every page words it: the station's, measured once. */
export function landedText(s: State): string {
  const l = s.mission.landing;
  if (l === null) return "LANDED · measuring the touchdown";
  return `LANDED · ${missPhrase(l.miss_m, l.body)}`;
}

/**
 * The station's one miss figure as every page words it: which body, how far, from the target —
 * to the decimetre, so that the header, map, log, recordings list and a replay read the same.
 * `body` is `null` for recordings made before the station named it.
 */
export function missPhrase(miss_m: number | null, body: string | null): string {
  const who = body === null ? "" : `${body} `;
  if (miss_m === null) return `${who}down, no target`;
  return `${who}${miss_m < 1000 ? `${miss_m.toFixed(1)} m` : fmtDistance(miss_m)} from the target`;
}

/**
 * `stale`/`age_s`: the page's verdict on the data (staleness.ts). A stale countdown is not
 * counted down by the page — the drone may have done anything since — but says how old it is.
 */
export function landingBadge(s: State | null, stale: boolean, age_s: N): LandingBadge {
  if (s === null) return { state: "none", text: "landing —" };
  if (isLanded(s)) return { state: "landed", text: `${landedText(s)}${stale ? " (link stale)" : ""}` };
  const c = landingCountdown(s);
  if (c === null) {
    if (!stale) return { state: "none", text: "landing —" };
    return { state: "stale", text: `landing — · data ${age_s === null ? "of an unknown age" : `${fmtDuration(age_s)} old`} — STALE` };
  }
  const n = `landing in ${fmtDuration(c.in_s)}${c.kind === "planned" ? "" : ` (${c.kind})`}`;
  if (!stale) return { state: "live", text: n };
  return { state: "stale", text: `${n} as of ${age_s === null ? "an unknown time" : fmtDuration(age_s)} ago — STALE` };
}

/** The phase to show: the drone's own (the station's replica may disagree), or `landed`. */
export function phaseLabel(s: State): string | null {
  if (isLanded(s)) return "landed";
  return s.vehicle?.phase ?? s.guidance?.phase ?? null;
}
