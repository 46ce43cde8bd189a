// The ascent's measured bands as the wind panel draws them: speed and direction with 2-σ
// intervals from the components, intervals across north, the band at an altitude, and the
// `ascent_wind` message read leniently.
import { describe, expect, it } from "vitest";
import { ascentBandAt, ascentPoint, directionSpans } from "./wind";
import { decodeMessage } from "./parse";
import type { AscentBand } from "./types";

const band = (over: Partial<AscentBand> = {}): AscentBand => ({
  alt_msl_m: 1000,
  alt_min_msl_m: 750,
  alt_max_msl_m: 1250,
  speed_mps: null,
  from_deg: null,
  wind_north_mps: 0,
  wind_east_mps: 4,
  sigma_north_mps: 0.1,
  sigma_east_mps: 0.1,
  samples: 200,
  method: "gps_velocity",
  refused: null,
  time_start_s: 0,
  time_end_s: 100,
  ...over,
});

describe("ascentPoint", () => {
  it("a wind blowing east comes from the west; σ of the along-wind component makes the speed's, the across-wind one the direction's", () => {
    const p = ascentPoint(band({ sigma_north_mps: 0.2, sigma_east_mps: 0.1 }));
    expect(p.speed_mps).toBeCloseTo(4, 12);
    expect(p.from_deg).toBeCloseTo(270, 12);
    // Speed: the east σ (0.1) along the wind; ±2σ.
    expect(p.speed_lo_mps).toBeCloseTo(3.8, 12);
    expect(p.speed_hi_mps).toBeCloseTo(4.2, 12);
    // Direction: the north σ (0.2) across the wind, over 4 m/s: 0.05 rad, ±2σ = 5.73°.
    expect(p.dir_half_deg).toBeCloseTo((2 * 0.05 * 180) / Math.PI, 9);
    expect([p.alt_min_msl_m, p.alt_max_msl_m]).toEqual([750, 1250]);
  });

  it("a wind within its noise has no direction and a speed interval that stops at 0", () => {
    const p = ascentPoint(band({ wind_north_mps: 0.05, wind_east_mps: 0, sigma_north_mps: 0.3, sigma_east_mps: 0.3 }));
    expect(p.dir_half_deg).toBeNull();
    expect(p.speed_lo_mps).toBe(0);
    expect(p.speed_hi_mps).toBeCloseTo(0.65, 12);
    const calm = ascentPoint(band({ wind_north_mps: 0, wind_east_mps: 0 }));
    expect(calm.dir_half_deg).toBeNull();
    expect(calm.speed_hi_mps).toBeCloseTo(0.2, 12);
  });

  it("a band without its extent is drawn at its altitude", () => {
    const p = ascentPoint(band({ alt_min_msl_m: null, alt_max_msl_m: null }));
    expect([p.alt_min_msl_m, p.alt_max_msl_m]).toEqual([1000, 1000]);
  });
});

describe("directionSpans", () => {
  it("splits an interval across north into two pieces and gives the whole axis for no direction", () => {
    expect(directionSpans(270, 10)).toEqual([[260, 280]]);
    expect(directionSpans(355, 10)).toEqual([[345, 360], [0, 5]]);
    expect(directionSpans(3, 10)).toEqual([[0, 13], [353, 360]]);
    expect(directionSpans(-90, 5)).toEqual([[265, 275]]);
    expect(directionSpans(100, null)).toEqual([[0, 360]]);
  });
});

describe("ascentBandAt", () => {
  it("is the band whose fixes span the altitude", () => {
    const pts = [ascentPoint(band({ alt_msl_m: 500, alt_min_msl_m: 250, alt_max_msl_m: 749 })), ascentPoint(band())];
    expect(ascentBandAt(pts, 900)?.alt_msl_m).toBe(1000);
    expect(ascentBandAt(pts, 300)?.alt_msl_m).toBe(500);
    expect(ascentBandAt(pts, 2000)).toBeNull();
  });
});

describe("decodeMessage: ascent_wind", () => {
  it("keeps the good bands and counts the ones without their wind or with a negative σ", () => {
    const raw = JSON.stringify({
      type: "ascent_wind",
      time_s: 12,
      band_height_m: 500,
      ascent_over: false,
      fixes_used: 400,
      bands: [band(), { ...band(), wind_east_mps: null }, { ...band(), sigma_north_mps: -1 }, "junk"],
    });
    const d = decodeMessage(raw);
    expect(d.ok).toBe(true);
    if (!d.ok || d.msg.type !== "ascent_wind") throw new Error("not an ascent_wind");
    expect(d.msg.bands).toEqual([band()]);
    expect(d.dropped).toBe(3);
    expect(d.msg.ascent_over).toBe(false);
    expect(decodeMessage(JSON.stringify({ type: "ascent_wind" })).ok).toBe(false);
  });
});
