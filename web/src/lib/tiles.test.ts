import { describe, expect, it } from "vitest";
import { packNote, tilesBadge } from "./tiles";

describe("tilesBadge", () => {
  // Regression: with no tile_url (the shipped config) the badge said "tiles: loading…" forever.
  it("says at once that no tile source is configured", () => {
    expect(tilesBadge(false, 0, 0)).toEqual({ state: "none", text: "no tiles configured — metric grid" });
  });
  it("follows a configured source: loading, ok, partial, offline", () => {
    expect(tilesBadge(true, 0, 0).state).toBe("loading");
    expect(tilesBadge(true, 3, 0).state).toBe("ok");
    expect(tilesBadge(true, 3, 2)).toEqual({ state: "partial", text: "tiles: 2 failed" });
    expect(tilesBadge(true, 0, 6)).toEqual({ state: "offline", text: "tiles unavailable — metric grid" });
  });
  it("names a failed tile pack instead of saying no tiles are configured", () => {
    const err = "tile pack /srv/field.mbtiles: no such file";
    expect(tilesBadge(false, 0, 0, err)).toEqual({ state: "pack-failed", text: "tile pack unusable — metric grid" });
    // Another source (a tile directory, an online server) is followed as before.
    expect(tilesBadge(true, 3, 0, err).state).toBe("ok");
    expect(tilesBadge(true, 0, 6, err).state).toBe("offline");
  });
});

describe("packNote", () => {
  it("shows the station's reason, or nothing", () => {
    expect(packNote("tile pack /srv/field.mbtiles: no such file")).toBe("Offline map: tile pack /srv/field.mbtiles: no such file");
    expect(packNote(null)).toBeNull();
    expect(packNote("  ")).toBeNull();
  });
});
