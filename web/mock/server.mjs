#!/usr/bin/env node
// A stand-in for `stx serve`, for developing the dashboard and for its smoke test. It implements
// crates/stx-station/API.md by example: the same paths, bodies, status codes, roles and message
// shapes, over a synthetic flight (a parafoil flying a box pattern down onto a target in a wind).
// It is not a simulator: the flight is kinematic and only as real as the page needs to look alive.
//
//   node mock/server.mjs [--port 8080] [--static dist] [--no-dropouts] [--speed 1]
//
// Tokens: `op` (operator "ops-1"), `op2` (operator "ops-2"), `view` (viewer "viewer-1").
// Link dropouts (8 s every 150 s, first at 100 s) show the STALE state; --no-dropouts turns them off.
// Tiles are not served (404), so the page shows its offline metric grid.

import { createServer } from "node:http";
import { readFile, stat } from "node:fs/promises";
import { extname, join, normalize, resolve } from "node:path";
import { WebSocketServer } from "ws";

// ---------------------------------------------------------------- options
const args = process.argv.slice(2);
const opt = (name, dflt) => {
  const i = args.indexOf(name);
  return i >= 0 && i + 1 < args.length ? args[i + 1] : dflt;
};
const PORT = Number(opt("--port", process.env.PORT ?? "8080"));
const STATIC_DIR = opt("--static", null);
const DROPOUTS = !args.includes("--no-dropouts");
const SPEED = Number(opt("--speed", "1")); // mission-clock speed-up, for quick looks

const TOKENS = {
  op: { role: "operator", name: "ops-1" },
  op2: { role: "operator", name: "ops-2" },
  view: { role: "viewer", name: "viewer-1" },
};
const MODES = ["uncontrolled", "manual", "heading", "course", "localizer", "spiral_landing"];
const ORIGIN = { lat_deg: 38.5333, lon_deg: -7.8889, alt_msl_m: 245 };
const STATION = {
  name: "STRAPLEX ground (mock)",
  origin: ORIGIN,
  tile_url: "/tiles/{z}/{x}/{y}.png",
  tile_attribution: "no tiles in the mock",
  offline_tiles: true,
  modes: MODES,
};

// ---------------------------------------------------------------- small maths
const R_EARTH = 6371008.8;
const RAD = Math.PI / 180;
const wrap360 = (d) => ((d % 360) + 360) % 360;
const wrap180 = (d) => ((((d + 180) % 360) + 360) % 360) - 180;
const clamp = (v, lo, hi) => Math.min(hi, Math.max(lo, v));
const toLatLon = (e, n) => ({
  lat_deg: ORIGIN.lat_deg + n / R_EARTH / RAD,
  lon_deg: ORIGIN.lon_deg + e / (R_EARTH * Math.cos(ORIGIN.lat_deg * RAD)) / RAD,
});
const toLocal = (lat, lon) => ({
  e: (lon - ORIGIN.lon_deg) * RAD * R_EARTH * Math.cos(ORIGIN.lat_deg * RAD),
  n: (lat - ORIGIN.lat_deg) * RAD * R_EARTH,
});
const r6 = (x) => Math.round(x * 1e6) / 1e6;
const r2 = (x) => Math.round(x * 100) / 100;
/** Seeded PRNG (mulberry32): the mock behaves the same on every run. */
let seed = 20260501;
const rand = () => {
  seed = (seed + 0x6d2b79f5) | 0;
  let t = seed;
  t = Math.imul(t ^ (t >>> 15), t | 1);
  t ^= t + Math.imul(t ^ (t >>> 7), t | 61);
  return ((t ^ (t >>> 14)) >>> 0) / 4294967296;
};
const noise = (a) => (rand() * 2 - 1) * a;

// ---------------------------------------------------------------- wind (forecast profile)
const FORECAST = [
  { alt_msl_m: 245, speed_mps: 2.5, from_deg: 300 },
  { alt_msl_m: 500, speed_mps: 3.2, from_deg: 295 },
  { alt_msl_m: 1000, speed_mps: 4.5, from_deg: 285 },
  { alt_msl_m: 1500, speed_mps: 6.0, from_deg: 275 },
  { alt_msl_m: 2000, speed_mps: 7.5, from_deg: 270 },
];
function windAt(alt) {
  const p = FORECAST;
  if (alt <= p[0].alt_msl_m) return { ...p[0] };
  for (let i = 1; i < p.length; i++) {
    if (alt <= p[i].alt_msl_m) {
      const f = (alt - p[i - 1].alt_msl_m) / (p[i].alt_msl_m - p[i - 1].alt_msl_m);
      return { speed_mps: p[i - 1].speed_mps + f * (p[i].speed_mps - p[i - 1].speed_mps), from_deg: p[i - 1].from_deg + f * (p[i].from_deg - p[i - 1].from_deg) };
    }
  }
  return { ...p[p.length - 1] };
}
/** The "true" wind blows 10 % stronger than forecast and 8° veered, so estimate and forecast differ. */
function trueWindNed(alt) {
  const w = windAt(alt);
  const speed = w.speed_mps * 1.1;
  const to = (w.from_deg + 8 + 180) * RAD;
  return [speed * Math.cos(to), speed * Math.sin(to), 0];
}

