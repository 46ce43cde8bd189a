import { describe, expect, it } from "vitest";
import { fmtAge, surfaceWindBody, surfaceWindShown, type ShownLine, type SurfaceWind } from "./surfaceWind";

const NONE: SurfaceWind = { wind: null, operator: null, held: null, drone: "none", drone_accepted_age_s: null, last_error: null, anemometer: null };
const MAST = { address: "udpin:0.0.0.0:10110", sentences: 412, rejected: 3, last_error: null, heard_age_s: 0.9, in_mean: 10 };
const typed = { speed_mps: 4.3, from_deg: 250, source: "operator" as const, age_s: 12 };
const measured = { speed_mps: 3.24, from_deg: 275.4, source: "anemometer" as const, age_s: 0.9 };

/** A line as the page shows it: its words, then whether it warns. */
const seen = (l: ShownLine | null): [string, boolean] | null => (l === null ? null : [`${l.text}${l.detail === "" ? "" : ` ${l.detail}`}`, l.warn]);

describe("what the Wind panel shows of the surface wind", () => {
  it("a station or recording without the block: dashes, no anemometer line", () => {
    const s = surfaceWindShown(null);
    expect([seen(s.wind), seen(s.drone), s.anemometer]).toEqual([["—", false], ["—", false], null]);
    expect(s.wind.title).toMatch(/reports no surface wind/);
  });

  it("no wind in force: none, not sent", () => {
    const s = surfaceWindShown(NONE);
    expect([seen(s.wind), seen(s.drone), s.anemometer]).toEqual([["none", false], ["not sent", false], null]);
  });

  it("the operator's value, held by the drone: its speed, from, source and age, and what the drone holds", () => {
    const s = surfaceWindShown({ ...NONE, wind: typed, operator: typed, drone: "held", held: { ...typed, age_s: 10 }, drone_accepted_age_s: 3.2 });
    expect(seen(s.wind)).toEqual(["4.3 m/s from 250° · operator 12 s", false]);
    expect(seen(s.drone)).toEqual(["held 4.3 m/s from 250° 3 s ago", false]);
    // A station that does not say what the drone holds: that it holds one, and since when.
    expect(seen(surfaceWindShown({ ...NONE, wind: typed, drone: "held", drone_accepted_age_s: 95 }).drone)).toEqual(["held 2 min ago", false]);
    // The station sends a typed value as measured now: its age is the operator block's, since typed.
    expect(seen(surfaceWindShown({ ...NONE, wind: { ...typed, age_s: 0 }, operator: { ...typed, age_s: 400 } }).wind)).toEqual(["4.3 m/s from 250° · operator 7 min", false]);
    expect(seen(surfaceWindShown({ ...NONE, wind: typed, drone: "sending" }).drone)).toEqual(["sending", false]);
  });

  it("the anemometer's mean wins: it is the wind, the operator's value is in the tooltip, the mast's line says it is heard", () => {
    const s = surfaceWindShown({ ...NONE, wind: measured, operator: typed, drone: "held", drone_accepted_age_s: 1, anemometer: MAST });
    expect(seen(s.wind)).toEqual(["3.2 m/s from 275° · anemometer", false]);
    expect(s.wind.title).toMatch(/operator's 4\.3 m\/s from 250° \(12 s old\) is not used/);
    expect(seen(s.anemometer)).toEqual(["heard 1 s ago · 412 ok · 3 bad", false]);
    expect(s.anemometer?.title).toMatch(/udpin:0\.0\.0\.0:10110.*10 in the mean/);
  });

  it("a failed uplink is a warning with its reason", () => {
    const s = surfaceWindShown({ ...NONE, wind: typed, operator: typed, drone: "failed", drone_accepted_age_s: 40, last_error: "no acknowledgement after 3 tries" });
    expect(seen(s.drone)).toEqual(["FAILED: no acknowledgement after 3 tries", true]);
    expect(s.drone.title).toMatch(/last accepted one 40 s ago/);
    expect(seen(surfaceWindShown({ ...NONE, wind: typed, drone: "failed" }).drone)).toEqual(["FAILED: no reason given", true]);
  });

  it("a stale anemometer: a warning that its wind is not used, and the operator's value sent instead", () => {
    const s = surfaceWindShown({ ...NONE, wind: typed, operator: typed, drone: "held", drone_accepted_age_s: 2, anemometer: { ...MAST, heard_age_s: 45, in_mean: 0 } });
    expect(seen(s.wind)).toEqual(["4.3 m/s from 250° · operator 12 s", false]);
    expect(seen(s.anemometer)).toEqual(["heard 45 s ago · stale, not used · 412 ok · 3 bad", true]);
    expect(s.anemometer?.title).toMatch(/NOT in use/);
  });

  it("an anemometer never heard names where it listens; a refused line is a warning", () => {
    expect(seen(surfaceWindShown({ ...NONE, anemometer: { ...MAST, sentences: 0, rejected: 0, heard_age_s: null, in_mean: 0 } }).anemometer))
      .toEqual(["not heard · on udpin:0.0.0.0:10110 · 0 ok · 0 bad", true]);
    expect(seen(surfaceWindShown({ ...NONE, wind: measured, anemometer: { ...MAST, last_error: "bad checksum 4F, computed 4E" } }).anemometer))
      .toEqual(["heard 1 s ago · 412 ok · 3 bad · bad checksum 4F, computed 4E", true]);
  });

  it("an unknown drone copy or a garbled count is a dash, not a guess", () => {
    const s = surfaceWindShown({ ...NONE, drone: null, anemometer: { ...MAST, sentences: null } });
    expect(seen(s.drone)).toEqual(["—", false]);
    expect(s.anemometer?.detail).toContain("— ok");
  });
});

describe("ages and the typed value", () => {
  it("ages in whole units", () => {
    expect([fmtAge(0.4), fmtAge(12.6), fmtAge(89), fmtAge(95), fmtAge(3000), fmtAge(7200), fmtAge(null), fmtAge(-1)]).toEqual(["0 s", "13 s", "89 s", "2 min", "50 min", "2.0 h", "— s", "0 s"]);
  });

  it("what the operator types becomes the body, or says which field is wrong", () => {
    expect(surfaceWindBody(" 4,3 ", "250")).toEqual({ ok: true, body: { speed_mps: 4.3, from_deg: 250 } });
    expect(surfaceWindBody("0", "-90")).toEqual({ ok: true, body: { speed_mps: 0, from_deg: -90 } });
    for (const [speed, from, error] of [["", "250", /speed.*required/], ["fast", "250", /speed.*not a number/], ["61", "250", /speed.*0…60/], ["-1", "250", /speed/], ["4", "", /from.*required/], ["4", "400", /from.*-360…360/]] as const) {
      const r = surfaceWindBody(speed, from);
      expect(r.ok).toBe(false);
      if (!r.ok) expect(r.error).toMatch(error);
    }
  });
});
