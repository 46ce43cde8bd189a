// What the map's tile badge says. The shipped station config has no tile source: then the badge
// must say so at once (waiting for tiles that will never come reads as a fault), and the metric
// grid is the map.

export type TilesState = "none" | "loading" | "ok" | "partial" | "offline";

export interface TilesBadge {
  state: TilesState;
  text: string;
}

/**
 * `configured`: the station gave a `tile_url`. `loaded`/`failed`: tiles counted so far.
 * A source with failures and no success is offline (no network, no cache).
 */
export function tilesBadge(configured: boolean, loaded: number, failed: number): TilesBadge {
  if (!configured) return { state: "none", text: "no tiles configured — metric grid" };
  if (loaded === 0 && failed === 0) return { state: "loading", text: "tiles: loading…" };
  if (loaded === 0) return { state: "offline", text: "tiles unavailable — metric grid" };
  if (failed > 0) return { state: "partial", text: `tiles: ${failed} failed` };
  return { state: "ok", text: "tiles OK" };
}
