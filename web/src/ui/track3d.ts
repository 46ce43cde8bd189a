// The track in the 3-D view: one line through every position heard, newest kept when it grows
// past `MAX_POINTS`, with the box that bounds it for framing.

import * as THREE from "three";
import { drawPoints, dynamicLine } from "./lines3d";

const MAX_POINTS = 20_000;

export class Track3D {
  readonly line: THREE.Line;
  private readonly positions = new Float32Array(MAX_POINTS * 3);
  count = 0;

  constructor() {
    this.line = dynamicLine(THREE.Line, this.positions, new THREE.LineBasicMaterial({ color: 0x0b2f8a }));
  }

  clear(): void {
    this.count = 0;
    this.line.geometry.setDrawRange(0, 0);
  }

  add(v: THREE.Vector3): void {
    if (this.count >= MAX_POINTS) {
      // Keep the newest: shift by a tenth at once rather than one at a time.
      const drop = MAX_POINTS / 10;
      this.positions.copyWithin(0, drop * 3, this.count * 3);
      this.count -= drop;
    }
    this.positions.set([v.x, v.y, v.z], this.count * 3);
    this.count += 1;
    drawPoints(this.line, this.count);
  }

  /** The box around the track. */
  bounds(): THREE.Box3 {
    const box = new THREE.Box3();
    for (let i = 0; i < this.count; i++) box.expandByPoint(new THREE.Vector3(this.positions[i * 3], this.positions[i * 3 + 1], this.positions[i * 3 + 2]));
    return box;
  }
}
