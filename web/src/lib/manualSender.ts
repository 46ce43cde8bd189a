// When may the page send joystick commands? Only while every condition holds: operator role,
// socket open, page focused and visible, sticks to read (a gamepad or the on-screen stick), and the dead-man held. The moment
// one fails the stream stops — the station then stops uplinking within 0.5 s (API.md). While it
// holds, messages go out at a steady 10 Hz from a timer, not from input events, so the rate is
// what the station expects whatever the gamepad or the display does. When a stream ends for any
// reason but a dead socket, one `manual_release` follows, so the station stops at once rather
// than after its 0.5 s silence timeout (a released dead-man must not fly on for half a second).
//
// Timers come from the global scope so tests drive them with fake timers; `now` is injectable.

import type { ManualMsg, ManualReleaseMsg } from "./types";

export const MANUAL_RATE_HZ = 10;

export interface ManualGate {
  operator: boolean;
  socketOpen: boolean;
  focused: boolean;
  visible: boolean;
  /** A gamepad, or the on-screen stick (lib/screenStick.ts), to read. */
  sticksConnected: boolean;
  deadman: boolean;
}

/** Why sending is not allowed (first failing condition), or null if it is. */
export function blockedBy(g: ManualGate): string | null {
  if (!g.operator) return "operator role required";
  if (!g.socketOpen) return "disconnected";
  if (!g.sticksConnected) return "no sticks";
  if (!g.visible) return "page hidden";
  if (!g.focused) return "page not focused";
  if (!g.deadman) return "dead-man released";
  return null;
}

export interface ManualSenderDeps {
  /** Sends one message; false if it could not be sent (socket gone), which stops the stream. */
  send: (m: ManualMsg | ManualReleaseMsg) => boolean;
  /** The current stick message, or null if the sticks vanished (a gamepad unplugged). */
  sample: () => ManualMsg | null;
  now?: () => number;
  rateHz?: number;
}

export class ManualSender {
  private timer: ReturnType<typeof setInterval> | null = null;
  private readonly deps: Required<ManualSenderDeps>;
  /** Messages sent since the page loaded. */
  sent = 0;
  /** `manual_release` messages sent since the page loaded (one per ended stream). */
  releases = 0;
  lastSentMs: number | null = null;
  lastMsg: ManualMsg | null = null;
  /** Why we are not sending (null while sending). */
  blocked: string | null = "dead-man released";
  private readonly recent: number[] = [];

  constructor(deps: ManualSenderDeps) {
    this.deps = { now: () => Date.now(), rateHz: MANUAL_RATE_HZ, ...deps };
  }

  get sending(): boolean {
    return this.timer !== null;
  }

  /** Re-evaluates the gate; starts or stops the stream accordingly. Cheap to call often. */
  update(g: ManualGate): void {
    const why = blockedBy(g);
    if (why !== null) {
      this.stop(why);
      return;
    }
    this.blocked = null;
    if (this.timer !== null) return;
    this.timer = setInterval(() => this.tick(), 1000 / this.deps.rateHz);
    this.tick(); // the first message goes at once, not one period late
  }

  stop(why: string): void {
    this.blocked = why;
    if (this.timer === null) return;
    clearInterval(this.timer);
    this.timer = null;
    // Only a stream that ran is released, and only once: the gate is re-evaluated at 50 Hz and
    // every later stop finds the timer already gone. A closed socket cannot carry it; the
    // station's own timeout covers that case.
    if (why !== "disconnected" && this.deps.send({ type: "manual_release" })) this.releases += 1;
  }

  /** Measured send rate over the last second, Hz. */
  rateHz(): number {
    const now = this.deps.now();
    while (this.recent.length > 0 && (this.recent[0] ?? 0) <= now - 1000) this.recent.shift();
    return this.recent.length;
  }

  private tick(): void {
    const msg = this.deps.sample();
    if (msg === null) {
      this.stop("no sticks");
      return;
    }
    if (!this.deps.send(msg)) {
      this.stop("disconnected");
      return;
    }
    const now = this.deps.now();
    this.sent += 1;
    this.lastSentMs = now;
    this.lastMsg = msg;
    this.recent.push(now);
    if (this.recent.length > 4 * this.deps.rateHz) this.recent.shift();
  }
}