// ---------------------------------------------------------------- the synthetic flight
const START = { e: -900, n: 700, alt: 1400, heading: 120 };
const fl = {
  t: 0, // mission clock, s
  e: 0, n: 0, alt: 0, heading: 0, roll: 0,
  mainLine: 0, brake: 0,
  mode: "spiral_landing",
  stage: "parafoil",
  phase: "approach",
  corner: 0,
  landedAt: null,
  target: { ...ORIGIN, approach_course_deg: null },
  heading_cmd: 90, course_cmd: 90,
  localizer: null, // {lat_deg, lon_deg, course_deg, glide_slope}
  plan: null,
  manual: null, // {y, z, at}
  cutdownArmedUntil: null,
};
function resetFlight() {
  Object.assign(fl, { e: START.e, n: START.n, alt: START.alt, heading: START.heading, roll: 0, mainLine: 0, brake: 0, stage: "parafoil", phase: "approach", corner: 0, landedAt: null, mode: "spiral_landing" });
}
resetFlight();

const AIRSPEED = 7.0; // m/s, trim
const SINK = 2.6; // m/s, trim
const FINAL_H = 172; // m above the target where the final approach starts
const BOX = 160; // m, half side of the box pattern

/** The box pattern and final approach for the current target and wind (local metres). */
function pattern() {
  const tl = toLocal(fl.target.lat_deg, fl.target.lon_deg);
  const w = windAt(fl.target.alt_msl_m + FINAL_H);
  // Final course: into the wind unless the operator gave one.
  const course = fl.target.approach_course_deg ?? wrap360(w.from_deg);
  const glideGround = (AIRSPEED - w.speed_mps) / SINK;
  const L = FINAL_H * glideGround;
  const c = course * RAD;
  const entry = { e: tl.e - L * Math.sin(c), n: tl.n - L * Math.cos(c) };
  // Box centred beside the final entry, first corner = final entry: the last leg ends where final begins.
  const u = { e: Math.sin(c), n: Math.cos(c) }; // along final
  const v = { e: Math.cos(c), n: -Math.sin(c) }; // to its right
  const corners = [
    entry,
    { e: entry.e - 2 * BOX * u.e, n: entry.n - 2 * BOX * u.n },
    { e: entry.e - 2 * BOX * u.e - 2 * BOX * v.e, n: entry.n - 2 * BOX * u.n - 2 * BOX * v.n },
    { e: entry.e - 2 * BOX * v.e, n: entry.n - 2 * BOX * v.n },
  ].reverse(); // fly 3 → 2 → 1 → entry (corner index 3)
  return { tl, entry, corners, course, glideGround };
}

function desiredCourseTo(p) {
  return wrap360(Math.atan2(p.e - fl.e, p.n - fl.n) / RAD);
}

function guidanceStep() {
  const heightAboveTarget = fl.alt - fl.target.alt_msl_m;
  switch (fl.mode) {
    case "spiral_landing": {
      const pat = pattern();
      if (fl.phase === "final") return { course: desiredCourseTo(pat.tl), brake: heightAboveTarget < 8 ? 1 : 0 };
      // Not enough height for another loop: cut across to the final entry (corner 3).
      const entry = pat.corners[3];
      const hNeeded = FINAL_H + (Math.hypot(entry.e - fl.e, entry.n - fl.n) * SINK) / 4;
      if (fl.corner !== 3 && heightAboveTarget < hNeeded) {
        fl.corner = 3;
        setPhase("branch4");
      }
      const c = pat.corners[fl.corner];
      const d = Math.hypot(c.e - fl.e, c.n - fl.n);
      if (d < 35) {
        if (fl.corner === 3 && heightAboveTarget < FINAL_H * 1.6) setPhase("final");
        else {
          fl.corner = (fl.corner + 1) % 4;
          setPhase(`branch${fl.corner + 1}`);
        }
      }
      return { course: desiredCourseTo(pat.corners[fl.corner]), brake: 0 };
    }
    case "heading":
      return { heading: fl.heading_cmd, brake: 0 };
    case "course":
      return { course: fl.course_cmd, brake: 0 };
    case "localizer": {
      const lz = fl.localizer ?? { ...fl.target, course_deg: 90 };
      const p = toLocal(lz.lat_deg, lz.lon_deg);
      const c = lz.course_deg * RAD;
      // Cross-track error to the line through p along the course; intercept at up to 60°.
      const xt = (fl.e - p.e) * Math.cos(c) - (fl.n - p.n) * Math.sin(c);
      return { course: wrap360(lz.course_deg - clamp(xt / 3, -60, 60)), brake: 0 };
    }
    case "manual": {
      const m = fl.manual && fl.t - fl.manual.at < 0.5 ? fl.manual : { y: 0, z: 0 };
      return { mainLine: m.y, brake: m.z };
    }
    default:
      return { mainLine: 0.05, brake: 0 }; // uncontrolled: the canopy's slight built-in turn
  }
}

function setPhase(p) {
  if (fl.phase === p) return;
  fl.phase = p;
  event("info", "guidance", `phase → ${p.replace(/_/g, " ")}`);
}

