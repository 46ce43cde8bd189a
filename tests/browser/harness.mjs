// The shared harness of the browser tests (tests/browser/*.mjs): one stx binary, one chromium,
// the checks' tally, the API contract every message is validated against, processes started and
// stopped, and small geodesy for the checks. Each test script imports it, runs its flights, and
// ends with `finish(expected)`, which prints the tally and exits with its verdict.
//
// Usage of a test script: node tests/browser/NAME.mjs [path/to/stx]   (default target/release/stx)
// Env: CHROMIUM (default /usr/bin/chromium), SIM_SPEED (default 5).

import { spawn } from "node:child_process";
import { createSocket } from "node:dgram";
import { copyFile, mkdir, mkdtemp, readFile, writeFile } from "node:fs/promises";
import { tmpdir } from "node:os";
import { createRequire } from "node:module";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath, pathToFileURL } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
export const root = resolve(here, "../..");
// playwright-core comes from the dashboard's own locked dependencies (web/package-lock.json).
const { chromium } = createRequire(join(root, "web/package.json"))("playwright-core");
const { contract } = await import(pathToFileURL(join(root, "web/scripts/contract.mjs")).href);
export const out = join(root, "tests/output/browser");
await mkdir(out, { recursive: true });

export const stxBin = resolve(process.argv[2] ?? join(root, "target/release/stx"));
export const speed = Number(process.env.SIM_SPEED ?? 5);
export const OPERATOR = "operator-token";
export const VIEWER = "viewer-token";
export const sleep = (ms) => new Promise((r) => setTimeout(r, ms));
const started = Date.now();
export const FIELD_HOST = "stx-field.test";

export const results = [];
let failed = false;
export function check(name, ok, detail = "") {
  results.push(`${ok ? "PASS" : "FAIL"}  ${name}${detail ? ` — ${detail}` : ""}`);
  console.log(results[results.length - 1]);
  if (!ok) failed = true;
}

