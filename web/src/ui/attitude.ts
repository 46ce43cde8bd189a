// Attitude indicator (roll and pitch) and compass (heading, course, wind). SVG, redrawn by
// transforms only. Roll is positive right wing down; the horizon turns the other way.

import { s, setAttr, setText, h } from "./dom";
import { fmt, fmtDir, wrap360 } from "../lib/format";
import type { N } from "../lib/types";

const PITCH_PX_PER_DEG = 2.2;

export class AttitudeIndicator {
  readonly root: HTMLElement;
  private readonly horizon: SVGGElement;
  private readonly rollText: HTMLElement;
  private readonly pitchText: HTMLElement;

  constructor() {
    const clip = s("clipPath", { id: "att-clip" }, s("circle", { cx: 0, cy: 0, r: 70 }));
    const ladder: SVGElement[] = [];
    for (const p of [-20, -10, 10, 20]) {
      const y = -p * PITCH_PX_PER_DEG;
      ladder.push(s("line", { x1: -18, x2: 18, y1: y, y2: y, stroke: "#fff", "stroke-width": 2 }));
      ladder.push(s("text", { x: 22, y: y + 4, fill: "#fff", "font-size": 10 }, String(Math.abs(p))));
    }
    this.horizon = s("g", {},
      s("rect", { x: -200, y: -400, width: 400, height: 400, fill: "#1d63c9" }),
      s("rect", { x: -200, y: 0, width: 400, height: 400, fill: "#7a4a1c" }),
      s("line", { x1: -200, x2: 200, y1: 0, y2: 0, stroke: "#fff", "stroke-width": 2.5 }),
      ...ladder,
    );
    const ticks: SVGElement[] = [];
    for (const a of [-60, -45, -30, -20, -10, 0, 10, 20, 30, 45, 60]) {
      const r = a * Math.PI / 180;
      const len = a % 30 === 0 ? 10 : 6;
      ticks.push(s("line", { x1: 70 * Math.sin(r), y1: -70 * Math.cos(r), x2: (70 - len) * Math.sin(r), y2: -(70 - len) * Math.cos(r), stroke: "#000", "stroke-width": 2 }));
    }
    const svg = s("svg", { viewBox: "-80 -80 160 160", class: "instrument", role: "img", "aria-label": "attitude indicator" },
      s("defs", {}, clip),
      s("g", { "clip-path": "url(#att-clip)" }, this.horizon),
      s("circle", { cx: 0, cy: 0, r: 70, fill: "none", stroke: "#000", "stroke-width": 3 }),
      ...ticks,
      // The aircraft symbol is fixed: wings and a centre dot, black edged yellow for sunlight.
      s("path", { d: "M -45 0 H -15 L -8 8 M 45 0 H 15 L 8 8", stroke: "#000", "stroke-width": 6, fill: "none" }),
      s("path", { d: "M -45 0 H -15 L -8 8 M 45 0 H 15 L 8 8", stroke: "#ffd400", "stroke-width": 3, fill: "none" }),
      s("circle", { cx: 0, cy: 0, r: 3, fill: "#ffd400", stroke: "#000" }),
    );
    this.rollText = h("span", { "data-testid": "ro-roll" });
    this.pitchText = h("span", { "data-testid": "ro-pitch" });
    this.root = h("div", { class: "inst" }, svg as unknown as Node, h("div", { class: "inst-cap" }, "roll ", this.rollText, h("br"), "pitch ", this.pitchText));
  }

  update(roll: N, pitch: N): void {
    const r = roll ?? 0;
    const p = Math.max(-40, Math.min(40, pitch ?? 0));
    setAttr(this.horizon, "transform", `rotate(${(-r).toFixed(1)}) translate(0 ${(p * PITCH_PX_PER_DEG).toFixed(1)})`);
    setText(this.rollText, fmt(roll, "°"));
    setText(this.pitchText, fmt(pitch, "°"));
  }
}

export class Compass {
  readonly root: HTMLElement;
  private readonly card: SVGGElement;
  private readonly course: SVGGElement;
  private readonly wind: SVGGElement;
  private readonly headingText: HTMLElement;
  private readonly courseText: HTMLElement;

  constructor() {
    const marks: SVGElement[] = [];
    for (let a = 0; a < 360; a += 10) {
      const r = a * Math.PI / 180;
      const len = a % 30 === 0 ? 10 : 5;
      marks.push(s("line", { x1: 68 * Math.sin(r), y1: -68 * Math.cos(r), x2: (68 - len) * Math.sin(r), y2: -(68 - len) * Math.cos(r), stroke: "#000", "stroke-width": a % 90 === 0 ? 3 : 1.5 }));
    }
    for (const [a, t] of [[0, "N"], [90, "E"], [180, "S"], [270, "W"]] as const) {
      const r = a * Math.PI / 180;
      marks.push(s("text", { x: 48 * Math.sin(r), y: -48 * Math.cos(r) + 6, "text-anchor": "middle", "font-size": 17, "font-weight": 700, fill: a === 0 ? "#b00000" : "#000", transform: `rotate(${a} ${48 * Math.sin(r)} ${-48 * Math.cos(r)})` }, t));
    }
    this.card = s("g", {}, ...marks);
    // Course over ground: a magenta triangle on the ring.
    this.course = s("g", {}, s("path", { d: "M 0 -70 L -7 -56 L 7 -56 Z", fill: "#c000c0", stroke: "#000" }));
    // Wind: an arrow through the centre pointing where the wind blows to.
    this.wind = s("g", {}, s("path", { d: "M 0 34 L 0 -30 M -8 -18 L 0 -32 L 8 -18", stroke: "#006b8f", "stroke-width": 4, fill: "none" }));
    const svg = s("svg", { viewBox: "-80 -80 160 160", class: "instrument", role: "img", "aria-label": "compass: heading, course (magenta) and wind (blue, blowing to)" },
      s("circle", { cx: 0, cy: 0, r: 72, fill: "#fff", stroke: "#000", "stroke-width": 3 }),
      this.card, this.wind, this.course,
      // Lubber line: the nose, fixed at the top.
      s("path", { d: "M 0 -78 L -6 -66 L 6 -66 Z", fill: "#000" }),
      s("path", { d: "M 0 -20 L 10 14 L 0 8 L -10 14 Z", fill: "#ffd400", stroke: "#000", "stroke-width": 2 }),
    );
    this.headingText = h("span", { "data-testid": "ro-heading" });
    this.courseText = h("span", { "data-testid": "ro-course" });
    this.root = h("div", { class: "inst" }, svg as unknown as Node, h("div", { class: "inst-cap" }, "heading ", this.headingText, h("br"), "course ", this.courseText));
  }

  update(heading: N, course: N, windFrom: N): void {
    const hd = heading ?? 0;
    setAttr(this.card, "transform", `rotate(${(-hd).toFixed(1)})`);
    setAttr(this.course, "transform", `rotate(${course === null ? 0 : wrap360(course - hd).toFixed(1)})`);
    setAttr(this.course, "visibility", course === null ? "hidden" : "visible");
    setAttr(this.wind, "transform", `rotate(${windFrom === null ? 0 : wrap360(windFrom + 180 - hd).toFixed(1)})`);
    setAttr(this.wind, "visibility", windFrom === null ? "hidden" : "visible");
    setText(this.headingText, fmtDir(heading));
    setText(this.courseText, fmtDir(course));
  }
}
