import { describe, expect, it } from "vitest";
import { flightPathSummary, parseFlightPath } from "./flightPath";

const P = (lat: number, lon: number, alt: number, t: number) => ({ lat_deg: lat, lon_deg: lon, alt_msl_m: alt, in_s: t });
const PATH = {
  computed_s: 100,
  stage: "ascent",
  burst: P(38.6, -7.5, 35000, 5400),
  deploy: P(38.62, -7.3, 2245, 7200),
  landing: P(38.63, -7.25, 245, 7600),
  round_chute_landing: P(38.63, -7.28, 245, 7500),
  reach_centre_lat_lon_deg: [38.62, -7.27],
  reach_radius_m: 3900,
  measured_bands: 12,
  measured_to_msl_m: 6245,
  burst_source: "station_config",
  ascent_rate_source: "station_config",
};

describe("the flight path of the state", () => {
  it("parses every point and says when the burst and the deployment come", () => {
    const p = parseFlightPath(PATH);
    expect(p?.burst?.alt_msl_m).toBe(35000);
    expect(p?.reach_centre).toEqual({ lat_deg: 38.62, lon_deg: -7.27 });
    const text = flightPathSummary(p!);
    expect(text).toContain("burst in 1 h 30 min at 35.0 km (station config)");
    expect(text).toContain("12 measured bands to 6.2 km");
  });
  it("has no burst under the round chute, and says when only the forecast was flown", () => {
    const p = parseFlightPath({ ...PATH, stage: "round_chute", burst: null, measured_bands: 0, measured_to_msl_m: null });
    expect(p?.burst).toBeNull();
    expect(flightPathSummary(p!)).toContain("forecast only");
    expect(flightPathSummary(p!)).not.toContain("burst");
  });
  it("says the burst altitude is the drone's when the drone gave it", () => {
    const p = parseFlightPath({ ...PATH, burst: P(38.6, -7.5, 3000, 600), burst_source: "drone" });
    expect(flightPathSummary(p!)).toContain("burst in 10 min 00 s at 3.0 km (drone)");
    expect(flightPathSummary(parseFlightPath({ ...PATH, burst_source: undefined })!)).toContain("(source not given)");
  });
  it("leaves out a path with a point it cannot read", () => {
    expect(parseFlightPath({ ...PATH, deploy: { lat_deg: 95, lon_deg: 0, alt_msl_m: 0, in_s: 0 } })).toBeNull();
    expect(parseFlightPath({ ...PATH, burst: "soon" })).toBeNull();
    expect(parseFlightPath({ ...PATH, reach_radius_m: "far" })).toBeNull();
  });
});
