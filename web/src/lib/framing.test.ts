import { describe, expect, it } from "vitest";
import { NO_READINESS } from "./readiness";
import { boxAround, keyPoints, MIN_SPAN_M, needsFraming, shareOfView, type Box } from "./framing";
import { distanceM } from "./geo";
import type { FlightStage, State } from "./types";

const O = { lat_deg: 38.5333, lon_deg: -7.8889 };
/** As the wire sends the pattern's points. */
const pair = (north_m: number, east_m: number): [number, number] => [at(north_m, east_m).lat_deg, at(north_m, east_m).lon_deg];
const at = (north_m: number, east_m: number) => ({ lat_deg: O.lat_deg + north_m / 111_320, lon_deg: O.lon_deg + east_m / (111_320 * Math.cos((O.lat_deg * Math.PI) / 180)) });

function state(stage: FlightStage, extra: Partial<State> = {}): State {
  const v = at(-600, -500);
  return {
    type: "state", time_s: 10, mission_time_s: 200, wall_ms: null,
    link: { connected: true, stale: false, age_s: 0.1, rate_hz: 30, loss_percent: 0, crc_errors: 0, parse_errors: 0, signature_errors: 0, ages_s: {}, radios: [] },
    vehicle: null,
    estimate: { lat_deg: v.lat_deg, lon_deg: v.lon_deg, alt_msl_m: 900, height_m: 655, velocity_ned_mps: null, ground_speed_mps: null, course_deg: null, heading_deg: null, heading_rate_dps: null, airspeed_mps: null, sink_rate_mps: null, glide_ratio_air: null, glide_ratio_ground: null, wind_ned_mps: null, wind_speed_mps: null, wind_from_deg: null, wind_sigma_mps: null, position_sigma_m: null, gps_ok: true, age_s: 0.1, stale: false },
    guidance: {
      mode: "spiral_landing", phase: "branch2", target: { ...at(0, 0), alt_msl_m: 245 }, target_source: "drone_plan", localizer: null,
      pattern: { corners: [pair(100, 100), pair(100, -100), pair(-100, -100), pair(-100, 100)], final_entry: pair(200, 300), final_course_deg: 250, final_approach_height_m: 100, target_reachable: true, reach_ratio: 0.5 },
      commands: null, age_s: 0.1, stale: false, disagreement: null, learned: null,
    },
    prediction: { planned: { ...at(10, 5), time_to_land_s: 100, semi_major_m: 50, semi_minor_m: 20, major_axis_deg: 0 }, uncontrolled: { ...at(900, 1200), time_to_land_s: 90, semi_major_m: 150, semi_minor_m: 100, major_axis_deg: 30 }, age_s: 0.5, stale: false },
    footprint: null,
    stack: null,
    flight_path: null,
    keep_out_alarms: [],
    forecast_wind: [],
    mission: { stage, cutdown_armed_until_s: null, landing: null },
    recording: null,
    readiness: NO_READINESS,
    replay: null,
    surface_wind: null,
    ...extra,
  };
}

const inBox = (b: Box, p: { lat_deg: number; lon_deg: number }) => p.lat_deg >= b.south && p.lat_deg <= b.north && p.lon_deg >= b.west && p.lon_deg <= b.east;

describe("keyPoints", () => {
  it("holds the vehicle, target, pattern, final entry and both predictions with their 1σ extent", () => {
    const s = state("parafoil");
    const b = boxAround(keyPoints(s))!;
    for (const p of [at(-600, -500), at(0, 0), at(100, 100), at(-100, -100), at(200, 300), at(10, 5), at(900, 1200)]) expect(inBox(b, p)).toBe(true);
    // The uncontrolled ellipse (150 m) reaches beyond its centre.
    expect(inBox(b, at(900 + 140, 1200))).toBe(true);
  });
  it("once landed: only the vehicle and the target (the plan and predictions are over)", () => {
    const pts = keyPoints(state("landed"));
    expect(pts).toHaveLength(2);
  });
});

describe("boxAround", () => {
  it("a lone point gets the minimum span", () => {
    const b = boxAround([O])!;
    expect(distanceM({ lat_deg: b.south, lon_deg: O.lon_deg }, { lat_deg: b.north, lon_deg: O.lon_deg })).toBeCloseTo(MIN_SPAN_M, -1);
    expect(distanceM({ lat_deg: O.lat_deg, lon_deg: b.west }, { lat_deg: O.lat_deg, lon_deg: b.east })).toBeCloseTo(MIN_SPAN_M, -1);
    expect(boxAround([])).toBeNull();
  });
});

describe("needsFraming", () => {
  const view: Box = { south: at(-1000, 0).lat_deg, north: at(1000, 0).lat_deg, west: at(0, -1000).lon_deg, east: at(0, 1000).lon_deg };
  const box = (s: number, w: number, n: number, e: number): Box => ({ south: at(s, 0).lat_deg, north: at(n, 0).lat_deg, west: at(0, w).lon_deg, east: at(0, e).lon_deg });
  it("keeps a view that shows everything with room", () => {
    expect(needsFraming(view, box(-800, -800, 800, 800))).toBe(false);
    expect(needsFraming(view, box(-400, -100, 300, 200))).toBe(false);
  });
  // Regression: the map sat at zoom 15 around the origin and never framed the pattern.
  it("moves when a key point nears the edge or leaves the view", () => {
    expect(needsFraming(view, box(-800, -800, 800, 990))).toBe(true);
    expect(needsFraming(view, box(-800, -800, 1500, 800))).toBe(true);
  });
  it("zooms in when everything has shrunk to a corner, but not after a framing (no flapping)", () => {
    expect(needsFraming(view, box(100, 100, 300, 300))).toBe(true);
    // After framing, the wanted box fills ~85 % of the view.
    expect(needsFraming(view, box(-850, -850, 850, 850))).toBe(false);
  });
});

describe("shareOfView", () => {
  const view: Box = { south: at(-1000, 0).lat_deg, north: at(1000, 0).lat_deg, west: at(0, -1000).lon_deg, east: at(0, 1000).lon_deg };
  it("is the larger of the box's two shares of the view", () => {
    const tall: Box = { south: at(-500, 0).lat_deg, north: at(500, 0).lat_deg, west: at(0, -100).lon_deg, east: at(0, 100).lon_deg };
    expect(shareOfView(view, tall)).toBeCloseTo(0.5, 3);
    expect(shareOfView(view, view)).toBeCloseTo(1, 6);
  });
});
