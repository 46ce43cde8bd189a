import { describe, expect, it } from "vitest";
import { applyDeadzone, DEADZONE, firstPad, manualMessage, readSticks, type PadLike } from "./joystick";

const pad = (axes: number[], pressed: Record<number, number> = {}): PadLike => ({
  connected: true,
  axes,
  buttons: Array.from({ length: 17 }, (_, i) => ({ pressed: (pressed[i] ?? 0) > 0.5, value: pressed[i] ?? 0 })),
});

describe("dead zone", () => {
  it("zero inside, full travel still reaches ±1, continuous at the edge", () => {
    expect(applyDeadzone(0.05)).toBe(0);
    expect(applyDeadzone(-DEADZONE)).toBe(0);
    expect(applyDeadzone(1)).toBe(1);
    expect(applyDeadzone(-1)).toBe(-1);
    expect(applyDeadzone(DEADZONE + 1e-9)).toBeCloseTo(0, 6);
    expect(applyDeadzone(Number.NaN)).toBe(0);
    expect(applyDeadzone(1.3)).toBe(1);
  });
});

describe("mapping", () => {
  it("right stick x → main line (message y); right trigger → brake (message z); button 0 → dead-man", () => {
    const s = readSticks(pad([0, 0, 0.5, 0], { 0: 1, 7: 0.6 }));
    expect(s.mainLine).toBeCloseTo((0.5 - DEADZONE) / (1 - DEADZONE));
    expect(s.brake).toBeCloseTo(0.6);
    expect(s.deadman).toBe(true);
    const m = manualMessage(s);
    expect(m).toMatchObject({ type: "manual", x: 0, r: 0, buttons: 1 | (1 << 7) });
    expect(m.y).toBeCloseTo(s.mainLine);
    expect(m.z).toBeCloseTo(0.6);
  });
  it("left stick pulled back brakes; pushed forward does not", () => {
    expect(readSticks(pad([0, 1, 0, 0])).brake).toBe(1);
    expect(readSticks(pad([0, -1, 0, 0])).brake).toBe(0);
  });
  it("full left is −1, centred is 0, and no dead-man without button 0", () => {
    const s = readSticks(pad([0, 0, -1, 0]));
    expect(s.mainLine).toBe(-1);
    expect(s.deadman).toBe(false);
    expect(readSticks(pad([0, 0, 0.03, 0])).mainLine).toBe(0);
  });
  it("a pad with missing axes or buttons maps to neutral", () => {
    const s = readSticks({ connected: true, axes: [], buttons: [] });
    expect(s).toEqual({ mainLine: 0, brake: 0, deadman: false, buttons: 0 });
  });
});

describe("firstPad", () => {
  it("skips nulls and disconnected pads", () => {
    const a = pad([0, 0, 0, 0]);
    const gone = { ...a, connected: false };
    expect(firstPad([null, gone, a])).toBe(a);
    expect(firstPad([null, null])).toBeNull();
    expect(firstPad(null)).toBeNull();
  });
});