function groundVelocity() {
  const w = trueWindNed(fl.alt);
  const va = AIRSPEED * (1 - 0.3 * fl.brake);
  return [va * Math.cos(fl.heading * RAD) + w[0], va * Math.sin(fl.heading * RAD) + w[1], SINK * (1 + 0.25 * Math.abs(fl.mainLine) + 0.3 * fl.brake)];
}

function step(dt) {
  fl.t += dt;
  if (fl.stage === "landed") {
    fl.mainLine = 0;
    fl.roll = 0;
    if (fl.t - fl.landedAt > 30) {
      event("info", "station", "mock: a new synthetic flight starts");
      resetFlight();
    }
    return;
  }
  const g = guidanceStep();
  let ml;
  if (g.mainLine !== undefined) ml = g.mainLine;
  else {
    let err;
    if (g.heading !== undefined) err = wrap180(g.heading - fl.heading);
    else {
      const v = groundVelocity();
      const course = Math.atan2(v[1], v[0]) / RAD;
      err = wrap180(g.course - course);
    }
    ml = clamp(err / 40, -1, 1);
  }
  // Servo lag ~0.5 s.
  fl.mainLine += (ml - fl.mainLine) * Math.min(1, dt / 0.5);
  fl.brake += (g.brake - fl.brake) * Math.min(1, dt / 0.5);
  const rate = 18 * fl.mainLine; // deg/s at full main line
  fl.heading = wrap360(fl.heading + rate * dt);
  fl.roll = 1.6 * rate;
  const v = groundVelocity();
  fl.e += v[1] * dt;
  fl.n += v[0] * dt;
  fl.alt -= v[2] * dt;
  if (fl.alt <= ORIGIN.alt_msl_m) {
    fl.alt = ORIGIN.alt_msl_m;
    fl.stage = "landed";
    fl.landedAt = fl.t;
    const tl = toLocal(fl.target.lat_deg, fl.target.lon_deg);
    setPhase("landed");
    event("info", "vehicle", `landed ${Math.round(Math.hypot(fl.e - tl.e, fl.n - tl.n))} m from the target`);
  }
}

// ---------------------------------------------------------------- the link (with dropouts)
let forcedDown = false; // set through POST /mock/link (tests)
function linkDown() {
  if (forcedDown) return true;
  if (!DROPOUTS || fl.t < 100) return false;
  return (fl.t - 100) % 150 < 8;
}
let wasDown = false;
let lastGood = null; // last vehicle/estimate blocks while the link was up
let lastRx = 0; // mission time of the last received telemetry

// ---------------------------------------------------------------- building the state message
function prediction(v, w) {
  const heightAboveGround = Math.max(0, fl.alt - ORIGIN.alt_msl_m);
  const sink = v[2];
  const ttl = sink > 0.1 ? heightAboveGround / sink : 0;
  const wind = Math.hypot(w[0], w[1]);
  const windTo = wrap360(Math.atan2(w[1], w[0]) / RAD);
  // Uncontrolled: keeps flying its current heading with the wind.
  const un = { e: fl.e + v[1] * ttl, n: fl.n + v[0] * ttl };
  const pl = toLocal(fl.target.lat_deg, fl.target.lon_deg);
  const plannedMiss = fl.mode === "spiral_landing" ? 4 + 0.02 * ttl : null;
  const mk = (p, semiMajor, semiMinor, axis) => ({ ...round(toLatLon(p.e, p.n)), time_to_land_s: r2(ttl), semi_major_m: r2(semiMajor), semi_minor_m: r2(semiMinor), major_axis_deg: r2(axis) });
  return {
    planned: plannedMiss === null ? null : mk({ e: pl.e + 0.3 * plannedMiss * Math.sin(windTo * RAD), n: pl.n + 0.3 * plannedMiss * Math.cos(windTo * RAD) }, 6 + 0.06 * ttl, 3 + 0.03 * ttl, windTo),
    uncontrolled: mk(un, 15 + 0.25 * ttl * (0.5 + wind / 8), 8 + 0.12 * ttl, wrap360(fl.heading)),
  };
}
const round = (ll) => ({ lat_deg: r6(ll.lat_deg), lon_deg: r6(ll.lon_deg) });

