// The keep-out zones on the live map, and their editing by an operator (issue 15 item 2).
//
// Out of editing the zones in force are drawn, and redrawn whenever the station says they changed
// (another operator's edit arrives as a `keep_out` message). "Edit zones" turns every zone's
// corners into handles and opens a bar at the foot of the map: draw a new zone, name it and give
// its kind, delete it; Save sends every zone (`PUT /api/keep-out`), Cancel puts back the zones in
// force. A refusal — this page's check (lib/zones.ts) or the station's — is shown in the bar and
// the edit stays on the map to be mended; a change by someone else meanwhile is announced, not
// drawn over the edit.
//
// The vertex handling (click to place, drag a corner, click a midpoint to add one, right-click a
// corner to delete it, no ring pulled through itself) is Leaflet-Geoman's (MIT, kept for Leaflet
// 1.x): a tested library beats hand-written dragging on touch screens and at the map's edges.
// This module keeps only what is ours: which layer is which zone, and the names and kinds.
// Viewers get no bar (styles/live.css hides it; the station refuses their PUT anyway).

import L from "leaflet";
import "@geoman-io/leaflet-geoman-free";
import "@geoman-io/leaflet-geoman-free/dist/leaflet-geoman.css";
import { h, setText } from "./dom";
import { KEEP_OUT } from "./mapSymbols";
import { parseKeepOut, isObj } from "../lib/parse";
import { collectionOf, newZoneName, polygonsOfLatLngs, withZoneNames, ZONE_KINDS, zonesProblem } from "../lib/zones";
import type { KeepOutMsg, Zone } from "../lib/types";

/** How the editor reaches the station and the map around it. */
export interface ZoneEditorHooks {
  /** Sends every zone; resolves to the station's answer (a `keep_out` message), rejects with its reason. */
  save: (collection: unknown) => Promise<unknown>;
  /** Editing began or ended: the map stops following the vehicle while corners are placed. */
  onEditing: (on: boolean) => void;
}

/** A zone on the map: its layer (whose corners Geoman moves) and what the layer cannot hold. */
interface Entry {
  layer: L.Polygon;
  name: string;
  kind: string;
  extra: Record<string, unknown>;
}

const STYLE = KEEP_OUT;
const EDIT_OPTIONS = { allowSelfIntersection: false, removeLayerBelowMinVertexCount: false, snappable: false, draggable: false } as const;

export class ZoneEditor {
  /** The bar at the foot of the map. */
  readonly root: HTMLElement;
  /** Under the other layers, so the zones never hide the vehicle or the predictions. */
  private readonly group = L.featureGroup();
  private entries: Entry[] = [];
  private inForce: KeepOutMsg | null = null;
  private editing = false;
  private selected: Entry | null = null;
  private readonly editBtn: HTMLButtonElement;
  private readonly tools: HTMLElement;
  private readonly drawBtn: HTMLButtonElement;
  private readonly nameInput: HTMLInputElement;
  private readonly kindSelect: HTMLSelectElement;
  private readonly deleteBtn: HTMLButtonElement;
  private readonly saveBtn: HTMLButtonElement;
  private readonly errorText: HTMLElement;
  private readonly noteText: HTMLElement;

  /** Zones on the map now (in force, or being edited). */
  get drawn(): number {
    return this.entries.length;
  }

