// Plan editing: waypoints added by clicking on the map (or typed), then the land item (the target,
// with its approach course); sent whole with POST /api/commands/plan.

import { h, panel } from "./dom";
import { parseAlt, parseDeg, parseLat, parseLon } from "../lib/inputs";
import { planBody, type PlanItem } from "../lib/plan";
import type { LatLon, State } from "../lib/types";
import type { MapView } from "./map";
import type { PickGroup } from "./pick";
import type { SendCommand } from "./controls";

export class PlanEditor {
  readonly root: HTMLElement;
  private readonly rows: HTMLElement;
  private readonly err: HTMLElement;
  private waypoints: PlanItem[] = [];
  private land: PlanItem | null = null;
  private defaultAlt = 0;

  constructor(send: SendCommand, picks: PickGroup, private readonly map: MapView) {
    this.rows = h("tbody", { "data-testid": "plan-items" });
    this.err = h("div", { class: "form-error", role: "alert", "data-testid": "plan-error" });
    const addWp = h("button", { type: "button", class: "small", "data-testid": "plan-pick-waypoint", "data-command": true }, "Add waypoints on map");
    picks.bind(addWp, (p) => this.addWaypoint(p), true);
    const setLand = h("button", { type: "button", class: "small", "data-testid": "plan-pick-land", "data-command": true }, "Land point on map");
    picks.bind(setLand, (p) => {
      this.land = { kind: "land", lat_deg: p.lat_deg, lon_deg: p.lon_deg, alt_msl_m: this.land?.alt_msl_m ?? this.defaultAlt, approach_course_deg: this.land?.approach_course_deg ?? null };
      this.render();
    });
    const clear = h("button", { type: "button", class: "small", "data-testid": "plan-clear", "data-command": true }, "Clear");
    clear.addEventListener("click", () => {
      this.waypoints = [];
      this.land = null;
      this.render();
    });
    const sendBtn = h("button", { type: "button", class: "primary", "data-testid": "plan-send", "data-command": true }, "Send plan");
    sendBtn.addEventListener("click", () => {
      const b = planBody(this.waypoints, this.land);
      if (!b.ok) {
        this.err.textContent = b.error;
        return;
      }
      this.err.textContent = "";
      send("set_plan", `plan → ${this.waypoints.length} waypoint(s) + land`, "/api/commands/plan", b.body);
    });
    // Fixed column widths: the inputs fill their cells instead of pushing the table out of the tab.
    const cols = h("colgroup", {}, ...["5%", "11%", "26%", "26%", "11%", "14%", "7%"].map((w) => h("col", { style: `width:${w}` })));
    const table = h("table", { class: "plan", "data-testid": "plan-table" }, cols, h("thead", {}, h("tr", {}, ...[["#", "item"], ["kind", "waypoint or land"], ["lat °", "latitude, degrees"], ["lon °", "longitude, degrees"], ["alt m", "altitude MSL, m"], ["appr °", "the final approach's course, degrees; empty: into the wind"], ["", ""]].map(([t, title]) => h("th", { title: title || null }, t)))), this.rows);
    this.root = panel("Plan", "panel-plan", h("div", { class: "form-row" }, addWp, setLand, clear), table, h("div", { class: "form-row" }, sendBtn), this.err);
    this.render();
  }

  /** Defaults for new items: the current target's altitude; the land item starts at the target. */
  update(s: State): void {
    const t = s.guidance?.target;
    if (t && this.defaultAlt === 0) {
      this.defaultAlt = t.alt_msl_m ?? 0;
      if (this.land === null) {
        this.land = { kind: "land", lat_deg: t.lat_deg, lon_deg: t.lon_deg, alt_msl_m: t.alt_msl_m ?? 0, approach_course_deg: null };
        this.render();
      }
    }
  }

  private addWaypoint(p: LatLon): void {
    const last = this.waypoints[this.waypoints.length - 1];
    this.waypoints.push({ kind: "waypoint", lat_deg: p.lat_deg, lon_deg: p.lon_deg, alt_msl_m: last?.alt_msl_m ?? this.defaultAlt + 300 });
    this.render();
  }

  private render(): void {
    const items = [...this.waypoints, ...(this.land ? [this.land] : [])];
    this.rows.replaceChildren(...items.map((it, i) => this.row(it, i)));
    this.map.showDraftPlan(items);
  }

  private row(it: PlanItem, i: number): HTMLElement {
    const num = (value: string, testid: string, onChange: (v: string) => string | null): HTMLInputElement => {
      const inp = h("input", { type: "text", inputmode: "decimal", value, "data-testid": testid, "data-command": true, "aria-label": testid, size: 9 });
      inp.addEventListener("change", () => {
        const e = onChange(inp.value);
        this.err.textContent = e ?? "";
        inp.classList.toggle("invalid", e !== null);
        if (e === null) this.map.showDraftPlan([...this.waypoints, ...(this.land ? [this.land] : [])]);
      });
      return inp;
    };
    const set = (key: "lat_deg" | "lon_deg" | "alt_msl_m", parse: (t: string) => { ok: true; value: number } | { ok: false; error: string }) => (t: string): string | null => {
      const r = parse(t);
      if (!r.ok) return `item ${i + 1}: ${r.error}`;
      it[key] = r.value;
      return null;
    };
    const del = h("button", { type: "button", class: "small", "data-testid": `plan-delete-${i}`, "data-command": true, "aria-label": `delete item ${i + 1}` }, "✕");
    del.addEventListener("click", () => {
      if (it.kind === "land") this.land = null;
      else this.waypoints.splice(i, 1);
      this.render();
    });
    const approach = it.kind === "land"
      ? num(it.approach_course_deg == null ? "" : String(it.approach_course_deg), "plan-land-approach", (t) => {
          if (t.trim() === "") {
            it.approach_course_deg = null;
            return null;
          }
          const r = parseDeg(t, "approach course");
          if (!r.ok) return r.error;
          it.approach_course_deg = r.value;
          return null;
        })
      : h("span", {}, "");
    if (it.kind === "land") {
      approach.setAttribute("placeholder", "wind");
      approach.setAttribute("title", "the final approach's course, degrees; empty: into the wind");
    }
    return h("tr", { "data-testid": `plan-item-${i}`, "data-kind": it.kind },
      h("td", {}, String(i + 1)), h("td", {}, it.kind),
      h("td", {}, num(it.lat_deg.toFixed(6), `plan-lat-${i}`, set("lat_deg", (t) => parseLat(t)))),
      h("td", {}, num(it.lon_deg.toFixed(6), `plan-lon-${i}`, set("lon_deg", (t) => parseLon(t)))),
      h("td", {}, num(String(Math.round(it.alt_msl_m)), `plan-alt-${i}`, set("alt_msl_m", (t) => parseAlt(t)))),
      h("td", {}, approach), h("td", {}, del));
  }
}