function buildState() {
  const down = linkDown();
  const wallNow = Date.now();
  const v = groundVelocity();
  const wTrue = trueWindNed(fl.alt);
  if (down !== wasDown) {
    event(down ? "warning" : "info", "link", down ? "link lost: no telemetry from the drone" : "link restored");
    wasDown = down;
  }
  if (!down) {
    lastRx = fl.t;
    const ll = toLatLon(fl.e, fl.n);
    const landed = fl.stage === "landed";
    const vel = landed ? [0, 0, 0] : v;
    const gs = Math.hypot(vel[0], vel[1]);
    const va = landed ? 0 : AIRSPEED * (1 - 0.3 * fl.brake);
    const course = wrap360(Math.atan2(vel[1], vel[0]) / RAD);
    const wEst = [wTrue[0] + noise(0.1), wTrue[1] + noise(0.1), 0];
    const wSpeed = Math.hypot(wEst[0], wEst[1]);
    const heading180 = wrap180(fl.heading);
    lastGood = {
      vehicle: {
        mode: fl.mode, stage: fl.stage, phase: fl.phase,
        gps: { fix: "3d", satellites: 11 + Math.round(noise(1)), lat_deg: r6(ll.lat_deg + noise(3e-6)), lon_deg: r6(ll.lon_deg + noise(3e-6)), alt_msl_m: r2(fl.alt + noise(1)), velocity_ned_mps: vel.map(r2), h_acc_m: 1.5 },
        attitude: { roll_deg: r2(fl.roll + noise(1)), pitch_deg: r2(-3 + noise(0.5) - 4 * fl.brake), yaw_deg: r2(heading180) },
        air: { static_pressure_pa: Math.round(101325 * Math.pow(1 - 2.25577e-5 * fl.alt, 5.25588)), differential_pressure_pa: r2(0.5 * 1.15 * va * va), temperature_c: r2(15 - 0.0065 * fl.alt), airspeed_mps: r2(va + noise(0.1)) },
        servos: { main_line: r2(fl.mainLine), brake_right: r2(fl.brake), brake_left: r2(fl.brake) },
        power: { voltage_v: r2(11.9 - fl.t / 5000), current_a: r2(0.8 + 0.4 * Math.abs(fl.mainLine)), remaining_percent: Math.round(clamp(78 - fl.t / 60, 0, 100)) },
        onboard_wind_ned_mps: wEst.map(r2),
      },
      estimate: {
        ...round(ll), alt_msl_m: r2(fl.alt), height_m: r2(fl.alt - ORIGIN.alt_msl_m),
        velocity_ned_mps: vel.map(r2), ground_speed_mps: r2(gs), course_deg: r2(wrap180(course)), heading_deg: r2(heading180), heading_rate_dps: r2(18 * fl.mainLine),
        airspeed_mps: r2(va), sink_rate_mps: r2(vel[2]), glide_ratio_air: vel[2] > 0.1 ? r2(va / vel[2]) : null, glide_ratio_ground: vel[2] > 0.1 ? r2(gs / vel[2]) : null,
        wind_ned_mps: wEst.map(r2), wind_speed_mps: r2(wSpeed), wind_from_deg: r2(wrap360(Math.atan2(-wEst[1], -wEst[0]) / RAD)), wind_sigma_mps: r2(0.15 + 0.1 * rand()),
        position_sigma_m: 1.8, gps_ok: true,
      },
      prediction: fl.stage === "landed" ? null : prediction(vel, wTrue),
    };
  }
  const age = fl.t - lastRx + 0.05 + 0.2 * rand();
  const msgAge = (base) => r2(age + base * rand());
  const pat = pattern();
  const finalEntry = toLatLon(pat.entry.e, pat.entry.n);
  return {
    type: "state",
    time_s: r2(fl.t),
    wall_ms: wallNow,
    link: {
      connected: !down, stale: down, age_s: r2(age), rate_hz: down ? 0 : r2(31.5 + noise(1.5)), loss_percent: down ? 100 : r2(0.4 + rand() * 0.4),
      crc_errors: 0, parse_errors: 0, signature_errors: 0,
      radios: [{ address: "udpin:127.0.0.1:14550", transmitting: true, stale: down, age_s: r2(age), rate_hz: down ? 0 : 31.5, loss_percent: 0.4, duplicates: 0 }],
      ages_s: { HEARTBEAT: msgAge(1), GPS_RAW_INT: msgAge(0.2), ATTITUDE: msgAge(0.05), SCALED_PRESSURE: msgAge(0.2), SERVO_OUTPUT_RAW: msgAge(0.1), WIND_COV: msgAge(0.25) },
    },
    vehicle: lastGood?.vehicle ?? null,
    estimate: lastGood?.estimate ?? null,
    guidance: {
      mode: fl.mode, phase: fl.phase,
      target: { lat_deg: r6(fl.target.lat_deg), lon_deg: r6(fl.target.lon_deg), alt_msl_m: fl.target.alt_msl_m },
      pattern: fl.mode === "spiral_landing" ? {
        corners: pat.corners.map((c) => { const ll = toLatLon(c.e, c.n); return [r6(ll.lat_deg), r6(ll.lon_deg)]; }),
        final_entry: [r6(finalEntry.lat_deg), r6(finalEntry.lon_deg)], final_course_deg: r2(pat.course),
        final_approach_height_m: FINAL_H, target_reachable: true, reach_ratio: r2(clamp(0.4 + (fl.alt - ORIGIN.alt_msl_m) / 4000, 0, 1)),
      } : null,
      commands: { main_line: r2(fl.mainLine), brake: r2(fl.brake) },
    },
    prediction: lastGood?.prediction ?? null,
    forecast_wind: FORECAST,
    mission: { stage: fl.stage, cutdown_armed_until_s: fl.cutdownArmedUntil },
  };
}

// ---------------------------------------------------------------- logs kept for history/REST
const events = [];
const track = [];
const states1hz = [];
let latestState = null;
const clients = new Set(); // {ws, who}

