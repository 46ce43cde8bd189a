// Cutdown is irreversible, so the page asks for a deliberate gesture: hold the button for 2 s.
// Releasing early cancels; only when the hold completes does the page arm (POST /api/cutdown/arm)
// and then confirm at once with the returned arm_id (POST /api/cutdown/confirm). A click — press
// and release — can therefore never send anything.
//
// The machine is pure apart from the global timer it schedules (fake timers in tests); the two
// HTTP calls are injected.

export const HOLD_MS = 2000;

export type CutdownPhase =
  | { kind: "idle" }
  | { kind: "holding"; startedMs: number }
  | { kind: "arming" }
  | { kind: "confirming"; armId: string }
  | { kind: "sent"; requestId: string }
  | { kind: "failed"; reason: string }
  | { kind: "cancelled" };

export interface CutdownDeps {
  arm: () => Promise<{ arm_id: string }>;
  confirm: (armId: string) => Promise<{ request_id: string }>;
  now?: () => number;
  onChange?: (p: CutdownPhase) => void;
  holdMs?: number;
}

export class CutdownHold {
  phase: CutdownPhase = { kind: "idle" };
  private timer: ReturnType<typeof setTimeout> | null = null;
  private readonly now: () => number;
  private readonly holdMs: number;

  constructor(private readonly deps: CutdownDeps) {
    this.now = deps.now ?? (() => Date.now());
    this.holdMs = deps.holdMs ?? HOLD_MS;
  }

  /** Busy while a request is in flight: new presses are ignored. */
  get busy(): boolean {
    return this.phase.kind === "arming" || this.phase.kind === "confirming";
  }

  /** 0…1 progress of the hold, for the ring. */
  progress(): number {
    if (this.phase.kind !== "holding") return this.phase.kind === "arming" || this.phase.kind === "confirming" ? 1 : 0;
    return Math.min(1, (this.now() - this.phase.startedMs) / this.holdMs);
  }

  press(): void {
    if (this.phase.kind === "holding" || this.busy) return;
    this.set({ kind: "holding", startedMs: this.now() });
    this.timer = setTimeout(() => {
      this.timer = null;
      void this.fire();
    }, this.holdMs);
  }

  /** Release (pointer up, leave, cancel, key up, blur): cancels an unfinished hold. */
  release(): void {
    if (this.phase.kind !== "holding") return;
    if (this.timer !== null) clearTimeout(this.timer);
    this.timer = null;
    this.set({ kind: "cancelled" });
  }

  private async fire(): Promise<void> {
    if (this.phase.kind !== "holding") return;
    this.set({ kind: "arming" });
    let armId: string;
    try {
      armId = (await this.deps.arm()).arm_id;
    } catch (e) {
      this.set({ kind: "failed", reason: `arm: ${errorText(e)}` });
      return;
    }
    this.set({ kind: "confirming", armId });
    try {
      const r = await this.deps.confirm(armId);
      this.set({ kind: "sent", requestId: r.request_id });
    } catch (e) {
      this.set({ kind: "failed", reason: `confirm: ${errorText(e)}` });
    }
  }

  private set(p: CutdownPhase): void {
    this.phase = p;
    this.deps.onChange?.(p);
  }
}

const errorText = (e: unknown): string => (e instanceof Error ? e.message : String(e));
