// Who may command: every control marked `data-command` is disabled for viewers (and until the
// session says otherwise), with a tooltip saying why: "operator role required", or for a replay,
// which has no drone, that reason instead. The station enforces this too (403, 409); the page only
// avoids offering what would be refused.

export const OPERATOR_REQUIRED = "operator role required";
export const REPLAY_HAS_NO_DRONE = "a replay has no drone to command";

/** Enables the command controls under `root`, or disables them with `why` as their tooltip. */
export function applyRole(root: ParentNode, operator: boolean, why: string = OPERATOR_REQUIRED): void {
  for (const el of Array.from(root.querySelectorAll<HTMLElement>("[data-command]"))) {
    if (el instanceof HTMLButtonElement || el instanceof HTMLInputElement || el instanceof HTMLSelectElement) el.disabled = !operator;
    if (operator) {
      if (el.dataset.roleTitle === "1") {
        el.removeAttribute("title");
        delete el.dataset.roleTitle;
      }
    } else if (!el.title || el.dataset.roleTitle === "1") {
      el.title = why;
      el.dataset.roleTitle = "1";
    }
  }
  document.body.classList.toggle("viewer", !operator);
}
