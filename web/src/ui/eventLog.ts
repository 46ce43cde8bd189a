// The event log, newest first, filterable by level. Events come from `history` and live `event`
// messages, and from this page itself (command outcomes are also logged here, marked "page").

import { h } from "./dom";
import { fmtMissionTime, fmtWallUtc } from "../lib/format";
import type { EventMsg, Level } from "../lib/types";

const MAX = 1000;
const LEVELS: Level[] = ["info", "warning", "error"];

export class EventLog {
  readonly root: HTMLElement;
  private readonly list: HTMLOListElement;
  private readonly shown = new Set<Level>(LEVELS);
  private readonly count: HTMLElement;

  constructor() {
    this.list = h("ol", { class: "events", "data-testid": "event-list", "aria-live": "polite" });
    this.count = h("span", { class: "muted", "data-testid": "event-count" });
    const filters = LEVELS.map((lv) => {
      const cb = h("input", { type: "checkbox", checked: true, "data-testid": `event-filter-${lv}` });
      cb.addEventListener("change", () => {
        if (cb.checked) this.shown.add(lv);
        else this.shown.delete(lv);
        this.applyFilter();
      });
      return h("label", { class: `filter lv-${lv}` }, cb, ` ${lv}`);
    });
    this.root = h("div", { class: "event-log", "data-testid": "event-log" }, h("div", { class: "event-filters", role: "group", "aria-label": "show levels" }, "Show: ", ...filters, this.count), this.list);
  }

  /** Replaces the log (after reconnecting, history holds everything the station kept). */
  reset(events: readonly EventMsg[]): void {
    this.list.replaceChildren();
    for (const e of events) this.add(e);
  }

  add(e: EventMsg): void {
    const li = h("li", { class: `ev lv-${e.level}`, "data-level": e.level, "data-testid": "event-item" },
      // The mission's clock (the drone's), as the header and the plots; the station's only for
      // events from before the drone was heard.
      h("span", { class: "ev-time", title: fmtWallUtc(e.wall_ms) }, fmtMissionTime(e.mission_time_s ?? e.time_s)),
      h("span", { class: "ev-level" }, e.level.toUpperCase()),
      h("span", { class: "ev-source" }, e.source),
      h("span", { class: "ev-text" }, e.text));
    li.hidden = !this.shown.has(e.level);
    this.list.prepend(li);
    while (this.list.childElementCount > MAX) this.list.lastElementChild?.remove();
    this.count.textContent = ` ${this.list.childElementCount} events`;
  }

  private applyFilter(): void {
    for (const li of Array.from(this.list.children) as HTMLElement[]) li.hidden = !this.shown.has(li.dataset.level as Level);
  }
}
