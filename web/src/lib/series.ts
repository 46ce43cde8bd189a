// Time series for the plots: a fixed window (10 minutes) of samples on the mission clock, fed
// first by `history.states` (1 Hz) and then by live `state` messages (4 Hz). Samples must move
// forward in time; a repeat or an older one (history overlapping live data) is dropped.
//
// A plot must never draw a line through time it has no current data for: the station keeps
// sending states while the drone's link is down, carrying the last values, and a socket that
// stalls sends nothing at all. So a stale sample is stored as nulls (uPlot leaves a gap) and
// flagged, a silence longer than `MAX_GAP_S` gets a null row of its own, and `staleSpans` gives
// the stretches to grey out so the gap reads as "no current data", not as a glitch.

export const WINDOW_S = 600;
/** Longest step between samples drawn as a line, s: history comes at 1 Hz, live states at 4 Hz. */
export const MAX_GAP_S = 3;

/** What a sample is: current data, old data (values withheld), or a silence marker. */
export type SampleKind = "live" | "stale" | "gap";

export class Series {
  readonly t: number[] = [];
  readonly cols: (number | null)[][];
  readonly kinds: SampleKind[] = [];

  constructor(readonly names: readonly string[], readonly windowS = WINDOW_S) {
    this.cols = names.map(() => []);
  }

  push(time_s: number, values: readonly (number | null)[], stale = false): boolean {
    const last = this.t[this.t.length - 1];
    if (last !== undefined && time_s <= last) {
      // The mission clock restarted (station restart, new recording): start over.
      if (time_s < last - this.windowS) this.clear();
      else return false;
    }
    const prev = this.t[this.t.length - 1];
    if (prev !== undefined && time_s - prev > MAX_GAP_S) this.row((prev + time_s) / 2, [], "gap");
    this.row(time_s, stale ? [] : values, stale ? "stale" : "live");
    const cut = time_s - this.windowS;
    let n = 0;
    while (n < this.t.length && (this.t[n] ?? 0) < cut) n++;
    if (n > 0) {
      this.t.splice(0, n);
      this.kinds.splice(0, n);
      this.cols.forEach((c) => c.splice(0, n));
    }
    return true;
  }

  clear(): void {
    this.t.length = 0;
    this.kinds.length = 0;
    this.cols.forEach((c) => (c.length = 0));
  }

  private row(time_s: number, values: readonly (number | null)[], kind: SampleKind): void {
    this.t.push(time_s);
    this.kinds.push(kind);
    this.cols.forEach((c, i) => c.push(values[i] ?? null));
  }
}

/**
 * Stretches of time without current data, as [from, to] on the mission clock: from the last live
 * sample before a run of stale/gap samples to the first live one after it (or to the last sample
 * if the run is still going).
 */
export function staleSpans(t: readonly number[], kinds: readonly SampleKind[]): [number, number][] {
  const out: [number, number][] = [];
  let start: number | null = null;
  for (let i = 0; i < t.length; i++) {
    const ti = t[i]!;
    if (kinds[i] !== "live") {
      if (start === null) start = i > 0 ? t[i - 1]! : ti;
    } else if (start !== null) {
      out.push([start, ti]);
      start = null;
    }
  }
  if (start !== null && t.length > 0) out.push([start, t[t.length - 1]!]);
  return out;
}

/**
 * Angles plotted on 0…360 jump from 359 to 0; a line across the chart would lie. Breaks the line
 * (null) at every sample that differs from the previous one by more than 180°.
 */
export function breakWraps(values: readonly (number | null)[]): (number | null)[] {
  let prev: number | null = null;
  return values.map((v) => {
    if (v === null) {
      prev = null;
      return null;
    }
    const w = ((v % 360) + 360) % 360;
    const jump = prev !== null && Math.abs(w - prev) > 180;
    prev = w;
    return jump ? null : w;
  });
}
