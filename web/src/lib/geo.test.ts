import { describe, expect, it } from "vitest";
import { wrap180 } from "./format";
import { bearingDeg, destination, distanceM, ellipsePoints, EARTH_RADIUS_M, fromLocal, gridValues, niceStep, toLocal } from "./geo";

const O = { lat_deg: 38.5333, lon_deg: -7.8889 };

describe("great circle", () => {
  it("one degree of latitude is πR/180", () => {
    expect(distanceM({ lat_deg: 0, lon_deg: 0 }, { lat_deg: 1, lon_deg: 0 })).toBeCloseTo((Math.PI * EARTH_RADIUS_M) / 180, 3);
  });
  it("is symmetric and zero on itself", () => {
    const b = { lat_deg: 38.54, lon_deg: -7.88 };
    expect(distanceM(O, b)).toBeCloseTo(distanceM(b, O), 9);
    expect(distanceM(O, O)).toBe(0);
  });
  it("bearings of the cardinal directions", () => {
    expect(bearingDeg(O, { lat_deg: O.lat_deg + 0.01, lon_deg: O.lon_deg })).toBeCloseTo(0, 6);
    expect(bearingDeg(O, { lat_deg: O.lat_deg - 0.01, lon_deg: O.lon_deg })).toBeCloseTo(180, 6);
    expect(bearingDeg(O, { lat_deg: O.lat_deg, lon_deg: O.lon_deg + 0.01 })).toBeCloseTo(90, 1);
    expect(bearingDeg(O, { lat_deg: O.lat_deg, lon_deg: O.lon_deg - 0.01 })).toBeCloseTo(270, 1);
  });
  it("destination then distance/bearing back gives the same leg", () => {
    for (const brg of [0, 37, 90, 181, 300]) {
      const d = destination(O, brg, 1234.5);
      expect(distanceM(O, d)).toBeCloseTo(1234.5, 3);
      expect(Math.abs(wrap180(bearingDeg(O, d) - brg))).toBeLessThan(1e-4);
    }
  });
  it("known pair: Lisbon to Porto ≈ 274 km, bearing ≈ 7°", () => {
    const lisbon = { lat_deg: 38.7223, lon_deg: -9.1393 };
    const porto = { lat_deg: 41.1579, lon_deg: -8.6291 };
    expect(distanceM(lisbon, porto) / 1000).toBeCloseTo(274.5, 0);
    expect(bearingDeg(lisbon, porto)).toBeCloseTo(9.0, 0);
  });
});

describe("local frame", () => {
  it("round-trips and agrees with the great circle over a few km", () => {
    const p = { lat_deg: 38.55, lon_deg: -7.86 };
    const en = toLocal(O, p);
    const back = fromLocal(O, en);
    expect(back.lat_deg).toBeCloseTo(p.lat_deg, 10);
    expect(back.lon_deg).toBeCloseTo(p.lon_deg, 10);
    expect(Math.hypot(en.east_m, en.north_m)).toBeCloseTo(distanceM(O, p), -1); // within ~5 m of 3.2 km
  });
});

describe("1-σ ellipse", () => {
  const a = 120;
  const b = 60;
  it("starts on the major axis, semi-major away, in the axis direction", () => {
    const pts = ellipsePoints(O, a, b, 40, 8);
    expect(distanceM(O, pts[0]!)).toBeCloseTo(a, 1);
    expect(bearingDeg(O, pts[0]!)).toBeCloseTo(40, 1);
    // A quarter turn later: the minor axis, perpendicular (clockwise).
    expect(distanceM(O, pts[2]!)).toBeCloseTo(b, 1);
    expect(bearingDeg(O, pts[2]!)).toBeCloseTo(130, 1);
  });
  it("every point satisfies the ellipse equation in the rotated frame", () => {
    const th = (40 * Math.PI) / 180;
    for (const p of ellipsePoints(O, a, b, 40, 36)) {
      const { east_m: e, north_m: n } = toLocal(O, p);
      const u = e * Math.sin(th) + n * Math.cos(th); // along the major axis
      const v = e * Math.cos(th) - n * Math.sin(th); // along the minor axis
      expect((u / a) ** 2 + (v / b) ** 2).toBeCloseTo(1, 6);
    }
  });
  it("a circle when both axes are equal", () => {
    for (const p of ellipsePoints(O, 50, 50, 123, 12)) expect(distanceM(O, p)).toBeCloseTo(50, 1);
  });
});

describe("grid", () => {
  it("picks 1/2/5 steps", () => {
    expect(niceStep(1000, 8)).toBe(100);
    expect(niceStep(1800, 8)).toBe(200);
    expect(niceStep(4000, 8)).toBe(500);
    expect(niceStep(0)).toBe(1);
  });
  it("lists the multiples inside the range", () => {
    expect(gridValues(-250, 420, 200)).toEqual([-200, 0, 200, 400]);
    expect(gridValues(10, 5, 1)).toEqual([]);
  });
});