function broadcast(msg) {
  const s = JSON.stringify(msg);
  for (const c of clients) if (c.ws.readyState === 1) c.ws.send(s);
}
function event(level, source, text) {
  const e = { type: "event", time_s: r2(fl.t), wall_ms: Date.now(), level, source, text };
  events.push(e);
  if (events.length > 1000) events.shift();
  broadcast(e);
}

// ---------------------------------------------------------------- params
const PARAMS = [
  ["HK1", 0.012, 0, 0.1, "m/rad", "heading controller: proportional gain"],
  ["HK2", 0.004, 0, 0.05, "m·s/rad", "heading controller: derivative gain"],
  ["HK_I", 0.0005, 0, 0.01, "m/(rad·s)", "heading controller: integral gain"],
  ["CRS_K", 1.2, 0, 5, "1", "course loop gain"],
  ["LOC_K", 0.02, 0, 0.2, "rad/m", "localizer cross-track gain"],
  ["SPIRAL_R", 160, 50, 400, "m", "box pattern half side"],
  ["FINAL_H", 172, 50, 400, "m", "final approach height above target"],
  ["FLARE_H", 8, 0, 30, "m", "flare (full brakes) height above ground"],
  ["ML_MAX", 1, 0, 1, "1", "main line command limit"],
  ["WIND_TAU", 20, 1, 120, "s", "wind estimator time constant"],
].map(([name, value, min, max, units, description]) => ({ name, value, min, max, units, description }));
const paramsBody = () => ({ params: PARAMS, complete: true, time_s: r2(fl.t) });

// ---------------------------------------------------------------- commands
const commands = new Map(); // request_id → result
let reqSeq = 0;
const newId = (p) => `${p}-${(++reqSeq).toString().padStart(4, "0")}-${Math.floor(rand() * 0xffff).toString(16)}`;

/** Answers 202 at once; the outcome follows like the daemon's (in_progress, then final after ~0.5 s). */
function runCommand(res, who, command, apply, describe) {
  const request_id = newId("req");
  const record = { request_id, command, outcome: "in_progress", attempts: 1, detail: "sent to the drone" };
  commands.set(request_id, record);
  send(res, 202, { request_id, status: "sent" });
  broadcast({ type: "command_result", ...record });
  const down = linkDown();
  setTimeout(() => {
    if (down || linkDown()) {
      Object.assign(record, { outcome: "timed_out", attempts: 3, detail: "no COMMAND_ACK after 3 attempts" });
    } else {
      const r = apply();
      const attempts = rand() < 0.2 ? 2 : 1;
      Object.assign(record, { attempts, ...r });
      if (record.outcome === "accepted") event("info", "command", `${describe} (by ${who.name})`);
      else event("warning", "command", `${describe} ${record.outcome}: ${record.detail} (by ${who.name})`);
    }
    broadcast({ type: "command_result", ...record });
  }, down ? 1500 : 450 + rand() * 150);
}

// ---------------------------------------------------------------- HTTP
function send(res, status, body, headers = {}) {
  const raw = typeof body === "string" || Buffer.isBuffer(body);
  const s = raw ? body : JSON.stringify(body);
  res.writeHead(status, { "Content-Type": raw ? headers["Content-Type"] ?? "text/plain" : "application/json", "Cache-Control": "no-store", ...headers });
  res.end(s);
}
const err = (res, status, error, reason) => send(res, status, { error, reason });

function authenticate(req, url) {
  const h = req.headers.authorization;
  const token = h && h.startsWith("Bearer ") ? h.slice(7) : url.searchParams.get("token");
  return token ? TOKENS[token] ?? null : null;
}

async function readJson(req) {
  let body = "";
  for await (const chunk of req) {
    body += chunk;
    if (body.length > 1e6) throw new Error("body too large");
  }
  if (body.trim() === "") return {};
  return JSON.parse(body);
}

const isNum = (v) => typeof v === "number" && Number.isFinite(v);
const isLat = (v) => isNum(v) && Math.abs(v) <= 90;
const isLon = (v) => isNum(v) && Math.abs(v) <= 180;
/** Returns the name of the first bad field, or null. */
function checkFields(body, spec) {
  if (typeof body !== "object" || body === null || Array.isArray(body)) return "body";
  for (const [k, test, optional] of spec) {
    if (optional && (body[k] === undefined || body[k] === null)) continue;
    if (!test(body[k])) return k;
  }
  return null;
}

const MIME = { ".html": "text/html; charset=utf-8", ".js": "text/javascript", ".css": "text/css", ".svg": "image/svg+xml", ".png": "image/png", ".json": "application/json", ".ico": "image/x-icon", ".webmanifest": "application/manifest+json" };
async function serveStatic(res, pathname) {
  if (!STATIC_DIR) return false;
  const root = resolve(STATIC_DIR);
  const p = normalize(join(root, pathname === "/" ? "index.html" : pathname));
  if (!p.startsWith(root)) return false;
  try {
    const s = await stat(p);
    if (!s.isFile()) return false;
    send(res, 200, await readFile(p), { "Content-Type": MIME[extname(p)] ?? "application/octet-stream" });
    return true;
  } catch {
    return false;
  }
}