// ------------------------------------------------------------------ the API's contract
const api = contract();
const seen = new Map(); // contract name (or WebSocket type) -> how many were valid
let broken = null; // the first message that broke the contract
const pendingBodies = [];
let lastRequestId = null;
/** Checks one message against the contract's definition `name`; remembers the first that breaks it. */
export function conform(where, name, value) {
  const error = api.check(name, value);
  if (error !== null) {
    if (broken === null) {
      broken = `${where}: ${error} in ${JSON.stringify(value).slice(0, 300)}`;
      console.log(`CONTRACT BROKEN  ${broken}`);
    }
    return;
  }
  const key = ["ServerMessage", "ClientMessage", "RelayMessage"].includes(name) ? `${name}:${value.type}` : name;
  seen.set(key, (seen.get(key) ?? 0) + 1);
}
/** REST calls other test scripts add to the contract's map: `[method, path RegExp, request name or null, response name]`. */
const extraRest = [];
/** Adds a REST call to the map from (method, path) to the contract's body names. */
export function registerRest(method, path, requestName, responseName) {
  extraRest.push([method, path, requestName, responseName]);
}
/** What the contract calls a REST body: `[request body or null, response body]` for one call. */
function restNames(method, path, status) {
  if (status >= 400) return [null, "ErrorBody"];
  const gets = { "/api/session": "Session", "/api/state": "StateMsg", "/api/params": "ParamsMsg", "/api/ascent_wind": "AscentWindMsg", "/api/keep-out": "KeepOutMsg", "/api/events": "EventsBody", "/api/track": "TrackBody", "/api/clients": "ClientsBody", "/api/sharing": "SharingBody" };
  if (method === "GET" && gets[path]) return [null, gets[path]];
  if (method === "GET" && /^\/api\/commands\/[^/]+$/.test(path)) return [null, "CommandResultMsg"];
  const commands = { mode: "ModeBody", heading: "HeadingBody", course: "CourseBody", localizer: "LocalizerBody", target: "TargetBody", plan: "PlanBody" };
  const command = /^\/api\/commands\/(\w+)$/.exec(path)?.[1];
  if (method === "POST" && command && commands[command]) return [commands[command], "CommandAccepted"];
  if (method === "POST" && /^\/api\/params\/[^/]+$/.test(path)) return ["ParamBody", "CommandAccepted"];
  if (method === "POST" && path === "/api/cutdown/arm") return [null, "CutdownArm"];
  if (method === "POST" && path === "/api/cutdown/confirm") return ["ConfirmBody", "CommandAccepted"];
  if (path === "/api/replay") return [method === "POST" ? "ReplayBody" : null, "ReplayView"];
  if (method === "GET" && path === "/api/recordings") return [null, "RecordingsBody"];
  if (method === "POST" && /^\/api\/recordings\/[^/]+\/replay$/.test(path)) return [null, "ReplayOpened"];
  if (method === "POST" && path === "/api/sondehub/chase") return ["ChaseCarBody", "SondehubView"];
  if (path === "/api/surface_wind" && ["GET", "POST", "DELETE"].includes(method)) return [method === "POST" ? "SurfaceWindBody" : null, "SurfaceWindView"];
  for (const [m, p, req, res] of extraRest) if (m === method && p.test(path)) return [req, res];
  return [null, null];
}
function conformRest(where, method, path, status, request, body) {
  const [requestName, responseName] = restNames(method, path, status);
  if (responseName === null) {
    broken ??= `${where}: ${method} ${path} (${status}) is not in the contract`;
    return;
  }
  if (requestName !== null && request !== undefined) conform(`${where} ${method} ${path} request`, requestName, request);
  conform(`${where} ${method} ${path} → ${status}`, responseName, body);
  if (responseName === "CommandAccepted" && typeof body?.request_id === "string") lastRequestId = body.request_id;
}
/** Validates everything a browser context's pages exchange with the station. */
export function watchContract(ctx, label, server = "ServerMessage") {
  const frames = (page) => page.on("websocket", (ws) => {
    if (!new URL(ws.url()).pathname.startsWith("/api/ws")) return;
    const json = (f, dir) => {
      try {
        return JSON.parse(f.payload);
      } catch {
        broken ??= `${label} WebSocket ${dir}: not JSON: ${String(f.payload).slice(0, 80)}`;
        return undefined;
      }
    };
    ws.on("framereceived", (f) => {
      const m = json(f, "received");
      if (m !== undefined) conform(`${label} WebSocket, station → page`, server, m);
    });
    ws.on("framesent", (f) => {
      const m = json(f, "sent");
      if (m !== undefined) conform(`${label} WebSocket, page → station`, "ClientMessage", m);
    });
  });
  ctx.on("page", frames);
  ctx.on("response", (r) => {
    const url = new URL(r.url());
    if (!url.pathname.startsWith("/api/") || url.pathname === "/api/ws") return;
    const req = r.request();
    let request;
    try {
      request = req.postData() === null ? undefined : req.postDataJSON();
    } catch {
      request = req.postData();
    }
    pendingBodies.push(r.text().then(
      (text) => {
        let body;
        try {
          body = JSON.parse(text);
        } catch {
          broken ??= `${label} ${req.method()} ${url.pathname} → ${r.status()}: not JSON: ${text.slice(0, 80)}`;
          return;
        }
        conformRest(label, req.method(), url.pathname, r.status(), request, body);
      },
      () => {}, // the page went away before the body arrived
    ));
  });
}
export async function newContext(label, options, server = "ServerMessage") {
  const ctx = await browser.newContext(options);
  watchContract(ctx, label, server);
  await watchPolicy(ctx, label);
  // A body still being read when its context closes is lost, and with it the contract's check
  // of it: a test that closes right after an answer it checked (plan.mjs's last 400) met an
  // ErrorBody the tally never saw.
  const close = ctx.close.bind(ctx);
  ctx.close = async (...args) => {
    await Promise.allSettled(pendingBodies);
    return close(...args);
  };
  return ctx;
}

// ------------------------------------------------------------------ the security headers
const policyErrors = [];
let policedPages = 0;
/**
 * Every page of `ctx` under the station's Content-Security-Policy and security headers, and none
 * breaking the policy: a page served without them, or any violation (a script, style, image,
 * socket or frame the policy blocked), fails the test, whether or not the test watches the
 * page's console.
 */
