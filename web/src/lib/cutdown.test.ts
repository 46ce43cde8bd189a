import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import { CutdownHold, HOLD_MS, type CutdownPhase } from "./cutdown";

describe("cutdown hold-to-arm", () => {
  let calls: string[];
  let phases: CutdownPhase["kind"][];
  let hold: CutdownHold;
  let armFails: boolean;

  beforeEach(() => {
    vi.useFakeTimers();
    calls = [];
    phases = [];
    armFails = false;
    hold = new CutdownHold({
      arm: async () => {
        calls.push("arm");
        if (armFails) throw new Error("409 not_armed");
        return { arm_id: "a1" };
      },
      confirm: async (id) => {
        calls.push(`confirm:${id}`);
        return { request_id: "r1" };
      },
      now: () => Date.now(),
      onChange: (p) => phases.push(p.kind),
    });
  });
  afterEach(() => vi.useRealTimers());

  it("a single click (press, release) never sends anything", async () => {
    hold.press();
    vi.advanceTimersByTime(120);
    hold.release();
    await vi.advanceTimersByTimeAsync(10_000);
    expect(calls).toEqual([]);
    expect(hold.phase.kind).toBe("cancelled");
  });

  it("releasing just before 2 s cancels", async () => {
    hold.press();
    vi.advanceTimersByTime(HOLD_MS - 1);
    expect(hold.progress()).toBeCloseTo(1, 2);
    hold.release();
    await vi.advanceTimersByTimeAsync(5000);
    expect(calls).toEqual([]);
  });

  it("holding 2 s arms, then confirms at once with the arm_id", async () => {
    hold.press();
    await vi.advanceTimersByTimeAsync(HOLD_MS);
    expect(calls).toEqual(["arm", "confirm:a1"]);
    expect(hold.phase).toEqual({ kind: "sent", requestId: "r1" });
    expect(phases).toEqual(["holding", "arming", "confirming", "sent"]);
  });

  it("a release after the hold completed changes nothing", async () => {
    hold.press();
    await vi.advanceTimersByTimeAsync(HOLD_MS);
    hold.release();
    expect(hold.phase.kind).toBe("sent");
  });

  it("a refused arm is reported and nothing is confirmed", async () => {
    armFails = true;
    hold.press();
    await vi.advanceTimersByTimeAsync(HOLD_MS);
    expect(calls).toEqual(["arm"]);
    expect(hold.phase).toEqual({ kind: "failed", reason: "arm: 409 not_armed" });
  });

  it("repeated presses while holding do not restart or double the timer", async () => {
    hold.press();
    vi.advanceTimersByTime(1000);
    hold.press(); // key auto-repeat, second pointer
    await vi.advanceTimersByTimeAsync(1000);
    expect(calls).toEqual(["arm", "confirm:a1"]);
  });

  it("progress runs 0 → 1 over the hold", () => {
    expect(hold.progress()).toBe(0);
    hold.press();
    vi.advanceTimersByTime(500);
    expect(hold.progress()).toBeCloseTo(0.25);
  });
});
