import { describe, expect, it } from "vitest";
import { CommandTracker, isFinal, MAX_ENTRIES } from "./commands";
import type { CommandResult } from "./types";

const result = (over: Partial<CommandResult>): CommandResult => ({ type: "command_result", request_id: "r1", command: "set_mode", outcome: "accepted", attempts: 1, detail: "", value: null, ...over });

describe("CommandTracker", () => {
  it("sending → in progress → accepted, with attempts", () => {
    const t = new CommandTracker();
    const id = t.begin("set_mode", "mode → heading", 0);
    expect(t.entries[0]!.status).toBe("sending");
    t.accepted(id, "r1", 1);
    expect(t.entries[0]!.status).toBe("in_progress");
    t.result(result({ outcome: "accepted", attempts: 2 }), 2);
    expect(t.entries[0]).toMatchObject({ status: "accepted", attempts: 2, foreign: false });
  });

  it("a result that overtakes the 202 is merged, not duplicated", () => {
    const t = new CommandTracker();
    const id = t.begin("set_param", "param HK1 → 0.015", 0);
    t.result(result({ request_id: "r9", command: "set_param", outcome: "accepted", value: 0.015 }), 1);
    expect(t.entries).toHaveLength(2);
    t.accepted(id, "r9", 2);
    expect(t.entries).toHaveLength(1);
    expect(t.entries[0]).toMatchObject({ status: "accepted", value: 0.015, label: "param HK1 → 0.015" });
  });

  it("a late in_progress does not hide a final outcome", () => {
    const t = new CommandTracker();
    const id = t.begin("set_mode", "m", 0);
    t.accepted(id, "r1", 0);
    t.result(result({ outcome: "timed_out", attempts: 3 }), 1);
    t.result(result({ outcome: "in_progress", attempts: 3 }), 2);
    expect(t.entries[0]!.status).toBe("timed_out");
  });

  it("HTTP refusals are shown as rejected with the reason", () => {
    const t = new CommandTracker();
    const id = t.begin("set_mode", "m", 0);
    t.rejected(id, "403 forbidden: operator role required", 1);
    expect(t.entries[0]).toMatchObject({ status: "rejected", detail: "403 forbidden: operator role required" });
    expect(isFinal("rejected")).toBe(true);
    expect(isFinal("in_progress")).toBe(false);
  });

  it("other operators' commands are listed as foreign", () => {
    const t = new CommandTracker();
    t.result(result({ request_id: "x", command: "set_target" }), 0);
    expect(t.entries[0]).toMatchObject({ foreign: true, label: "set target" });
  });

  it("keeps a bounded history", () => {
    const t = new CommandTracker();
    for (let i = 0; i < MAX_ENTRIES + 20; i++) t.begin("c", `${i}`, i);
    expect(t.entries).toHaveLength(MAX_ENTRIES);
    expect(t.entries[0]!.label).toBe(`${MAX_ENTRIES + 19}`);
  });
});
