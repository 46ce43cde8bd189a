// The recordings list's texts: sizes, start times, and where a flight landed or why it did not.
import { describe, expect, it } from "vitest";
import type * as Wire from "../generated/api";
import { landingText, sizeText, startText } from "../ui/recordingsPanel";

const base: Wire.RecordingSummary = {
  name: "a.mcap",
  size_bytes: 1,
  start_ms: null,
  duration_ms: 0,
  messages: 0,
  mission: null,
  vehicle: null,
  complete: true,
  recording_now: false,
  last_stage: null,
  landing: null,
};

describe("recordings list", () => {
  it("gives sizes in kB below a megabyte and MB above", () => {
    expect(sizeText(52_300)).toBe("52 kB");
    expect(sizeText(3_456_000)).toBe("3.5 MB");
    expect(sizeText(65_200_000)).toBe("65 MB");
  });
  it("gives the start in UTC to the minute", () => {
    expect(startText(Date.UTC(2026, 10, 25, 14, 3, 59))).toBe("2026-11-25 14:03Z");
    expect(startText(null)).toBe("—");
  });
  it("says where a flight landed and its miss, or the stage it ended in", () => {
    expect(landingText({ ...base, landing: { lat_deg: 50.1, lon_deg: 14.2, miss_m: 3.44, body: "drone" } })).toContain("drone 3.4 m from the target");
    expect(landingText({ ...base, landing: { lat_deg: 50.1, lon_deg: 14.2, miss_m: 3.4, body: null } })).toContain("· 3.4 m from the target");
    expect(landingText({ ...base, landing: { lat_deg: 50.1, lon_deg: 14.2, miss_m: null, body: "drone" } })).toContain("no target");
    expect(landingText({ ...base, last_stage: "round_chute" })).toBe("not landed (round chute)");
    expect(landingText(base)).toBe("—");
  });
});
