import { describe, expect, it } from "vitest";
import { recordingText } from "./linkPanel";
import type { Recording } from "../lib/types";

// 2026-11-29T06:42:26Z.
const SINCE_MS = Date.UTC(2026, 10, 29, 6, 42, 26);
const ENOSPC = "writing the recording: No space left on device (os error 28)";

const ON: Recording = {
  state: "on", file: "/rec/stx-20261129T064226Z-001.mcap", bytes_written: 2_065_754, messages_written: 65_982,
  messages_lost: 0, problem: null, failing_since_ms: null, next_try_in_s: null, failed_tries: 0, resumed_ms: null,
  resumed_after_s: null,
};
const FAILING: Recording = {
  ...ON, state: "failing", file: null, messages_lost: 11_373, problem: ENOSPC, failing_since_ms: SINCE_MS,
  next_try_in_s: 37.4, failed_tries: 4,
};

describe("the Link panel's recording line", () => {
  it("recording: the readout says what was written, and there is nothing more to say", () => {
    expect(recordingText(ON)).toEqual({ readout: "REC 2.1 MB", detail: "", warn: false, title: ON.file });
  });
  it("a full disk: the problem, since when, the next try and the tries that failed", () => {
    const t = recordingText(FAILING);
    expect(t.readout).toBe("FAILING, 11373 lost");
    expect(t.detail).toBe(`${ENOSPC} — since 06:42:26Z; next try in 37 s (4 tries failed); 11373 messages lost`);
    expect(t.warn).toBe(true);
    expect(recordingText({ ...FAILING, failed_tries: 1, next_try_in_s: 4.96, messages_lost: 0 }).detail).toBe(`${ENOSPC} — since 06:42:26Z; next try in 5.0 s (1 try failed)`);
  });
  it("a try under way (a file open, no message on it yet) is still failing", () => {
    const t = recordingText({ ...FAILING, file: "/rec/stx-20261129T064226Z-002.mcap", next_try_in_s: 0 });
    expect(t.readout).toBe("FAILING, 11373 lost");
    expect(t.detail).toBe(`${ENOSPC} — since 06:42:26Z; trying again now (4 tries failed); 11373 messages lost`);
  });
  it("resumed: recording again, saying when it resumed, after how long, and why it had failed", () => {
    const t = recordingText({ ...ON, messages_lost: 11_373, problem: ENOSPC, resumed_ms: SINCE_MS + 95_000, resumed_after_s: 95 });
    expect(t.readout).toBe("REC 2.1 MB, 11373 lost");
    expect(t.detail).toBe(`Resumed 06:44:01Z after failing 1 min 35 s (${ENOSPC}); 11373 messages lost`);
    expect(t.warn).toBe(true);
  });
  it("no directory at all: the station does not retry, so the problem alone", () => {
    const why = "no recording directory: set recording.dir, --record-dir or a state directory";
    const t = recordingText({ ...ON, state: "failing", file: null, bytes_written: 0, problem: why });
    expect([t.readout, t.detail, t.warn]).toEqual(["FAILING", why, true]);
    expect(recordingText({ ...ON, state: "failing", file: null, messages_lost: 12, problem: why }).detail).toBe(`${why}; 12 messages lost`);
  });
  it("off, and no recording block at all", () => {
    expect(recordingText({ ...ON, state: "off", file: null, bytes_written: 0 })).toEqual({ readout: "OFF", detail: "", warn: false, title: "" });
    expect(recordingText(null)).toEqual({ readout: "—", detail: "", warn: false, title: "" });
  });
});
