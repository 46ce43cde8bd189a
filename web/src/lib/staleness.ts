// When are the numbers on screen no longer current? The station says so (`link.stale`), but the
// page must also notice on its own: the station itself may stop sending (WebSocket stalled or
// closed), and a single message type may stop while others flow (GPS lost, heartbeat fine).
// Everything here is a pure function of the last state, when it arrived, and now.

import type { Link } from "./types";

/** Telemetry older than this is stale: the drone streams at 4…30 Hz, so 2 s is several misses. */
export const LINK_AGE_STALE_S = 2;
/** The station sends `state` at 4 Hz; 2 s without one means the station or the socket stalled. */
export const STATE_GAP_STALE_S = 2;
/** Per-message limits; HEARTBEAT comes at 1 Hz, so it gets more room than the 4 Hz streams. */
export const MESSAGE_AGE_LIMIT_S: Readonly<Record<string, number>> = { HEARTBEAT: 3.5 };
export const DEFAULT_MESSAGE_AGE_LIMIT_S = 2;
/**
 * Messages the drone sends once, as an answer or on an event, not as a stream: their age says
 * when the last answer came, so it never makes them OLD.
 */
export const ONE_SHOT_MESSAGES: ReadonlySet<string> = new Set([
  "PARAM_VALUE", "MISSION_ACK", "MISSION_COUNT", "MISSION_ITEM_INT", "MISSION_REQUEST_INT", "MISSION_REQUEST",
  "COMMAND_ACK", "AUTOPILOT_VERSION", "PROTOCOL_VERSION", "STATUSTEXT", "MESSAGE_INTERVAL",
]);

export type Freshness = "fresh" | "stale" | "disconnected" | "no_data";

export interface StaleVerdict {
  freshness: Freshness;
  /** True whenever the values on screen must not be read as current. */
  stale: boolean;
  /** Best estimate of the age of the vehicle data now, s (null when unknown). */
  age_s: number | null;
  /** Why, for the banner: one short phrase per cause. */
  reasons: string[];
}

export interface StaleInput {
  socketOpen: boolean;
  link: Link | null;
  /** Page clock (ms) when the last state arrived; null if none yet. */
  receivedAtMs: number | null;
  nowMs: number;
}

export function judgeStaleness({ socketOpen, link, receivedAtMs, nowMs }: StaleInput): StaleVerdict {
  if (link === null || receivedAtMs === null) {
    return { freshness: socketOpen ? "no_data" : "disconnected", stale: true, age_s: null, reasons: [socketOpen ? "no telemetry yet" : "station disconnected"] };
  }
  const gap_s = Math.max(0, (nowMs - receivedAtMs) / 1000);
  // The link age was measured when the state was built; it has grown by the gap since.
  const age_s = link.age_s === null ? null : link.age_s + gap_s;
  const reasons: string[] = [];
  if (!socketOpen) reasons.push("station disconnected");
  if (link.stale) reasons.push("station reports the link stale");
  if (!link.connected) reasons.push("no link to the drone");
  if (age_s !== null && age_s > LINK_AGE_STALE_S) reasons.push(`last message ${age_s.toFixed(1)} s ago`);
  if (age_s === null) reasons.push("age of last message unknown");
  if (gap_s > STATE_GAP_STALE_S) reasons.push(`no update from the station for ${gap_s.toFixed(1)} s`);
  const freshness: Freshness = !socketOpen ? "disconnected" : reasons.length > 0 ? "stale" : "fresh";
  return { freshness, stale: reasons.length > 0, age_s, reasons };
}

/**
 * Whether one state's vehicle data were already old when the station built it: what the plots
 * use for each sample (the page's own clock does not matter for a sample's past).
 */
export function linkStale(link: Link): boolean {
  return link.stale || !link.connected || link.age_s === null || link.age_s > LINK_AGE_STALE_S;
}

export interface MessageAge {
  name: string;
  age_s: number;
  /** Null for a one-shot message, which has no limit. */
  limit_s: number | null;
  old: boolean;
}

/** Per-message ages, grown by the time since the state arrived: streams oldest first, then one-shot answers. */
export function messageAges(link: Link, receivedAtMs: number, nowMs: number): MessageAge[] {
  const gap_s = Math.max(0, (nowMs - receivedAtMs) / 1000);
  return Object.entries(link.ages_s)
    .map(([name, a]) => {
      const limit_s = ONE_SHOT_MESSAGES.has(name) ? null : MESSAGE_AGE_LIMIT_S[name] ?? DEFAULT_MESSAGE_AGE_LIMIT_S;
      const age_s = a + gap_s;
      return { name, age_s, limit_s, old: limit_s !== null && age_s > limit_s };
    })
    .sort((x, y) => Number(x.limit_s === null) - Number(y.limit_s === null) || y.age_s - x.age_s);
}
