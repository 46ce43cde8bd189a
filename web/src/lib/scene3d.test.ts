import { describe, expect, it } from "vitest";
import { applyBasis, bodyBasis, chasePose, coneRadius, enuToScene, scaleBar, scaleLabel, stackMagnification, topPose, type V3 } from "./scene3d";
import { parseStack } from "./stack";

const close = (a: V3, b: V3, digits = 9) => a.forEach((v, i) => expect(v).toBeCloseTo(b[i] ?? NaN, digits));

describe("a body's attitude in the scene", () => {
  it("points a level body's nose along its heading and its belly down", () => {
    close(applyBasis(bodyBasis(0, 0, 0), [1, 0, 0]), [0, 0, -1]); // north is −z
    close(applyBasis(bodyBasis(0, 0, 90), [1, 0, 0]), [1, 0, 0]); // east
    close(applyBasis(bodyBasis(0, 0, 90), [0, 1, 0]), [0, 0, 1]); // right wing south
    close(applyBasis(bodyBasis(0, 0, 37), [0, 0, 1]), [0, -1, 0]); // down
  });
  it("pitches the nose up and rolls the right wing down", () => {
    close(applyBasis(bodyBasis(0, 30, 0), [1, 0, 0]), [0, Math.sin(Math.PI / 6), -Math.cos(Math.PI / 6)]);
    close(applyBasis(bodyBasis(20, 0, 0), [0, 1, 0]), [Math.cos((20 * Math.PI) / 180), -Math.sin((20 * Math.PI) / 180), 0]);
  });
  it("is a rotation (orthonormal, right-handed)", () => {
    const m = bodyBasis(12, -33, 217);
    const [f, r, d] = [applyBasis(m, [1, 0, 0]), applyBasis(m, [0, 1, 0]), applyBasis(m, [0, 0, 1])];
    const dot = (a: V3, b: V3) => a[0] * b[0] + a[1] * b[1] + a[2] * b[2];
    for (const [a, b, want] of [[f, f, 1], [r, r, 1], [d, d, 1], [f, r, 0], [r, d, 0], [f, d, 0]] as const) expect(dot(a, b)).toBeCloseTo(want, 12);
    // forward × right = down: a proper rotation, no mirror.
    close([f[1] * r[2] - f[2] * r[1], f[2] * r[0] - f[0] * r[2], f[0] * r[1] - f[1] * r[0]], d, 12);
  });
  it("puts east/north/up into the scene as x, y, −z", () => close(enuToScene([1, 2, 3]), [1, 3, -2]));
});

describe("the cameras", () => {
  it("chase rides behind the stack along its heading, above it, looking at it", () => {
    const p = chasePose([100, 500, -200], 90); // heading east: behind is west
    close(p.position, [72, 509, -200]);
    close(p.target, [100, 500, -200]);
    const south = chasePose([0, 0, 0], 180);
    expect(south.position[2]).toBeCloseTo(-28, 9); // heading south: behind is north (−z)
  });
  it("top looks straight down on the drone and the target, north up, high enough for both", () => {
    const p = topPose([1000, 400, 0], [0, 0, 0], 50);
    expect(p.position[0]).toBe(500);
    expect(p.target).toEqual([500, 0, 0]);
    expect(p.up).toEqual([0, 0, -1]);
    expect(p.position[1]).toBeGreaterThan(600 / Math.tan((25 * Math.PI) / 180) - 1);
    expect(topPose([0, 2000, 0], null, 50).position[1]).toBe(2050);
  });
});

describe("the glide cone, the scale and the stack's magnification", () => {
  it("widens by the glide ratio per metre of height", () => {
    expect(coneRadius(300, 2.1)).toBeCloseTo(630, 9);
    expect(coneRadius(-5, 2)).toBe(0);
  });
  it("shows a nice length that fits, longer from further away", () => {
    const near = scaleBar(100, 50, 600)!;
    const far = scaleBar(1000, 50, 600)!;
    expect(near.metres).toBe(10); // 0.155 m/px × 120 px = 18.6 m → 10 m
    expect(near.px).toBeCloseTo(10 / ((2 * 100 * Math.tan((25 * Math.PI) / 180)) / 600), 9);
    expect(far.metres).toBe(100);
    expect(far.px).toBeLessThanOrEqual(120);
    expect(scaleBar(100, 50, 0)).toBeNull();
    expect(scaleLabel(2000)).toBe("2 km");
    expect(scaleLabel(50)).toBe("50 m");
  });
  it("draws the stack life-size up close and larger only from afar", () => {
    expect(stackMagnification(30)).toBe(1);
    expect(stackMagnification(1200)).toBe(10);
  });
});

describe("the stack of the state", () => {
  const body = (name: string, up: number) => ({ body: name, roll_deg: 1, pitch_deg: 2, yaw_deg: 3, position_enu_m: [0, 0, up], size_m: [1, 1, 1], source: "measured", age_s: 0.2 });
  it("keeps what parses and drops the rest", () => {
    const s = parseStack({
      bodies: [body("canopy", 3.3), body("drone", 0), { ...body("capsule", -3), position_enu_m: [0, "x", 1] }, body("kite", 9)],
      lines: [{ line: "capsule", top_enu_m: [0, 0, -0.1], bottom_enu_m: [0, 0, -3] }, { line: "main_left" }],
    });
    expect(s?.bodies.map((b) => b.body)).toEqual(["canopy", "drone"]);
    expect(s?.lines.map((l) => l.line)).toEqual(["capsule"]);
  });
  it("is no stack without its drone", () => expect(parseStack({ bodies: [body("canopy", 3)], lines: [] })).toBeNull());
});
