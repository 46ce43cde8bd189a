// The plan in the 3-D view: the guidance pattern as a loop at the final-approach height, the
// final approach from its entry down to the target (what the 2-D map draws as the pattern and the
// final line, lifted to their heights), and the glide cone: apex at the target, its rim at the
// drone's height with radius height × the current glide ratio. From inside the cone the target is
// within a straight glide in still air.

import * as THREE from "three";
import { coneRadius, type V3 } from "../lib/scene3d";
import { drawPoints, dynamicLine } from "./lines3d";

const MAX_PATH = 64;

export class Plan3D {
  readonly group = new THREE.Group();
  private readonly path: THREE.Line;
  private readonly pathPositions = new Float32Array(MAX_PATH * 3);
  private readonly final: THREE.Line;
  private readonly finalPositions = new Float32Array(2 * 3);
  private readonly cone: THREE.Mesh;
  /** The cone as drawn: apex, height and rim radius, m; null when hidden. */
  coneShown: { apex: V3; height_m: number; radius_m: number; glide_ratio: number } | null = null;
  pathPoints = 0;
  finalShown = false;

  constructor() {
    const line = (positions: Float32Array, color: number, dashed: boolean): THREE.Line => {
      const material = dashed ? new THREE.LineDashedMaterial({ color, dashSize: 20, gapSize: 12 }) : new THREE.LineBasicMaterial({ color });
      const l = dynamicLine(THREE.Line, positions, material);
      this.group.add(l);
      return l;
    };
    this.path = line(this.pathPositions, 0x7b1fa2, true);
    this.final = line(this.finalPositions, 0x00897b, false);
    // A unit cone, apex down at the origin, rim at y = 1: scaled per update.
    const g = new THREE.ConeGeometry(1, 1, 48, 1, true);
    g.rotateX(Math.PI);
    g.translate(0, 0.5, 0);
    this.cone = new THREE.Mesh(g, new THREE.MeshBasicMaterial({ color: 0x00897b, transparent: true, opacity: 0.12, side: THREE.DoubleSide, depthWrite: false }));
    this.cone.visible = false;
    this.group.add(this.cone);
  }

  /** The pattern's corners and the final approach's entry, both at `height`, and the target; null: none. */
  setPlan(corners: V3[], finalEntry: V3 | null, target: V3 | null): void {
    const first = corners[0];
    const loop = first && corners.length >= 2 ? [...corners, first].slice(0, MAX_PATH) : [];
    loop.forEach((p, i) => this.pathPositions.set(p, i * 3));
    drawPoints(this.path, loop.length);
    if (loop.length > 1) this.path.computeLineDistances();
    this.pathPoints = loop.length;
    this.finalShown = finalEntry !== null && target !== null;
    if (finalEntry && target) this.finalPositions.set([...finalEntry, ...target]);
    drawPoints(this.final, this.finalShown ? 2 : 0);
  }

  /** The glide cone on `target` up to the drone's `height_m` above it; hidden without a glide ratio. */
  setCone(target: V3 | null, height_m: number | null, glideRatio: number | null): void {
    const r = target && height_m !== null && height_m > 0 && glideRatio !== null && glideRatio > 0 ? coneRadius(height_m, glideRatio) : 0;
    this.cone.visible = r > 0;
    if (!target || r <= 0 || height_m === null || glideRatio === null) {
      this.coneShown = null;
      return;
    }
    this.cone.position.set(...target);
    this.cone.scale.set(r, height_m, r);
    this.coneShown = { apex: target, height_m, radius_m: r, glide_ratio: glideRatio };
  }
}
