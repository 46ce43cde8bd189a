#!/usr/bin/env node
// Browser smoke test of the built pages against the mock daemon (mock/server.mjs serving dist/).
// Uses playwright-core with the system's Chromium (no browser download). Screenshots go to
// test-output/. Run with `npm run e2e:mock` (builds first). Exit code 0 only if every check holds.
//
// Env: CHROMIUM (default /usr/bin/chromium), E2E_PORT (default: a free port).

import { spawn } from "node:child_process";
import { mkdir } from "node:fs/promises";
import { createServer } from "node:net";
import { fileURLToPath } from "node:url";
import { dirname, join } from "node:path";
import { chromium } from "playwright-core";

const here = dirname(fileURLToPath(import.meta.url));
const root = join(here, "..");
const out = join(root, "test-output");
await mkdir(out, { recursive: true });

const freePort = () =>
  new Promise((res) => {
    const s = createServer();
    s.listen(0, "127.0.0.1", () => {
      const p = s.address().port;
      s.close(() => res(p));
    });
  });
const port = Number(process.env.E2E_PORT ?? (await freePort()));
const base = `http://127.0.0.1:${port}`;
const sleep = (ms) => new Promise((r) => setTimeout(r, ms));

const results = [];
let failed = false;
function check(name, ok, detail = "") {
  results.push(`${ok ? "PASS" : "FAIL"}  ${name}${detail ? ` — ${detail}` : ""}`);
  console.log(results[results.length - 1]);
  if (!ok) failed = true;
}

// ---------------------------------------------------------------- mock daemon
const mock = spawn(process.execPath, [join(root, "mock/server.mjs"), "--port", String(port), "--static", join(root, "dist"), "--no-dropouts"], { stdio: ["ignore", "pipe", "pipe"] });
let mockLog = "";
mock.stdout.on("data", (d) => (mockLog += d));
mock.stderr.on("data", (d) => (mockLog += d));
for (let i = 0; i < 50 && !mockLog.includes("mock stx station on"); i++) await sleep(100);
if (!mockLog.includes("mock stx station on")) {
  console.error("mock did not start:\n" + mockLog);
  process.exit(2);
}

const browser = await chromium.launch({
  executablePath: process.env.CHROMIUM ?? "/usr/bin/chromium",
  // --enable-unsafe-swiftshader: software WebGL, so the 3-D view renders without a GPU.
  args: ["--headless", "--no-sandbox", "--disable-gpu", "--disable-background-networking", "--disable-component-update", "--disable-sync", "--no-first-run", "--enable-unsafe-swiftshader"],
});

/** Console errors and uncaught exceptions of a page: there must be none. */
function watchErrors(page, label) {
  const errors = [];
  page.on("console", (m) => {
    if (m.type() !== "error") return;
    const t = m.text();
    // Failed tile loads (the mock serves none) are expected network 404s, logged by the browser itself.
    if (/Failed to load resource.*404/.test(t)) return;
    errors.push(`${label}: ${t}`);
  });
  page.on("pageerror", (e) => errors.push(`${label}: ${e.message}`));
  return errors;
}
const text = (page, id) => page.locator(`[data-testid="${id}"]`).first().innerText();

