// Time series for the plots: a fixed window (10 minutes) of samples on the mission clock, fed
// first by `history.states` (1 Hz) and then by live `state` messages (4 Hz). Samples must move
// forward in time; a repeat or an older one (history overlapping live data) is dropped.

export const WINDOW_S = 600;

export class Series {
  readonly t: number[] = [];
  readonly cols: (number | null)[][];

  constructor(readonly names: readonly string[], readonly windowS = WINDOW_S) {
    this.cols = names.map(() => []);
  }

  push(time_s: number, values: readonly (number | null)[]): boolean {
    const last = this.t[this.t.length - 1];
    if (last !== undefined && time_s <= last) {
      // The mission clock restarted (station restart, new recording): start over.
      if (time_s < last - this.windowS) this.clear();
      else return false;
    }
    this.t.push(time_s);
    this.cols.forEach((c, i) => c.push(values[i] ?? null));
    const cut = time_s - this.windowS;
    let n = 0;
    while (n < this.t.length && (this.t[n] ?? 0) < cut) n++;
    if (n > 0) {
      this.t.splice(0, n);
      this.cols.forEach((c) => c.splice(0, n));
    }
    return true;
  }

  clear(): void {
    this.t.length = 0;
    this.cols.forEach((c) => (c.length = 0));
  }
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
