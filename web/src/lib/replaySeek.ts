// Which seek of a replay the page shows, so it never mixes two timelines. After a seek the
// station sends every page the `history` at the new position (replay_epoch) and states of the
// new epoch (state.replay.epoch); the two travel on different channels, so either may come
// first, and a state built before the seek may still arrive after the history. A state of a
// new epoch starts the track and plots over (its history then fills them); anything of an
// earlier epoch is dropped. A live station's messages carry no epoch and are always kept.
// Also the speed box's reading: any speed the station accepts, not a fixed list.

/** Slowest and fastest replay the station accepts, × real time (crates/stx-station replay::clock). */
export const MIN_SPEED = 0.25;
export const MAX_SPEED = 64;

export type StateVerdict = "keep" | "drop" | "restart";

export class SeekEpoch {
  private epoch: number | null = null;

  /** The epoch shown, `null` before any (or live). */
  get current(): number | null {
    return this.epoch;
  }

  /** A state of `epoch` (its `replay.epoch`; `null` live): keep it, drop it (from before the
   *  seek shown), or start over (the first of a new seek: clear, then keep it). */
  state(epoch: number | null): StateVerdict {
    if (epoch === null) return "keep";
    if (this.epoch !== null && epoch < this.epoch) return "drop";
    if (epoch === this.epoch) return "keep";
    this.epoch = epoch;
    return "restart";
  }

  /** A history of `epoch` (its `replay_epoch`): whether to apply it (it then is the epoch shown). */
  history(epoch: number | null): boolean {
    if (epoch === null) return true;
    if (this.epoch !== null && epoch < this.epoch) return false;
    this.epoch = epoch;
    return true;
  }

  /** Whether a state of `epoch` belongs with what is shown (it may follow the history). */
  shows(epoch: number | null): boolean {
    return epoch === null || epoch === this.epoch;
  }
}

/** The speed typed in the replay bar, × real time, or why it is not one the station accepts. */
export function parseSpeed(text: string): { ok: true; value: number } | { ok: false; error: string } {
  const t = text.trim().replace(/[×x]$/i, "").trim();
  const v = Number(t);
  if (t === "" || !Number.isFinite(v)) return { ok: false, error: `not a number: "${text}"` };
  if (v < MIN_SPEED || v > MAX_SPEED) return { ok: false, error: `${v}× is not within ${MIN_SPEED}–${MAX_SPEED}×` };
  return { ok: true, value: v };
}
