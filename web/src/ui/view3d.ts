// 3-D view of the descent (three.js), in local metres around the session origin (x east, y up,
// z south): the stack's four bodies at their attitudes with their lines (stack3d.ts), the track,
// the planned pattern and final approach and the glide cone (plan3d.ts), the ground with the
// target and the keep-out zones (ground3d.ts), a camera in one of three modes — chase (behind
// the stack along its heading), top (straight down) or free (orbit by drag, zoom by wheel) — and
// a scale bar for the distance looked at. Rendered on demand (new data or camera moves), not in a
// loop: the cores are shared. What is drawn is published on `window.__view3d` and the root's
// data attributes for the browser tests, as the other views publish theirs.

import * as THREE from "three";
import { OrbitControls } from "three/examples/jsm/controls/OrbitControls.js";
import { h, setText } from "./dom";
import { toLocal } from "../lib/geo";
import { chasePose, scaleBar, scaleLabel, stackMagnification, topPose, type CameraMode, type CameraPose, type V3 } from "../lib/scene3d";
import type { KeepOutMsg, LatLon, State, TrackPoint } from "../lib/types";
import { Ground3D } from "./ground3d";
import { Plan3D } from "./plan3d";
import { Stack3D, type DrawnBody } from "./stack3d";
import { Track3D } from "./track3d";

function webglAvailable(): boolean {
  try {
    const c = document.createElement("canvas");
    return c.getContext("webgl2") !== null || c.getContext("webgl") !== null;
  } catch {
    return false;
  }
}

/** What the view draws, for the browser tests. */
export interface View3DDebug {
  webgl: boolean;
  /** `time_s` of the state drawn. */
  state_time_s: number | null;
  mode: CameraMode;
  camera: { position: V3; target: V3; up: V3 };
  scale_m: number | null;
  scale_px: number | null;
  magnification: number;
  drone: V3 | null;
  heading_deg: number | null;
  bodies: Record<string, DrawnBody>;
  lines: number;
  pattern_points: number;
  final: boolean;
  cone: Plan3D["coneShown"];
  target: V3 | null;
  zones: number;
  track_points: number;
  frames: number;
}

declare global {
  interface Window {
    __view3d?: View3DDebug;
  }
}

const v3 = (v: THREE.Vector3): V3 => [v.x, v.y, v.z];
const MODES: CameraMode[] = ["chase", "top", "free"];

export class View3D {
  readonly root: HTMLElement;
  private renderer: THREE.WebGLRenderer | null = null;
  private readonly scene = new THREE.Scene();
  private readonly camera = new THREE.PerspectiveCamera(50, 1, 0.5, 200_000);
  private controls: OrbitControls | null = null;
  private readonly track = new Track3D();
  private readonly ground = new Ground3D();
  private readonly plan = new Plan3D();
  private readonly stack = new Stack3D();
  private readonly buttons = new Map<CameraMode, HTMLButtonElement>();
  private readonly scaleBarEl: HTMLElement;
  private readonly scaleText: HTMLElement;
  private readonly magnificationText: HTMLElement;
  private mode: CameraMode = "free";
  private state: State | null = null;
  private drone: THREE.Vector3 | null = null;
  private heading_deg: number | null = null;
  private pending = false;
  /** Where the camera looks (the orbit's centre in free mode), m. */
  private readonly lookAt = new THREE.Vector3();
  /** Scene radius at the last automatic framing, m. */
  private framedRadius = 0;
  /** Set once the operator orbits or zooms: automatic framing stops. */
  private userMoved = false;
  private updates = 0;
  private frames = 0;
  private scale: { metres: number; px: number } | null = null;

