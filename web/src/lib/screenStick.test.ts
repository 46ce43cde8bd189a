import { describe, expect, it } from "vitest";
import { KEY_STEP, ScreenStick } from "./screenStick";

describe("ScreenStick", () => {
  it("Space holds the dead-man; arrows move the main line and the brake in steps, within their ranges", () => {
    const s = new ScreenStick();
    expect(s.key(" ", true)).toBe(true);
    for (let i = 0; i < 3; i++) s.key("ArrowRight", true);
    s.key("ArrowDown", true);
    expect(s.sticks()).toEqual({ mainLine: 0.3, brake: KEY_STEP, deadman: true, buttons: 0 });
    for (let i = 0; i < 25; i++) s.key("ArrowLeft", true);
    for (let i = 0; i < 5; i++) s.key("ArrowUp", true);
    expect([s.mainLine, s.brake]).toEqual([-1, 0]);
    for (let i = 0; i < 15; i++) s.key("ArrowDown", true);
    expect(s.brake).toBe(1);
  });

  it("releasing the dead-man centres the stick: the next hold starts neutral", () => {
    const s = new ScreenStick();
    s.key(" ", true);
    s.key("ArrowRight", true);
    s.key(" ", false);
    expect(s.sticks()).toEqual({ mainLine: 0, brake: 0, deadman: false, buttons: 0 });
  });

  it("C centres without releasing; other keys are not the stick's", () => {
    const s = new ScreenStick();
    s.key(" ", true);
    s.key("ArrowLeft", true);
    expect(s.key("c", true)).toBe(true);
    expect([s.mainLine, s.held]).toEqual([0, true]);
    expect(s.key("Tab", true)).toBe(false);
    expect(s.key("a", true)).toBe(false);
  });

  it("the pointer holds and places the stick: centre neutral, the right edge full main line, the bottom full brake", () => {
    const s = new ScreenStick();
    s.point(50, 4);
    expect(s.sticks()).toEqual({ mainLine: 0, brake: 0, deadman: true, buttons: 0 });
    s.point(100, 100);
    expect([s.mainLine, s.brake]).toEqual([1, 1]);
    s.point(27, 50);
    expect(s.mainLine).toBeCloseTo(-0.5);
    expect(s.brake).toBeCloseTo(0.5);
    s.release();
    expect(s.sticks().deadman).toBe(false);
  });
});
