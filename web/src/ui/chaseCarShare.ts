// The recovery page's opt-in to show the phone on SondeHub's map as a chase car: a box to tick,
// shown only when the station uploads to SondeHub (`GET /api/sharing`), and while ticked the
// phone's own GPS position (never one typed by hand, which may be the destination) sent to
// `POST /api/sondehub/chase` every 10 s, the station's upload pace for chase cars. Off by
// default: where a person is goes on a public map only when they say so.

import type { Api } from "../lib/api";
import { parseSondehub } from "../lib/sharing";
import { isObj } from "../lib/parseFields";
import type { LatLon } from "../lib/types";
import { h, setText } from "./dom";

const EVERY_MS = 10_000;
/** A page opened without network asks again this often whether the station uploads. */
const PROBE_EVERY_MS = 30_000;

export class ChaseCarShare {
  readonly root: HTMLElement;
  private readonly box: HTMLInputElement;
  private readonly status: HTMLElement;
  private position: LatLon | null = null;
  private lastSentMs = -Infinity;
  private probedMs = -Infinity;
  private known = false;

  constructor(private readonly api: Api) {
    this.box = h("input", { type: "checkbox", "data-testid": "rec-chase-share" });
    this.status = h("div", { class: "small muted", role: "status", "data-testid": "rec-chase-status" });
    this.root = h("div", { class: "chase-share", hidden: true },
      h("label", {}, this.box, " Show this phone on SondeHub as a chase car"), this.status);
    this.box.addEventListener("change", () => {
      this.lastSentMs = -Infinity;
      void this.tick();
    });
  }

  /** Asks the station whether it uploads to SondeHub; the box shows only if it does. */
  async probe(): Promise<void> {
    this.probedMs = Date.now();
    try {
      const sharing: unknown = await this.api.get("/api/sharing");
      const s = isObj(sharing) ? parseSondehub(sharing.sondehub) : null;
      this.root.hidden = s === null;
      this.known = true;
    } catch {
      // no network: asked again on the next probe
    }
  }

  /** The phone's GPS position, or null when it has none. */
  setPosition(p: LatLon | null): void {
    this.position = p;
  }

  /** Sends the position when ticked and due (and asks again whether to show, until known). */
  async tick(): Promise<void> {
    if (!this.known && Date.now() - this.probedMs >= PROBE_EVERY_MS) await this.probe();
    if (!this.box.checked) return;
    if (this.position === null) {
      setText(this.status, "waiting for the phone's GPS position");
      return;
    }
    const now = Date.now();
    if (now - this.lastSentMs < EVERY_MS) return;
    this.lastSentMs = now;
    try {
      const view: unknown = await this.api.post("/api/sondehub/chase", { lat_deg: this.position.lat_deg, lon_deg: this.position.lon_deg });
      const car = isObj(view) ? parseSondehub(view)?.chase_car : null;
      setText(this.status, car?.uploaded_wall_ms ? `shared as ${car.callsign}; last upload ${new Date(car.uploaded_wall_ms).toISOString().slice(11, 19)} UTC` : "given to the station; it uploads every 10 s");
    } catch (e) {
      setText(this.status, `not shared: ${e instanceof Error ? e.message : String(e)}`);
    }
  }
}
