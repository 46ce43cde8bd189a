// Reconnect delays for the WebSocket: exponential from 0.5 s to 15 s, with jitter so that every
// browser in the room does not hammer a restarting daemon at the same instant.

export const BACKOFF_MIN_MS = 500;
export const BACKOFF_MAX_MS = 15_000;

/** Delay before reconnect attempt `attempt` (0-based). `random` in [0,1) spreads it by ±20 %. */
export function backoffMs(attempt: number, random: () => number = Math.random): number {
  const base = Math.min(BACKOFF_MAX_MS, BACKOFF_MIN_MS * 2 ** Math.max(0, Math.min(attempt, 20)));
  return Math.round(base * (0.8 + 0.4 * random()));
}
