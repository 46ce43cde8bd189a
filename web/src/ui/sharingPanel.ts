// What the station shares beyond its pages, under the go/no-go board: each read-only MAVLink
// forward (where it goes, what its watcher may send the drone, its traffic) and the chase cars'
// broadcast. Read from `GET /api/sharing` by the page every few seconds.

import { h, panel, setText } from "./dom";
import { chaseLine, forwardCounts, forwardRights, type Sharing } from "../lib/sharing";

export class SharingPanel {
  readonly root: HTMLElement;
  private readonly chase: HTMLElement;
  private readonly forwards: HTMLElement;

  constructor() {
    this.chase = h("p", { "data-testid": "sharing-chase" }, "…");
    this.forwards = h("ul", { class: "sharing-forwards", "data-testid": "sharing-forwards" });
    this.root = panel("Shared with", "panel-sharing", h("h3", {}, "Chase cars"), this.chase, h("h3", {}, "Other ground stations (MAVLink forwards)"), this.forwards);
  }

  /** `GET /api/sharing` failed: said where the broadcast's line is, the last list kept. */
  failed(reason: string): void {
    setText(this.chase, `not read from the station: ${reason}`);
    this.chase.dataset.state = "unknown";
  }

  update(s: Sharing, nowMs: number): void {
    setText(this.chase, chaseLine(s.chase, nowMs));
    this.chase.dataset.state = s.chase === null ? "off" : s.chase.error !== null ? "failing" : "on";
    const items = s.forwards.map((f) =>
      h("li", { "data-testid": `sharing-forward-${f.name}`, "data-rights": f.may_send_to_drone.length === 0 ? "read-only" : "may-send" },
        h("strong", {}, f.name), ` → ${f.address} · ${forwardRights(f)} · ${forwardCounts(f)}`));
    this.forwards.replaceChildren(...(items.length > 0 ? items : [h("li", {}, "none (no [[forward]] in the station's config)")]));
  }
}
