import { afterEach, beforeEach, describe, expect, it, vi } from "vitest";
import { blockedBy, ManualSender, type ManualGate } from "./manualSender";
import type { ManualMsg } from "./types";

const OPEN: ManualGate = { operator: true, socketOpen: true, focused: true, visible: true, padConnected: true, deadman: true };
const MSG: ManualMsg = { type: "manual", x: 0, y: 0.3, z: 0.1, r: 0, buttons: 1 };

describe("blockedBy", () => {
  it("names the first failing condition", () => {
    expect(blockedBy(OPEN)).toBeNull();
    expect(blockedBy({ ...OPEN, operator: false })).toBe("operator role required");
    expect(blockedBy({ ...OPEN, deadman: false })).toBe("dead-man released");
    expect(blockedBy({ ...OPEN, focused: false })).toBe("page not focused");
    expect(blockedBy({ ...OPEN, visible: false })).toBe("page hidden");
    expect(blockedBy({ ...OPEN, padConnected: false })).toBe("no gamepad");
    expect(blockedBy({ ...OPEN, socketOpen: false })).toBe("disconnected");
  });
});

describe("ManualSender", () => {
  let sent: ManualMsg[];
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
    expect(sent).toHaveLength(1);
    vi.advanceTimersByTime(1000);
    expect(sent).toHaveLength(11);
    // Re-evaluating the gate (the 50 Hz poll) must not add messages or restart the timer.
    for (let i = 0; i < 50; i++) {
      sender.update(OPEN);
      vi.advanceTimersByTime(20);
    }
    expect(sent).toHaveLength(21);
    expect(sender.rateHz()).toBe(10);
  });

  for (const [name, gate] of [
    ["dead-man released", { ...OPEN, deadman: false }],
    ["window blur", { ...OPEN, focused: false }],
    ["page hidden (visibilitychange)", { ...OPEN, visible: false }],
    ["gamepad disconnected", { ...OPEN, padConnected: false }],
    ["socket closed", { ...OPEN, socketOpen: false }],
  ] as const) {
    it(`stops immediately on ${name}`, () => {
      sender.update(OPEN);
      vi.advanceTimersByTime(350);
      const n = sent.length;
      sender.update(gate);
      vi.advanceTimersByTime(2000);
      expect(sent).toHaveLength(n);
      expect(sender.sending).toBe(false);
      expect(sender.blocked).toBe(blockedBy(gate));
    });
  }

  it("stops when the pad vanishes between polls", () => {
    sender.update(OPEN);
    sample = null;
    vi.advanceTimersByTime(500);
    expect(sent).toHaveLength(1);
    expect(sender.blocked).toBe("no gamepad");
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
    expect(sent).toHaveLength(2);
    expect(sender.lastMsg).toEqual(MSG);
  });
});
