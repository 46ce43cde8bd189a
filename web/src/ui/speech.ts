// The browser's voice and a short tone: `speechSynthesis` for the words, WebAudio for the tone
// before an alarm. Browsers speak and play only after a person has clicked or typed on the page
// (autoplay rules), and some have no speech at all: this says which, so the panel can tell the
// operator instead of failing silently, and it never throws into the page.

export type SpeechState = "unavailable" | "waiting_for_gesture" | "refused" | "ready";

/** The tone before an alarm: two short beeps, high enough to cut through a tent's noise. */
const BEEP_HZ = 880;
const BEEP_S = 0.12;

export class Speaker {
  private readonly synth: SpeechSynthesis | null;
  private audio: AudioContext | null = null;
  private refused = false;
  private gestured: boolean;

  constructor(private readonly onChange: () => void) {
    this.synth = typeof window !== "undefined" && "speechSynthesis" in window && typeof SpeechSynthesisUtterance === "function" ? window.speechSynthesis : null;
    this.gestured = navigator.userActivation?.hasBeenActive ?? true;
    if (!this.gestured) {
      const woke = (): void => {
        this.gestured = true;
        this.refused = false;
        // A context made before the gesture starts suspended: resume it now that it may play.
        void this.audio?.resume().catch(() => {});
        window.removeEventListener("pointerdown", woke, true);
        window.removeEventListener("keydown", woke, true);
        this.onChange();
      };
      window.addEventListener("pointerdown", woke, true);
      window.addEventListener("keydown", woke, true);
    }
  }

  get state(): SpeechState {
    if (this.synth === null) return "unavailable";
    if (!this.gestured) return "waiting_for_gesture";
    return this.refused ? "refused" : "ready";
  }

  /** Says `text`; before the page's first gesture nothing (the browser would refuse it). */
  say(text: string): void {
    if (this.synth === null || !this.gestured) return;
    try {
      const u = new SpeechSynthesisUtterance(text);
      u.lang = "en-GB";
      u.onerror = (e) => {
        // "not-allowed": the browser wants a gesture first (or the system has no voice).
        if (e.error === "not-allowed" || e.error === "synthesis-unavailable") {
          this.refused = true;
          this.onChange();
        }
      };
      this.synth.speak(u);
    } catch {
      this.refused = true;
      this.onChange();
    }
  }

  /** Two short beeps; nothing where WebAudio is missing or not yet allowed. */
  beep(): void {
    if (!this.gestured) return;
    try {
      this.audio ??= new AudioContext();
      const ctx = this.audio;
      for (const start of [0, BEEP_S * 1.8]) {
        const osc = ctx.createOscillator();
        const gain = ctx.createGain();
        osc.frequency.value = BEEP_HZ;
        gain.gain.value = 0.2;
        osc.connect(gain).connect(ctx.destination);
        osc.start(ctx.currentTime + start);
        osc.stop(ctx.currentTime + start + BEEP_S);
      }
    } catch {
      // No WebAudio here: the words still come.
    }
  }
}