async function watchPolicy(ctx, label) {
  await ctx.addInitScript(() => {
    document.addEventListener("securitypolicyviolation", (e) =>
      console.error(`CSP violation: ${e.effectiveDirective} blocked ${e.blockedURI || "inline"} at ${e.sourceFile}:${e.lineNumber}`));
  });
  ctx.on("page", (page) => page.on("console", (m) => {
    if (/Content Security Policy|CSP violation/.test(m.text())) policyErrors.push(`${label}: ${m.text()}`);
  }));
  ctx.on("response", (r) => {
    if (r.request().resourceType() !== "document") return;
    policedPages += 1;
    const h = r.headers();
    const ok = (h["content-security-policy"] ?? "").includes("frame-ancestors 'none'") && h["x-frame-options"] === "DENY" && h["x-content-type-options"] === "nosniff" && h["referrer-policy"] === "no-referrer";
    if (!ok) policyErrors.push(`${label}: ${r.url()} came without the security headers: ${JSON.stringify(h)}`);
  });
}

// ------------------------------------------------------------------ geodesy for the checks
const R = 6371008.8;
export const rad = Math.PI / 180;
/** Great-circle distance, m. */
export function distanceM(a, b) {
  const h = Math.sin(((b.lat_deg - a.lat_deg) * rad) / 2) ** 2 + Math.cos(a.lat_deg * rad) * Math.cos(b.lat_deg * rad) * Math.sin(((b.lon_deg - a.lon_deg) * rad) / 2) ** 2;
  return 2 * R * Math.asin(Math.sqrt(h));
}
/** Initial great-circle bearing from a to b, degrees [0, 360). */
export function bearingDeg(a, b) {
  const y = Math.sin((b.lon_deg - a.lon_deg) * rad) * Math.cos(b.lat_deg * rad);
  const x = Math.cos(a.lat_deg * rad) * Math.sin(b.lat_deg * rad) - Math.sin(a.lat_deg * rad) * Math.cos(b.lat_deg * rad) * Math.cos((b.lon_deg - a.lon_deg) * rad);
  return (Math.atan2(y, x) / rad + 360) % 360;
}
/** North/east metres from a site to lat/lon on the WGS-84 tangent plane (as stx-gnc's LocalFrame). */
export function fromNorthEast(site, north_m, east_m) {
  const s = Math.sin(site.lat_deg * rad);
  const w = Math.sqrt(1 - 6.69437999014e-3 * s * s);
  const meridian = (6378137 * (1 - 6.69437999014e-3)) / w ** 3;
  const prime = 6378137 / w;
  return { lat_deg: site.lat_deg + north_m / meridian / rad, lon_deg: site.lon_deg + east_m / (prime * Math.cos(site.lat_deg * rad)) / rad };
}
/**
 * Whether a predicted landing has settled: of `heard` ({ at: ms, point: lat/lon or null }, oldest
 * first) the newest is known, the last `n` known lie within `withinM` of it, and the first known
 * was heard at least `afterMs` before it. As the parafoil opens the station's estimate
 * starts over and its predictions jump (by 1.3 km on one run); a zone put under the first one may
 * never be entered.
 */
export function settled(heard, { n = 6, withinM = 60, afterMs = 2000 } = {}) {
  const known = heard.filter((h) => h.point);
  const recent = known.slice(-n);
  const last = recent[recent.length - 1];
  return recent.length === n && heard[heard.length - 1] === last && last.at - known[0].at >= afterMs && recent.every((h) => distanceM(h.point, last.point) < withinM);
}
/** Ray casting: whether point `p` lies inside `ring`, both as pairs in the same order ([lat, lon] or GeoJSON's [lon, lat]). */
export function inRing(ring, p) {
  let inside = false;
  for (let i = 0, j = ring.length - 1; i < ring.length; j = i++) {
    const [ai, bi] = ring[i];
    const [aj, bj] = ring[j];
    if (bi > p[1] !== bj > p[1] && p[0] < ((aj - ai) * (p[1] - bi)) / (bj - bi) + ai) inside = !inside;
  }
  return inside;
}
export const angleDiff = (a, b) => Math.abs(((a - b + 540) % 360) - 180);
/** "812 m" / "1.23 km" → metres. */
export const shownMetres = (t) => (/km/.test(t) ? parseFloat(t) * 1000 : parseFloat(t));