function kmlLive() {
  const s = latestState;
  const coords = track.map((p) => `${p.lon_deg},${p.lat_deg},${p.alt_msl_m}`).join(" ");
  const pm = (name, lat, lon, alt = 0) => `<Placemark><name>${name}</name><Point><altitudeMode>absolute</altitudeMode><coordinates>${lon},${lat},${alt}</coordinates></Point></Placemark>`;
  const parts = [];
  parts.push(`<Placemark><name>track</name><LineString><altitudeMode>absolute</altitudeMode><coordinates>${coords}</coordinates></LineString></Placemark>`);
  if (s?.estimate) parts.push(pm("vehicle", s.estimate.lat_deg, s.estimate.lon_deg, s.estimate.alt_msl_m));
  if (s?.guidance?.target) parts.push(pm("target", s.guidance.target.lat_deg, s.guidance.target.lon_deg, s.guidance.target.alt_msl_m));
  if (s?.prediction?.planned) parts.push(pm("predicted landing (planned)", s.prediction.planned.lat_deg, s.prediction.planned.lon_deg));
  if (s?.prediction?.uncontrolled) parts.push(pm("predicted landing (uncontrolled)", s.prediction.uncontrolled.lat_deg, s.prediction.uncontrolled.lon_deg));
  if (s?.guidance?.pattern) {
    const c = s.guidance.pattern.corners.map(([la, lo]) => `${lo},${la},0`);
    parts.push(`<Placemark><name>pattern</name><LineString><coordinates>${[...c, c[0]].join(" ")}</coordinates></LineString></Placemark>`);
  }
  return `<?xml version="1.0" encoding="UTF-8"?><kml xmlns="http://www.opengis.net/kml/2.2"><Document><name>stx live</name>${parts.join("")}</Document></kml>`;
}