  constructor(private readonly origin: LatLon & { alt_msl_m: number | null }) {
    this.root = h("div", { class: "view3d", "data-testid": "view3d", "data-camera-mode": this.mode, "aria-label": "3-D view of the descent; drag to orbit, wheel to zoom" });
    this.scene.background = new THREE.Color(0xf4f6fa);
    this.scene.add(new THREE.AmbientLight(0xffffff, 1.2));
    const sun = new THREE.DirectionalLight(0xffffff, 1.5);
    sun.position.set(1000, 3000, 500);
    this.scene.add(sun, this.track.line, this.ground.group, this.plan.group, this.stack.group);
    this.camera.position.set(-1500, 1200, 1500);
    const bar = h("div", { class: "view3d-bar" });
    for (const m of MODES) {
      const b = h("button", { type: "button", class: "small", "data-testid": `view3d-camera-${m}`, "aria-pressed": String(m === this.mode), title: { chase: "follow behind the stack along its heading", top: "look straight down on the drone and the target", free: "orbit by drag, zoom by wheel" }[m] }, m) as HTMLButtonElement;
      b.addEventListener("click", () => this.setMode(m));
      this.buttons.set(m, b);
      bar.append(b);
    }
    this.scaleBarEl = h("span", { class: "view3d-scale-bar" });
    this.scaleText = h("span", { class: "view3d-scale-text" });
    this.magnificationText = h("span", { class: "muted", "data-testid": "view3d-magnification" });
    bar.append(h("span", { class: "view3d-scale", "data-testid": "view3d-scale" }, this.scaleBarEl, this.scaleText), this.magnificationText);
    this.root.append(bar);
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
    this.controls.enabled = this.mode === "free";
  }

  /** Local frame: x east, y up (above the origin's altitude), z south. */
  private local(p: LatLon, alt: number | null): THREE.Vector3 {
    const en = toLocal(this.origin, p);
    return new THREE.Vector3(en.east_m, (alt ?? this.origin.alt_msl_m ?? 0) - (this.origin.alt_msl_m ?? 0), -en.north_m);
  }

  setMode(mode: CameraMode): void {
    if (mode === "free" && this.mode !== "free") {
      // The orbit starts from where the camera is, around what it looked at.
      this.controls?.target.copy(this.lookAt);
      this.camera.up.set(0, 1, 0);
      this.userMoved = true;
    }
    this.mode = mode;
    this.root.dataset.cameraMode = mode;
    for (const [m, b] of this.buttons) b.setAttribute("aria-pressed", String(m === mode));
    if (this.controls) {
      this.controls.enabled = mode === "free";
      if (mode === "free") this.controls.update();
    }
    this.requestRender();
  }

  setTrack(points: readonly TrackPoint[]): void {
    this.track.clear();
    for (const p of points.slice(-20_000)) this.track.add(this.local(p, p.alt_msl_m));
    this.refit();
    this.requestRender();
  }

  addPoint(p: TrackPoint): void {
    this.track.add(this.local(p, p.alt_msl_m));
    this.requestRender();
  }

  /** The keep-out zones in force. */
  setZones(k: KeepOutMsg): void {
    this.ground.setZones(k.areas.map((a) => a.rings.map((r) => r.map(([lat_deg, lon_deg]) => {
      const v = this.local({ lat_deg, lon_deg }, null);
      return [v.x, v.z] as [number, number];
    }))));
    this.requestRender();
  }

