// One map click, one owner: the target editor, the localizer editor and the plan editor each have
// a "pick on map" toggle; turning one on turns the others off.

import type { LatLon } from "../lib/types";
import type { Picker } from "./map";

export class PickGroup {
  private active: { button: HTMLButtonElement; onPick: (p: LatLon) => void; sticky: boolean } | null = null;

  constructor(private readonly setPicker: (p: Picker) => void) {}

  /** Makes `button` a pick toggle. `sticky` keeps it on after a pick (adding several waypoints). */
  bind(button: HTMLButtonElement, onPick: (p: LatLon) => void, sticky = false): void {
    button.setAttribute("aria-pressed", "false");
    button.addEventListener("click", () => {
      if (this.active?.button === button) this.off();
      else this.on({ button, onPick, sticky });
    });
  }

  off(): void {
    if (this.active) {
      this.active.button.setAttribute("aria-pressed", "false");
      this.active.button.classList.remove("on");
    }
    this.active = null;
    this.setPicker(null);
  }

  private on(a: { button: HTMLButtonElement; onPick: (p: LatLon) => void; sticky: boolean }): void {
    this.off();
    this.active = a;
    a.button.setAttribute("aria-pressed", "true");
    a.button.classList.add("on");
    this.setPicker((p) => {
      a.onPick(p);
      if (!a.sticky) this.off();
    });
  }
}
