// Tracks every command the page sent, from the click to its outcome. A command is "sending" until
// the station answers the POST (202 with a request_id, or an HTTP error), then "in_progress" until a
// final `command_result`. The result may overtake the 202 on a busy socket, and other operators'
// commands produce results too: results for unknown ids are kept as entries of their own and merged
// when our POST returns with that id.

import type { CommandResult, N, Outcome } from "./types";

export type CommandStatus = "sending" | "rejected" | Outcome;

export interface CommandEntry {
  /** Page-local id, stable for the DOM. */
  id: number;
  requestId: string | null;
  command: string;
  /** What the operator asked, in words (`mode → spiral landing`). */
  label: string;
  status: CommandStatus;
  attempts: N;
  detail: string;
  /** Value read back from the drone (parameter writes). */
  value: N;
  sentMs: number;
  updatedMs: number;
  /** True for results of commands this page did not send (another operator's). */
  foreign: boolean;
}

export const isFinal = (s: CommandStatus): boolean => s !== "sending" && s !== "in_progress";

export const MAX_ENTRIES = 100;

export class CommandTracker {
  private next = 1;
  /** Newest first. */
  entries: CommandEntry[] = [];

  constructor(private readonly onChange: (e: CommandEntry) => void = () => {}) {}

  begin(command: string, label: string, nowMs: number): number {
    const e: CommandEntry = {
      id: this.next++, requestId: null, command, label, status: "sending",
      attempts: null, detail: "", value: null, sentMs: nowMs, updatedMs: nowMs, foreign: false,
    };
    this.entries.unshift(e);
    if (this.entries.length > MAX_ENTRIES) this.entries.length = MAX_ENTRIES;
    this.onChange(e);
    return e.id;
  }

  /** The POST returned 202 with this request id. */
  accepted(id: number, requestId: string, nowMs: number): void {
    const e = this.byId(id);
    if (!e) return;
    e.requestId = requestId;
    e.updatedMs = nowMs;
    const early = this.entries.find((x) => x.foreign && x.requestId === requestId);
    if (early) {
      this.entries = this.entries.filter((x) => x !== early);
      Object.assign(e, { status: early.status, attempts: early.attempts, detail: early.detail, value: early.value });
    } else {
      e.status = "in_progress";
    }
    this.onChange(e);
  }

  /** The POST failed: HTTP error (401/403/400/409) or network. Nothing reached the drone. */
  rejected(id: number, reason: string, nowMs: number): void {
    const e = this.byId(id);
    if (!e) return;
    e.status = "rejected";
    e.detail = reason;
    e.updatedMs = nowMs;
    this.onChange(e);
  }

  result(r: CommandResult, nowMs: number): CommandEntry {
    let e = this.entries.find((x) => x.requestId === r.request_id);
    if (!e) {
      e = {
        id: this.next++, requestId: r.request_id, command: r.command, label: r.command.replace(/_/g, " "),
        status: r.outcome, attempts: null, detail: "", value: null, sentMs: nowMs, updatedMs: nowMs, foreign: true,
      };
      this.entries.unshift(e);
      if (this.entries.length > MAX_ENTRIES) this.entries.length = MAX_ENTRIES;
    }
    // A late in_progress must not overwrite a final outcome.
    if (!(isFinal(e.status) && r.outcome === "in_progress")) e.status = r.outcome;
    e.attempts = r.attempts;
    e.detail = r.detail;
    if (r.value !== null) e.value = r.value;
    e.updatedMs = nowMs;
    this.onChange(e);
    return e;
  }

  private byId(id: number): CommandEntry | undefined {
    return this.entries.find((x) => x.id === id);
  }
}
