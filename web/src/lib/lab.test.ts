import { describe, expect, it } from "vitest";
import { comparedPart, compareRows, complexPlane, correlationCells, fittedEdits, identifyParams, identifyRows, metres, outcomeLine, progressOf, recordingOption, recordingWindow, vehicleEdits } from "./lab";

const fields = [
  { name: "canopy.mass_kg", unit: "kg", seed: 0.7 },
  { name: "canopy.span_m", unit: "m", seed: 3.3 },
  { name: "gravity_mps2", unit: "m/s²", seed: 9.80665 },
];

describe("vehicleEdits", () => {
  it("sends only the fields changed from the seed", () => {
    const r = vehicleEdits(fields, new Map([["canopy.mass_kg", "0.9"], ["canopy.span_m", "3.3"], ["gravity_mps2", ""]]));
    expect(r.edits).toEqual({ "canopy.mass_kg": 0.9 });
    expect(r.errors).toEqual({});
  });
  it("names a field that is not a number", () => {
    const r = vehicleEdits(fields, new Map([["canopy.span_m", "3,5"], ["canopy.mass_kg", "Infinity"]]));
    expect(r.errors).toEqual({ "canopy.span_m": "not a number", "canopy.mass_kg": "not a number" });
    expect(r.edits).toEqual({});
  });
});

describe("progressOf", () => {
  const job = { id: 1, kind: "monte_carlo", started_by: "op", elapsed_s: 12.4, done: 3, total: 12, cancelling: false };
  it("gives the runs done as a fraction and a label", () => {
    expect(progressOf(job)).toEqual({ fraction: 0.25, label: "3/12 runs, 12 s" });
  });
  it("counts a comparison's recorded samples", () => {
    expect(progressOf({ ...job, kind: "compare", done: 40, total: 160 })).toEqual({ fraction: 0.25, label: "40/160 samples, 12 s" });
  });
  it("counts an identification's iterations", () => {
    expect(progressOf({ ...job, kind: "identify", done: 2, total: 30 }).label).toBe("2/30 iterations, 12 s");
  });
  it("has no fraction when the job cannot tell, and shows a cancel", () => {
    expect(progressOf({ ...job, kind: "scenario", total: 0, done: 0, cancelling: true })).toEqual({ fraction: null, label: "scenario running, 12 s, cancelling…" });
  });
});

describe("outcomeLine", () => {
  it("reads an outcome with its reason", () => {
    expect(outcomeLine({ id: 4, kind: "monte_carlo", started_by: "op", outcome: "timed_out", reason: "stopped at the cap", elapsed_s: 600.04, result: null })).toBe(
      "job 4 (monte_carlo, op): timed out after 600.0 s — stopped at the cap",
    );
  });
});

describe("complexPlane", () => {
  it("puts zero on the box's middle line and keeps both axes at one scale", () => {
    const p = complexPlane([[-4, 2], [0, 0], [0.5, -1]], { width: 220, height: 120, margin: 10 });
    expect(p.y(0)).toBe(60);
    // Imaginary extent 2 fits the 100 px height: 25 px per unit, same on the real axis.
    expect(p.y(2) - p.y(0)).toBeCloseTo(-50);
    expect(p.x(1) - p.x(0)).toBeCloseTo(25);
    expect(p.x(-4)).toBeGreaterThanOrEqual(10);
    expect(p.x(0.5)).toBeLessThanOrEqual(210);
  });
  it("ignores points that are not finite", () => {
    const p = complexPlane([[Number.NaN, 1e9], [-2, 1]], { width: 100, height: 100, margin: 0 });
    expect(p.imMax).toBe(1);
    expect(p.reMin).toBe(-2);
  });
});

describe("metres", () => {
  it("shows a missing or infinite figure as a dash", () => {
    expect(metres(null)).toBe("–");
    expect(metres(12.345)).toBe("12.3 m");
  });
});

describe("recordingOption", () => {
  const r = { name: "stx-20261128T120733Z-001.mcap", size_bytes: 217715, start_ms: Date.UTC(2026, 10, 28, 12, 7, 33), duration_ms: 24_900, messages: 1847, mission: "rehearsal", vehicle: "straplex-2", complete: true, recording_now: false, last_stage: "descent", landing: null };
  it("names the file, when it starts, how long it lasts and its mission", () => {
    expect(recordingOption(r)).toEqual({ value: r.name, label: "stx-20261128T120733Z-001.mcap — 2026-11-28 12:07 UTC, 25 s, rehearsal" });
  });
  it("says which one is being written, and leaves out what it does not know", () => {
    expect(recordingOption({ ...r, start_ms: null, mission: null, duration_ms: 3_725_000, recording_now: true }).label).toBe("stx-20261128T120733Z-001.mcap — 1 h 02 min (recording now)");
  });
});