async function handle(req, res) {
  const url = new URL(req.url, "http://localhost");
  const path = url.pathname;
  if (!path.startsWith("/api/") && !path.startsWith("/kml") && !path.startsWith("/tiles/") && !path.startsWith("/mock/")) {
    if (req.method === "GET" && (await serveStatic(res, path))) return;
    return err(res, 404, "not_found", `no such path ${path}`);
  }
  if (path.startsWith("/tiles/")) return err(res, 404, "not_found", "the mock serves no tiles");
  if (path.startsWith("/mock/")) return mockControl(req, res, url);
  const who = authenticate(req, url);
  if (!who) return err(res, 401, "unauthorized", "missing or unknown token");

  if (req.method === "GET") {
    if (path === "/api/session") return send(res, 200, { role: who.role, name: who.name, station: STATION });
    if (path === "/api/state") return latestState ? send(res, 200, latestState) : err(res, 503, "no_state", "no state yet");
    if (path === "/api/params") return send(res, 200, paramsBody());
    if (path === "/api/events") {
      const since = Number(url.searchParams.get("since_s") ?? "-Infinity");
      return send(res, 200, { events: events.filter((e) => e.time_s >= since) });
    }
    if (path === "/api/track") {
      const every = Math.max(0, Number(url.searchParams.get("every_s") ?? "0")) || 0;
      let last = -Infinity;
      const points = track.filter((p) => (p.time_s - last >= every ? ((last = p.time_s), true) : false));
      return send(res, 200, { points });
    }
    if (path.startsWith("/api/commands/")) {
      const r = commands.get(decodeURIComponent(path.slice("/api/commands/".length)));
      return r ? send(res, 200, r) : err(res, 404, "not_found", "unknown request_id");
    }
    if (path === "/kml") {
      const token = url.searchParams.get("token") ?? "";
      const host = req.headers.host ?? `127.0.0.1:${PORT}`;
      const href = `http://${host}/kml/live?token=${encodeURIComponent(token)}`.replace(/&/g, "&amp;");
      return send(res, 200, `<?xml version="1.0" encoding="UTF-8"?><kml xmlns="http://www.opengis.net/kml/2.2"><NetworkLink><name>stx live</name><Link><href>${href}</href><refreshMode>onInterval</refreshMode><refreshInterval>2</refreshInterval></Link></NetworkLink></kml>`, { "Content-Type": "application/vnd.google-earth.kml+xml" });
    }
    if (path === "/kml/live") return send(res, 200, kmlLive(), { "Content-Type": "application/vnd.google-earth.kml+xml" });
    return err(res, 404, "not_found", `no such path ${path}`);
  }

  if (req.method !== "POST") return err(res, 405, "method_not_allowed", `${req.method} not allowed`);
  if (who.role !== "operator") return err(res, 403, "forbidden", "viewers cannot command: operator role required");
  let body;
  try {
    body = await readJson(req);
  } catch (e) {
    return err(res, 400, "bad_request", `body is not JSON: ${e.message}`);
  }
  const bad = (field) => err(res, 400, "bad_request", `bad or missing field \`${field}\``);

  switch (path) {
    case "/api/commands/mode": {
      const f = checkFields(body, [["mode", (m) => MODES.includes(m)]]);
      if (f) return bad(f);
      return runCommand(res, who, "set_mode", () => {
        fl.mode = body.mode;
        if (body.mode === "spiral_landing") {
          fl.corner = 0;
          setPhase("approach");
        } else setPhase(body.mode);
        return { outcome: "accepted", detail: `mode ${body.mode}` };
      }, `mode → ${body.mode}`);
    }
    case "/api/commands/heading": {
      const f = checkFields(body, [["heading_deg", isNum]]);
      if (f) return bad(f);
      return runCommand(res, who, "set_heading", () => ((fl.heading_cmd = wrap360(body.heading_deg)), { outcome: "accepted", detail: `heading ${fl.heading_cmd}°` }), `heading → ${body.heading_deg}°`);
    }
    case "/api/commands/course": {
      const f = checkFields(body, [["course_deg", isNum]]);
      if (f) return bad(f);
      return runCommand(res, who, "set_course", () => ((fl.course_cmd = wrap360(body.course_deg)), { outcome: "accepted", detail: `course ${fl.course_cmd}°` }), `course → ${body.course_deg}°`);
    }
    case "/api/commands/localizer": {
      const f = checkFields(body, [["lat_deg", isLat], ["lon_deg", isLon], ["course_deg", isNum], ["glide_slope", isNum, true]]);
      if (f) return bad(f);
      return runCommand(res, who, "set_localizer", () => ((fl.localizer = body), { outcome: "accepted", detail: "localizer set" }), `localizer → ${body.course_deg}°`);
    }
    case "/api/commands/target": {
      const f = checkFields(body, [["lat_deg", isLat], ["lon_deg", isLon], ["alt_msl_m", isNum], ["approach_course_deg", isNum, true]]);
      if (f) return bad(f);
      if (!("approach_course_deg" in body)) return bad("approach_course_deg");
      return runCommand(res, who, "set_target", () => {
        fl.target = { lat_deg: body.lat_deg, lon_deg: body.lon_deg, alt_msl_m: body.alt_msl_m, approach_course_deg: body.approach_course_deg ?? null };
        fl.corner = 0;
        return { outcome: "accepted", detail: "target set" };
      }, `target → ${body.lat_deg.toFixed(5)}, ${body.lon_deg.toFixed(5)}`);
    }
    case "/api/commands/plan": {
      if (typeof body !== "object" || !Array.isArray(body.items) || body.items.length === 0) return bad("items");
      for (const [i, it] of body.items.entries()) {
        const f = checkFields(it, [["kind", (k) => k === "waypoint" || k === "land"], ["lat_deg", isLat], ["lon_deg", isLon], ["alt_msl_m", isNum], ["approach_course_deg", isNum, true]]);
        if (f) return bad(`items[${i}].${f}`);
      }
      const land = body.items.filter((i) => i.kind === "land");
      if (land.length !== 1 || body.items[body.items.length - 1].kind !== "land") return bad("items (exactly one land item, last)");
      return runCommand(res, who, "set_plan", () => {
        fl.plan = body.items;
        const l = land[0];
        fl.target = { lat_deg: l.lat_deg, lon_deg: l.lon_deg, alt_msl_m: l.alt_msl_m, approach_course_deg: l.approach_course_deg ?? null };
        return { outcome: "accepted", detail: `plan of ${body.items.length} items` };
      }, `plan → ${body.items.length} items`);
    }
    case "/api/cutdown/arm": {
      const arm_id = newId("arm");
      armed.set(arm_id, { who: who.name, until: Date.now() + 5000 });
      fl.cutdownArmedUntil = r2(fl.t + 5);
      event("warning", "command", `cutdown armed (by ${who.name})`);
      return send(res, 200, { arm_id, expires_in_s: 5 });
    }
    case "/api/cutdown/confirm": {
      const f = checkFields(body, [["arm_id", (a) => typeof a === "string"]]);
      if (f) return bad(f);
      const a = armed.get(body.arm_id);
      if (!a || a.until < Date.now()) return err(res, 409, "not_armed", a ? "the arm has expired" : "not armed or the arm_id does not match");
      armed.delete(body.arm_id);
      fl.cutdownArmedUntil = null;
      return runCommand(res, who, "cutdown", () => ({ outcome: "accepted", detail: "flight termination acknowledged" }), "CUTDOWN confirmed");
    }
    default:
      break;
  }
  if (path.startsWith("/api/params/")) {
    const name = decodeURIComponent(path.slice("/api/params/".length));
    const p = PARAMS.find((x) => x.name === name);
    if (!p) return err(res, 400, "bad_request", `unknown parameter \`${name}\``);
    const f = checkFields(body, [["value", isNum]]);
    if (f) return bad(f);
    return runCommand(res, who, "set_param", () => {
      if (body.value < p.min || body.value > p.max) return { outcome: "denied", detail: `${name}: ${body.value} outside ${p.min}…${p.max}`, value: p.value };
      // The drone stores float32: the read-back differs in the last digits, as with real PARAM_VALUE.
      p.value = Math.fround(body.value);
      setTimeout(() => broadcast({ type: "params", ...paramsBody() }), 10);
      return { outcome: "accepted", detail: `${name} = ${p.value} (read back)`, value: p.value };
    }, `param ${name} → ${body.value}`);
  }
  return err(res, 404, "not_found", `no such path ${path}`);
}
const armed = new Map();

