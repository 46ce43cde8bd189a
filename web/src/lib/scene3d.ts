// The 3-D view's geometry, free of three.js and the page so that it is tested on its own.
//
// The scene's frame is three.js's: x east, y up, z south (right-handed, y up), in metres around
// the session's origin. A body's attitude comes as roll, pitch, yaw in the seed's convention
// (NED, Z-Y-X); its mesh is built in its own axes (x forward, y right, z down), and
// `bodyBasis` gives the matrix that turns those into the scene's.

export type V3 = [number, number, number];

const RAD = Math.PI / 180;

/** East/north/up → the scene's x, y, z. */
export const enuToScene = ([e, n, u]: V3): V3 => [e, u, -n];

/**
 * The 3×3 matrix (row-major) taking a body's own axes (forward, right, down) to the scene's axes,
 * for its roll, pitch and yaw in degrees: the NED rotation Rz(ψ)·Ry(θ)·Rx(φ), then NED → scene.
 */
export function bodyBasis(roll_deg: number, pitch_deg: number, yaw_deg: number): number[] {
  const [cf, sf] = [Math.cos(roll_deg * RAD), Math.sin(roll_deg * RAD)];
  const [ct, st] = [Math.cos(pitch_deg * RAD), Math.sin(pitch_deg * RAD)];
  const [cp, sp] = [Math.cos(yaw_deg * RAD), Math.sin(yaw_deg * RAD)];
  // Body → NED, rows north, east, down; then scene x = east, y = −down, z = −north.
  const north = [ct * cp, sf * st * cp - cf * sp, cf * st * cp + sf * sp];
  const east = [ct * sp, sf * st * sp + cf * cp, cf * st * sp - sf * cp];
  const down = [-st, sf * ct, cf * ct];
  return [...east, ...down.map((v) => -v), ...north.map((v) => -v)];
}

/** A vector of a body's own axes in the scene's, by `bodyBasis`. */
export function applyBasis(m: readonly number[], [x, y, z]: V3): V3 {
  const at = (i: number): number => m[i] ?? 0;
  return [at(0) * x + at(1) * y + at(2) * z, at(3) * x + at(4) * y + at(5) * z, at(6) * x + at(7) * y + at(8) * z];
}

/** Camera modes: behind the stack along its heading, straight down from above, or the user's own orbit. */
export type CameraMode = "chase" | "top" | "free";

export interface CameraPose {
  position: V3;
  target: V3;
  /** The camera's up: the scene's up, except looking straight down, where it is north. */
  up: V3;
}

/** How far behind and above the stack the chase camera rides, m. */
export const CHASE_BACK_M = 28;
export const CHASE_UP_M = 9;

/**
 * The chase camera: `CHASE_BACK_M` behind the point `at` (the middle of the stack) along the
 * heading `yaw_deg` (from north, clockwise), `CHASE_UP_M` above it, looking at it.
 */
export function chasePose(at: V3, yaw_deg: number): CameraPose {
  const east = Math.sin(yaw_deg * RAD);
  const north = Math.cos(yaw_deg * RAD);
  // Behind = against the heading; north is −z in the scene.
  return { position: [at[0] - east * CHASE_BACK_M, at[1] + CHASE_UP_M, at[2] + north * CHASE_BACK_M], target: at, up: [0, 1, 0] };
}

/**
 * The top camera: straight above the middle of the drone and the target, high enough to see
 * both with a margin (never under `min_m`), looking down with north up on the screen.
 */
export function topPose(drone: V3, target: V3 | null, fov_deg: number, min_m = 300): CameraPose {
  const t = target ?? drone;
  const cx = (drone[0] + t[0]) / 2;
  const cz = (drone[2] + t[2]) / 2;
  const half = Math.hypot(drone[0] - t[0], drone[2] - t[2]) / 2 + 100;
  const above = Math.max(min_m, half / Math.tan((fov_deg * RAD) / 2), drone[1] + 50);
  return { position: [cx, above, cz], target: [cx, 0, cz], up: [0, 0, -1] };
}

/** Radius of the glide cone at `height_m` above its apex (the target) for a glide ratio, m. */
export function coneRadius(height_m: number, glide_ratio: number): number {
  return Math.max(0, height_m) * Math.max(0, glide_ratio);
}

/**
 * A scale bar for a view: the longest "nice" length (1, 2 or 5 × 10ⁿ m) that fits in `max_px`
 * at the camera distance `distance_m` with vertical field of view `fov_deg` on a view
 * `height_px` tall; null for a view with no size.
 */
export function scaleBar(distance_m: number, fov_deg: number, height_px: number, max_px = 120): { metres: number; px: number } | null {
  if (!(height_px > 0) || !(distance_m > 0)) return null;
  const metresPerPx = (2 * distance_m * Math.tan((fov_deg * RAD) / 2)) / height_px;
  const most = metresPerPx * max_px;
  const decade = 10 ** Math.floor(Math.log10(most));
  const metres = [5, 2, 1].map((k) => k * decade).find((m) => m <= most) ?? decade;
  return { metres, px: metres / metresPerPx };
}

/** "500 m", "2 km", "0.5 m". */
export const scaleLabel = (m: number): string => (m >= 1000 ? `${m / 1000} km` : `${m} m`);

/**
 * How much the stack is drawn larger than life so that it stays visible from `distance_m`
 * (a 12 m stack is under a pixel from 5 km): 1 up close, growing with the distance beyond
 * `true_within_m`.
 */
export function stackMagnification(distance_m: number, true_within_m = 120): number {
  return Math.max(1, distance_m / true_within_m);
}
