// 3-D view of the descent (three.js): the track as a line in local metres around the session
// origin (x east, y up, z south), the vehicle, the target on a ground grid; orbit by drag, zoom by
// wheel. Rendered on demand (new data or camera moves), not in a loop: the cores are shared.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { h } from "./dom";
import { toLocal } from "../lib/geo";
import type { LatLon, State, TrackPoint } from "../lib/types";

const MAX_POINTS = 20_000;

function webglAvailable(): boolean {
  try {
    const c = document.createElement("canvas");
    return c.getContext("webgl2") !== null || c.getContext("webgl") !== null;
  } catch {
    return false;
  }
}

export class View3D {
  readonly root: HTMLElement;
  private renderer: THREE.WebGLRenderer | null = null;
  private readonly scene = new THREE.Scene();
  private readonly camera = new THREE.PerspectiveCamera(50, 1, 1, 200_000);
  private controls: OrbitControls | null = null;
  private readonly line: THREE.Line;
  private readonly positions = new Float32Array(MAX_POINTS * 3);
  private count = 0;
  private readonly vehicle: THREE.Mesh;
  private readonly target: THREE.Mesh;
  private grid: THREE.GridHelper;
  private gridSize = 0;
  private pending = false;
  /** Scene radius at the last automatic framing, m. */
  private framedRadius = 0;
  /** Set once the operator orbits or zooms: automatic framing stops. */
  private userMoved = false;
  private updates = 0;

  constructor(private readonly origin: LatLon & { alt_msl_m: number | null }) {
    this.root = h("div", { class: "view3d", "data-testid": "view3d", "aria-label": "3-D view of the descent; drag to orbit, wheel to zoom" });
    this.scene.background = new THREE.Color(0xf4f6fa);
    this.scene.add(new THREE.AmbientLight(0xffffff, 1.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(1000, 3000, 500);
    this.scene.add(sun);
    const geom = new THREE.BufferGeometry();
    geom.setAttribute("position", new THREE.BufferAttribute(this.positions, 3));
    geom.setDrawRange(0, 0);
    this.line = new THREE.Line(geom, new THREE.LineBasicMaterial({ color: 0x0b2f8a }));
    this.line.frustumCulled = false;
    this.scene.add(this.line);
    this.vehicle = new THREE.Mesh(new THREE.ConeGeometry(12, 36, 12), new THREE.MeshLambertMaterial({ color: 0xffc400 }));
    this.vehicle.visible = false;
    this.scene.add(this.vehicle);
    this.target = new THREE.Mesh(new THREE.CylinderGeometry(20, 20, 2, 32), new THREE.MeshLambertMaterial({ color: 0xd00000 }));
    this.scene.add(this.target);
    this.grid = new THREE.GridHelper(2000, 20, 0x444444, 0xaaaaaa);
    this.scene.add(this.grid);
    this.camera.position.set(-1500, 1200, 1500);
    if (!webglAvailable()) {
      this.root.append(h("p", { class: "muted", "data-testid": "view3d-unavailable" }, "3-D view unavailable: this browser has no WebGL."));
      return;
    }
    this.renderer = new THREE.WebGLRenderer({ antialias: true });
    this.renderer.setPixelRatio(Math.min(2, window.devicePixelRatio));
    this.root.append(this.renderer.domElement);
    this.controls = new OrbitControls(this.camera, this.renderer.domElement);
    this.controls.addEventListener("change", () => this.requestRender());
    this.controls.addEventListener("start", () => (this.userMoved = true));
  }

  /** Local frame: x east, y up (above the origin's altitude), z south (three is right-handed, y up). */
  private local(p: LatLon, alt: number | null): THREE.Vector3 {
    const en = toLocal(this.origin, p);
    return new THREE.Vector3(en.east_m, (alt ?? this.origin.alt_msl_m ?? 0) - (this.origin.alt_msl_m ?? 0), -en.north_m);
  }

  setTrack(points: readonly TrackPoint[]): void {
    const pts = points.slice(-MAX_POINTS);
    this.count = 0;
    for (const p of pts) this.addPoint(p);
    this.refit();
  }

  addPoint(p: TrackPoint): void {
    if (this.count >= MAX_POINTS) {
      // Keep the newest: shift by a tenth at once rather than one at a time.
      const drop = MAX_POINTS / 10;
      this.positions.copyWithin(0, drop * 3, this.count * 3);
      this.count -= drop;
    }
    const v = this.local(p, p.alt_msl_m);
    this.positions.set([v.x, v.y, v.z], this.count * 3);
    this.count += 1;
    const attr = this.line.geometry.getAttribute("position") as THREE.BufferAttribute;
    attr.needsUpdate = true;
    this.line.geometry.setDrawRange(0, this.count);
    this.line.geometry.computeBoundingSphere();
    this.requestRender();
  }

  update(s: State): void {
    const e = s.estimate;
    if (e?.lat_deg != null && e.lon_deg != null) {
      this.vehicle.position.copy(this.local({ lat_deg: e.lat_deg, lon_deg: e.lon_deg }, e.alt_msl_m));
      // The cone points along +y: tip it to north (−z), then turn it clockwise by the heading.
      const hd = ((e.heading_deg ?? 0) * Math.PI) / 180;
      this.vehicle.rotation.set(-Math.PI / 2, -hd, 0, "YXZ");
      this.vehicle.visible = true;
    }
    const t = s.guidance?.target;
    if (t) this.target.position.copy(this.local(t, t.alt_msl_m));
    if (this.count > 1 && ++this.updates % 8 === 0) this.refit(); // every ~2 s at 4 Hz
    this.requestRender();
  }

  /** Call when the container is shown or resized. */
  layout(): void {
    if (!this.renderer) return;
    const w = this.root.clientWidth;
    const hgt = this.root.clientHeight;
    if (w === 0 || hgt === 0) return;
    this.renderer.setSize(w, hgt);
    this.camera.aspect = w / hgt;
    this.camera.updateProjectionMatrix();
    this.requestRender();
  }

  /**
   * Sizes the grid to the track and target and aims the camera at them, again whenever the scene
   * has grown by half since the last framing — until the operator orbits, which is respected.
   */
  private refit(): void {
    if (this.count < 2) return;
    const box = new THREE.Box3();
    for (let i = 0; i < this.count; i++) box.expandByPoint(new THREE.Vector3(this.positions[i * 3], this.positions[i * 3 + 1], this.positions[i * 3 + 2]));
    box.expandByPoint(this.target.position);
    box.expandByPoint(new THREE.Vector3(box.min.x, 0, box.min.z)); // down to the ground
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(200, box.getSize(new THREE.Vector3()).length() / 2);
    const size = Math.max(1000, Math.ceil((radius * 2.5) / 500) * 500);
    if (size !== this.gridSize) {
      this.scene.remove(this.grid);
      this.grid.dispose();
      this.grid = new THREE.GridHelper(size, Math.round(size / 100), 0x444444, 0xbbbbbb);
      this.gridSize = size;
      this.scene.add(this.grid);
    }
    this.grid.position.set(centre.x, 0, centre.z);
    if (this.controls && !this.userMoved && radius > this.framedRadius * 1.5) {
      this.controls.target.copy(centre);
      this.camera.position.set(centre.x - radius * 1.3, centre.y + radius * 0.9, centre.z + radius * 1.3);
      this.controls.update();
      this.framedRadius = radius;
    }
  }

  private requestRender(): void {
    if (this.pending || !this.renderer) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      if (this.renderer && this.root.clientWidth > 0) this.renderer.render(this.scene, this.camera);
    });
  }
}
