// The live page's voice: call-outs (../lib/callouts.ts) made from each state and command outcome,
// said or not by this browser's settings (../lib/voiceSettings.ts), and the Voice tab that sets
// them — mute all, each class, only while flying — with the last call-outs written out (a call-out
// muted, or one the browser could not say, is still there to read). A quick mute sits in the
// header, since the moment to silence the station is rarely the moment to open a tab. Any role
// hears: a viewer in the recovery car wants "Landed, 6 metres from the target" as much as the
// operator does.

import { CALLOUT_CLASSES, CLASS_LABELS, CommandCallouts, isFlying, stateCallouts, type Callout, type CalloutMemory } from "../lib/callouts";
import type { CommandEntry } from "../lib/commands";
import { fmtMissionTime } from "../lib/format";
import type { State } from "../lib/types";
import { audible, parseSettings, VOICE_KEY, type VoiceSettings } from "../lib/voiceSettings";
import { h, setText } from "./dom";
import { Speaker } from "./speech";

/** The longest a refusal waits for this page's own unanswered request to claim it, ms. */
const HOLD_REFUSAL_MS = 3000;
/** Call-outs listed in the tab, newest first. */
const SHOWN = 12;

const STATUS_TEXT = {
  unavailable: "This browser cannot speak (no speech synthesis): the call-outs are only written below.",
  waiting_for_gesture: "The browser speaks only after a first click or key press on this page: click anywhere to hear the call-outs.",
  refused: "The browser refused to speak (no voice installed, or it wants a click on the page first): the call-outs are written below.",
  ready: "Call-outs are spoken.",
} as const;

/** localStorage, or nothing where the browser refuses it (private modes, file pages). */
function storage(): Storage | null {
  try {
    return window.localStorage;
  } catch {
    return null;
  }
}

export class VoicePanel {
  /** The Voice tab's content. */
  readonly root: HTMLElement;
  /** The header's quick mute. */
  readonly quick: HTMLButtonElement;
  private settings: VoiceSettings;
  private memory: CalloutMemory | null = null;
  private readonly commands = new CommandCallouts();
  private flying = false;
  private missionTime: number | null = null;
  private readonly speaker: Speaker;
  private readonly status: HTMLElement;
  private readonly said: HTMLOListElement;
  private readonly muteAll: HTMLInputElement;
  private readonly onlyFlying: HTMLInputElement;
  private readonly classBoxes: Map<(typeof CALLOUT_CLASSES)[number], HTMLInputElement>;

  constructor() {
    this.settings = parseSettings(storage()?.getItem(VOICE_KEY) ?? null);
    this.speaker = new Speaker(() => this.showStatus());
    this.status = h("p", { class: "voice-status", "data-testid": "voice-status", role: "status" });
    this.muteAll = h("input", { type: "checkbox", "data-testid": "voice-mute-all" });
    this.onlyFlying = h("input", { type: "checkbox", "data-testid": "voice-only-flying" });
    this.muteAll.addEventListener("change", () => this.change((s) => (s.muted = this.muteAll.checked)));
    this.onlyFlying.addEventListener("change", () => this.change((s) => (s.onlyWhileFlying = this.onlyFlying.checked)));
    this.classBoxes = new Map(CALLOUT_CLASSES.map((c) => {
      const box = h("input", { type: "checkbox", "data-testid": `voice-class-${c}` });
      box.addEventListener("change", () => this.change((s) => (s.classes[c] = box.checked)));
      return [c, box];
    }));
    const test = h("button", { type: "button", class: "small", "data-testid": "voice-test", title: "say a short sentence now, whatever the settings, to check the sound" }, "Test voice");
    test.addEventListener("click", () => this.speaker.say("Voice check. Call-outs come from this screen."));
    this.said = h("ol", { class: "voice-said", "data-testid": "voice-said", "aria-live": "off" });
    this.root = h("div", { class: "voice", "data-testid": "panel-voice" },
      this.status,
      h("div", { class: "voice-row" },
        h("label", { class: "voice-master" }, this.muteAll, " Mute all"),
        h("label", { title: "quiet on the pad and on the ground after the landing (the landing itself is said)" }, this.onlyFlying, " Only while flying"),
        test),
      h("fieldset", { class: "voice-classes" }, h("legend", {}, "Say"),
        ...CALLOUT_CLASSES.map((c) => h("label", {}, this.classBoxes.get(c)!, ` ${CLASS_LABELS[c]}`))),
      h("h3", {}, "Last call-outs"),
      this.said);
    this.quick = h("button", { type: "button", class: "voice-quick", "data-testid": "voice-quick", title: "voice call-outs: mute or unmute (the Voice tab sets which are said)" });
    this.quick.addEventListener("click", () => this.change((s) => (s.muted = !s.muted)));
    this.showSettings();
    this.showStatus();
  }

  /** A new state: its call-outs said (or listed as muted). */
  onState(s: State, nowMs: number): void {
    const r = stateCallouts(this.memory, s, nowMs);
    this.memory = r.memory;
    this.flying = isFlying(s.mission.stage ?? s.vehicle?.stage ?? null);
    this.missionTime = s.mission_time_s;
    for (const c of r.callouts) this.emit(c);
  }

  /** A command's entry changed (`entries`: all the page's): a refusal is said once. */
  onCommand(e: CommandEntry, entries: readonly CommandEntry[]): void {
    for (const c of this.commands.take(e, entries, this.flying)) this.emit(c);
    if (this.commands.holding) {
      setTimeout(() => {
        for (const c of this.commands.release(this.flying)) this.emit(c);
      }, HOLD_REFUSAL_MS);
    }
  }

  /** A replay jumped: the next state is a baseline, not a change. */
  restart(): void {
    this.memory = null;
  }

  private emit(c: Callout): void {
    const hear = audible(c, this.settings);
    if (hear) {
      if (c.alarm) this.speaker.beep();
      this.speaker.say(c.text);
    }
    const why = hear ? "" : this.settings.muted ? "muted" : !this.settings.classes[c.class] ? "class off" : "not flying";
    const li = h("li", { "data-testid": "voice-said-item", "data-class": c.class, "data-heard": String(hear), class: hear ? "" : "quiet" },
      h("span", { class: "voice-time" }, fmtMissionTime(this.missionTime)), " ", c.text, why ? h("small", {}, ` (${why})`) : null);
    this.said.prepend(li);
    while (this.said.childElementCount > SHOWN) this.said.lastElementChild?.remove();
  }

  private change(edit: (s: VoiceSettings) => void): void {
    edit(this.settings);
    try {
      storage()?.setItem(VOICE_KEY, JSON.stringify(this.settings));
    } catch {
      // Storage full or refused: the settings hold for this page.
    }
    this.showSettings();
    this.showStatus();
  }

  private showSettings(): void {
    const s = this.settings;
    this.muteAll.checked = s.muted;
    this.onlyFlying.checked = s.onlyWhileFlying;
    for (const [c, box] of this.classBoxes) box.checked = s.classes[c];
    this.root.classList.toggle("muted-all", s.muted);
    setText(this.quick, s.muted ? "VOICE MUTED" : "VOICE");
    this.quick.setAttribute("aria-pressed", String(s.muted));
    this.quick.dataset.state = s.muted ? "muted" : "on";
  }

  private showStatus(): void {
    const state = this.speaker.state;
    setText(this.status, this.settings.muted && state === "ready" ? "All call-outs muted." : STATUS_TEXT[state]);
    this.status.dataset.state = state;
  }
}
