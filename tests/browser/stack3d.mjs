#!/usr/bin/env node
// The stack in 3-D (issue 32, item 3) in a real browser: `stx serve` with the simulated drone
// flying the rehearsal (parafoil from 900 m, spiral landing) at 5×. The 3-D view's drawing, as
// the page publishes it (`window.__view3d`, ui/view3d.ts), is held against the station's own
// state (`/api/state`) of the very frame drawn: the drone's attitude, the canopy above the drone
// by the rigging's height and the capsule and transponder below, every body measured by its own
// IMU; the planned pattern, the final approach and the glide cone while the parafoil flies its
// pattern; the target and the keep-out zones on the ground; each camera mode doing what it says
// (top looks straight down, chase rides behind the stack along its heading, free keeps the
// user's orbit); the scale bar following the zoom. A screenshot of each camera mode is kept.
//
// Usage: node tests/browser/stack3d.mjs [path/to/stx]   (default target/release/stx)

import { join } from "node:path";
import { OPERATOR, VIEWER, out, check, newContext, startStation, freeUdpPort, apiOf, run, until, watchErrors, runFlights, angleDiff, sleep } from "./harness.mjs";

const SPEED = 5;

async function flight() {
  const port = await freeUdpPort();
  const { base } = await startStation(["--link", `udpin:127.0.0.1:${port}`]);
  const api = apiOf(base);
  run(["drone", "--connect", `udpout:127.0.0.1:${port}`, "--scenario", "rehearsal", "--speed", String(SPEED)], "stx drone");
  const ctx = await newContext("stack3d", { viewport: { width: 1280, height: 800 } });
  const page = await ctx.newPage();
  watchErrors(page, "stack3d");
  // The station's states as it sent them to the page, by their time: what each frame drew from.
  const sent = new Map();
  page.on("websocket", (ws) => ws.on("framereceived", (f) => {
    try {
      const m = JSON.parse(f.payload);
      if (m.type === "state") sent.set(m.time_s, m);
    } catch {
      // the harness's contract check reports a frame that is not JSON
    }
  }));
  await page.goto(`${base}/?token=${OPERATOR}`);
  await page.click('[data-testid="tab-3d"]');
  const view = () => page.evaluate(() => window.__view3d ?? null);
  const ready = await until(view, (v) => v?.bodies?.transponder && v.pattern_points > 0 && v.cone && v.frames > 0, 30000, 250);
  const unavailable = await page.locator('[data-testid="view3d-unavailable"]').count();
  check("WebGL renders in headless Chromium (SwiftShader): the view draws frames", ready?.webgl === true && unavailable === 0 && ready.frames > 0,
    `webgl ${ready?.webgl}, frames ${ready?.frames}, unavailable notice ${unavailable}`);

  // The drawing against the station's state it was drawn from (the one sent at that time).
  const v0 = await view();
  const pair = v0 && sent.has(v0.state_time_s) ? { v: v0, s: sent.get(v0.state_time_s) } : null;
  check("the view's frame is of a state the station sent", pair !== null, `view at ${v0?.state_time_s}, ${sent.size} states sent`);
  if (!pair) return;
  const { v, s } = pair;
  const drone = v.bodies.drone;
  const att = s.vehicle?.attitude;
  const sd = s.stack?.bodies.find((b) => b.body === "drone");
  check("drone: drawn at the attitude of the station's state (its AHRS, vehicle.attitude) within 0.01°",
    att && Math.abs(drone.roll_deg - att.roll_deg) < 0.01 && Math.abs(drone.pitch_deg - att.pitch_deg) < 0.01 && angleDiff(drone.yaw_deg, att.yaw_deg) < 0.01 && sd?.source === "measured",
    `drawn ${[drone.roll_deg, drone.pitch_deg, drone.yaw_deg].map((x) => x.toFixed(2))}; state ${att && [att.roll_deg, att.pitch_deg, att.yaw_deg].map((x) => x.toFixed(2))}`);
  const rel = (b) => [0, 1, 2].map((k) => (v.bodies[b].position[k] - v.drone[k]) / v.magnification);
  const [canopy, capsule, transponder] = ["canopy", "capsule", "transponder"].map(rel);
  check("canopy drawn above the drone by the rigging's height (3.3 m ± 0.6), within a metre sideways",
    Math.abs(canopy[1] - 3.3) < 0.6 && Math.hypot(canopy[0], canopy[2]) < 1.5, `canopy at ${canopy.map((x) => x.toFixed(2))} m from the drone (×${v.magnification.toFixed(1)} drawn)`);
  check("capsule 3 m and transponder 8 m below the drone, each hanging under the one above",
    Math.abs(capsule[1] + 3.15) < 0.5 && Math.abs(transponder[1] - capsule[1] + 5) < 0.6,
    `capsule ${capsule.map((x) => x.toFixed(2))}, transponder ${transponder.map((x) => x.toFixed(2))}`);
  const sources = s.stack.bodies.map((b) => `${b.body}:${b.source}`);
  const drawnCanopy = v.bodies.canopy;
  const stateCanopy = s.stack.bodies.find((b) => b.body === "canopy");
  check("every body measured by its own IMU with the simulated drone, and the canopy drawn at its own attitude",
    s.stack.bodies.length === 4 && s.stack.bodies.every((b) => b.source === "measured" && b.age_s < 3) && ["canopy", "capsule", "transponder"].every((b) => v.bodies[b].source === "measured")
      && Math.abs(drawnCanopy.roll_deg - stateCanopy.roll_deg) < 1e-6 && Math.abs(drawnCanopy.pitch_deg - stateCanopy.pitch_deg) < 1e-6,
    `${sources.join(" ")}; canopy drawn roll ${drawnCanopy.roll_deg.toFixed(1)}°`);
  check("the four lines joining the bodies are drawn", v.lines === 4 && s.stack.lines.length === 4, `${v.lines} lines`);

  // The plan and the glide cone.
  const pat = s.guidance?.pattern;
  check("the planned pattern (a closed loop of its corners) and the final approach are drawn while the parafoil flies its pattern",
    s.mission.stage === "parafoil" && pat && v.pattern_points === pat.corners.length + 1 && v.final === true, `phase ${s.guidance?.phase}, ${pat?.corners.length} corners, ${v.pattern_points} points, final ${v.final}`);
  const glide = s.estimate?.glide_ratio_air;
  const cone = v.cone;
  check("glide cone: apex on the target, height the drone's over it, radius height × the state's glide ratio",
    cone && glide > 0 && Math.abs(cone.glide_ratio - glide) < 1e-9 && Math.abs(cone.radius_m - cone.height_m * glide) < 1e-6
      && Math.abs(cone.height_m - (v.drone[1] - v.target[1])) < 1e-6 && cone.apex.every((x, k) => Math.abs(x - v.target[k]) < 1e-9),
    cone ? `height ${cone.height_m.toFixed(0)} m × ${glide?.toFixed(2)} = ${cone.radius_m.toFixed(0)} m` : "no cone");
  const zones = (await api("/api/keep-out", VIEWER)).body;
  const origin = (await api("/api/session", VIEWER)).body.station.origin;
  const t = s.guidance.target;
  check("the target on the ground at its altitude, and every keep-out area drawn on the ground",
    v.target && Math.abs(v.target[1] - (t.alt_msl_m - origin.alt_msl_m)) < 1e-6 && zones?.areas > 0 && v.zones === zones.areas,
    `target ${v.target?.map((x) => x.toFixed(0))}; zones ${v.zones} of ${zones?.areas}`);
  const now = (await api("/api/state", VIEWER)).body;
  check("the station's state over REST carries the stack too, all four bodies measured",
    now?.stack?.bodies?.map((b) => `${b.body}:${b.source}`).join() === "canopy:measured,drone:measured,capsule:measured,transponder:measured", JSON.stringify(now?.stack?.bodies?.map((b) => b.source)));

  // The camera modes.
  const mode = async (m) => {
    await page.click(`[data-testid="view3d-camera-${m}"]`);
    return until(view, (x) => x?.mode === m && x.frames > 0, 3000, 100);
  };
  const top = await mode("top");
  const [c, tg] = [top.camera.position, top.camera.target];
  check("top: the camera looks straight down (north up) from above the drone and the target",
    Math.abs(c[0] - tg[0]) < 1e-6 && Math.abs(c[2] - tg[2]) < 1e-6 && c[1] > top.drone[1] && top.camera.up.join() === "0,0,-1"
      && (await page.locator('[data-testid="view3d-camera-top"]').getAttribute("aria-pressed")) === "true",
    `camera ${c.map((x) => x.toFixed(0))}, looking at ${tg.map((x) => x.toFixed(0))}`);
  await page.locator('[data-testid="view3d"]').screenshot({ path: join(out, "stack3d-top.png") });
  const chase = await mode("chase");
  await sleep(600);
  const ch = await view();
  const toDrone = [ch.drone[0] - ch.camera.position[0], ch.drone[2] - ch.camera.position[2]];
  const bearing = ((Math.atan2(toDrone[0], -toDrone[1]) * 180) / Math.PI + 360) % 360;
  const distance = Math.hypot(...toDrone);
  check("chase: the camera rides behind the stack along its heading, above it, close enough to see it life-size",
    chase && angleDiff(bearing, ch.heading_deg) < 1 && ch.camera.position[1] > ch.drone[1] && distance > 15 && distance < 45 && ch.magnification === 1,
    `camera→drone bearing ${bearing.toFixed(1)}°, heading ${ch.heading_deg?.toFixed(1)}°, ${distance.toFixed(1)} m behind, ×${ch.magnification}`);
  await page.locator('[data-testid="view3d"]').screenshot({ path: join(out, "stack3d-chase.png") });

  // Free: the user's orbit and zoom stay; the scale follows the zoom.
  await mode("free");
  const canvas = await page.locator('[data-testid="view3d"] canvas').boundingBox();
  const cx = canvas.x + canvas.width / 2;
  const cy = canvas.y + canvas.height / 2;
  const before = await view();
  await page.mouse.move(cx, cy);
  await page.mouse.down();
  await page.mouse.move(cx + 150, cy + 40, { steps: 8 });
  await page.mouse.up();
  const orbited = await until(view, (x) => x.camera.position.some((p, k) => Math.abs(p - before.camera.position[k]) > 0.5), 2000, 100);
  await sleep(2500); // ten states and more: the camera must stay where the user put it
  const kept = await view();
  check("free: a drag orbits the camera, and it stays there while the states keep coming",
    orbited.camera.position.some((p, k) => Math.abs(p - before.camera.position[k]) > 0.5) && kept.camera.position.every((p, k) => Math.abs(p - orbited.camera.position[k]) < 1e-6) && kept.state_time_s > orbited.state_time_s,
    `moved from ${before.camera.position.map((x) => x.toFixed(1))} to ${orbited.camera.position.map((x) => x.toFixed(1))}; ${kept.state_time_s - orbited.state_time_s} s of states later at ${kept.camera.position.map((x) => x.toFixed(1))}`);
  const scaleText = () => page.locator('[data-testid="view3d-scale"]').innerText();
  const s0 = { v: kept.scale_m, text: await scaleText() };
  for (let i = 0; i < 5; i++) {
    await page.mouse.wheel(0, 400);
    await sleep(80);
  }
  const zoomedOut = await until(view, (x) => x.scale_m > s0.v, 2000, 100);
  const s1 = { v: zoomedOut.scale_m, text: await scaleText() };
  for (let i = 0; i < 10; i++) {
    await page.mouse.wheel(0, -400);
    await sleep(80);
  }
  const zoomedIn = await until(view, (x) => x.scale_m < s1.v, 2000, 100);
  const s2 = { v: zoomedIn.scale_m, text: await scaleText() };
  check("scale: the bar's length grows when zooming out and shrinks when zooming in, its label with it",
    s1.v > s0.v && s2.v < s1.v && s0.text !== s1.text && s1.text !== s2.text && /\d+ k?m/.test(s2.text),
    `${s0.text} → (out) ${s1.text} → (in) ${s2.text}`);
  await page.locator('[data-testid="view3d"]').screenshot({ path: join(out, "stack3d-free.png") });
  await ctx.close();
}

await runFlights(flight, ["ServerMessage:state", "StateMsg", "KeepOutMsg", "Session"]);
