// Autonomous-control panel: mode buttons, landing target (with approach course: into the wind or
// a number), heading, course and localizer. Controls marked `data-command` are disabled for
// viewers (see role.ts). Nothing is sent unless every field validates.

import type { CommandBodies, CommandPath } from "../lib/api";
import { h, panel } from "./dom";
import { all, parseAlt, parseDeg, parseLat, parseLon, parseNumber } from "../lib/inputs";
import { label } from "../lib/format";
import type { FlightMode, LatLon, State } from "../lib/types";
import type { LocalizerBody } from "../generated/api";
import type { PickGroup } from "./pick";
import type { MapView } from "./map";

export type SendCommand = <P extends CommandPath>(command: string, label: string, path: P, body: CommandBodies[P]) => void;

const field = (lbl: string, testid: string, attrs: Record<string, string> = {}): { root: HTMLElement; input: HTMLInputElement } => {
  const input = h("input", { type: "text", inputmode: "decimal", "data-testid": testid, "data-command": true, "aria-label": lbl, ...attrs });
  return { root: h("label", { class: "field" }, h("span", {}, lbl), input), input };
};
const button = (text: string, testid: string, cls = "", aria?: string): HTMLButtonElement => h("button", { type: "button", "data-testid": testid, "data-command": true, class: cls, "aria-label": aria ?? null }, text);
const errorLine = (testid: string): HTMLElement => h("div", { class: "form-error", role: "alert", "data-testid": testid });

export class ModeButtons {
  readonly root: HTMLElement;
  private readonly buttons = new Map<string, HTMLButtonElement>();

  constructor(modes: readonly FlightMode[], send: SendCommand) {
    const row = h("div", { class: "modes", role: "group", "aria-label": "flight mode" });
    for (const m of modes) {
      const b = button(label(m), `mode-${m}`, "mode");
      b.setAttribute("aria-pressed", "false");
      b.addEventListener("click", () => send("set_mode", `mode → ${label(m)}`, "/api/commands/mode", { mode: m }));
      this.buttons.set(m, b);
      row.append(b);
    }
    this.root = panel("Mode", "panel-modes", row);
  }

  update(s: State): void {
    const current = s.vehicle?.mode ?? s.guidance?.mode ?? null;
    for (const [m, b] of this.buttons) {
      const on = m === current;
      if (b.classList.contains("current") !== on) {
        b.classList.toggle("current", on);
        b.setAttribute("aria-pressed", String(on));
      }
    }
  }
}

export class TargetEditor {
  readonly root: HTMLElement;
  private readonly lat = field("Latitude °", "target-lat");
  private readonly lon = field("Longitude °", "target-lon");
  private readonly alt = field("Alt. MSL m", "target-alt");
  private readonly course = field("Course °", "target-approach-course");
  private readonly intoWind: HTMLInputElement;
  private readonly fixed: HTMLInputElement;
  private readonly err = errorLine("target-error");
  private filled = false;

  constructor(send: SendCommand, picks: PickGroup, private readonly map: MapView) {
    const pick = button("Pick on map", "target-pick", "small");
    picks.bind(pick, (p) => this.setPoint(p));
    this.intoWind = h("input", { type: "radio", name: "approach", checked: true, "data-testid": "target-approach-wind", "data-command": true });
    this.fixed = h("input", { type: "radio", name: "approach", "data-testid": "target-approach-fixed", "data-command": true });
    this.course.input.addEventListener("input", () => (this.fixed.checked = true));
    const sendBtn = button("Send target", "target-send", "primary");
    sendBtn.addEventListener("click", () => {
      const c = all(parseLat(this.lat.input.value), parseLon(this.lon.input.value), parseAlt(this.alt.input.value));
      if (!c.ok) return this.fail(c.error);
      let approach: number | null = null;
      if (this.fixed.checked) {
        const a = parseDeg(this.course.input.value, "approach course");
        if (!a.ok) return this.fail(a.error);
        approach = a.value;
      }
      this.err.textContent = "";
      const [lat_deg, lon_deg, alt_msl_m] = c.values;
      send("set_target", `target → ${lat_deg.toFixed(5)}, ${lon_deg.toFixed(5)}, approach ${approach === null ? "into wind" : `${approach}°`}`, "/api/commands/target", { lat_deg, lon_deg, alt_msl_m, approach_course_deg: approach });
      this.map.showDraftTarget(null);
    });
    this.root = panel("Landing target", "panel-target",
      h("div", { class: "form-row" }, this.lat.root, this.lon.root, pick),
      h("div", { class: "form-row" }, this.alt.root,
        h("div", { class: "approach", role: "radiogroup", "aria-label": "approach course" },
          h("span", {}, "Approach"), h("div", {}, h("label", {}, this.intoWind, " into the wind"), " ", h("label", {}, this.fixed, " fixed"))), this.course.root),
      h("div", { class: "form-row" }, sendBtn), this.err);
  }

