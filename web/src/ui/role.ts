// Who may command: every control marked `data-command` is disabled for viewers (and until the
// session says otherwise), with the tooltip "operator role required". The station enforces this
// too (403); the page only avoids offering what would be refused.

export const OPERATOR_REQUIRED = "operator role required";

export function applyRole(root: ParentNode, operator: boolean): void {
  for (const el of Array.from(root.querySelectorAll<HTMLElement>("[data-command]"))) {
    if (el instanceof HTMLButtonElement || el instanceof HTMLInputElement || el instanceof HTMLSelectElement) el.disabled = !operator;
    if (operator) {
      if (el.dataset.roleTitle === "1") {
        el.removeAttribute("title");
        delete el.dataset.roleTitle;
      }
    } else if (!el.title || el.dataset.roleTitle === "1") {
      el.title = OPERATOR_REQUIRED;
      el.dataset.roleTitle = "1";
    }
  }
  document.body.classList.toggle("viewer", !operator);
}