const allErrors = [];
try {
  // ------------------------------------------------------------ operator: page loads, vehicle moves
  const ctx = await browser.newContext({ viewport: { width: 1440, height: 900 } });
  const page = await ctx.newPage();
  allErrors.push(watchErrors(page, "operator"));
  const cutdownRequests = [];
  page.on("request", (r) => {
    if (r.url().includes("/api/cutdown/")) cutdownRequests.push(r.url());
  });
  await page.goto(`${base}/?token=op`);
  await page.waitForSelector('[data-testid="ro-position"]');
  await page.waitForFunction(() => !document.querySelector('[data-testid="ro-position"]')?.textContent?.startsWith("—"), null, { timeout: 10000 });
  check("token removed from the address bar", !page.url().includes("token="), page.url());
  check("operator role shown", (await text(page, "role-badge")).includes("OPERATOR"));
  const pos1 = await text(page, "ro-position");
  const alt1 = await text(page, "ro-alt-msl");
  await sleep(2500);
  const pos2 = await text(page, "ro-position");
  const alt2 = await text(page, "ro-alt-msl");
  check("vehicle moves", pos1 !== pos2 && alt1 !== alt2, `${pos1} → ${pos2}; ${alt1} → ${alt2}`);
  check("values carry units", /m\/s$/.test(await text(page, "ro-airspeed")) && /m$/.test(alt2), `${await text(page, "ro-airspeed")}, ${alt2}`);
  check("not stale while data flow", (await page.evaluate(() => document.body.dataset.freshness)) === "fresh");
  check("KML link carries the token", (await page.getAttribute('[data-testid="kml-link"]', "href")) === "/kml?token=op");
  await page.screenshot({ path: join(out, "live-operator.png") });

  // ------------------------------------------------------------ a mode click produces a command result
  await page.click('[data-testid="mode-heading"]');
  const modeRow = page.locator('[data-testid="command-item"][data-command="set_mode"]').first();
  await modeRow.waitFor();
  await page.waitForFunction(() => document.querySelector('[data-testid="command-item"][data-command="set_mode"]')?.getAttribute("data-status") === "accepted", null, { timeout: 5000 }).catch(() => {});
  check("mode click → command result accepted", (await modeRow.getAttribute("data-status")) === "accepted", await modeRow.innerText());
  await page.waitForFunction(() => document.querySelector('[data-testid="mode-heading"]')?.classList.contains("current"), null, { timeout: 3000 }).catch(() => {});
  check("mode button shows the vehicle's mode", await page.locator('[data-testid="mode-heading"]').evaluate((e) => e.classList.contains("current")));
  await page.click('[data-testid="mode-spiral_landing"]');

  // ------------------------------------------------------------ parameter write shows the read-back
  await page.click('[data-testid="tab-params"]');
  await page.waitForSelector('[data-testid="param-input-HK1"]');
  await page.fill('[data-testid="param-input-HK1"]', "0.0155");
  await page.click('[data-testid="param-set-HK1"]');
  await page.waitForFunction(() => document.querySelector('[data-testid="param-result-HK1"]')?.textContent?.includes("read back"), null, { timeout: 5000 }).catch(() => {});
  const pr = await text(page, "param-result-HK1");
  check("param write → accepted with read-back", pr.includes("accepted") && pr.includes("read back 0.0155"), pr);
  await page.fill('[data-testid="param-input-HK1"]', "5");
  await page.click('[data-testid="param-set-HK1"]');
  check("out-of-range param refused before sending", (await text(page, "param-result-HK1")).includes("within"), await text(page, "param-result-HK1"));
  await page.screenshot({ path: join(out, "live-params.png") });
  await page.click('[data-testid="tab-command"]');

  // ------------------------------------------------------------ target placed by a map click
  await page.click('[data-testid="target-pick"]');
  const box = await page.locator('[data-testid="map"]').boundingBox();
  await page.mouse.click(box.x + box.width * 0.4, box.y + box.height * 0.6);
  const tlat = await page.inputValue('[data-testid="target-lat"]');
  await page.click('[data-testid="target-send"]');
  await page.waitForFunction(() => document.querySelector('[data-testid="command-item"][data-command="set_target"]')?.getAttribute("data-status") === "accepted", null, { timeout: 5000 }).catch(() => {});
  check("target from a map click → accepted", (await page.locator('[data-testid="command-item"][data-command="set_target"]').first().getAttribute("data-status")) === "accepted", `lat ${tlat}`);

  // ------------------------------------------------------------ cutdown: a click sends nothing; a 2 s hold arms and confirms
  await page.click('[data-testid="cutdown-button"]');
  await sleep(2600);
  check("single click on cutdown sends nothing", cutdownRequests.length === 0, `${cutdownRequests.length} requests; status "${await text(page, "cutdown-status")}"`);
  const cb = await page.locator('[data-testid="cutdown-button"]').boundingBox();
  await page.mouse.move(cb.x + cb.width / 2, cb.y + cb.height / 2);
  await page.mouse.down();
  await sleep(900);
  await page.mouse.up();
  await sleep(1600);
  check("releasing after 0.9 s cancels", cutdownRequests.length === 0 && (await text(page, "cutdown-status")).includes("cancelled"));
  await page.mouse.down();
  await sleep(1000);
  await page.screenshot({ path: join(out, "live-cutdown-holding.png"), clip: { x: 1440 - 400, y: 600, width: 400, height: 300 } });
  await sleep(1300);
  await page.mouse.up();
  await page.waitForFunction(() => document.querySelector('[data-testid="command-item"][data-command="cutdown"]')?.getAttribute("data-status") === "accepted", null, { timeout: 5000 }).catch(() => {});
  check("2 s hold → arm then confirm → accepted", cutdownRequests.length === 2 && cutdownRequests[0].endsWith("/arm") && cutdownRequests[1].endsWith("/confirm"), cutdownRequests.map((u) => u.split("/").pop()).join(","));
  await page.click('[data-testid="tab-events"]');
  const evText = await text(page, "event-list");
  check("cutdown who/when in the event log", /cutdown: confirmed by ops-1 at \d\d:\d\d:\d\dZ/.test(evText) && /CUTDOWN confirmed \(by ops-1\)/.test(evText));
  await page.screenshot({ path: join(out, "live-events.png") });

  // ------------------------------------------------------------ malformed messages are counted, not fatal
  await fetch(`${base}/mock/garbage`, { method: "POST" });
  await sleep(600);
  const bad = await text(page, "link-bad-messages");
  check("malformed station messages counted and shown", /^[1-9]/.test(bad), bad);

  // ------------------------------------------------------------ 3-D view and plots
  await page.click('[data-testid="tab-3d"]');
  await sleep(800);
  const has3d = (await page.locator('[data-testid="view3d"] canvas').count()) === 1;
  check("3-D view renders a canvas", has3d || (await page.locator('[data-testid="view3d-unavailable"]').count()) === 1, has3d ? "webgl" : "no webgl (message shown)");
  await page.screenshot({ path: join(out, "live-3d.png") });
  await page.click('[data-testid="tab-plots"]');
  await sleep(1200);
  check("four plots drawn", (await page.locator('[data-testid="plots"] canvas').count()) >= 4);

  // ------------------------------------------------------------ STALE: link down → banner, greyed values
  await fetch(`${base}/mock/link?down=1`, { method: "POST" });
  await page.waitForFunction(() => document.body.dataset.freshness === "stale", null, { timeout: 5000 }).catch(() => {});
  await sleep(2500);
  const bannerKind = await page.getAttribute('[data-testid="banner"]', "data-kind");
  const staleLook = await page.locator('[data-testid="ro-airspeed"]').evaluate((e) => getComputedStyle(e).color);
  check("link down → STALE banner and greyed values", bannerKind === "stale" && staleLook === "rgb(107, 107, 107)", `${bannerKind}, ${staleLook}: ${await text(page, "banner")}`);
  await page.click('[data-testid="link-details-toggle"]');
  await page.screenshot({ path: join(out, "live-stale.png") });
  await fetch(`${base}/mock/link?down=0`, { method: "POST" });
  await page.waitForFunction(() => document.body.dataset.freshness === "fresh", null, { timeout: 5000 }).catch(() => {});
  check("link back → fresh again", (await page.evaluate(() => document.body.dataset.freshness)) === "fresh");

  // ------------------------------------------------------------ gamepad: 10 Hz while held, stops on release
  const gctx = await browser.newContext({ viewport: { width: 1440, height: 900 } });
  await gctx.addInitScript(() => {
    // A scripted gamepad in the browser's standard layout; the test drives window.__pad.
    const pad = {
      id: "Scripted test pad (STANDARD GAMEPAD)", index: 0, connected: true, mapping: "standard", timestamp: 0,
      axes: [0, 0, 0.5, 0],
      buttons: Array.from({ length: 17 }, () => ({ pressed: false, touched: false, value: 0 })),
    };
    window.__pad = pad;
    navigator.getGamepads = () => [pad, null, null, null];
  });
  const gpage = await gctx.newPage();
  allErrors.push(watchErrors(gpage, "gamepad"));
  const manual = [];
  gpage.on("websocket", (ws) => ws.on("framesent", (f) => {
    try {
      const m = JSON.parse(String(f.payload));
      if (m.type === "manual") manual.push({ t: Date.now(), m });
    } catch {
      /* not ours */
    }
  }));
  await gpage.goto(`${base}/?token=op`);
  await gpage.waitForFunction(() => document.querySelector('[data-testid="conn-status"]')?.textContent === "CONNECTED", null, { timeout: 10000 });
  await sleep(1000);
  check("no manual messages without the dead-man", manual.length === 0, `${manual.length}`);
  await gpage.evaluate(() => {
    window.__pad.buttons[0] = { pressed: true, touched: true, value: 1 };
    window.__pad.buttons[7] = { pressed: false, touched: true, value: 0.6 };
  });
  const t0 = Date.now();
  await sleep(600);
  await gpage.screenshot({ path: join(out, "live-joystick.png"), clip: { x: 1440 - 400, y: 0, width: 400, height: 900 } });
  await sleep(2400);
  await gpage.evaluate(() => {
    window.__pad.buttons[0] = { pressed: false, touched: false, value: 0 };
  });
  const tRelease = Date.now();
  const during = manual.filter((x) => x.t >= t0 && x.t <= tRelease);
  const rate = during.length / ((tRelease - t0) / 1000);
  check("dead-man held → manual messages at ~10 Hz", rate > 8 && rate < 12, `${during.length} in ${((tRelease - t0) / 1000).toFixed(1)} s = ${rate.toFixed(1)} Hz`);
  const first = during[0]?.m;
  check("stick mapping: right stick x → y (main line), trigger → z (brake)", first !== undefined && Math.abs(first.y - 0.457) < 0.01 && Math.abs(first.z - 0.6) < 0.01 && (first.buttons & 1) === 1, JSON.stringify(first));
  await sleep(1000);
  const after = manual.filter((x) => x.t > tRelease + 60);
  check("released → manual messages stop", after.length === 0, `${after.length} after release`);
  // Focus loss stops the stream too.
  await gpage.evaluate(() => {
    window.__pad.buttons[0] = { pressed: true, touched: true, value: 1 };
  });
  await sleep(500);
  await gpage.evaluate(() => window.dispatchEvent(new Event("blur")));
  const tBlur = Date.now();
  await sleep(800);
  const afterBlur = manual.filter((x) => x.t > tBlur + 60);
  check("window blur → manual messages stop", afterBlur.length === 0 && (await text(gpage, "joystick-sending")).includes("not focused"), `${afterBlur.length} after blur; ${await text(gpage, "joystick-sending")}`);
  await gctx.close();

  // ------------------------------------------------------------ viewer: commands disabled
  const vctx = await browser.newContext({ viewport: { width: 1440, height: 900 } });
  const vpage = await vctx.newPage();
  allErrors.push(watchErrors(vpage, "viewer"));
  const vposts = [];
  vpage.on("request", (r) => {
    if (r.method() === "POST") vposts.push(r.url());
  });
  await vpage.goto(`${base}/?token=view`);
  await vpage.waitForFunction(() => document.querySelector('[data-testid="role-badge"]')?.textContent?.startsWith("VIEWER"), null, { timeout: 10000 });
  await sleep(1500);
  const ids = ["mode-heading", "target-send", "heading-send", "cutdown-button", "joystick-hold", "plan-send"];
  const states = await Promise.all(ids.map((id) => vpage.locator(`[data-testid="${id}"]`).evaluate((e) => [e.disabled, e.title])));
  check("viewer: command controls disabled with tooltip", states.every(([d, t]) => d === true && t === "operator role required"), JSON.stringify(states));
  await vpage.locator('[data-testid="cutdown-button"]').click({ force: true }).catch(() => {});
  check("viewer: no POST sent", vposts.length === 0, vposts.join(","));
  check("viewer still sees live data", !(await text(vpage, "ro-position")).startsWith("—"));
  await vpage.screenshot({ path: join(out, "live-viewer.png") });
  await vctx.close();

  // ------------------------------------------------------------ recovery page on a phone
  const rctx = await browser.newContext({
    viewport: { width: 390, height: 844 }, deviceScaleFactor: 2, isMobile: true, hasTouch: true,
    geolocation: { latitude: 38.5400, longitude: -7.8800, accuracy: 8 }, permissions: ["geolocation"],
  });
  const rpage = await rctx.newPage();
  allErrors.push(watchErrors(rpage, "recovery"));
  await rpage.goto(`${base}/recovery.html?token=view`);
  await rpage.waitForFunction(() => /\d/.test(document.querySelector('[data-testid="rec-distance"]')?.textContent ?? ""), null, { timeout: 10000 }).catch(() => {});
  const dist = await text(rpage, "rec-distance");
  const brg = await text(rpage, "rec-bearing");
  check("recovery: distance and bearing from the phone", /\d/.test(dist) && /\d{3}°/.test(brg), `${dist}, ${brg}`);
  const geo = await rpage.getAttribute('[data-testid="rec-geo-link"]', "href");
  check("recovery: geo: and OpenStreetMap links", /^geo:-?\d+\.\d+,-?\d+\.\d+$/.test(geo ?? "") && ((await rpage.getAttribute('[data-testid="rec-osm-link"]', "href")) ?? "").includes("openstreetmap.org"), geo ?? "");
  await rpage.screenshot({ path: join(out, "recovery-phone.png") });

  // ------------------------------------------------------------ station gone → DISCONNECTED
  mock.kill("SIGTERM");
  await page.waitForFunction(() => document.querySelector('[data-testid="banner"]')?.getAttribute("data-kind") === "disconnected", null, { timeout: 8000 }).catch(() => {});
  check("station gone → DISCONNECTED banner", (await page.getAttribute('[data-testid="banner"]', "data-kind")) === "disconnected", await text(page, "banner"));
  // Offline: the station is gone; reloading the recovery page must still show the last point
  // (page files from the service worker's cache, the state from localStorage), flagged stale.
  await rpage.reload({ waitUntil: "domcontentloaded" }).catch(() => {});
  await rpage.waitForTimeout(2500);
  check("recovery: reload with the station gone → last point kept, flagged stale", /\d/.test(await text(rpage, "rec-distance")) && (await text(rpage, "rec-stale")).startsWith("STALE"), `${await text(rpage, "rec-distance")}; ${await text(rpage, "rec-stale")}`);
  await rpage.screenshot({ path: join(out, "recovery-stale.png") });
  await page.screenshot({ path: join(out, "live-disconnected.png") });
  await rctx.close();
  await ctx.close();
} catch (e) {
  check("smoke test ran to the end", false, e instanceof Error ? e.stack ?? e.message : String(e));
} finally {
  await browser.close();
  if (mock.exitCode === null) mock.kill("SIGTERM");
}

const errs = allErrors.flat().filter((e) => !/ERR_CONNECTION_REFUSED|WebSocket connection to .* failed/.test(e));
check("no console errors", errs.length === 0, errs.slice(0, 5).join(" | "));
console.log(`\n${results.filter((r) => r.startsWith("PASS")).length} passed, ${results.filter((r) => r.startsWith("FAIL")).length} failed; screenshots in ${out}`);
process.exit(failed ? 1 : 0);