  private fail(e: string): void {
    this.err.textContent = e;
  }

  setPoint(p: LatLon): void {
    this.lat.input.value = p.lat_deg.toFixed(6);
    this.lon.input.value = p.lon_deg.toFixed(6);
    this.map.showDraftTarget(p);
  }

  /** Prefills with the current target once, so editing starts from what the drone has. */
  update(s: State): void {
    const t = s.guidance?.target;
    if (this.filled || !t) return;
    this.filled = true;
    this.lat.input.value = t.lat_deg.toFixed(6);
    this.lon.input.value = t.lon_deg.toFixed(6);
    this.alt.input.value = t.alt_msl_m === null ? "" : String(t.alt_msl_m);
  }
}

export class GuidanceInputs {
  readonly root: HTMLElement;

  constructor(send: SendCommand, picks: PickGroup, map: MapView) {
    const hd = field("Heading °", "heading-input");
    const hdErr = errorLine("heading-error");
    const hdBtn = button("Send", "heading-send", "", "send heading");
    hdBtn.addEventListener("click", () => {
      const v = parseDeg(hd.input.value, "heading");
      hdErr.textContent = v.ok ? "" : v.error;
      if (v.ok) send("set_heading", `heading → ${v.value}°`, "/api/commands/heading", { heading_deg: v.value });
    });
    const cs = field("Course °", "course-input");
    const csErr = errorLine("course-error");
    const csBtn = button("Send", "course-send", "", "send course");
    csBtn.addEventListener("click", () => {
      const v = parseDeg(cs.input.value, "course");
      csErr.textContent = v.ok ? "" : v.error;
      if (v.ok) send("set_course", `course → ${v.value}°`, "/api/commands/course", { course_deg: v.value });
    });

    const lat = field("Latitude °", "localizer-lat");
    const lon = field("Longitude °", "localizer-lon");
    const crs = field("Course °", "localizer-course");
    const gs = field("Glide slope (opt.)", "localizer-glide", { placeholder: "e.g. 0.5" });
    const lzErr = errorLine("localizer-error");
    const pick = button("Pick on map", "localizer-pick", "small");
    const draw = (): void => {
      const la = parseLat(lat.input.value);
      const lo = parseLon(lon.input.value);
      const c = parseDeg(crs.input.value, "course");
      map.showDraftLocalizer(la.ok && lo.ok ? { lat_deg: la.value, lon_deg: lo.value } : null, c.ok ? c.value : null);
    };
    picks.bind(pick, (p) => {
      lat.input.value = p.lat_deg.toFixed(6);
      lon.input.value = p.lon_deg.toFixed(6);
      draw();
    });
    for (const f of [lat, lon, crs]) f.input.addEventListener("input", draw);
    const lzBtn = button("Send", "localizer-send", "", "send localizer");
    lzBtn.addEventListener("click", () => {
      const c = all(parseLat(lat.input.value), parseLon(lon.input.value), parseDeg(crs.input.value, "course"));
      if (!c.ok) {
        lzErr.textContent = c.error;
        return;
      }
      const body: LocalizerBody = { lat_deg: c.values[0], lon_deg: c.values[1], course_deg: c.values[2] };
      if (gs.input.value.trim() !== "") {
        const g = parseNumber(gs.input.value, "glide slope", 0, 10);
        if (!g.ok) {
          lzErr.textContent = g.error;
          return;
        }
        body.glide_slope = g.value;
      }
      lzErr.textContent = "";
      send("set_localizer", `localizer → ${c.values[2]}° through ${c.values[0].toFixed(5)}, ${c.values[1].toFixed(5)}`, "/api/commands/localizer", body);
    });

    this.root = panel("Heading · course · localizer", "panel-guidance-inputs",
      h("div", { class: "form-row" }, hd.root, hdBtn, h("span", { class: "sep" }), cs.root, csBtn), hdErr, csErr,
      h("h3", {}, "Localizer"),
      h("div", { class: "form-row" }, lat.root, lon.root, pick),
      h("div", { class: "form-row" }, crs.root, gs.root, lzBtn), lzErr);
  }
}