// ------------------------------------------------------------------ processes
const children = [];
const logs = [];
export function run(args, label) {
  const p = spawn(stxBin, args, { cwd: root, stdio: ["ignore", "pipe", "pipe"], env: { ...process.env, RUST_LOG: "warn" } });
  const io = { proc: p, out: "", err: "", label };
  p.stdout.on("data", (d) => (io.out += d));
  p.stderr.on("data", (d) => (io.err += d));
  children.push(io);
  logs.push(io);
  return io;
}
/** Each station of the test records its run here (not in the user's state directory). */
export const recordDir = await mkdtemp(join(tmpdir(), "stx-browser-recordings-"));
export async function startStation(args) {
  const io = run(["serve", "--listen", "127.0.0.1:0", "--record-dir", recordDir, ...args], "stx serve");
  for (let i = 0; i < 100 && !/open (http:\/\/\S+)\/\?token=/.test(io.out); i++) await sleep(100);
  const found = /open (http:\/\/\S+)\/\?token=/.exec(io.out);
  if (!found) throw new Error(`stx serve did not start:\n${io.out}\n${io.err}`);
  return { io, base: found[1] };
}

/**
 * The shipped station config with its sample zones copied aside: an operator's edit is written to
 * the configured file, and the test's edits must not land in the repository's sample.
 */
export async function configWithZoneCopy() {
  const dir = await mkdtemp(join(tmpdir(), "stx-browser-zones-"));
  const zones = join(dir, "zones.geojson");
  await copyFile(join(root, "config/keep-out/sample.geojson"), zones);
  const toml = await readFile(join(root, "config/station.toml"), "utf8");
  const edited = toml.replace(/^keep_out = .*$/m, `keep_out = ${JSON.stringify(zones)}`);
  if (edited === toml) throw new Error("config/station.toml has no keep_out line to point at the copy");
  const file = join(dir, "station.toml");
  await writeFile(file, edited);
  return { file, zones };
}

/** A free loopback UDP port for the station's link (the drone must know it before it starts). */
export async function freeUdpPort() {
  const s = createSocket("udp4");
  await new Promise((r) => s.bind(0, "127.0.0.1", r));
  const port = s.address().port;
  await new Promise((r) => s.close(r));
  return port;
}

/** The station's API, as the drone's telemetry arrives in it. */
export function apiOf(base) {
  return async (path, token = VIEWER, init = {}) => {
    const r = await fetch(`${base}${path}`, { ...init, headers: { authorization: `Bearer ${token}`, "content-type": "application/json", ...(init.headers ?? {}) } });
    const body = await r.json().catch(() => null);
    const request = typeof init.body === "string" ? JSON.parse(init.body) : undefined;
    conformRest("test", init.method ?? "GET", new URL(r.url).pathname, r.status, request, body);
    return { status: r.status, body };
  };
}
export async function until(what, pred, timeoutMs, everyMs = 200) {
  const t0 = Date.now();
  let last;
  while (Date.now() - t0 < timeoutMs) {
    last = await what();
    if (pred(last)) return last;
    await sleep(everyMs);
  }
  return last;
}

export const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  // FIELD_HOST is the station under a name that is not loopback, as a phone reaches the field
  // laptop: plain HTTP there is not a secure context, so the browser gives no position.
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run", "--enable-unsafe-swiftshader", `--host-resolver-rules=MAP ${FIELD_HOST} 127.0.0.1`],
});
export const text = (page, id) => page.locator(`[data-testid="${id}"]`).first().innerText();
export const attr = (page, id, name) => page.locator(`[data-testid="${id}"]`).first().getAttribute(name);
/** The readouts on the page whose text is cut short (an ellipsis shown): "testid: text". */
export const cutShort = (page) => page.locator(".ro-val").evaluateAll((els) =>
  els.filter((e) => e.offsetParent !== null && e.scrollWidth > e.clientWidth + 1).map((e) => `${e.dataset.testid ?? "?"}: ${e.textContent}`));
