// The stack in the 3-D view: the canopy (an arced wing), the drone, capsule and transponder
// (boxes) at their attitudes, and the lines between their attachment points, all placed around
// the drone from `state.stack`. A body placed by the rigging (no IMU of its own heard) is drawn
// paler than a measured one. Far from the camera the whole group is drawn larger than life
// (`magnification`) so that a 12 m stack stays visible over kilometres; the view says so.

import * as THREE from "three";
import { applyBasis, bodyBasis, enuToScene, type V3 } from "../lib/scene3d";
import type { Stack, StackBody } from "../lib/types";
import { drawPoints, dynamicLine } from "./lines3d";

const COLOURS: Record<StackBody["body"], number> = { canopy: 0xe07000, drone: 0xffc400, capsule: 0x1f77b4, transponder: 0x2ca02c };

/** What the stack draws, for the page's tests (`window.__view3d.bodies`). */
export interface DrawnBody {
  /** Where the body's centre is drawn in the scene, m. */
  position: V3;
  roll_deg: number;
  pitch_deg: number;
  yaw_deg: number;
  source: StackBody["source"];
  /** Its forward axis as drawn, in the scene. */
  forward: V3;
}

/** An arced wing of chord × span × arc height (body axes: x forward, y right, z down). */
function canopyGeometry([chord, span, height]: V3): THREE.BufferGeometry {
  // A slice of a cylinder whose axis runs fore and aft: the arc drops `height` at the tips.
  const halfSpan = span / 2;
  const radius = (halfSpan * halfSpan + height * height) / (2 * height);
  const angle = 2 * Math.asin(Math.min(1, halfSpan / radius));
  const g = new THREE.CylinderGeometry(radius, radius, chord, 24, 1, true, -angle / 2, angle);
  // The cylinder's axis is y and its arc is centred on +z: turn the axis to x (forward) and
  // the arc's crown to −z (up, in body axes), then bring the crown half the height above the
  // body's centre and the tips half below.
  g.rotateZ(Math.PI / 2);
  g.rotateX(Math.PI);
  g.translate(0, 0, radius - height / 2);
  return g;
}

export class Stack3D {
  readonly group = new THREE.Group();
  private readonly meshes = new Map<StackBody["body"], THREE.Mesh>();
  private readonly lines: THREE.LineSegments;
  private readonly linePositions = new Float32Array(4 * 2 * 3);
  drawn: Record<string, DrawnBody> = {};
  magnification = 1;

  constructor() {
    this.lines = dynamicLine(THREE.LineSegments, this.linePositions, new THREE.LineBasicMaterial({ color: 0x333333 }));
    this.group.add(this.lines);
    this.group.visible = false;
  }

  private mesh(b: StackBody): THREE.Mesh {
    let m = this.meshes.get(b.body);
    if (!m) {
      const geometry = b.body === "canopy" ? canopyGeometry(b.size_m) : new THREE.BoxGeometry(...b.size_m);
      m = new THREE.Mesh(geometry, new THREE.MeshLambertMaterial({ color: COLOURS[b.body], side: THREE.DoubleSide, transparent: true }));
      m.matrixAutoUpdate = false;
      m.name = b.body;
      this.meshes.set(b.body, m);
      this.group.add(m);
    }
    return m;
  }

  /** Places the stack around the drone drawn at `drone` (scene, m), `magnification` × life. */
  update(stack: Stack | null, drone: V3 | null, magnification: number): void {
    if (!stack || !drone) {
      this.group.visible = false;
      this.drawn = {};
      return;
    }
    this.magnification = magnification;
    this.group.visible = true;
    this.group.position.set(...drone);
    this.group.scale.setScalar(magnification);
    this.group.updateMatrixWorld(true);
    const drawn: Record<string, DrawnBody> = {};
    for (const b of stack.bodies) {
      const m = this.mesh(b);
      const basis = bodyBasis(b.roll_deg, b.pitch_deg, b.yaw_deg);
      const [x, y, z] = enuToScene(b.position_enu_m);
      // The basis's columns are the body's axes in the scene, its origin the body's centre.
      const [fx, fy, fz] = applyBasis(basis, [1, 0, 0]);
      const [rx, ry, rz] = applyBasis(basis, [0, 1, 0]);
      const [dx, dy, dz] = applyBasis(basis, [0, 0, 1]);
      m.matrix.set(fx, rx, dx, x, fy, ry, dy, y, fz, rz, dz, z, 0, 0, 0, 1);
      m.matrixWorldNeedsUpdate = true;
      (m.material as THREE.MeshLambertMaterial).opacity = b.source === "measured" ? 1 : 0.45;
      m.visible = true;
      drawn[b.body] = {
        position: [drone[0] + x * magnification, drone[1] + y * magnification, drone[2] + z * magnification],
        roll_deg: b.roll_deg,
        pitch_deg: b.pitch_deg,
        yaw_deg: b.yaw_deg,
        source: b.source,
        forward: applyBasis(basis, [1, 0, 0]),
      };
    }
    for (const [name, m] of this.meshes) if (!drawn[name]) m.visible = false;
    let n = 0;
    for (const l of stack.lines.slice(0, 4)) {
      this.linePositions.set([...enuToScene(l.top_enu_m), ...enuToScene(l.bottom_enu_m)], n * 6);
      n += 1;
    }
    drawPoints(this.lines, n * 2);
    this.drawn = drawn;
  }

  /** Lines drawn. */
  get lineCount(): number {
    return this.lines.geometry.drawRange.count / 2;
  }
}