  update(s: State): void {
    this.state = s;
    const e = s.estimate;
    this.drone = e?.lat_deg != null && e.lon_deg != null ? this.local({ lat_deg: e.lat_deg, lon_deg: e.lon_deg }, e.alt_msl_m) : null;
    const droneBody = s.stack?.bodies.find((b) => b.body === "drone");
    this.heading_deg = droneBody?.yaw_deg ?? e?.heading_deg ?? null;
    const t = s.guidance?.target;
    const target = t ? this.local(t, t.alt_msl_m) : null;
    this.ground.setTarget(target ? v3(target) : null);
    const landed = s.mission.stage === "landed";
    const pat = landed ? null : (s.guidance?.pattern ?? null);
    const patternHeight = target && pat?.final_approach_height_m != null ? target.y + pat.final_approach_height_m : null;
    const at = ([lat, lon]: [number, number]): V3 => {
      const v = this.local({ lat_deg: lat, lon_deg: lon }, null);
      return [v.x, patternHeight ?? v.y, v.z];
    };
    this.plan.setPlan(pat && patternHeight !== null ? pat.corners.map(at) : [], pat?.final_entry && patternHeight !== null ? at(pat.final_entry) : null, target ? v3(target) : null);
    const parafoil = s.mission.stage === "parafoil";
    this.plan.setCone(target ? v3(target) : null, this.drone && target ? this.drone.y - target.y : null, parafoil ? (e?.glide_ratio_air ?? null) : null);
    if (this.track.count > 1 && ++this.updates % 8 === 0) this.refit(); // every ~2 s at 4 Hz
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
   * Sizes the grid to the track and target and, in free mode, aims the camera at them again
   * whenever the scene has grown by half since the last framing — until the operator orbits.
   */
  private refit(): void {
    if (this.track.count < 2) return;
    const box = this.track.bounds();
    if (this.ground.target.visible) box.expandByPoint(this.ground.target.position);
    box.expandByPoint(new THREE.Vector3(box.min.x, 0, box.min.z)); // down to the ground
    const centre = box.getCenter(new THREE.Vector3());
    const radius = Math.max(200, box.getSize(new THREE.Vector3()).length() / 2);
    this.ground.fit(centre, radius);
    if (this.mode === "free" && this.controls && !this.userMoved && radius > this.framedRadius * 1.5) {
      this.controls.target.copy(centre);
      this.camera.position.set(centre.x - radius * 1.3, centre.y + radius * 0.9, centre.z + radius * 1.3);
      this.controls.update();
      this.framedRadius = radius;
    }
  }

  /** The middle of the stack (between the canopy and the lowest body), or the drone. */
  private stackMiddle(): THREE.Vector3 | null {
    if (!this.drone) return null;
    const ups = this.state?.stack?.bodies.map((b) => b.position_enu_m[2]) ?? [0];
    return this.drone.clone().add(new THREE.Vector3(0, (Math.max(...ups) + Math.min(...ups)) / 2, 0));
  }

  private pose(): CameraPose | null {
    if (this.mode === "chase") {
      const mid = this.stackMiddle();
      return mid ? chasePose(v3(mid), this.heading_deg ?? 0) : null;
    }
    if (this.mode === "top") {
      const target = this.ground.target.visible ? v3(this.ground.target.position) : null;
      return this.drone ? topPose(v3(this.drone), target, this.camera.fov) : null;
    }
    return null;
  }

  /** Places the camera, the stack (magnified by the distance) and the scale; then draws. */
  private frame(): void {
    const pose = this.pose();
    if (pose) {
      this.camera.position.set(...pose.position);
      this.camera.up.set(...pose.up);
      this.lookAt.set(...pose.target);
      this.camera.lookAt(this.lookAt);
    } else if (this.controls) {
      this.lookAt.copy(this.controls.target);
    }
    this.camera.updateMatrixWorld();
    const magnification = this.drone ? stackMagnification(this.camera.position.distanceTo(this.drone)) : 1;
    this.stack.update(this.state?.stack ?? null, this.drone ? v3(this.drone) : null, magnification);
    setText(this.magnificationText, this.stack.group.visible && magnification > 1.05 ? `stack drawn ×${magnification.toFixed(magnification < 10 ? 1 : 0)}` : "");
    this.scale = scaleBar(this.camera.position.distanceTo(this.lookAt), this.camera.fov, this.root.clientHeight);
    this.scaleBarEl.style.width = this.scale ? `${this.scale.px.toFixed(0)}px` : "0";
    setText(this.scaleText, this.scale ? scaleLabel(this.scale.metres) : "");
    this.root.dataset.scaleM = this.scale ? String(this.scale.metres) : "";
    if (this.renderer && this.root.clientWidth > 0) {
      this.renderer.render(this.scene, this.camera);
      this.frames += 1;
    }
    this.publish();
  }

  private publish(): void {
    window.__view3d = {
      webgl: this.renderer !== null,
      state_time_s: this.state?.time_s ?? null,
      mode: this.mode,
      camera: { position: v3(this.camera.position), target: v3(this.lookAt), up: v3(this.camera.up) },
      scale_m: this.scale?.metres ?? null,
      scale_px: this.scale?.px ?? null,
      magnification: this.stack.magnification,
      drone: this.drone ? v3(this.drone) : null,
      heading_deg: this.heading_deg,
      bodies: this.stack.drawn,
      lines: this.stack.group.visible ? this.stack.lineCount : 0,
      pattern_points: this.plan.pathPoints,
      final: this.plan.finalShown,
      cone: this.plan.coneShown,
      target: this.ground.target.visible ? v3(this.ground.target.position) : null,
      zones: this.ground.zonesDrawn,
      track_points: this.track.count,
      frames: this.frames,
    };
  }

  private requestRender(): void {
    if (this.pending) return;
    this.pending = true;
    requestAnimationFrame(() => {
      this.pending = false;
      this.frame();
    });
  }
}