export const rectOf = (page, sel) => page.evaluate((s) => {
  const e = document.querySelector(s);
  if (!e) return null;
  const b = e.getBoundingClientRect();
  return { left: b.left, top: b.top, right: b.right, bottom: b.bottom, width: b.width, height: b.height };
}, sel);
const pageErrors = [];
export function watchErrors(page, label) {
  page.on("pageerror", (e) => pageErrors.push(`${label}: ${e.message}`));
  page.on("console", (m) => {
    if (m.type() === "error" && !/Failed to load resource/.test(m.text())) pageErrors.push(`${label}: ${m.text()}`);
  });
}
/**
 * A map's legend (ui/mapLegend.ts) against its map. `symbols` maps each legend key to the map
 * element that draws it (a CSS selector) and the style property carrying its colour. For each:
 * whether the map shows it (a path of two points or more, another element with a size: Leaflet
 * leaves an emptied layer's path in the page with nothing in it), whether the legend lists it, and the colour and text of
 * both, the legend's read from its swatch's marked shape (`data-sw`).
 */
export const legendAgainstMap = (page, legend, symbols) => page.evaluate(([legend, symbols]) => {
  // A path is drawn from two points on, however close (a 1-σ ellipse of a few metres, which
  // Leaflet rounds to one pixel); its empty path is "M0 0", and a line of one point draws
  // nothing. Anything else is drawn when it has a size (a grid line has no width).
  const seen = (e) => {
    if (e instanceof SVGPathElement) return ((e.getAttribute("d") ?? "").match(/-?[\d.]+/g) ?? []).length >= 4;
    const r = e?.getBoundingClientRect();
    return !!r && (r.width > 0 || r.height > 0);
  };
  const rows = {};
  for (const [key, [sel, prop]] of Object.entries(symbols)) {
    const onMap = [...document.querySelectorAll(sel)].find(seen) ?? null;
    const row = document.querySelector(`[data-testid="${legend}-${key}"]`);
    const sw = row?.querySelector("[data-sw]") ?? null;
    const look = (e) => (e ? `${getComputedStyle(e)[prop]}${e instanceof HTMLElement ? ` ${e.textContent}` : ""}` : null);
    rows[key] = { drawn: onMap !== null, listed: row !== null && seen(row), map: look(onMap), legend: look(sw), label: row?.textContent ?? null };
  }
  return rows;
}, [legend, symbols]);
/**
 * Checks a legend against its map: each symbol drawn is listed with its own colour (and glyph),
 * none is listed that is not drawn, and each of `expected` is drawn (so the check cannot pass
 * on an empty map).
 */
