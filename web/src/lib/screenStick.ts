// Manual control without a gamepad: a stick on the screen, moved by the pointer or the keyboard,
// behind the same dead-man as the gamepad. Pointer: pressing the stick holds the dead-man and
// puts the stick there; letting go releases both. Keyboard (the stick or the HOLD button focused):
// Space is the dead-man, ←/→ move the main line, ↑/↓ take brake off/on, C centres. Whenever the
// dead-man is released the stick centres, so the next hold starts neutral, not where the last one
// left the canopy. Pure: the panel feeds it events and reads `sticks()`.

import { clamp, type Sticks } from "./joystick";

/** One key press (or auto-repeat) moves the stick this much. */
export const KEY_STEP = 0.1;
/** Margins of the drawn square (viewBox units of 100) that the stick's travel leaves out. */
const EDGE = 4;

export class ScreenStick {
  mainLine = 0;
  brake = 0;
  held = false;

  /** A key went down (`down`) or up; true if it was the stick's and the page must not use it. */
  key(key: string, down: boolean): boolean {
    if (key === " " || key === "Spacebar") {
      if (down) this.held = true;
      else this.release();
      return true;
    }
    if (!down) return ["ArrowLeft", "ArrowRight", "ArrowUp", "ArrowDown", "c", "C"].includes(key);
    switch (key) {
      case "ArrowLeft":
        this.mainLine = step(this.mainLine, -KEY_STEP, -1);
        return true;
      case "ArrowRight":
        this.mainLine = step(this.mainLine, KEY_STEP, -1);
        return true;
      case "ArrowUp":
        this.brake = step(this.brake, -KEY_STEP, 0);
        return true;
      case "ArrowDown":
        this.brake = step(this.brake, KEY_STEP, 0);
        return true;
      case "c":
      case "C":
        this.centre();
        return true;
      default:
        return false;
    }
  }

  /** The pointer at (x, y) of the drawn square, 0…100 each way (x right, y down): held there. */
  point(x: number, y: number): void {
    this.held = true;
    this.mainLine = clamp((x - 50) / (50 - EDGE), -1, 1);
    this.brake = clamp((y - EDGE) / (100 - 2 * EDGE), 0, 1);
  }

  /** The dead-man let go (pointer up, Space up, focus lost): released and centred. */
  release(): void {
    this.held = false;
    this.centre();
  }

  centre(): void {
    this.mainLine = 0;
    this.brake = 0;
  }

  sticks(): Sticks {
    return { mainLine: this.mainLine, brake: this.brake, deadman: this.held, buttons: 0 };
  }
}

/** `v + d` within [lo, 1], rounded to the step so that ten presses make exactly 1. */
function step(v: number, d: number, lo: number): number {
  return clamp(Math.round((v + d) / KEY_STEP) / Math.round(1 / KEY_STEP), lo, 1);
}
