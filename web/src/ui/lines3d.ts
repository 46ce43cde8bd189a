// Lines of the 3-D view whose points change with the data: a fixed buffer written in place,
// only its first points drawn, never culled (its bounds change with every point).

import * as THREE from "three";

/** A line (or separate segments) over `positions` (x, y, z per point), nothing drawn yet. */
export function dynamicLine<T extends THREE.Line>(Kind: new (g: THREE.BufferGeometry, m: THREE.Material) => T, positions: Float32Array, material: THREE.Material): T {
  const geom = new THREE.BufferGeometry();
  geom.setAttribute("position", new THREE.BufferAttribute(positions, 3));
  geom.setDrawRange(0, 0);
  const line = new Kind(geom, material);
  line.frustumCulled = false;
  return line;
}

/** Marks the line's points changed and draws the first `count`. */
export function drawPoints(line: THREE.Line, count: number): void {
  line.geometry.getAttribute("position").needsUpdate = true;
  line.geometry.setDrawRange(0, count);
}
