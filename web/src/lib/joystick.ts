// Maps a gamepad to the `manual` message of API.md. The mapping follows the browser's "standard"
// gamepad layout: axes [0] left x, [1] left y (down +), [2] right x, [3] right y; buttons[0] is the
// bottom face button (our dead-man), buttons[6]/[7] the left/right triggers (analogue 0…1).
//
// Message fields follow MAVLink MANUAL_CONTROL as API.md names them: `y` (roll, right stick
// left/right) drives the main line −1…1; `z` (throttle) drives the symmetric brake 0…1.

import type { ManualMsg } from "./types";

/** Stick travel ignored around centre, so a resting stick commands exactly zero. */
export const DEADZONE = 0.08;
export const DEADMAN_BUTTON = 0;
const RIGHT_X = 2;
const LEFT_Y = 1;
const RIGHT_TRIGGER = 7;
const LEFT_TRIGGER = 6;

/** The part of `Gamepad` we read, so tests can hand in plain objects. */
export interface PadLike {
  connected: boolean;
  axes: readonly number[];
  buttons: readonly { pressed: boolean; value: number }[];
}

export const clamp = (v: number, lo: number, hi: number): number => Math.min(hi, Math.max(lo, v));

/** Removes the dead zone and rescales so full travel still reaches ±1. */
export function applyDeadzone(v: number, dz = DEADZONE): number {
  if (!Number.isFinite(v)) return 0;
  const a = Math.abs(v);
  if (a <= dz) return 0;
  return Math.sign(v) * clamp((a - dz) / (1 - dz), 0, 1);
}

export interface Sticks {
  /** Main line command, −1 (left) … 1 (right). */
  mainLine: number;
  /** Symmetric brake command, 0 … 1. */
  brake: number;
  deadman: boolean;
  buttons: number;
}

export function readSticks(pad: PadLike): Sticks {
  const axis = (i: number): number => applyDeadzone(pad.axes[i] ?? 0);
  const trig = (i: number): number => clamp(pad.buttons[i]?.value ?? 0, 0, 1);
  // Brakes from whichever source is used: a trigger, or the left stick pulled back (down is +y).
  const brake = clamp(Math.max(trig(RIGHT_TRIGGER), trig(LEFT_TRIGGER), axis(LEFT_Y)), 0, 1);
  let buttons = 0;
  pad.buttons.slice(0, 16).forEach((b, i) => {
    if (b.pressed) buttons |= 1 << i;
  });
  return { mainLine: clamp(axis(RIGHT_X), -1, 1), brake, deadman: pad.buttons[DEADMAN_BUTTON]?.pressed === true, buttons };
}

export function manualMessage(s: Sticks): ManualMsg {
  return { type: "manual", x: 0, y: s.mainLine, z: s.brake, r: 0, buttons: s.buttons };
}

/** First connected pad in a `navigator.getGamepads()` result (which may hold nulls). */
export function firstPad<T extends PadLike>(pads: readonly (T | null)[] | null | undefined): T | null {
  if (!pads) return null;
  for (const p of pads) if (p && p.connected) return p;
  return null;
}
