// Every command's outcome: sending → in progress → accepted / denied / failed / unsupported /
// timed out (or rejected by the station before reaching the drone), with attempts and detail.

import { h, setText } from "./dom";
import { isFinal, type CommandEntry } from "../lib/commands";
import { fmtParam } from "../lib/format";

const STATUS_TEXT: Record<string, string> = {
  sending: "sending…", in_progress: "in progress…", accepted: "ACCEPTED", denied: "DENIED", failed: "FAILED",
  unsupported: "UNSUPPORTED", timed_out: "TIMED OUT", rejected: "REJECTED",
};

export class CommandList {
  readonly root: HTMLElement;
  private readonly list: HTMLOListElement;
  private readonly rows = new Map<number, HTMLLIElement>();

  constructor() {
    this.list = h("ol", { class: "commands", "data-testid": "command-list", "aria-live": "polite" });
    this.root = h("section", { class: "panel", "data-testid": "panel-commands", "aria-label": "command outcomes" }, h("h2", {}, "Command outcomes"), this.list);
  }

  update(e: CommandEntry, all: readonly CommandEntry[]): void {
    let li = this.rows.get(e.id);
    if (!li) {
      li = h("li", { class: "cmd", "data-testid": "command-item" },
        h("span", { class: "cmd-label", "data-testid": "command-label" }),
        h("span", { class: "cmd-status", "data-testid": "command-status" }),
        h("span", { class: "cmd-detail", "data-testid": "command-detail" }));
      this.rows.set(e.id, li);
      this.list.prepend(li);
    }
    li.dataset.status = e.status;
    li.dataset.requestId = e.requestId ?? "";
    li.dataset.command = e.command;
    const [label, status, detail] = Array.from(li.children) as HTMLElement[];
    setText(label!, `${e.foreign ? "(other) " : ""}${e.label}`);
    setText(status!, STATUS_TEXT[e.status] ?? e.status);
    const parts = [];
    if (e.attempts !== null) parts.push(`${e.attempts} attempt${e.attempts === 1 ? "" : "s"}`);
    if (e.value !== null) parts.push(`read back ${fmtParam(e.value)}`);
    if (e.detail) parts.push(e.detail);
    if (!isFinal(e.status)) parts.push(`${((Date.now() - e.sentMs) / 1000).toFixed(0)} s`);
    setText(detail!, parts.join(" · "));
    // Drop rows the tracker forgot (it keeps the last 100) and merged early results.
    const keep = new Set(all.map((x) => x.id));
    for (const [id, row] of this.rows) if (!keep.has(id)) {
      row.remove();
      this.rows.delete(id);
    }
  }
}
