// A GPS without a fix is never a position on the page: not the map's vehicle, not its framing,
// not the recovery point, not the readouts, not a track point.
import { describe, expect, it } from "vitest";
import { gpsPosition, isPosition, trackPositions, vehiclePosition } from "./fix";
import { keyPoints } from "./framing";
import { recoveryPoint } from "./recovery";
import { decodeMessage } from "./parse";
import type { State } from "./types";

const state = (over: Record<string, unknown>): State => {
  const d = decodeMessage(JSON.stringify({ type: "state", time_s: 1, link: { connected: true, stale: false, age_s: 0.1, ages_s: {} }, mission: { stage: "prelaunch" }, ...over }));
  if (!d.ok || d.msg.type !== "state") throw new Error("bad fixture");
  return d.msg;
};
const gps = (fix: string, lat_deg: number, lon_deg: number) => ({ vehicle: { gps: { fix, satellites: 0, lat_deg, lon_deg, alt_msl_m: 0 } } });

describe("positions without a fix", () => {
  it("coordinates are a position unless out of range, not finite or exactly 0°, 0°", () => {
    expect(isPosition(38.5, -7.9)).toBe(true);
    expect(isPosition(0, -7.9)).toBe(true);
    expect(isPosition(38.5, 0)).toBe(true);
    expect(isPosition(0, 0)).toBe(false);
    expect(isPosition(null, -7.9)).toBe(false);
    expect(isPosition(Number.NaN, -7.9)).toBe(false);
    expect(isPosition(91, 0)).toBe(false);
  });

  it("the drone's GPS places the vehicle only with a 2-D fix or better, away from 0°, 0°", () => {
    for (const fix of ["no_gps", "no_fix"]) {
      expect(gpsPosition(state(gps(fix, 0, 0)).vehicle?.gps)).toBeNull();
      expect(gpsPosition(state(gps(fix, 38.5, -7.9)).vehicle?.gps)).toBeNull();
    }
    expect(gpsPosition(state(gps("fix3d", 0, 0)).vehicle?.gps)).toBeNull();
    expect(gpsPosition(state(gps("fix2d", 38.5, -7.9)).vehicle?.gps)).toMatchObject({ lat_deg: 38.5, lon_deg: -7.9 });
    expect(gpsPosition(state(gps("garbage", 38.5, -7.9)).vehicle?.gps)).toBeNull();
  });

  it("the vehicle is where the estimate is, else where a GPS with a fix is, else nowhere", () => {
    const noFix = state(gps("no_fix", 0, 0));
    expect(vehiclePosition(noFix)).toBeNull();
    expect(keyPoints(noFix)).toEqual([]);
    const withEstimate = state({ ...gps("no_fix", 0, 0), estimate: { lat_deg: 38.6, lon_deg: -7.9, alt_msl_m: 900 } });
    expect(vehiclePosition(withEstimate)).toEqual({ lat_deg: 38.6, lon_deg: -7.9, alt_msl_m: 900 });
    expect(vehiclePosition(state(gps("fix3d", 38.5, -7.8)))).toMatchObject({ lat_deg: 38.5, lon_deg: -7.8 });
  });

  it("a landed vehicle without a fix gives no recovery point at 0°, 0°", () => {
    const landed = state({ ...gps("no_fix", 0, 0), mission: { stage: "landed" } });
    expect(recoveryPoint(landed)).toBeNull();
  });

  it("track points at 0°, 0° are not drawn", () => {
    const pts = [{ time_s: 1, mission_time_s: 1, lat_deg: 0, lon_deg: 0, alt_msl_m: 0 }, { time_s: 2, mission_time_s: 2, lat_deg: 38.5, lon_deg: -7.9, alt_msl_m: 900 }];
    expect(trackPositions(pts).map((p) => p.time_s)).toEqual([2]);
  });
});