/**
 * Test hooks, outside the API (the real daemon has none of these):
 *   POST /mock/link?down=1|0   force the drone link down (STALE) or let it follow the schedule
 *   POST /mock/garbage         broadcast malformed frames (the page must count them, not crash)
 *   GET  /mock/stats           manual and manual_release messages received
 */
function mockControl(req, res, url) {
  if (req.method === "POST" && url.pathname === "/mock/link") {
    forcedDown = url.searchParams.get("down") === "1";
    return send(res, 200, { forced_down: forcedDown });
  }
  if (req.method === "POST" && url.pathname === "/mock/garbage") {
    for (const c of clients) {
      if (c.ws.readyState !== 1) continue;
      c.ws.send("{not json");
      c.ws.send(JSON.stringify({ type: "state" }));
      c.ws.send(JSON.stringify({ type: "event", level: "info" }));
      c.ws.send(JSON.stringify([1, 2, 3]));
    }
    return send(res, 200, { sent: 4 });
  }
  if (req.method === "GET" && url.pathname === "/mock/stats") return send(res, 200, { manual_total: manualTotal, manual_releases: manualReleases });
  return err(res, 404, "not_found", "unknown mock hook");
}
let manualTotal = 0;
let manualReleases = 0;

const server = createServer((req, res) => {
  handle(req, res).catch((e) => {
    console.error("mock: handler error", e);
    if (!res.headersSent) err(res, 500, "internal", String(e));
  });
});

// ---------------------------------------------------------------- WebSocket
const wss = new WebSocketServer({ noServer: true, maxPayload: 64 * 1024 });
server.on("upgrade", (req, socket, head) => {
  const url = new URL(req.url, "http://localhost");
  if (url.pathname !== "/api/ws") {
    socket.end("HTTP/1.1 404 Not Found\r\n\r\n");
    return;
  }
  const who = authenticate(req, url);
  if (!who) {
    socket.end('HTTP/1.1 401 Unauthorized\r\nContent-Type: application/json\r\n\r\n{"error":"unauthorized","reason":"missing or unknown token"}');
    return;
  }
  wss.handleUpgrade(req, socket, head, (ws) => {
    const client = { ws, who };
    clients.add(client);
    ws.send(JSON.stringify({ type: "hello", role: who.role, name: who.name, station: STATION }));
    if (latestState) ws.send(JSON.stringify(latestState));
    ws.send(JSON.stringify({ type: "history", track: track.slice(-3600), events: events.slice(-200), states: states1hz }));
    ws.on("message", (data) => {
      let m;
      try {
        m = JSON.parse(String(data));
      } catch {
        ws.send(JSON.stringify({ type: "event", time_s: r2(fl.t), wall_ms: Date.now(), level: "error", source: "station", text: "unreadable message from this page" }));
        return;
      }
      if (m.type === "ping") ws.send(JSON.stringify({ type: "pong" }));
      else if (m.type === "manual") {
        if (who.role !== "operator") {
          ws.send(JSON.stringify({ type: "event", time_s: r2(fl.t), wall_ms: Date.now(), level: "error", source: "command", text: "manual control refused: operator role required" }));
          return;
        }
        if (![m.x, m.y, m.z, m.r].every(isNum)) return;
        fl.manual = { y: clamp(m.y, -1, 1), z: clamp(m.z, 0, 1), at: fl.t };
        manualCount += 1;
        manualTotal += 1;
      } else if (m.type === "manual_release") {
        // As the daemon does: the sticks stop at once, not after the 0.5 s silence.
        if (who.role === "operator") fl.manual = null;
        manualReleases += 1;
      }
    });
    ws.on("close", () => clients.delete(client));
    ws.on("error", () => clients.delete(client));
  });
});
let manualCount = 0;

// ---------------------------------------------------------------- the clock
const TICK_S = 0.25; // 4 Hz state
let lastTrackT = -Infinity;
let lastHistT = -Infinity;
let lastManualLog = 0;
event("info", "station", "mock station started");
setInterval(() => {
  for (let i = 0; i < 5; i++) step((TICK_S * SPEED) / 5);
  const s = buildState();
  latestState = s;
  if (s.estimate && !s.link.stale && fl.t - lastTrackT >= 1) {
    lastTrackT = fl.t;
    track.push({ time_s: s.time_s, lat_deg: s.estimate.lat_deg, lon_deg: s.estimate.lon_deg, alt_msl_m: s.estimate.alt_msl_m });
    if (track.length > 7200) track.shift();
  }
  if (fl.t - lastHistT >= 1) {
    lastHistT = fl.t;
    states1hz.push(s);
    while (states1hz.length > 300) states1hz.shift();
  }
  if (manualCount > 0 && fl.t - lastManualLog > 5) {
    lastManualLog = fl.t;
    event("info", "command", `manual control: ${manualCount} stick messages in the last 5 s`);
    manualCount = 0;
  }
  broadcast(s);
}, TICK_S * 1000);

server.listen(PORT, "127.0.0.1", () => {
  console.log(`mock stx station on http://127.0.0.1:${PORT}${STATIC_DIR ? ` (serving ${STATIC_DIR})` : ""} — tokens: op, op2, view`);
});
for (const sig of ["SIGINT", "SIGTERM"]) process.on(sig, () => process.exit(0));
