// The REPLAY bar: shown only when the station replays a recording (`stx replay`). Says so in
// large letters, and lets the operator pause, seek on the timeline and change the speed (any the
// station accepts, typed or picked from the usual ones); the station answers with the replay's
// new position, which the next `state` confirms. After a seek it says "seeking…" until the
// station shows the new position (it runs the recording up to it first).

import { h, setText } from "./dom";
import { MAX_SPEED, MIN_SPEED, parseSpeed } from "../lib/replaySeek";
import type { Replay } from "../lib/types";
import type * as Wire from "../generated/api";

/** Speeds offered in the box's list; any other within the station's range may be typed. */
export const REPLAY_SPEEDS = [0.25, 0.5, 1, 2, 4, 8, 16, 32, 64] as const;

/** `m:ss` (or `h:mm:ss`) of a duration in ms. */
export function clockText(ms: number): string {
  const s = Math.max(0, Math.floor(ms / 1000));
  const hh = Math.floor(s / 3600);
  const mm = Math.floor((s % 3600) / 60);
  const ss = String(s % 60).padStart(2, "0");
  return hh > 0 ? `${hh}:${String(mm).padStart(2, "0")}:${ss}` : `${mm}:${ss}`;
}

export class ReplayBar {
  readonly root: HTMLElement;
  private readonly toggle: HTMLButtonElement;
  private readonly seek: HTMLInputElement;
  private readonly position: HTMLElement;
  private readonly speed: HTMLInputElement;
  private readonly info: HTMLElement;
  private paused = false;
  /** While the operator drags the slider, the station's position does not move it. */
  private dragging = false;
  /** The epoch shown when the operator sought, until the station shows a newer one. */
  private seekingFrom: number | null = null;
  private epoch: number | null = null;

  constructor(private readonly control: (body: Wire.ReplayBody) => Promise<void>) {
    this.toggle = h("button", { "data-testid": "replay-toggle", title: "pause or play the replay" }, "Pause") as HTMLButtonElement;
    this.seek = h("input", { type: "range", min: "0", max: "0", step: "1000", value: "0", "data-testid": "replay-seek", "aria-label": "replay position" }) as HTMLInputElement;
    this.position = h("span", { class: "replay-pos", "data-testid": "replay-position" }, "—");
    this.speed = h("input", {
      type: "number", min: String(MIN_SPEED), max: String(MAX_SPEED), step: "any", list: "replay-speeds", class: "replay-speed",
      "data-testid": "replay-speed", "aria-label": "replay speed, × real time", title: `replay speed, ${MIN_SPEED}–${MAX_SPEED}× real time`,
    }) as HTMLInputElement;
    const speeds = h("datalist", { id: "replay-speeds" }, ...REPLAY_SPEEDS.map((s) => h("option", { value: String(s) })));
    this.info = h("span", { class: "replay-file", "data-testid": "replay-file" });
    this.root = h("div", { class: "replay-bar", "data-testid": "replay-bar", role: "region", "aria-label": "replay", hidden: true },
      h("strong", { class: "replay-badge", "data-testid": "replay-badge" }, "REPLAY"), this.toggle, this.seek, this.position, this.speed, h("span", {}, "×"), speeds, this.info);
    this.toggle.addEventListener("click", () => void this.control({ paused: !this.paused }));
    this.seek.addEventListener("input", () => {
      this.dragging = true;
    });
    this.seek.addEventListener("change", () => {
      this.dragging = false;
      this.seekingFrom = this.epoch ?? -1;
      void this.control({ position_ms: Number(this.seek.value) });
    });
    this.speed.addEventListener("change", () => {
      const v = parseSpeed(this.speed.value);
      this.speed.setCustomValidity(v.ok ? "" : v.error);
      this.speed.title = v.ok ? `replay speed, ${MIN_SPEED}–${MAX_SPEED}× real time` : v.error;
      if (v.ok) void this.control({ speed: v.value });
      else this.speed.reportValidity();
    });
  }

  update(r: Replay | null): void {
    this.root.hidden = r === null;
    document.body.classList.toggle("replaying", r !== null);
    if (r === null) return;
    this.paused = r.paused === true;
    this.epoch = r.epoch;
    if (this.seekingFrom !== null && r.epoch !== null && r.epoch > this.seekingFrom && r.seeking !== true) this.seekingFrom = null;
    const seeking = this.seekingFrom !== null || r.seeking === true;
    setText(this.toggle, this.paused ? "Play" : "Pause");
    const duration = r.duration_ms ?? 0;
    const at = r.position_ms ?? 0;
    this.seek.max = String(duration);
    if (!this.dragging && !seeking) this.seek.value = String(at);
    setText(this.position, `${clockText(at)} / ${clockText(duration)}${seeking ? " (seeking…)" : r.finished ? " (end)" : this.paused ? " (paused)" : ""}`);
    this.root.dataset.paused = String(this.paused);
    this.root.dataset.positionMs = String(at);
    this.root.dataset.epoch = String(r.epoch ?? "");
    this.root.dataset.seeking = String(seeking);
    if (r.speed !== null && document.activeElement !== this.speed) {
      this.speed.value = String(r.speed);
      this.speed.setCustomValidity("");
    }
    const started = r.start_ms === null ? "" : ` · recorded ${new Date(r.start_ms).toISOString().replace("T", " ").slice(0, 19)} UTC`;
    setText(this.info, `${r.mode === "recorded" ? "as recorded" : "re-run"} · ${r.file}${started}`);
  }
}
