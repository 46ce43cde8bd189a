import { describe, expect, it } from "vitest";
import { launchWarning, parseReadiness, verdict } from "./readiness";

const wire = {
  checks: [
    { id: "link", label: "Link up and signed", manual: false, status: "go", detail: "up and signed, 18 Hz", ticked_by: null, ticked_wall_ms: null },
    { id: "chute", label: "Round chute packed", manual: true, status: "go", detail: "ticked by ana", ticked_by: "ana", ticked_wall_ms: 1_800_000_000_000 },
    { id: "battery", label: "Battery", manual: false, status: "unknown", detail: "no battery reading", ticked_by: null, ticked_wall_ms: null },
    { id: "odd", label: "?", manual: false, status: "maybe", detail: "" },
    { label: "no id", status: "go" },
  ],
  open: 99,
  launched_with_open: ["Battery"],
  checklist_error: null,
};

describe("readiness", () => {
  it("keeps checks with an id and a known status, and counts the open ones itself", () => {
    const r = parseReadiness(wire);
    expect(r.checks.map((c) => c.id)).toEqual(["link", "chute", "battery"]);
    expect(r.open).toBe(1);
    expect(r.checks[1]).toMatchObject({ manual: true, ticked_by: "ana", ticked_wall_ms: 1_800_000_000_000 });
    expect(verdict(r)).toBe("NO-GO · 1 open");
  });

  it("is GO only when every check holds, and says nothing without checks", () => {
    const all = parseReadiness({ ...wire, checks: wire.checks.slice(0, 2) });
    expect(verdict(all)).toBe("GO");
    expect(verdict(parseReadiness(null))).toBe("—");
  });

  it("announces a launch with the open checks by name", () => {
    expect(launchWarning(parseReadiness(wire))).toBe("LAUNCHED WITH 1 CHECK OPEN: Battery");
    expect(launchWarning(parseReadiness({ ...wire, launched_with_open: [] }))).toBeNull();
  });
});
