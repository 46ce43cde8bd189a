#!/usr/bin/env node
// End-to-end test of the whole station in a real browser: `stx serve --sim` (the daemon with the
// built-in simulated drone over loopback MAVLink) and Debian's chromium driven by playwright-core.
// Every check reads what the drone itself reports back through the link, never the page's own
// echo. Screenshots go to tests/output/browser/. Exit code 0 only if every check holds.
//
// Usage: node tests/browser/live.mjs [path/to/stx]   (default target/release/stx)
// Env: CHROMIUM (default /usr/bin/chromium), SIM_SPEED (default 5).

import { spawn } from "node:child_process";
import { mkdir } from "node:fs/promises";
import { createRequire } from "node:module";
import { dirname, join, resolve } from "node:path";
import { fileURLToPath } from "node:url";

const here = dirname(fileURLToPath(import.meta.url));
const root = resolve(here, "../..");
// playwright-core comes from the dashboard's own locked dependencies (web/package-lock.json).
const { chromium } = createRequire(join(root, "web/package.json"))("playwright-core");
const out = join(root, "tests/output/browser");
await mkdir(out, { recursive: true });

const stxBin = resolve(process.argv[2] ?? join(root, "target/release/stx"));
const speed = Number(process.env.SIM_SPEED ?? 5);
const OPERATOR = "operator-token";
const VIEWER = "viewer-token";
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const results = [];
let failed = false;
function check(name, ok, detail = "") {
  results.push(`${ok ? "PASS" : "FAIL"}  ${name}${detail ? ` — ${detail}` : ""}`);
  console.log(results[results.length - 1]);
  if (!ok) failed = true;
}

// ------------------------------------------------------------------ the station and its drone
const station = spawn(
  stxBin,
  ["serve", "--sim", "--sim-scenario", "rehearsal", "--sim-speed", String(speed), "--listen", "127.0.0.1:0", "--link", "udpin:127.0.0.1:0"],
  { cwd: root, stdio: ["ignore", "pipe", "pipe"], env: { ...process.env, RUST_LOG: "warn" } },
);
let stationOut = "";
let stationErr = "";
station.stdout.on("data", (d) => (stationOut += d));
station.stderr.on("data", (d) => (stationErr += d));
for (let i = 0; i < 100 && !/open (http:\/\/\S+)\/\?token=/.test(stationOut); i++) await sleep(100);
const found = /open (http:\/\/\S+)\/\?token=/.exec(stationOut);
if (!found) {
  console.error(`stx serve --sim did not start:\n${stationOut}\n${stationErr}`);
  station.kill("SIGTERM");
  process.exit(2);
}
const base = found[1];
console.log(`station at ${base}, simulated drone at ${speed}× real time`);

/** The station's API, as the drone's telemetry arrives in it. */
async function api(path, token = VIEWER, init = {}) {
  const r = await fetch(`${base}${path}`, { ...init, headers: { authorization: `Bearer ${token}`, "content-type": "application/json", ...(init.headers ?? {}) } });
  return { status: r.status, body: await r.json().catch(() => null) };
}
const vehicle = async () => (await api("/api/state")).body?.vehicle ?? null;
async function until(what, pred, timeoutMs) {
  const t0 = Date.now();
  let last;
  while (Date.now() - t0 < timeoutMs) {
    last = await what();
    if (pred(last)) return last;
    await sleep(200);
  }
  return last;
}
/** Distance between two lat/lon points, m (spherical Earth, enough at a few hundred metres). */
function distanceM(a, b) {
  const rad = Math.PI / 180;
  const x = (b.lon_deg - a.lon_deg) * rad * Math.cos(((a.lat_deg + b.lat_deg) / 2) * rad);
  const y = (b.lat_deg - a.lat_deg) * rad;
  return 6371000 * Math.hypot(x, y);
}

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run", "--enable-unsafe-swiftshader"],
});
const text = (page, id) => page.locator(`[data-testid="${id}"]`).first().innerText();
const pageErrors = [];
function watchErrors(page, label) {
  page.on("pageerror", (e) => pageErrors.push(`${label}: ${e.message}`));
  page.on("console", (m) => {
    if (m.type() === "error" && !/Failed to load resource/.test(m.text())) pageErrors.push(`${label}: ${m.text()}`);
  });
}

