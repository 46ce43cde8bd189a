import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import { blockedBy, ManualSender, type ManualGate } from "./manualSender";
import type { ManualMsg, ManualReleaseMsg } from "./types";

const OPEN: ManualGate = { operator: true, socketOpen: true, focused: true, visible: true, sticksConnected: true, deadman: true };
const MSG: ManualMsg = { type: "manual", x: 0, y: 0.3, z: 0.1, r: 0, buttons: 1 };

describe("blockedBy", () => {
  it("names the first failing condition", () => {
    expect(blockedBy(OPEN)).toBeNull();
    expect(blockedBy({ ...OPEN, operator: false })).toBe("operator role required");
    expect(blockedBy({ ...OPEN, deadman: false })).toBe("dead-man released");
    expect(blockedBy({ ...OPEN, focused: false })).toBe("page not focused");
    expect(blockedBy({ ...OPEN, visible: false })).toBe("page hidden");
    expect(blockedBy({ ...OPEN, sticksConnected: false })).toBe("no sticks");
    expect(blockedBy({ ...OPEN, socketOpen: false })).toBe("disconnected");
  });
});

describe("ManualSender", () => {
  let sent: (ManualMsg | ManualReleaseMsg)[];
  const sticks = (): ManualMsg[] => sent.filter((m): m is ManualMsg => m.type === "manual");
  const releases = (): ManualReleaseMsg[] => sent.filter((m): m is ManualReleaseMsg => m.type === "manual_release");
  let sender: ManualSender;
  let sample: ManualMsg | null;
  let socketOk: boolean;

  beforeEach(() => {
    vi.useFakeTimers();
    sent = [];
    sample = MSG;
    socketOk = true;
    sender = new ManualSender({ send: (m) => (socketOk ? (sent.push(m), true) : false), sample: () => sample, now: () => Date.now() });
  });
  afterEach(() => vi.useRealTimers());

  it("sends nothing until every condition holds", () => {
    sender.update({ ...OPEN, deadman: false });
    vi.advanceTimersByTime(1000);
    expect(sent).toHaveLength(0);
    expect(sender.sending).toBe(false);
  });

  it("sends at once, then at a steady 10 Hz while the dead-man is held", () => {
    sender.update(OPEN);
    expect(sticks()).toHaveLength(1);
    vi.advanceTimersByTime(1000);
    expect(sticks()).toHaveLength(11);
    // Re-evaluating the gate (the 50 Hz poll) must not add messages or restart the timer.
    for (let i = 0; i < 50; i++) {
      sender.update(OPEN);
      vi.advanceTimersByTime(20);
    }
    expect(sticks()).toHaveLength(21);
    expect(releases()).toHaveLength(0);
    expect(sender.rateHz()).toBe(10);
  });

  for (const [name, gate] of [
    ["dead-man released", { ...OPEN, deadman: false }],
    ["window blur", { ...OPEN, focused: false }],
    ["page hidden (visibilitychange)", { ...OPEN, visible: false }],
    ["gamepad disconnected", { ...OPEN, sticksConnected: false }],
    ["socket closed", { ...OPEN, socketOpen: false }],
  ] as const) {
    it(`stops immediately on ${name}`, () => {
      sender.update(OPEN);
      vi.advanceTimersByTime(350);
      const n = sticks().length;
      sender.update(gate);
      vi.advanceTimersByTime(2000);
      expect(sticks()).toHaveLength(n);
      expect(sender.sending).toBe(false);
      expect(sender.blocked).toBe(blockedBy(gate));
    });
  }

  it("stops when the pad vanishes between polls", () => {
    sender.update(OPEN);
    sample = null;
    vi.advanceTimersByTime(500);
    expect(sticks()).toHaveLength(1);
    expect(sender.blocked).toBe("no sticks");
  });

  it("stops when a send fails", () => {
    sender.update(OPEN);
    socketOk = false;
    vi.advanceTimersByTime(500);
    expect(sender.sending).toBe(false);
    expect(sender.blocked).toBe("disconnected");
  });

  it("resumes with a fresh first message after a release", () => {
    sender.update(OPEN);
    sender.update({ ...OPEN, deadman: false });
    vi.advanceTimersByTime(50);
    sender.update(OPEN);
    expect(sticks()).toHaveLength(2);
    expect(sender.lastMsg).toEqual(MSG);
  });

  // Regression: releasing the dead-man only stopped the 10 Hz stream, so the station flew the
  // last sticks until its 0.5 s silence timeout.
  for (const [name, gate] of [
    ["dead-man released", { ...OPEN, deadman: false }],
    ["window blur", { ...OPEN, focused: false }],
    ["page hidden", { ...OPEN, visible: false }],
    ["gamepad disconnected", { ...OPEN, sticksConnected: false }],
  ] as const) {
    it(`sends exactly one manual_release, right after the last sticks, on ${name}`, () => {
      sender.update(OPEN);
      vi.advanceTimersByTime(250);
      sender.update(gate);
      // The 50 Hz poll keeps re-evaluating the closed gate: still one release.
      for (let i = 0; i < 100; i++) {
        sender.update(gate);
        vi.advanceTimersByTime(20);
      }
      expect(releases()).toEqual([{ type: "manual_release" }]);
      expect(sent[sent.length - 1]).toEqual({ type: "manual_release" });
      expect(sender.releases).toBe(1);
    });
  }

  it("sends no release when nothing was streaming", () => {
    sender.update({ ...OPEN, deadman: false });
    sender.update({ ...OPEN, focused: false });
    vi.advanceTimersByTime(1000);
    expect(sent).toHaveLength(0);
  });

  it("sends no release on a closed socket (it could not arrive)", () => {
    sender.update(OPEN);
    sender.update({ ...OPEN, socketOpen: false });
    expect(releases()).toHaveLength(0);
    socketOk = false;
    sender.update(OPEN);
    vi.advanceTimersByTime(500);
    expect(releases()).toHaveLength(0);
  });

  it("releases once per stream: hold, release, hold again, blur", () => {
    sender.update(OPEN);
    sender.update({ ...OPEN, deadman: false });
    sender.update(OPEN);
    vi.advanceTimersByTime(300);
    sender.update({ ...OPEN, focused: false });
    sender.update({ ...OPEN, focused: false, deadman: false });
    expect(releases()).toHaveLength(2);
    // Each release follows the stream it ends.
    const kinds = sent.map((m) => m.type);
    expect(kinds.indexOf("manual_release")).toBe(1);
    expect(kinds[kinds.length - 1]).toBe("manual_release");
  });
});