describe("compareRows", () => {
  const channel = (name: string, unit: string, rms: number, max_abs: number, bias: number, count: number) => ({ name, unit, rms, max_abs, bias, count, recorded: [], model: [] });
  it("reads each channel's errors with its unit and a sensible precision", () => {
    expect(compareRows({ channels: [channel("north_m", "m", 4.2549, 5.616, 3.976, 98), channel("airspeed_mps", "m/s", 0.2163, 1.021, -0.0874, 97), channel("turn_rate_deg_s", "deg/s", 8.737, 38.735, -0.763, 98)] })).toEqual([
      ["north", "m", "4.3 m", "5.6 m", "4.0 m", "98"],
      ["airspeed", "m/s", "0.22 m/s", "1.02 m/s", "-0.09 m/s", "97"],
      ["turn rate", "deg/s", "8.7 deg/s", "38.7 deg/s", "-0.8 deg/s", "98"],
    ]);
  });
  it("keeps a channel it does not know by its name, and shows a figure that is no number as a dash", () => {
    expect(compareRows({ channels: [channel("glide", "", Number.NaN, Infinity, 0.5, 0)] })).toEqual([["glide", "", "–", "–", "0.50", "0"]]);
  });
});

describe("identifyParams", () => {
  it("splits the names at commas and spaces", () => {
    expect(identifyParams(" cl_alpha, cd0  cn_da,")).toEqual({ params: ["cl_alpha", "cd0", "cn_da"] });
  });
  it("refuses an empty list and a name given twice (in any case)", () => {
    expect(identifyParams(" , ")).toEqual({ error: "name at least one parameter to fit, e.g. cl_alpha, cd0" });
    expect(identifyParams("cd0, CL_alpha, cl_alpha")).toEqual({ error: "cl_alpha is listed twice" });
  });
});

describe("identification", () => {
  const param = (name: string, nominal: number, fitted: number, se: number | null) => ({
    name,
    nominal,
    fitted,
    std_error: se,
    interval95_low: se === null ? null : fitted - 1.96 * se,
    interval95_high: se === null ? null : fitted + 1.96 * se,
  });
  const r = { params: [param("cl_alpha", 2.7, 2.16043, 0.0123), param("cd0", 0.12, 0.1293, null), param("rigging_deg", 0, 1.25, 0.5), param("cn_da", 0.0115, 0.01, 0.001)], correlation: [[1, -0.4567, 0.1, 0], [-0.4567, 1, 0, 0], [0.1, 0, 1, 0], [0, 0, 0, 1]] };
  it("reads before, fitted, standard error, interval and change with four significant figures", () => {
    expect(identifyRows(r)).toEqual([
      ["cl_alpha", "2.7", "2.16", "± 0.012", "2.136 … 2.185", "-20.0 %"],
      ["cd0", "0.12", "0.1293", "–", "not determined", "7.8 %"],
      ["rigging_deg", "0", "1.25", "± 0.5", "0.27 … 2.23", "–"],
      ["cn_da", "0.0115", "0.01", "± 0.001", "0.00804 … 0.01196", "-13.0 %"],
    ]);
  });
  it("shows the correlation matrix with two decimals, or nothing when the flight cannot tell", () => {
    expect(correlationCells(r)?.[0]).toEqual(["1.00", "-0.46", "0.10", "0.00"]);
    expect(correlationCells({ correlation: null })).toBeNull();
  });
  it("puts the fitted coefficients into the vehicle form's fields, the rigging apart", () => {
    const form = [{ name: "canopy.aero.cl_alpha", unit: "1", seed: 2.7 }, { name: "canopy.aero.cd0", unit: "1", seed: 0.12 }, { name: "canopy.brakes.cn_da", unit: "1", seed: 0.0115 }, { name: "canopy.mass_kg", unit: "kg", seed: 0.7 }];
    expect(fittedEdits(r, form)).toEqual({ edits: { "canopy.aero.cl_alpha": 2.16043, "canopy.aero.cd0": 0.1293, "canopy.brakes.cn_da": 0.01 }, apart: ["rigging_deg"] });
  });
});

describe("comparedPart", () => {
  it("says when a mission recording was compared over its parafoil stage only", () => {
    expect(comparedPart({ parafoil_stage_s: [796.84, 1179.52], recorded_s: 1270.3 })).toBe("its parafoil stage, 796.8 … 1179.5 s of 1270.3 s recorded");
    expect(comparedPart({ parafoil_stage_s: null, recorded_s: 12 })).toBe("the whole recording");
  });
});

describe("recordingWindow", () => {
  it("leaves a blank end open and reads seconds", () => {
    expect(recordingWindow("", "")).toEqual({});
    expect(recordingWindow(" 30 ", "")).toEqual({ from_s: 30 });
    expect(recordingWindow("30", "58.5")).toEqual({ from_s: 30, to_s: 58.5 });
  });
  it("refuses what is no time and an end before the start", () => {
    expect(recordingWindow("-1", "")).toEqual({ error: 'from: "-1" is not a number of seconds ≥ 0' });
    expect(recordingWindow("", "soon")).toEqual({ error: 'to: "soon" is not a number of seconds ≥ 0' });
    expect(recordingWindow("40", "40")).toEqual({ error: "to (40 s) must be after from (40 s)" });
  });
});