try {
  // ---------------------------------------------------------------- operator page with a scripted gamepad
  const ctx = await browser.newContext({ viewport: { width: 1440, height: 900 } });
  await ctx.addInitScript(() => {
    // A gamepad in the browser's standard layout; the test moves it through window.__pad.
    const pad = {
      id: "Scripted test pad (STANDARD GAMEPAD)", index: 0, connected: true, mapping: "standard", timestamp: 0,
      axes: [0, 0, 0, 0],
      buttons: Array.from({ length: 17 }, () => ({ pressed: false, touched: false, value: 0 })),
    };
    window.__pad = pad;
    navigator.getGamepads = () => [pad, null, null, null];
  });
  const page = await ctx.newPage();
  watchErrors(page, "operator");
  const cutdownRequests = [];
  page.on("request", (r) => {
    if (r.url().includes("/api/cutdown/")) cutdownRequests.push(r.url());
  });
  await page.goto(`${base}/?token=${OPERATOR}`);
  await page.waitForFunction(() => document.querySelector('[data-testid="conn-status"]')?.textContent === "CONNECTED", null, { timeout: 15000 });

  // ---------------------------------------------------------------- telemetry updates on the page
  await page.waitForFunction(() => !document.querySelector('[data-testid="ro-alt-msl"]')?.textContent?.startsWith("—"), null, { timeout: 20000 }).catch(() => {});
  const alt1 = await text(page, "ro-alt-msl");
  const att1 = await text(page, "ro-heading");
  await sleep(3000);
  const alt2 = await text(page, "ro-alt-msl");
  check("telemetry updates the page (altitude falls)", alt1 !== alt2 && parseFloat(alt2) < parseFloat(alt1), `${alt1} → ${alt2}; heading ${att1}`);
  check("the drone's stage is shown", /parafoil/i.test(await text(page, "hdr-stage")), await text(page, "hdr-stage"));
  check("the link is fresh", (await page.evaluate(() => document.body.dataset.freshness)) === "fresh");
  await page.screenshot({ path: join(out, "live-operator.png") });

  // ---------------------------------------------------------------- a viewer watches but cannot command
  const vctx = await browser.newContext({ viewport: { width: 1440, height: 900 } });
  const vpage = await vctx.newPage();
  watchErrors(vpage, "viewer");
  const viewerPosts = [];
  vpage.on("request", (r) => {
    if (r.method() === "POST") viewerPosts.push(r.url());
  });
  await vpage.goto(`${base}/?token=${VIEWER}`);
  await vpage.waitForFunction(() => document.querySelector('[data-testid="role-badge"]')?.textContent?.startsWith("VIEWER"), null, { timeout: 10000 });
  await vpage.waitForFunction(() => !document.querySelector('[data-testid="ro-alt-msl"]')?.textContent?.startsWith("—"), null, { timeout: 10000 }).catch(() => {});
  const disabled = await Promise.all(["mode-heading", "target-send", "cutdown-button", "joystick-hold"].map((id) => vpage.locator(`[data-testid="${id}"]`).evaluate((e) => e.disabled)));
  await vpage.locator('[data-testid="mode-heading"]').click({ force: true }).catch(() => {});
  const viewerApi = await api("/api/commands/mode", VIEWER, { method: "POST", body: JSON.stringify({ mode: "heading" }) });
  check("viewer sees live data", !(await text(vpage, "ro-alt-msl")).startsWith("—"));
  check("viewer: command controls disabled, nothing posted", disabled.every(Boolean) && viewerPosts.length === 0, `${disabled} / ${viewerPosts.length} posts`);
  check("viewer: the API refuses with 403 and says why", viewerApi.status === 403 && /operator/.test(viewerApi.body?.reason ?? ""), JSON.stringify(viewerApi.body));
  await vpage.screenshot({ path: join(out, "live-viewer.png") });
  await vctx.close();

  // ---------------------------------------------------------------- a parameter edited in the page is read back from the drone
  await page.click('[data-testid="tab-params"]');
  await page.waitForSelector('[data-testid="param-input-GN_HK1"]', { timeout: 15000 });
  const hk1Before = await text(page, "param-value-GN_HK1");
  const hk1New = parseFloat(hk1Before) > 0.0135 ? "0.0125" : "0.0145";
  await page.fill('[data-testid="param-input-GN_HK1"]', hk1New);
  await page.click('[data-testid="param-set-GN_HK1"]');
  await page.waitForFunction(() => document.querySelector('[data-testid="param-result-GN_HK1"]')?.getAttribute("data-status") === "accepted", null, { timeout: 10000 }).catch(() => {});
  const readBack = (await api("/api/params")).body?.params?.find((p) => p.name === "GN_HK1")?.value;
  check("parameter edited in the page → read back from the drone", Math.abs(readBack - parseFloat(hk1New)) < 1e-6, `${hk1Before} → ${readBack} (${await text(page, "param-result-GN_HK1")})`);
  await page.screenshot({ path: join(out, "live-params.png") });
  await page.click('[data-testid="tab-command"]');

  // ---------------------------------------------------------------- a mode change reaches the drone
  await page.click('[data-testid="mode-heading"]');
  const headingMode = await until(vehicle, (v) => v?.mode === "heading", 10000);
  check("mode button → the drone reports heading mode", headingMode?.mode === "heading", headingMode?.mode);
  await page.waitForFunction(() => document.querySelector('[data-testid="mode-heading"]')?.classList.contains("current"), null, { timeout: 5000 }).catch(() => {});
  check("the page shows the drone's mode", await page.locator('[data-testid="mode-heading"]').evaluate((e) => e.classList.contains("current")));

  // ---------------------------------------------------------------- a scripted gamepad moves the main line
  // The drone refuses manual mode without fresh sticks: the operator holds the dead-man
  // (button 0) and the stick first, then asks for manual.
  await page.evaluate(() => {
    window.__pad.buttons[0] = { pressed: true, touched: true, value: 1 };
    window.__pad.axes[2] = 0.9;
  });
  await sleep(500);
  await page.click('[data-testid="mode-manual"]');
  const manualMode = await until(vehicle, (v) => v?.mode === "manual", 10000);
  check("manual mode reported by the drone", manualMode?.mode === "manual", manualMode?.mode);
  const turned = await until(vehicle, (v) => (v?.servos?.main_line ?? 0) > 0.3, 8000);
  await page.screenshot({ path: join(out, "live-joystick.png") });
  check("gamepad right stick → the drone's main-line servo moves", (turned?.servos?.main_line ?? 0) > 0.3, `main_line ${turned?.servos?.main_line}`);
  await page.evaluate(() => {
    window.__pad.buttons[0] = { pressed: false, touched: false, value: 0 };
    window.__pad.axes[2] = 0;
  });
  const released = await until(vehicle, (v) => Math.abs(v?.servos?.main_line ?? 1) < 0.1, 8000);
  check("dead-man released → the main line returns", Math.abs(released?.servos?.main_line ?? 1) < 0.1, `main_line ${released?.servos?.main_line}`);

  // ---------------------------------------------------------------- cutdown does nothing without its confirmation
  await page.click('[data-testid="cutdown-button"]');
  await sleep(2500);
  check("a click on cutdown sends nothing", cutdownRequests.length === 0, `${cutdownRequests.length} requests`);
  const armed = await api("/api/cutdown/arm", OPERATOR, { method: "POST", body: "{}" });
  const windowS = armed.body?.expires_in_s ?? 5;
  await sleep((windowS + 1) * 1000);
  const afterArm = await vehicle();
  const events = (await api("/api/events?since_s=0")).body?.events ?? [];
  check("armed but not confirmed → no cutdown, the drone flies on", armed.status === 200 && /parafoil/.test(afterArm?.stage ?? "") && !events.some((e) => /confirmed the CUTDOWN/.test(e.text)), `${armed.status}, stage ${afterArm?.stage}`);

  // ---------------------------------------------------------------- a landing target set in the page is flown to
  const here = (await api("/api/state")).body;
  const from = here.estimate ?? here.vehicle.gps;
  const target = { lat_deg: from.lat_deg + 200 / 111320, lon_deg: from.lon_deg + 150 / (111320 * Math.cos((from.lat_deg * Math.PI) / 180)) };
  await page.fill('[data-testid="target-lat"]', target.lat_deg.toFixed(6));
  await page.fill('[data-testid="target-lon"]', target.lon_deg.toFixed(6));
  await page.click('[data-testid="target-send"]');
  await page.waitForFunction(() => document.querySelector('[data-testid="command-item"][data-command="set_target"]')?.getAttribute("data-status") === "accepted", null, { timeout: 10000 }).catch(() => {});
  check("target from the page accepted by the drone", (await page.locator('[data-testid="command-item"][data-command="set_target"]').first().getAttribute("data-status")) === "accepted");
  await page.click('[data-testid="mode-spiral_landing"]');
  const spiral = await until(vehicle, (v) => v?.mode === "spiral_landing", 10000);
  check("spiral landing reported by the drone", spiral?.mode === "spiral_landing", spiral?.mode);
  await sleep(4000);
  await page.screenshot({ path: join(out, "live-spiral.png") });
  const landed = await until(vehicle, (v) => v?.stage === "landed", (600 / speed) * 1000 + 30000);
  const miss = landed?.gps ? distanceM(landed.gps, target) : NaN;
  check("the drone lands on the target set in the page", landed?.stage === "landed" && miss < 60, `stage ${landed?.stage}, ${miss.toFixed(1)} m from the target`);
  await page.screenshot({ path: join(out, "live-landed.png") });
} catch (e) {
  check("the test ran to the end", false, e instanceof Error ? (e.stack ?? e.message) : String(e));
} finally {
  await browser.close();
  station.kill("SIGTERM");
}

check("no page errors", pageErrors.length === 0, pageErrors.slice(0, 5).join(" | "));
const passed = results.filter((r) => r.startsWith("PASS")).length;
console.log(`\n${passed} passed, ${results.length - passed} failed; screenshots in ${out}`);
if (failed) console.log(`station stderr (tail):\n${stationErr.split("\n").slice(-30).join("\n")}`);
process.exit(failed ? 1 : 0);
