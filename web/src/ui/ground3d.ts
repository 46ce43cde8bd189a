// The ground of the 3-D view: a metric grid sized to the scene, the target, and the keep-out
// zones as flat red polygons (outer ring and holes) from the station's `keep_out` message.

import * as THREE from "three";
import type { V3 } from "../lib/scene3d";

/** A zone as the view draws it: its outer ring then its holes, each as scene x, z points. */
export type GroundRing = [number, number][];

export class Ground3D {
  readonly group = new THREE.Group();
  readonly target: THREE.Mesh;
  private grid: THREE.GridHelper;
  private gridSize = 0;
  private readonly zones = new THREE.Group();
  private zoneCount = 0;

  constructor() {
    this.target = new THREE.Mesh(new THREE.CylinderGeometry(20, 20, 2, 32), new THREE.MeshLambertMaterial({ color: 0xd00000 }));
    this.target.visible = false;
    this.grid = new THREE.GridHelper(2000, 20, 0x444444, 0xaaaaaa);
    this.group.add(this.grid, this.target, this.zones);
  }

  setTarget(p: V3 | null): void {
    this.target.visible = p !== null;
    if (p) this.target.position.set(...p);
  }

  /** Draws the zones, each a list of areas (outer ring then holes), just above the grid. */
  setZones(areas: GroundRing[][]): void {
    for (const m of this.zones.children) {
      const mesh = m as THREE.Mesh;
      mesh.geometry.dispose();
    }
    this.zones.clear();
    const material = new THREE.MeshBasicMaterial({ color: 0xc62828, transparent: true, opacity: 0.35, side: THREE.DoubleSide, depthWrite: false });
    for (const rings of areas) {
      const [outer, ...holes] = rings;
      if (!outer || outer.length < 3) continue;
      // The shape is drawn in x, −z and laid down on the ground (y up): rotate x by −90°.
      const shape = new THREE.Shape(outer.map(([x, z]) => new THREE.Vector2(x, -z)));
      for (const h of holes) if (h.length >= 3) shape.holes.push(new THREE.Path(h.map(([x, z]) => new THREE.Vector2(x, -z))));
      const geometry = new THREE.ShapeGeometry(shape);
      geometry.rotateX(-Math.PI / 2);
      const mesh = new THREE.Mesh(geometry, material);
      mesh.position.y = 0.5;
      mesh.name = "keep-out";
      this.zones.add(mesh);
    }
    this.zoneCount = this.zones.children.length;
  }

  get zonesDrawn(): number {
    return this.zoneCount;
  }

  /** Sizes the grid to cover `radius` around `centre` (grid lines every 100 m). */
  fit(centre: THREE.Vector3, radius: number): void {
    const size = Math.max(1000, Math.ceil((radius * 2.5) / 500) * 500);
    if (size !== this.gridSize) {
      this.group.remove(this.grid);
      this.grid.dispose();
      this.grid = new THREE.GridHelper(size, Math.round(size / 100), 0x444444, 0xbbbbbb);
      this.gridSize = size;
      this.group.add(this.grid);
    }
    this.grid.position.set(centre.x, 0, centre.z);
  }
}
