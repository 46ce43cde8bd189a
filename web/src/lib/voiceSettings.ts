// Who hears which call-out (callouts.ts) on this browser: mute for all, per class, and "only while
// flying". Kept in localStorage, per browser rather than per station or role: it is the person at
// this screen (an operator in a noisy tent, a viewer in the recovery car) who chooses.

import { CALLOUT_CLASSES, type Callout, type CalloutClass } from "./callouts";

export const VOICE_KEY = "stx.voice";

export interface VoiceSettings {
  /** Nothing is said. */
  muted: boolean;
  /** Only call-outs made while the stack flies (and its landing): the pad and the ground after are quiet. */
  onlyWhileFlying: boolean;
  /** Each class on or off. */
  classes: Record<CalloutClass, boolean>;
}

/** Everything said, on the pad too: a station nobody set up still speaks when something happens. */
export function defaultSettings(): VoiceSettings {
  return { muted: false, onlyWhileFlying: false, classes: Object.fromEntries(CALLOUT_CLASSES.map((c) => [c, true])) as Record<CalloutClass, boolean> };
}

/** The settings stored (a garbled or older entry gives the defaults for what it lacks). */
export function parseSettings(raw: string | null): VoiceSettings {
  const s = defaultSettings();
  let v: unknown;
  try {
    v = JSON.parse(raw ?? "null");
  } catch {
    return s;
  }
  if (typeof v !== "object" || v === null) return s;
  const o = v as Record<string, unknown>;
  if (typeof o.muted === "boolean") s.muted = o.muted;
  if (typeof o.onlyWhileFlying === "boolean") s.onlyWhileFlying = o.onlyWhileFlying;
  if (typeof o.classes === "object" && o.classes !== null) {
    const c = o.classes as Record<string, unknown>;
    for (const k of CALLOUT_CLASSES) if (typeof c[k] === "boolean") s.classes[k] = c[k];
  }
  return s;
}

/** Whether this browser says a call-out. */
export function audible(c: Callout, s: VoiceSettings): boolean {
  return !s.muted && s.classes[c.class] && (!s.onlyWhileFlying || c.inFlight);
}