export function checkLegend(name, rows, expected) {
  const wrong = Object.entries(rows).filter(([, r]) => r.drawn !== r.listed || (r.drawn && r.map !== r.legend));
  const missing = expected.filter((k) => !rows[k]?.drawn);
  check(name, wrong.length === 0 && missing.length === 0,
    `${wrong.map(([k, r]) => `${k}: ${r.drawn ? "drawn" : "not drawn"} (${r.map}), ${r.listed ? "listed" : "not listed"} (${r.legend})`).join("; ") || "legend agrees"}${missing.length ? `; expected on the map: ${missing.join(", ")}` : ""}; listed: ${Object.entries(rows).filter(([, r]) => r.listed).map(([k]) => k).join(", ")}`);
}
/** What the live map draws (ui/mapSymbols.ts), as the page's elements show it. */
export const LIVE_SYMBOLS = {
  vehicle: ['[data-testid="map-vehicle"] path', "fill"],
  track: ["path.map-track", "stroke"],
  target: ['[data-testid="map-target"] circle:nth-of-type(2)', "stroke"],
  pattern: ["path.map-pattern", "stroke"],
  final: ["path.map-final-line", "stroke"],
  planned: ['[data-testid="map-pred-planned"] circle', "fill"],
  "ellipse-planned": ["path.map-ellipse-planned", "stroke"],
  uncontrolled: ['[data-testid="map-pred-uncontrolled"] circle', "fill"],
  "ellipse-uncontrolled": ["path.map-ellipse-uncontrolled", "stroke"],
  "reach-50": ["path.map-footprint-50", "fill"],
  "reach-95": ["path.map-footprint-95", "stroke"],
  path: ["path.map-flight-path", "stroke"],
  burst: ['[data-testid="map-burst"]', "color"],
  deploy: ['[data-testid="map-deploy"]', "color"],
  unsteered: ['[data-testid="map-unsteered-landing"]', "color"],
  chute: ['[data-testid="map-chute-landing"]', "color"],
  "path-reach": ["path.map-path-reach", "stroke"],
  "keep-out": ["path.map-keep-out", "fill"],
  "draft-target": ['[data-testid="map-draft-target"] circle:nth-of-type(2)', "stroke"],
  "draft-plan": ["path.map-draft-plan", "stroke"],
  "draft-localizer": ["path.map-draft-localizer", "stroke"],
  grid: ['[data-testid="map"] path.map-grid', "stroke"],
};
/** Zooms the live map out by `steps` (following stops), so that nothing drawn lies outside the view. */
export async function zoomOut(page, steps) {
  for (let i = 0; i < steps; i++) {
    await page.click('[data-testid="map"] .leaflet-control-zoom-out');
    await sleep(350);
  }
}

/** Presses the pointer on an element for `ms`, as a person holding a button. */
export async function hold(page, id, ms) {
  const b = await page.locator(`[data-testid="${id}"]`).boundingBox();
  await page.mouse.move(b.x + b.width / 2, b.y + b.height / 2);
  await page.mouse.down();
  await sleep(ms);
  await page.mouse.up();
}
/** The REST call whose answer carried the newest request id, to read its result back. */
export const lastRequest = () => lastRequestId;
/** Stops every process started so far (a flight's drone and station, before the next flight). */
export function stopChildren() {
  for (const c of children.splice(0)) c.proc.kill("SIGTERM");
}

/**
 * Ends the test: page errors, the contract (every kind in `expected` must have been met, so the
 * check cannot pass on silence), the tally; closes the browser, stops the processes and exits
 * with the verdict.
 */
export async function finish(expected) {
  check("no page errors", pageErrors.length === 0, pageErrors.slice(0, 5).join(" | "));
  check("every page under the station's Content-Security-Policy and security headers, none breaking it", policedPages > 0 && policyErrors.length === 0,
    // Our listener's lines first: they name the directive and where the page broke it.
    policyErrors.length > 0 ? [...new Set(policyErrors)].sort((a, b) => Number(b.includes("CSP violation:")) - Number(a.includes("CSP violation:"))).slice(0, 5).join(" | ") : `${policedPages} pages`);
  await Promise.allSettled(pendingBodies);
  const missing = expected.filter((k) => !seen.has(k));
  check("every message between the station and the pages matches the contract (web/src/generated/api.schema.json)", broken === null && missing.length === 0,
    broken ?? (missing.length > 0 ? `never seen: ${missing.join(", ")}` : [...seen].map(([k, n]) => `${k} ${n}`).join(", ")));
  await browser.close();
  for (const c of children) c.proc.kill("SIGTERM");
  const passed = results.filter((r) => r.startsWith("PASS")).length;
  console.log(`\n${passed} passed, ${results.length - passed} failed in ${((Date.now() - started) / 1000).toFixed(0)} s; screenshots in ${out}`);
  if (failed) for (const c of logs) console.log(`${c.label} stderr (tail):\n${c.err.split("\n").slice(-20).join("\n")}`);
  process.exit(failed ? 1 : 0);
}

/** Runs the test's flights, failing the tally if one throws, then `finish(expected)`. */
export async function runFlights(flights, expected) {
  try {
    await flights();
  } catch (e) {
    check("the test ran to the end", false, e instanceof Error ? (e.stack ?? e.message) : String(e));
  }
  await finish(expected);
}
