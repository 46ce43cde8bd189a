import { describe, expect, it } from "vitest";
import { chaseLine, forwardCounts, forwardRights, parseSharing, relaysLine, sondehubCounts, sondehubLine, sondehubListeners, type ForwardView, type SondehubView } from "./sharing";

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

  it("reads the SondeHub upload: working, failing with its queue on disk, and off", () => {
    const wire = {
      url: "https://api.v2.sondehub.org", uploader_callsign: "CT1ABC", payload_callsign: "STRAPLEX1", period_s: 10,
      made: 12, sent: 10, historical: 0, refused: 1, queued: 1, queue_max: 20000, dropped: 0, restored: 0, on_disk: true,
      last_upload_wall_ms: 100_000, last_result: "202: 2 of 3 points taken, 1 refused, 0 warnings", failing: false, retry_wall_ms: null,
      errors: [{ wall_ms: 90_000, text: "Missing lat field" }, { text: 3 }], warnings: [], station_uploaded_wall_ms: 50_000,
      chase_car: { callsign: "CT1ABC_CHASE", position: [38.5, -7.9, 200], uploaded_wall_ms: null },
    };
    const s = parseSharing({ forwards: [], chase: null, sondehub: wire }).sondehub;
    if (s === null) throw new Error("sondehub expected");
    expect(s.errors).toEqual([{ wall_ms: 90_000, text: "Missing lat field" }]);
    expect(sondehubLine(s, 103_000)).toBe("STRAPLEX1 by CT1ABC to https://api.v2.sondehub.org every 10 s: last upload 3 s ago (202: 2 of 3 points taken, 1 refused, 0 warnings)");
    expect(sondehubCounts(s)).toBe("10 points taken, 1 queued on disk (of 20000), 1 refused by the server");
    expect(sondehubListeners(s, 103_000)).toBe("station position uploaded 53 s ago; chase car CT1ABC_CHASE at 38.50000, -7.90000 waiting to upload");
    const failing: SondehubView = { ...s, failing: true, last_result: "no answer: timed out", retry_wall_ms: 108_000, dropped: 4, last_upload_wall_ms: null, chase_car: null };
    expect(sondehubLine(failing, 103_000)).toBe("STRAPLEX1 by CT1ABC to https://api.v2.sondehub.org every 10 s: FAILING (no answer: timed out, next try in 5 s); nothing uploaded yet");
    expect(sondehubCounts(failing)).toContain("4 DROPPED (queue full)");
    expect(sondehubListeners(failing, 0)).toMatch(/no chase car/);
    expect(sondehubLine(parseSharing({}).sondehub, 0)).toMatch(/^SondeHub upload off/);
    expect(parseSharing({ sondehub: { url: "x" } }).sondehub).toBeNull();
  });
  it("sums the public relays' pages and drops a relay without a name", () => {
    const s = parseSharing({ relays: [{ id: 4, name: "school", connected_s: 12, viewers: 37 }, { id: 9, name: "club", viewers: 5 }, { id: 10, viewers: 3 }] });
    expect(s.relays.map((r) => r.viewers)).toEqual([37, 5]);
    expect(relaysLine(s.relays)).toBe("42 public pages through 2 relays (school #4: 37, club #9: 5)");
    expect(relaysLine(parseSharing({}).relays)).toMatch(/^no public relay connected/);
  });
});
