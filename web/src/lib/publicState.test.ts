import { describe, expect, it } from "vitest";
import { caveat, freshness, parsePublicHistory, parsePublicState } from "./publicState";

const msg = {
  type: "public_state", wall_ms: 1_000_000, mission_time_s: 512.5, stage: "parafoil", link_stale: false,
  position: { lat_deg: 49.1, lon_deg: 16.2, alt_msl_m: 1500, ground_speed_mps: 7, course_deg: 90, climb_mps: -4 },
  landing: { lat_deg: 49.0, lon_deg: 16.0 }, target: null, delay_s: 30, coarsen_m: 500,
};

describe("public state", () => {
  it("parses what a relay sends and refuses what is not a public state", () => {
    const s = parsePublicState(msg);
    expect(s?.position?.climb_mps).toBe(-4);
    expect(s?.landing).toEqual({ lat_deg: 49.0, lon_deg: 16.0 });
    expect(s?.target).toBeNull();
    expect(parsePublicState({ ...msg, type: "state" })).toBeNull();
    expect(parsePublicState({ ...msg, wall_ms: "late" })).toBeNull();
    expect(parsePublicState({ ...msg, position: { lat_deg: "x" } })?.position).toBeNull();
  });
  it("keeps the track points that parse", () => {
    const t = parsePublicHistory({ type: "public_history", track: [{ mission_time_s: 1, lat_deg: 1, lon_deg: 2, alt_msl_m: 3 }, { lat_deg: 1 }, 7] });
    expect(t).toEqual([{ mission_time_s: 1, lat_deg: 1, lon_deg: 2, alt_msl_m: 3 }]);
    expect(parsePublicHistory({ type: "history", track: [] })).toBeNull();
  });
  it("says how late and how exact it is, and when it is old beyond the delay", () => {
    const s = parsePublicState(msg)!;
    expect(caveat(s)).toBe("shown 30 s after the station; positions rounded to 500 m");
    expect(caveat({ ...s, delay_s: 0, coarsen_m: 0 })).toBe("");
    expect(freshness(s, 1_000_000 + 35_000)).toEqual({ stale: false, text: "live" });
    expect(freshness(s, 1_000_000 + 60_000).stale).toBe(true);
    expect(freshness({ ...s, link_stale: true }, 1_000_000).stale).toBe(true);
  });
});
