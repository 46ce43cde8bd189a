// The alarm the pages raise when the station's guidance replica and the drone disagree: which
// value, each side's, for how long and since when on the mission clock — instead of the map
// silently drawing the replica's own story.

import { fmtDuration, fmtMissionTime, label } from "./format";
import type { Disagreement } from "./types";

export function replicaAlarm(d: Disagreement): string {
  const sides = `station ${label(d.replica)}, drone ${label(d.drone)}`;
  const since = `since ${fmtMissionTime(d.since_s)}`;
  if (!d.resolved) return `REPLICA ≠ DRONE: ${d.what} (${sides}) for ${fmtDuration(d.for_s)}, ${since}`;
  const how = d.adopted ? "the replica took the drone's" : "they agree again";
  return `replica and drone disagreed on the ${d.what} for ${fmtDuration(d.for_s)} (${sides}, ${since}): ${how}`;
}
