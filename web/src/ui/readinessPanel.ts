// The go/no-go board (a tab of the control column): every check with its status and why, the
// checklist's manual items with a tick box for operators and who ticked them when. Ticks go to
// `POST /api/readiness/{id}`; the board itself comes back in every `state`, so every page shows
// the same ticks. The header's badge (`badge`) carries the verdict, and after a launch with
// checks open, the warning every page must show.

import { h, panel, setText } from "./dom";
import { launchWarning, verdict, type Check, type Readiness } from "../lib/readiness";

const STATUS_TEXT: Record<Check["status"], string> = { go: "GO", no_go: "NO-GO", unknown: "?" };

export class ReadinessPanel {
  readonly root: HTMLElement;
  /** For the header: the verdict, or the launch-with-checks-open alarm. */
  readonly badge: HTMLElement;
  private readonly verdictEl: HTMLElement;
  private readonly errorEl: HTMLElement;
  private readonly body: HTMLElement;
  private lastKey = "";

  constructor(private readonly tick: (id: string, ticked: boolean) => Promise<void>) {
    this.verdictEl = h("div", { class: "readiness-verdict", "data-testid": "readiness-verdict" });
    this.errorEl = h("div", { class: "form-error", role: "alert", "data-testid": "readiness-error" });
    this.body = h("tbody", { "data-testid": "readiness-checks" });
    const table = h("table", { class: "readiness" }, h("thead", {}, h("tr", {}, h("th", {}, ""), h("th", {}, "check"), h("th", {}, "why"))), this.body);
    this.root = panel("Go / no-go", "panel-readiness", this.verdictEl, table, this.errorEl);
    this.badge = h("span", { class: "badge", "data-testid": "hdr-readiness", title: "the go/no-go board (Control column, Go/no-go tab)" });
  }

  update(r: Readiness): void {
    const warning = launchWarning(r);
    setText(this.badge, warning ?? verdict(r));
    this.badge.dataset.state = warning !== null ? "launched_open" : r.open === 0 && r.checks.length > 0 ? "go" : "no_go";
    this.badge.classList.toggle("alarm", warning !== null);
    this.badge.setAttribute("role", warning !== null ? "alert" : "status");
    setText(this.verdictEl, warning ?? verdict(r));
    this.verdictEl.dataset.state = this.badge.dataset.state;
    if (r.checklist_error !== null) setText(this.errorEl, r.checklist_error);
    // Rebuilt only when something changed: a tick box being clicked must not be replaced under the pointer at 4 Hz.
    const key = JSON.stringify(r.checks);
    if (key === this.lastKey) return;
    this.lastKey = key;
    this.body.replaceChildren(...r.checks.map((c) => this.row(c)));
  }

  private row(c: Check): HTMLElement {
    const chip = h("span", { class: `chip ${c.status}`, "data-testid": `readiness-status-${c.id}` }, STATUS_TEXT[c.status]);
    let detail: Node = document.createTextNode(c.detail);
    if (c.manual) {
      const box = h("input", { type: "checkbox", "data-command": true, "data-testid": `readiness-tick-${c.id}`, "aria-label": `tick: ${c.label}` }) as HTMLInputElement;
      box.checked = c.ticked_by !== null;
      box.addEventListener("change", () => {
        box.disabled = true;
        this.tick(c.id, box.checked).then(
          () => setText(this.errorEl, ""),
          (e: unknown) => {
            box.checked = !box.checked;
            setText(this.errorEl, `tick not taken: ${e instanceof Error ? e.message : String(e)}`);
          },
        ).finally(() => (box.disabled = false));
      });
      const who = c.ticked_by !== null && c.ticked_wall_ms !== null ? `${c.ticked_by}, ${new Date(c.ticked_wall_ms).toLocaleTimeString([], { hour12: false })}` : "not ticked";
      detail = h("label", { "data-testid": `readiness-who-${c.id}` }, box, ` ${who}`);
    }
    return h("tr", { "data-testid": `readiness-${c.id}`, "data-status": c.status, "data-manual": String(c.manual) }, h("td", {}, chip), h("td", {}, c.label), h("td", {}, detail));
  }
}
