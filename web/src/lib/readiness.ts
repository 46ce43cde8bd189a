// The go/no-go board as the page reads it from `state.readiness`: the station's own checks and
// the checklist's manual items (who ticked, when), what is still open, and the launch made with
// checks open that every page announces. Parsing is lenient like the rest of the state: a check
// without an id or a known status is dropped, not shown as go.

import { bool, isObj, num, str, type Obj } from "./parseFields";
import type { CheckStatus } from "../generated/api";
import type { Check, Readiness } from "./types";

export type { Check, Readiness };

const STATUSES = { go: true, no_go: true, unknown: true } as const satisfies Record<CheckStatus, true>;

export const NO_READINESS: Readiness = { checks: [], open: 0, launched_with_open: [], checklist_error: null };

export function parseReadiness(v: unknown): Readiness {
  if (!isObj(v)) return NO_READINESS;
  const checks: Check[] = [];
  for (const c of Array.isArray(v.checks) ? v.checks : []) {
    if (!isObj(c)) continue;
    const id = str(c, "id");
    const status = str(c, "status");
    if (id === null || status === null || !(status in STATUSES)) continue;
    checks.push({
      id, status: status as CheckStatus, label: str(c, "label") ?? id, manual: bool(c, "manual") ?? false, detail: str(c, "detail") ?? "",
      ticked_by: str(c, "ticked_by"), ticked_wall_ms: num(c, "ticked_wall_ms"),
    });
  }
  const launched = Array.isArray(v.launched_with_open) ? v.launched_with_open.filter((x): x is string => typeof x === "string") : [];
  return { checks, open: checks.filter((c) => c.status !== "go").length, launched_with_open: launched, checklist_error: str(v as Obj, "checklist_error") };
}

/** "GO" when every check holds, else how many are open. */
export function verdict(r: Readiness): string {
  if (r.checks.length === 0) return "—";
  return r.open === 0 ? "GO" : `NO-GO · ${r.open} open`;
}

/** The header's announcement of a launch made with checks open; null when there is none. */
export function launchWarning(r: Readiness): string | null {
  const n = r.launched_with_open.length;
  return n === 0 ? null : `LAUNCHED WITH ${n} CHECK${n === 1 ? "" : "S"} OPEN: ${r.launched_with_open.join("; ")}`;
}
