// What the map's tile badge says. The shipped station config has no tile source: then the badge
// must say so at once (waiting for tiles that will never come reads as a fault), and the metric
// grid is the map.

export type TilesState = "none" | "pack-failed" | "loading" | "ok" | "partial" | "offline";

export interface TilesBadge {
  state: TilesState;
  text: string;
}

/**
 * `configured`: the station gave a `tile_url`. `loaded`/`failed`: tiles counted so far.
 * A source with failures and no success is offline (no network, no cache). `packError`: the
 * station's tile pack gives no map (`offline_tiles_error`); with no other source that is why the
 * grid is the map, and saying "none configured" would send the operator to the wrong fix.
 */
export function tilesBadge(configured: boolean, loaded: number, failed: number, packError: string | null = null): TilesBadge {
  if (!configured) {
    if (packError !== null) return { state: "pack-failed", text: "tile pack unusable — metric grid" };
    return { state: "none", text: "no tiles configured — metric grid" };
  }
  if (loaded === 0 && failed === 0) return { state: "loading", text: "tiles: loading…" };
  if (loaded === 0) return { state: "offline", text: "tiles unavailable — metric grid" };
  if (failed > 0) return { state: "partial", text: `tiles: ${failed} failed` };
  return { state: "ok", text: "tiles OK" };
}

/**
 * The note under the badge when the station's tile pack failed: its reason, as the station put it
 * (names the file and what is wrong with it). `null`: nothing to say.
 */
export function packNote(packError: string | null): string | null {
  const text = packError?.trim() ?? "";
  return text === "" ? null : `Offline map: ${text}`;
}
