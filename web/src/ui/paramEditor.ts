// Parameter editor: the table from /api/params (and `params` messages); an edit is sent with
// POST /api/params/{name}, and the row shows the outcome with the value read back from the drone.
// The table must fit its 390 px column without scrolling sideways (a sideways-scrolled table hid
// the names): four fixed columns, units and range under the value, the outcome on a line of its
// own below the row.

import { h, panel, setText } from "./dom";
import { parseNumber } from "../lib/inputs";
import { fmtParam } from "../lib/format";
import type { CommandEntry } from "../lib/commands";
import type { Param } from "../lib/types";

interface Row {
  tr: HTMLElement;
  value: HTMLElement;
  input: HTMLInputElement;
  result: HTMLElement;
  /** The outcome of the last write, on its own line under the row (hidden until there is one). */
  resultRow: HTMLElement;
}

export type SendParam = (name: string, value: number) => number | null;

export class ParamEditor {
  readonly root: HTMLElement;
  private readonly body: HTMLTableSectionElement;
  private readonly status: HTMLElement;
  private readonly filter: HTMLInputElement;
  private readonly rows = new Map<string, Row>();
  /** Command entry id → parameter name, to route outcomes to their row. */
  private readonly pending = new Map<number, string>();

  constructor(private readonly send: SendParam) {
    this.body = h("tbody", { "data-testid": "param-rows" });
    this.status = h("span", { class: "muted", "data-testid": "param-status" }, "loading…");
    this.filter = h("input", { type: "search", placeholder: "filter", "aria-label": "filter parameters", "data-testid": "param-filter" });
    this.filter.addEventListener("input", () => this.applyFilter());
    const table = h("table", { class: "params" },
      h("colgroup", {}, h("col", { class: "c-name" }), h("col", { class: "c-value" }), h("col", { class: "c-input" }), h("col", { class: "c-set" })),
      h("thead", {}, h("tr", {}, ...["name", "value · units · range", "new value", ""].map((t) => h("th", {}, t)))), this.body);
    this.root = panel("Parameters", "panel-params", h("div", { class: "form-row" }, this.filter, this.status), h("div", { class: "scroll" }, table));
  }

  setParams(params: readonly Param[], complete: boolean): void {
    setText(this.status, `${params.length} parameters${complete ? "" : " (still loading from the drone)"}`);
    for (const p of params) {
      let r = this.rows.get(p.name);
      if (!r) {
        r = this.makeRow(p);
        this.rows.set(p.name, r);
        this.body.append(r.tr, r.resultRow);
      }
      setText(r.value, fmtParam(p.value));
      r.input.setAttribute("placeholder", p.value === null ? "" : fmtParam(p.value));
    }
    this.applyFilter();
  }

  /** A command outcome; if it belongs to a parameter write, show it on the row. */
  onCommand(e: CommandEntry): void {
    const name = this.pending.get(e.id);
    if (name === undefined) return;
    const r = this.rows.get(name);
    if (!r) return;
    r.result.dataset.status = e.status;
    r.resultRow.hidden = r.tr.hidden;
    const readBack = e.value !== null ? `read back ${fmtParam(e.value)}` : "";
    setText(r.result, [e.status.replace(/_/g, " "), readBack, e.status === "accepted" || e.status === "in_progress" ? "" : e.detail].filter((x) => x !== "").join(" · "));
  }

  private makeRow(p: Param): Row {
    const value = h("span", { class: "num pval", "data-testid": `param-value-${p.name}` });
    const input = h("input", { type: "text", inputmode: "decimal", size: 8, "data-testid": `param-input-${p.name}`, "data-command": true, "aria-label": `new value of ${p.name}` });
    const result = h("td", { class: "param-result", colspan: 4, "data-testid": `param-result-${p.name}` });
    const resultRow = h("tr", { class: "result-row" }, result);
    const btn = h("button", { type: "button", class: "small", "data-testid": `param-set-${p.name}`, "data-command": true }, "Set");
    const submit = (): void => {
      const v = parseNumber(input.value, p.name, p.min ?? -Infinity, p.max ?? Infinity);
      resultRow.hidden = false;
      if (!v.ok) {
        result.dataset.status = "rejected";
        setText(result, v.error);
        return;
      }
      const id = this.send(p.name, v.value);
      if (id !== null) this.pending.set(id, p.name);
    };
    btn.addEventListener("click", submit);
    input.addEventListener("keydown", (e) => {
      if (e.key === "Enter") submit();
    });
    const range = `${p.min ?? "—"} … ${p.max ?? "—"}`;
    const tr = h("tr", { "data-testid": `param-row-${p.name}`, title: p.description, "data-name": p.name.toLowerCase() },
      h("td", { class: "pname" }, p.name),
      h("td", {}, value, h("span", { class: "punits" }, ` ${p.units}`), h("div", { class: "prange" }, range)),
      h("td", {}, input), h("td", {}, btn));
    resultRow.hidden = true;
    return { tr, value, input, result, resultRow };
  }

  private applyFilter(): void {
    const f = this.filter.value.trim().toLowerCase();
    for (const [name, r] of this.rows) {
      r.tr.hidden = f !== "" && !name.toLowerCase().includes(f) && !(r.tr.getAttribute("title") ?? "").toLowerCase().includes(f);
      r.resultRow.hidden = r.tr.hidden || r.result.textContent === "";
    }
  }
}
