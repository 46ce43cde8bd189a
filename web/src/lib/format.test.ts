import { describe, expect, it } from "vitest";
import { cardinal, fmt, fmtDir, fmtDistance, fmtDuration, fmtLatLon, fmtMissionTime, fmtParam, fmtWallUtc, wrap180, wrap360 } from "./format";

describe("fmt", () => {
  it("always carries the unit, also when the value is missing", () => {
    expect(fmt(6.66, "m/s")).toBe("6.7 m/s");
    expect(fmt(null, "m/s")).toBe("— m/s");
    expect(fmt(undefined, "m")).toBe("— m");
    expect(fmt(Number.NaN, "Hz")).toBe("— Hz");
    expect(fmt(12, "°")).toBe("12.0°");
  });
  it("never shows a negative zero", () => {
    expect(fmt(-0.04, "m/s")).toBe("0.0 m/s");
    expect(fmt(-0.06, "m/s")).toBe("-0.1 m/s");
  });
});

describe("angles", () => {
  it("wraps", () => {
    expect(wrap360(-12)).toBe(348);
    expect(wrap360(720)).toBe(0);
    expect(wrap180(190)).toBe(-170);
    expect(wrap180(180)).toBe(180);
  });
  it("formats directions as three digits in 0…359", () => {
    expect(fmtDir(-12)).toBe("348°");
    expect(fmtDir(5)).toBe("005°");
    expect(fmtDir(359.6)).toBe("000°");
    expect(fmtDir(null)).toBe("—°");
  });
  it("names compass points", () => {
    expect(cardinal(0)).toBe("N");
    expect(cardinal(226)).toBe("SW");
    expect(cardinal(350)).toBe("N");
    expect(cardinal(-90)).toBe("W");
  });
});

describe("distances, durations, times", () => {
  it("switches from metres to kilometres at 1 km", () => {
    expect(fmtDistance(999.4)).toBe("999 m");
    expect(fmtDistance(1070)).toBe("1.07 km");
    expect(fmtDistance(25_300)).toBe("25.3 km");
    expect(fmtDistance(null)).toBe("— m");
  });
  it("writes durations for people", () => {
    expect(fmtDuration(4.25)).toBe("4.3 s");
    expect(fmtDuration(45)).toBe("45 s");
    expect(fmtDuration(187)).toBe("3 min 07 s");
    expect(fmtDuration(3725)).toBe("1 h 02 min");
    expect(fmtDuration(-5)).toBe("−5.0 s");
  });
  it("mission clock and UTC wall clock", () => {
    expect(fmtMissionTime(123.25)).toBe("T+00:02:03.3");
    expect(fmtMissionTime(null)).toBe("T+—");
    expect(fmtWallUtc(Date.UTC(2026, 4, 1, 14, 3, 7))).toBe("14:03:07Z");
  });
  it("positions with hemispheres", () => {
    expect(fmtLatLon(38.5333, -7.8889)).toBe("38.53330° N, 7.88890° W");
    expect(fmtLatLon(null, 1)).toBe("—");
  });
  it("parameter read-backs at float32 precision", () => {
    expect(fmtParam(Math.fround(0.0155))).toBe("0.0155");
    expect(fmtParam(160)).toBe("160");
    expect(fmtParam(null)).toBe("—");
  });
});
