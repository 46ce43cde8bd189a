import { describe, expect, it } from "vitest";
import { complexPlane, metres, outcomeLine, progressOf, vehicleEdits } from "./lab";

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