  constructor(
    private readonly map: L.Map,
    private readonly hooks: ZoneEditorHooks,
  ) {
    this.group.addTo(map);
    map.pm.setGlobalOptions({ finishOnEnter: true, snappable: false });
    this.editBtn = h("button", { type: "button", class: "small", "data-command": "keep_out", "data-testid": "zones-edit", title: "draw, move, name and delete keep-out zones" }, "Edit zones");
    this.editBtn.addEventListener("click", () => this.start());
    this.drawBtn = h("button", { type: "button", class: "small", "data-testid": "zones-draw", title: "click the map at each corner; click the first corner again (or press Enter) to close the zone" }, "Draw zone");
    this.drawBtn.addEventListener("click", () => this.draw());
    this.nameInput = h("input", { type: "text", "data-testid": "zones-name", "aria-label": "zone name", placeholder: "click a zone", size: 16, disabled: true });
    this.nameInput.addEventListener("input", () => this.rename(this.nameInput.value));
    this.kindSelect = h("select", { "data-testid": "zones-kind", "aria-label": "zone kind", disabled: true }, h("option", { value: "" }, "kind —"), ...ZONE_KINDS.map((k) => h("option", { value: k }, k)));
    this.kindSelect.addEventListener("change", () => {
      if (this.selected) this.selected.kind = this.kindSelect.value;
    });
    this.deleteBtn = h("button", { type: "button", class: "small", "data-testid": "zones-delete", disabled: true }, "Delete zone");
    this.deleteBtn.addEventListener("click", () => this.deleteSelected());
    this.saveBtn = h("button", { type: "button", class: "small primary", "data-testid": "zones-save", title: "send every zone to the station (PUT /api/keep-out)" }, "Save");
    this.saveBtn.addEventListener("click", () => void this.save());
    const cancel = h("button", { type: "button", class: "small", "data-testid": "zones-cancel", title: "forget this edit and show the zones in force" }, "Cancel");
    cancel.addEventListener("click", () => this.stop(true));
    this.errorText = h("div", { class: "zones-error", role: "alert", "data-testid": "zones-error", hidden: true });
    this.noteText = h("div", { class: "zones-note", "data-testid": "zones-note", hidden: true });
    const hint = h("div", { class: "zones-hint" }, "Drag a corner to move it, click a midpoint to add one, right-click a corner to delete it; click a zone to name or delete it.");
    this.tools = h("div", { class: "zones-tools", hidden: true },
      h("div", { class: "zones-row" }, this.drawBtn, this.nameInput, this.kindSelect, this.deleteBtn, this.saveBtn, cancel), hint, this.errorText, this.noteText);
    this.root = h("div", { class: "zone-editor", "data-testid": "zone-editor", "data-editing": "false" }, this.editBtn, this.tools);
    L.DomEvent.disableClickPropagation(this.root);
    L.DomEvent.disableScrollPropagation(this.root);

    map.on("pm:create", (e) => {
      if (!this.editing || e.shape !== "Polygon" || !(e.layer instanceof L.Polygon)) return;
      // Geoman adds the drawn layer to the map itself; it belongs with the other zones.
      e.layer.remove();
      const entry = this.add({ name: newZoneName(this.entries.map((z) => z.name)), kind: "", extra: {}, polygons: [] }, e.layer);
      this.drawBtn.classList.remove("on");
      this.select(entry);
      this.nameInput.select();
    });
  }

  /** The zones in force, from the station: drawn at once unless an edit is on the map. */
  show(k: KeepOutMsg): void {
    const before = this.inForce;
    this.inForce = k;
    if (!this.editing) {
      this.drawInForce();
      return;
    }
    // Compared by content: a reconnection re-reads the same zones, and this page's own save
    // comes back as a `keep_out` message too.
    if (before !== null && JSON.stringify([k.zones, k.changed_by]) !== JSON.stringify([before.zones, before.changed_by])) {
      this.noteText.hidden = false;
      setText(this.noteText, `${k.changed_by ?? "someone"} changed the zones while you edit: Save replaces theirs with yours, Cancel shows theirs.`);
    }
  }

  private drawInForce(): void {
    this.group.clearLayers();
    this.entries = [];
    this.selected = null;
    for (const z of this.inForce?.zones ?? []) this.add(z, null);
  }

