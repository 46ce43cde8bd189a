// What the station shares beyond its pages, under the go/no-go board: each read-only MAVLink
// forward (where it goes, what its watcher may send the drone, its traffic), the chase cars'
// broadcast, the SondeHub upload (its state, queue and the server's latest errors and
// warnings) and the public relays with the pages they serve. Read from `GET /api/sharing` by the page every few seconds.

import { h, panel, setText } from "./dom";
import { chaseLine, forwardCounts, relaysLine, forwardRights, sondehubCounts, sondehubLine, sondehubListeners, type Sharing } from "../lib/sharing";

export class SharingPanel {
  readonly root: HTMLElement;
  private readonly chase: HTMLElement;
  private readonly forwards: HTMLElement;
  private readonly sondehub: HTMLElement;
  private readonly sondehubCounts: HTMLElement;
  private readonly sondehubListeners: HTMLElement;
  private readonly sondehubNotes: HTMLElement;
  private readonly relays: HTMLElement;

  constructor() {
    this.chase = h("p", { "data-testid": "sharing-chase" }, "…");
    this.forwards = h("ul", { class: "sharing-forwards", "data-testid": "sharing-forwards" });
    this.sondehub = h("p", { "data-testid": "sharing-sondehub" }, "…");
    this.sondehubCounts = h("p", { class: "muted", "data-testid": "sharing-sondehub-counts" });
    this.sondehubListeners = h("p", { class: "muted", "data-testid": "sharing-sondehub-listeners" });
    this.sondehubNotes = h("ul", { class: "sharing-notes", "data-testid": "sharing-sondehub-notes" });
    this.relays = h("p", { "data-testid": "sharing-relays" }, "…");
    this.root = panel("Shared with", "panel-sharing", h("h3", {}, "Chase cars"), this.chase,
      h("h3", {}, "SondeHub-Amateur"), this.sondehub, this.sondehubCounts, this.sondehubListeners, this.sondehubNotes,
      h("h3", {}, "Public relays"), this.relays,
      h("h3", {}, "Other ground stations (MAVLink forwards)"), this.forwards);
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
    this.updateSondehub(s, nowMs);
    setText(this.relays, relaysLine(s.relays));
    this.relays.dataset.viewers = String(s.relays.reduce((n, r) => n + r.viewers, 0));
  }

  private updateSondehub(s: Sharing, nowMs: number): void {
    const sh = s.sondehub;
    setText(this.sondehub, sondehubLine(sh, nowMs));
    this.sondehub.dataset.state = sh === null ? "off" : sh.failing ? "failing" : "on";
    setText(this.sondehubCounts, sh === null ? "" : sondehubCounts(sh));
    setText(this.sondehubListeners, sh === null ? "" : sondehubListeners(sh, nowMs));
    // The newest first, errors before warnings: what needs looking at on top.
    const notes = sh === null ? [] : [
      ...sh.errors.slice().reverse().map((n) => h("li", { class: "error", "data-kind": "error" }, `error: ${n.text}`)),
      ...sh.warnings.slice().reverse().map((n) => h("li", { class: "warning", "data-kind": "warning" }, `warning: ${n.text}`)),
    ];
    this.sondehubNotes.replaceChildren(...notes);
  }
}
