import { describe, expect, it } from "vitest";
import type * as Wire from "../generated/api";
import { buildRequest, ellipsePolygon, forecastText, formOf, measuredLines, parseForecast } from "./preflight";

const request: Wire.PlanRequest = {
  launch_lat_deg: 38.5333,
  launch_lon_deg: -7.8889,
  launch_alt_msl_m: 245,
  forecast: [
    { alt_msl_m: 300, speed_mps: 2, from_deg: 270 },
    { alt_msl_m: 3000, speed_mps: 6, from_deg: 250 },
  ],
  ascent_rate_mps: 5,
  ascent_rate_sigma_mps: 0.5,
  burst_altitude_msl_m: 35000,
  burst_altitude_sigma_m: 1500,
  deploy_height_m: 2500,
  default_wind_sigma_mps: 1.5,
  target_lat_lon_deg: null,
  runs: 500,
  seed: 1,
};

describe("the plan form", () => {
  it("gives back the request it was filled from", () => {
    const built = buildRequest(formOf(request));
    expect(built).toEqual({ ok: true, body: { request, from_recording: null } });
  });

  it("sends a target and a recording when given, and leaves empty optional boxes to the station", () => {
    const form = { ...formOf(request, "flight-1.mcap"), target_lat_deg: "38.6", target_lon_deg: " -7.7 ", deploy_height_m: "" };
    const built = buildRequest(form);
    if (!built.ok) throw new Error(built.error);
    expect(built.body.request.target_lat_lon_deg).toEqual([38.6, -7.7]);
    expect(built.body.from_recording).toBe("flight-1.mcap");
    expect("deploy_height_m" in built.body.request).toBe(false);
  });

  it("names the box that is wrong", () => {
    const cases: [Partial<ReturnType<typeof formOf>>, string, string][] = [
      [{ launch_lat_deg: "" }, "launch_lat_deg", "required"],
      [{ ascent_rate_mps: "fast" }, "ascent_rate_mps", 'not a number: "fast"'],
      [{ runs: "2.5" }, "runs", "whole number"],
      [{ seed: "-1" }, "seed", "whole number"],
      [{ target_lat_deg: "38.6" }, "target_lon_deg", "both latitude and longitude"],
      [{ forecast: "300,2\n" }, "forecast", "forecast line 1: expected"],
      [{ forecast: "# calm\n300,2,west\n" }, "forecast", 'line 2: from_deg is not a number: "west"'],
      [{ forecast: "alt_msl_m,speed_mps,from_deg\n" }, "forecast", "at least one row"],
    ];
    for (const [change, field, error] of cases) {
      const built = buildRequest({ ...formOf(request), ...change });
      expect(built.ok, field).toBe(false);
      if (built.ok) continue;
      expect(built.field).toBe(field);
      expect(built.error).toContain(error);
    }
  });
});

describe("the forecast text", () => {
  it("reads what it writes, sigmas included", () => {
    const rows: Wire.ForecastRow[] = [
      { alt_msl_m: 0, speed_mps: 10, from_deg: 270, sigma_mps: 0 },
      { alt_msl_m: 5000, speed_mps: 12.5, from_deg: 260 },
    ];
    const text = forecastText(rows);
    expect(text).toBe("alt_msl_m,speed_mps,from_deg,sigma_mps\n0,10,270,0\n5000,12.5,260");
    expect(parseForecast(text)).toEqual({ ok: true, rows });
    expect(parseForecast("0,10,270,\n")).toEqual({ ok: false, error: 'forecast line 1: sigma_mps is not a number: ""' });
  });
});

describe("an ellipse as a polygon", () => {
  it("puts the major axis along its bearing and the minor across it", () => {
    const centre: [number, number] = [38.5, -7.9];
    // 1000 × 200 m, major axis towards the east.
    const pts = ellipsePolygon(centre, { semi_major_m: 1000, semi_minor_m: 200, major_axis_rad: Math.PI / 2 }, 4);
    const mPerDegLat = (6378137 * Math.PI) / 180;
    const mPerDegLon = mPerDegLat * Math.cos((38.5 * Math.PI) / 180);
    const ne = pts.map(([lat, lon]) => [(lat - centre[0]) * mPerDegLat, (lon - centre[1]) * mPerDegLon]);
    expect(ne[0]![0]).toBeCloseTo(0, 6);
    expect(ne[0]![1]).toBeCloseTo(1000, 6); // t = 0: the major axis's end, east
    expect(ne[1]![0]).toBeCloseTo(-200, 6); // t = 90°: the minor axis's end, to the south
    expect(ne[1]![1]).toBeCloseTo(0, 6);
    expect(ne[2]![1]).toBeCloseTo(-1000, 6);
  });

  it("is a point for a zero ellipse", () => {
    for (const p of ellipsePolygon([1, 2], { semi_major_m: 0, semi_minor_m: 0, major_axis_rad: 0 })) expect(p).toEqual([1, 2]);
  });
});

describe("the measured bands", () => {
  const band = (alt: number, east: number, refused: string | null): Wire.AscentBandView => ({
    alt_msl_m: alt + 250, alt_min_msl_m: alt, alt_max_msl_m: alt + 499, speed_mps: Math.abs(east), from_deg: 270,
    wind_north_mps: 0, wind_east_mps: east, sigma_north_mps: 0.12, sigma_east_mps: 0.2, samples: 400,
    method: "gps_velocity", time_start_s: 0, time_end_s: 100, refused,
  });
  it("says which bands were merged and why the others were refused", () => {
    const lines = measuredLines({ recording: "a.mcap", bands: [band(245, 2.4, null), band(745, 88, "88.0 m/s is faster than any wind a balloon meets at this height (at most 55 m/s)")] });
    expect(lines).toEqual([
      { text: "245–744 m MSL: 2.4 m/s from 270°, 1σ 0.20 m/s · merged", refused: false },
      { text: "745–1244 m MSL: 88.0 m/s from 270°, 1σ 0.20 m/s · refused: 88.0 m/s is faster than any wind a balloon meets at this height (at most 55 m/s)", refused: true },
    ]);
  });
});
