// A replay's seeks on the page: one timeline at a time, whichever of state and history comes first.
import { describe, expect, it } from "vitest";
import { parseSpeed, SeekEpoch } from "./replaySeek";

describe("seek epochs", () => {
  it("a new seek's state starts over; its history then applies; older messages are dropped", () => {
    const e = new SeekEpoch();
    expect(e.state(0)).toBe("restart");
    expect(e.history(0)).toBe(true);
    expect(e.state(0)).toBe("keep");
    // Seek: the state comes first.
    expect(e.state(1)).toBe("restart");
    expect(e.history(1)).toBe(true);
    // Seek: the history comes first, then a late state from before it.
    expect(e.history(2)).toBe(true);
    expect(e.shows(1)).toBe(false);
    expect(e.state(1)).toBe("drop");
    expect(e.history(1)).toBe(false);
    expect(e.state(2)).toBe("keep");
    expect(e.current).toBe(2);
  });
  it("a live station's messages carry no epoch and are always kept", () => {
    const e = new SeekEpoch();
    expect(e.state(null)).toBe("keep");
    expect(e.history(null)).toBe(true);
    expect(e.shows(null)).toBe(true);
    expect(e.current).toBeNull();
  });
});

describe("replay speed", () => {
  it("takes any speed the station accepts, with or without ×", () => {
    expect(parseSpeed("3")).toEqual({ ok: true, value: 3 });
    expect(parseSpeed(" 0.5× ")).toEqual({ ok: true, value: 0.5 });
    expect(parseSpeed("64")).toEqual({ ok: true, value: 64 });
    expect(parseSpeed("0.25x")).toEqual({ ok: true, value: 0.25 });
  });
  it("refuses what it is not, saying why", () => {
    for (const bad of ["", "fast", "0.2", "65", "-1", "NaN"]) expect(parseSpeed(bad).ok).toBe(false);
    const r = parseSpeed("100");
    expect(r.ok ? "" : r.error).toContain("0.25–64");
  });
});
