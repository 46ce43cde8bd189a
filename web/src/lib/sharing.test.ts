import { describe, expect, it } from "vitest";
import { chaseLine, forwardCounts, forwardRights, parseSharing, type ForwardView } from "./sharing";

function only(fs: ForwardView[]): ForwardView {
  const [f] = fs;
  if (fs.length !== 1 || f === undefined) throw new Error(`one forward expected, got ${fs.length}`);
  return f;
}

describe("sharing", () => {
  it("reads forwards and the chase broadcast, dropping what has no name", () => {
    const s = parseSharing({
      forwards: [
        { name: "qgc", address: "udpout:10.0.0.2:14550", may_send_to_drone: [], out_passed: 120, out_filtered: 3, out_dropped: 0, in_passed: 0, in_refused: 7 },
        { address: "udpout:x:1" },
        "junk",
      ],
      chase: { callsign: "STRAPLEX1", landing_callsign: "STRAPLEX1_LANDING", to: "255.255.255.255:55672", period_s: 2, sent: 10, last_sent_wall_ms: 1000, error: null },
    });
    expect(s.forwards.map((f) => f.name)).toEqual(["qgc"]);
    expect(forwardRights(only(s.forwards))).toBe("read-only");
    expect(forwardCounts(only(s.forwards))).toBe("120 frames sent, 3 filtered; from it: 0 passed, 7 kept from the drone");
    expect(chaseLine(s.chase, 5400)).toBe("STRAPLEX1 and STRAPLEX1_LANDING to 255.255.255.255:55672 every 2 s: 10 datagrams sent, the last 4 s ago");
  });

  it("says what a watcher may send, a failing broadcast and one that is off", () => {
    const s = parseSharing({ forwards: [{ name: "mp", address: "tcpin:0.0.0.0:5760", may_send_to_drone: [0, 76], out_dropped: 2 }], chase: { callsign: "A", to: "10.0.0.255:55672", period_s: 1, sent: 0, last_sent_wall_ms: null, error: "Network is unreachable" } });
    expect(forwardRights(only(s.forwards))).toBe("may send the drone message ids 0, 76");
    expect(forwardCounts(only(s.forwards))).toContain("2 lost (it fell behind)");
    expect(chaseLine(s.chase, 0)).toBe("A and A_LANDING to 10.0.0.255:55672 every 1 s: FAILING (Network is unreachable)");
    expect(chaseLine(parseSharing(null).chase, 0)).toMatch(/^chase broadcast off/);
    expect(chaseLine(parseSharing({ chase: { callsign: "B", to: "x", period_s: 2, sent: 0, last_sent_wall_ms: null, error: null } }).chase, 0)).toMatch(/nothing sent yet/);
  });
});