  /** Puts a zone on the map: `layer` when Geoman drew it, else one made from its polygons. */
  private add(z: Zone, layer: L.Polygon | null): Entry {
    const shape = z.polygons.length === 1 ? (z.polygons[0] ?? []) : z.polygons;
    const entry: Entry = { layer: layer ?? L.polygon(shape, STYLE), name: z.name, kind: z.kind, extra: z.extra };
    entry.layer.setStyle(STYLE);
    entry.layer.bindTooltip(`keep out: ${z.name}`, { sticky: true });
    entry.layer.on("click", () => {
      if (this.editing) this.select(entry);
    });
    entry.layer.addTo(this.group);
    if (this.editing) entry.layer.pm.enable(EDIT_OPTIONS);
    this.entries.push(entry);
    return entry;
  }

  private start(): void {
    if (this.editing) return;
    this.editing = true;
    this.root.dataset.editing = "true";
    this.tools.hidden = false;
    this.editBtn.hidden = true;
    this.showError(null);
    this.noteText.hidden = true;
    for (const e of this.entries) e.layer.pm.enable(EDIT_OPTIONS);
    this.select(null);
    this.hooks.onEditing(true);
  }

  /** Ends editing; `revert`: the zones in force replace the edit. */
  private stop(revert: boolean): void {
    this.map.pm.disableDraw();
    for (const e of this.entries) e.layer.pm.disable();
    this.editing = false;
    this.root.dataset.editing = "false";
    this.tools.hidden = true;
    this.editBtn.hidden = false;
    this.drawBtn.classList.remove("on");
    if (revert) this.drawInForce();
    this.select(null);
    this.hooks.onEditing(false);
  }

  private draw(): void {
    this.select(null);
    this.drawBtn.classList.add("on");
    this.map.pm.enableDraw("Polygon", { allowSelfIntersection: false, finishOnEnter: true, snappable: false, pathOptions: STYLE, templineStyle: { color: STYLE.color }, hintlineStyle: { color: STYLE.color, dashArray: [5, 5] } });
  }

  private select(entry: Entry | null): void {
    this.selected = entry;
    for (const e of this.entries) e.layer.setStyle({ weight: e === entry ? 5 : 2 });
    this.nameInput.disabled = entry === null;
    this.kindSelect.disabled = entry === null;
    this.deleteBtn.disabled = entry === null;
    this.nameInput.value = entry?.name ?? "";
    // A kind read from a file that is not one of ours is offered as it is.
    if (entry && entry.kind && !Array.from(this.kindSelect.options).some((o) => o.value === entry.kind)) this.kindSelect.append(h("option", { value: entry.kind }, entry.kind));
    this.kindSelect.value = entry?.kind ?? "";
  }

  private rename(name: string): void {
    if (!this.selected) return;
    this.selected.name = name;
    this.selected.layer.setTooltipContent(`keep out: ${name}`);
  }

  private deleteSelected(): void {
    const gone = this.selected;
    if (!gone) return;
    gone.layer.pm.disable();
    this.group.removeLayer(gone.layer);
    this.entries = this.entries.filter((e) => e !== gone);
    this.select(null);
  }

  private showError(text: string | null): void {
    this.errorText.hidden = text === null;
    setText(this.errorText, text ?? "");
  }

  private async save(): Promise<void> {
    const zones: Zone[] = this.entries.map((e) => ({ name: e.name, kind: e.kind, extra: e.extra, polygons: polygonsOfLatLngs(e.layer.getLatLngs()) }));
    const problem = zonesProblem(zones);
    if (problem !== null) {
      this.showError(`Not sent: ${problem}.`);
      return;
    }
    this.saveBtn.disabled = true;
    try {
      const answer = await this.hooks.save(collectionOf(zones));
      const k = isObj(answer) ? parseKeepOut(answer) : null;
      if (k?.ok) this.inForce = k.value;
      this.stop(true);
    } catch (e) {
      this.showError(`Not saved: ${withZoneNames(e instanceof Error ? e.message : String(e), zones)}. Your edit is still on the map.`);
    } finally {
      this.saveBtn.disabled = false;
    }
  }
}
