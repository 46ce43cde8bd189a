#!/usr/bin/env node
// The go/no-go board (issue 32, item 1) in a real browser, on the pad and through the launch:
// `stx serve` with a saved parameter set and the shipped checklist, `stx drone` flying
// mission-short with a long wait on the pad. The board's station checks are held against what
// the station itself reports (link, GPS, plan, recording, forecast, battery) and against changes
// made on purpose (a parameter changed away from the saved set, a plan made); an operator ticks
// an item in the page and every page shows who; a viewer cannot; the launch comes with items open
// and every page says which. Beside the board, what the station shares: a chase broadcast and a
// MAVLink forward, each to a UDP socket of the test's own, shown as the station counts them, and
// the SondeHub upload to the test server written from SondeHub's API
// (tests/peers/sondehub_server.py), with a 202 carrying an error.
//
// Usage: node tests/browser/gonogo.mjs [path/to/stx]   (default target/release/stx)

import { spawn } from "node:child_process";
import { createSocket } from "node:dgram";
import { mkdtemp, readFile, writeFile } from "node:fs/promises";
import { tmpdir } from "node:os";
import { join } from "node:path";
import {
  OPERATOR, VIEWER, root, out, check, newContext, startStation, freeUdpPort, apiOf, run, text, attr, until, watchErrors, runFlights, registerRest,
} from "./harness.mjs";

registerRest("GET", /^\/api\/readiness$/, null, "ReadinessView");
registerRest("POST", /^\/api\/readiness\/[^/]+$/, "TickBody", "ReadinessView");
registerRest("GET", /^\/api\/plan\/defaults$/, null, "PreflightDefaults");
registerRest("POST", /^\/api\/plan$/, "PreflightBody", "PreflightReport");

const SPEED = 4;
/** On the pad for this long, mission seconds: time to look at the board and tick. */
const ON_PAD_S = 140;
/** The drone's own GN_HK1, saved as the flight's set. */
const HK1 = 0.00661;

/**
 * A loopback UDP socket of the test's own, keeping what it hears. Its receive buffer holds
 * seconds of the forward's ~190 frames/s: with the default (208 KiB, ~200 datagrams) a CI run
 * on a loaded machine, whose event loop was busy with the browser, lost 64 of 2,803 frames.
 */
async function listener() {
  const sock = createSocket({ type: "udp4", recvBufferSize: 4 * 1024 * 1024 });
  const heard = [];
  sock.on("message", (m) => heard.push(m));
  await new Promise((r) => sock.bind(0, "127.0.0.1", r));
  return { port: sock.address().port, heard, close: () => sock.close() };
}

/** The SondeHub test server (Python's standard library only), on loopback. */
async function sondehubServer() {
  const proc = spawn("python3", [join(root, "tests/peers/sondehub_server.py")], { stdio: ["pipe", "pipe", "inherit"] });
  let line = "";
  await new Promise((resolve, reject) => {
    proc.stdout.on("data", (d) => {
      line += d;
      if (line.includes("\n")) resolve();
    });
    proc.on("exit", () => reject(new Error("the SondeHub test server stopped")));
  });
  const ports = JSON.parse(line.split("\n")[0]);
  const control = async (method, path, body) =>
    (await fetch(`http://127.0.0.1:${ports.control}${path}`, { method, body: body === undefined ? undefined : JSON.stringify(body) })).json();
  return { api: ports.api, received: () => control("GET", "/"), fault: (f) => control("POST", "/fault", f), close: () => proc.kill() };
}

async function setup(chasePort, forwardPort, sondehubPort) {
  const dir = await mkdtemp(join(tmpdir(), "stx-browser-gonogo-"));
  const params = join(dir, "flight-params.toml");
  await writeFile(params, `GN_HK1 = ${HK1}\n`);
  const toml = await readFile(join(root, "config/station.toml"), "utf8");
  const withParams = toml.replace(/^checklist = .*$/m, (line) => `${line}\nparams_file = ${JSON.stringify(params)}`);
  if (withParams === toml) throw new Error("config/station.toml has no [readiness] checklist line");
  const station = `${withParams}\n[chase]\ncallsign = "GONOGO1"\naddress = "127.0.0.1"\nport = ${chasePort}\nperiod_s = 1.0\n`
    + `\n[[forward]]\nname = "watcher"\naddress = "udpout:127.0.0.1:${forwardPort}"\n`
    + `\n[sondehub]\nurl = "http://127.0.0.1:${sondehubPort}"\nuploader_callsign = "GONOGOTEST"\npayload_callsign = "GONOGO1"\n`
    + `period_s = 2.0\nqueue_dir = ${JSON.stringify(join(dir, "sondehub"))}\n`
    + `station_position = { lat_deg = 38.53, lon_deg = -7.89, alt_m = 245.0 }\n`;
  const stationFile = join(dir, "station.toml");
  await writeFile(stationFile, station);
  const scenario = (await readFile(join(root, "config/scenarios/mission-short.toml"), "utf8")).replace(/^launch_delay_s = .*$/m, `launch_delay_s = ${ON_PAD_S}.0`);
  const scenarioFile = join(dir, "scenario.toml");
  await writeFile(scenarioFile, scenario);
  return { stationFile, scenarioFile };
}

async function flight() {
  const chaseEar = await listener();
  const forwardEar = await listener();
  const sondehub = await sondehubServer();
  const { stationFile, scenarioFile } = await setup(chaseEar.port, forwardEar.port, sondehub.api);
  const port = await freeUdpPort();
  const { base, io: stationIo } = await startStation(["--config", stationFile, "--link", `udpin:127.0.0.1:${port}`]);
  const api = apiOf(base);
  run(["drone", "--connect", `udpout:127.0.0.1:${port}`, "--scenario", scenarioFile, "--speed", String(SPEED)], "stx drone");
  const board = async () => (await api("/api/readiness", VIEWER)).body;
  const byId = (b) => Object.fromEntries((b?.checks ?? []).map((c) => [c.id, c]));

  const ctx = await newContext("gonogo operator", { viewport: { width: 1440, height: 900 } });
  const page = await ctx.newPage();
  watchErrors(page, "gonogo operator");
  await page.goto(`${base}/?token=${OPERATOR}`);
  const vctx = await newContext("gonogo viewer", { viewport: { width: 1280, height: 800 } });
  const viewer = await vctx.newPage();
  watchErrors(viewer, "gonogo viewer");
  await viewer.goto(`${base}/?token=${VIEWER}`);

  // ---------------------------------------------------------------- the station's own checks
  const heard = await until(board, (b) => ["gps", "params", "plan", "battery"].every((id) => byId(b)[id]?.status === "go"), 30000, 500);
  const st = (await api("/api/state")).body;
  const c = byId(heard);
  const signed = false; // the rehearsal's station.toml configures no signing key
  check("board: the link is up but unsigned in the rehearsal, and the board says so (no-go)",
    st.link.connected && !st.link.stale && c.link?.status === (signed ? "go" : "no_go") && /unsigned/.test(c.link?.detail ?? ""), JSON.stringify(c.link));
  check("board: GPS, plan read back, parameters equal to the saved set, battery, recording and forecast go, as the station's state has them",
    c.gps?.status === "go" && /Fix3d|3d/i.test(c.gps.detail) && st.vehicle?.gps?.fix?.includes("3d")
      && c.plan?.status === "go" && st.guidance?.target_source === "drone_plan"
      && c.params?.status === "go" && c.battery?.status === "go" && st.vehicle?.power?.voltage_v >= 11.5 && c.battery.detail.startsWith(st.vehicle.power.voltage_v.toFixed(2).slice(0, 4))
      && c.recording?.status === "go" && st.recording?.state === "on" && c.forecast?.status === "go" && st.forecast_wind.length > 0,
    ["gps", "plan", "params", "battery", "recording", "forecast"].map((id) => `${id} ${c[id]?.status} (${c[id]?.detail})`).join("; "));
  check("board: no plan made yet, so its reach is unknown (open)", c.reach?.status === "unknown", JSON.stringify(c.reach));

  // A parameter changed away from the saved set turns that check no-go, naming it.
  const set = await api("/api/params/GN_HK1", OPERATOR, { method: "POST", body: JSON.stringify({ value: 0.0145 }) });
  const changed = await until(board, (b) => byId(b).params?.status === "no_go", 10000, 300);
  check("board: GN_HK1 set away from the saved set → parameters no-go, naming it", set.status === 202 && /GN_HK1/.test(byId(changed).params?.detail ?? ""), `${set.status}; ${JSON.stringify(byId(changed).params)}`);
  // A plan made on the Plan page's endpoint: the reach check reads its share.
  const defaults = (await api("/api/plan/defaults", VIEWER)).body;
  const plan = (await api("/api/plan", OPERATOR, { method: "POST", body: JSON.stringify({ request: { ...defaults.request, runs: 20, seed: 1 } }) })).body;
  const share = plan?.target?.reachable_probability;
  const reach = byId(await board()).reach;
  check("board: after a plan, the reach check is its target's share against 90 %", typeof share === "number" && reach?.status === (share >= 0.9 ? "go" : "no_go") && reach.detail.startsWith(`${(share * 100).toFixed(0)} %`),
    `share ${share}; ${JSON.stringify(reach)}`);

  // ---------------------------------------------------------------- the board in the page
  await page.click('[data-testid="tab-readiness"]');
  await page.waitForSelector('[data-testid="readiness-canopy"]', { timeout: 10000 });
  const rows = await page.locator('[data-testid="readiness-checks"] tr').evaluateAll((trs) => trs.map((tr) => [tr.dataset.testid.replace("readiness-", ""), tr.dataset.status]));
  const now = byId(await board());
  check("page: the board lists the station's nine checks then the checklist's six items, each with the station's status",
    rows.length === 15 && rows.slice(0, 9).map(([id]) => id).join() === "link,gps,plan,fence,params,battery,recording,forecast,reach" && rows.every(([id, s]) => now[id]?.status === s || id === "link"),
    rows.map(([id, s]) => `${id}:${s}`).join(" "));
  // A viewer sees the box but cannot tick; the station refuses the viewer's tick.
  await viewer.click('[data-testid="tab-readiness"]');
  await viewer.waitForSelector('[data-testid="readiness-tick-canopy"]', { timeout: 10000 });
  const viewerBox = await viewer.locator('[data-testid="readiness-tick-canopy"]').isDisabled();
  const viewerTick = await api("/api/readiness/canopy", VIEWER, { method: "POST", body: JSON.stringify({ ticked: true }) });
  const unknown = await api("/api/readiness/nope", OPERATOR, { method: "POST", body: JSON.stringify({ ticked: true }) });
  check("viewer: the tick box is disabled and the station refuses a viewer's tick (403); an unknown item is 404",
    viewerBox && viewerTick.status === 403 && unknown.status === 404 && unknown.body?.error === "unknown_item", `disabled ${viewerBox}; viewer ${viewerTick.status}; unknown ${unknown.status} ${unknown.body?.error}`);
  // The operator ticks two items in the page.
  for (const id of ["canopy", "round-chute"]) await page.click(`[data-testid="readiness-tick-${id}"]`);
  const ticked = await until(board, (b) => byId(b).canopy?.status === "go" && byId(b)["round-chute"]?.status === "go", 5000, 200);
  await viewer.waitForFunction(() => document.querySelector('[data-testid="readiness-canopy"]')?.dataset.status === "go", null, { timeout: 5000 }).catch(() => {});
  const who = await text(viewer, "readiness-who-canopy");
  const logged = await until(async () => (await api("/api/events", VIEWER)).body?.events ?? [], (es) => es.some((e) => /checklist: "Parafoil and lines .*" ticked by operator/.test(e.text)), 5000, 300);
  check("operator: items ticked in the page are go with who and when, on the viewer's page too, and said in the event log",
    byId(ticked).canopy?.ticked_by === "operator" && typeof byId(ticked).canopy?.ticked_wall_ms === "number" && /^operator, \d\d:\d\d:\d\d/.test(who.trim()) && logged.some((e) => /ticked by operator/.test(e.text)),
    `${JSON.stringify(byId(ticked).canopy)}; viewer shows "${who.trim()}"`);
  await page.locator('[data-testid="panel-readiness"]').screenshot({ path: join(out, "gonogo-board.png") });

  // ---------------------------------------------------------------- what is shared, beside the board
  await page.waitForFunction(() => /datagrams sent/.test(document.querySelector('[data-testid="sharing-chase"]')?.textContent ?? ""), null, { timeout: 10000 }).catch(() => {});
  const chaseText = await text(page, "sharing-chase");
  const forwardText = await text(page, "sharing-forward-watcher");
  const sharing = (await api("/api/sharing", VIEWER)).body;
  const shownSent = Number(/: (\d+) datagrams sent/.exec(chaseText)?.[1] ?? NaN);
  await until(async () => chaseEar.heard.length, (n) => n >= shownSent, 5000, 100);
  const callsigns = new Set(chaseEar.heard.map((m) => JSON.parse(m.toString()).callsign));
  check("shared: the chase broadcast is shown with its callsigns, where it goes and what it sent, as the test's own socket heard it",
    sharing.chase?.to === `127.0.0.1:${chaseEar.port}` && chaseText.includes(`GONOGO1 and GONOGO1_LANDING to 127.0.0.1:${chaseEar.port} every 1 s`)
      && shownSent > 0 && shownSent <= sharing.chase.sent && callsigns.has("GONOGO1") && chaseEar.heard.length >= shownSent,
    `page "${chaseText}"; station sent ${sharing.chase?.sent}; heard ${chaseEar.heard.length} (${[...callsigns].join(", ")})`);
  const shownFrames = Number(/(\d+) frames sent/.exec(forwardText)?.[1] ?? NaN);
  // The test's sockets hear datagrams as its event loop gets to them: give it a moment.
  await until(async () => forwardEar.heard.length, (n) => n >= shownFrames, 5000, 100);
  const f = sharing.forwards?.[0];
  check("shared: the MAVLink forward is shown read-only with the frames it sent, which reached the test's socket",
    /watcher → udpout:127\.0\.0\.1:\d+ · read-only · /.test(forwardText) && f?.name === "watcher" && f.may_send_to_drone.length === 0
      && shownFrames > 0 && shownFrames <= f.out_passed && forwardEar.heard.length >= shownFrames,
    `page "${forwardText}"; station ${JSON.stringify(f)}; heard ${forwardEar.heard.length} datagrams`);
  // SondeHub: what the page says was taken, against the API and what the test server holds.
  await until(async () => (await api("/api/sharing", VIEWER)).body?.sondehub, (s) => s?.sent >= 2, 30000, 300);
  await page.waitForFunction(() => /^[1-9]\d* points taken/.test(document.querySelector('[data-testid="sharing-sondehub-counts"]')?.textContent ?? ""), null, { timeout: 10000 }).catch(() => {});
  const shText = await text(page, "sharing-sondehub");
  const shCounts = await text(page, "sharing-sondehub-counts");
  const shListeners = await text(page, "sharing-sondehub-listeners");
  const shApi = (await api("/api/sharing", VIEWER)).body?.sondehub;
  const taken = Number(/^(\d+) points taken/.exec(shCounts)?.[1] ?? NaN);
  const held = (await sondehub.received()).points.filter((p) => p.software_name === "stx" && p.payload_callsign === "GONOGO1");
  check("shared: the SondeHub upload is shown with its callsigns, its last upload and the points taken, as the test server holds them",
    shText.startsWith(`GONOGO1 by GONOGOTEST to http://127.0.0.1:${sondehub.api} every 2 s: last upload`) && taken > 0 && taken <= shApi?.sent
      && held.length >= taken && shApi?.failing === false && /station position uploaded/.test(shListeners),
    `page "${shText}" / "${shCounts}" / "${shListeners}"; station ${JSON.stringify(shApi)}; server holds ${held.length}`);
  await sondehub.fault({ reject_first: true, count: 1 });
  await page.waitForFunction(() => /test fault: refused/.test(document.querySelector('[data-testid="sharing-sondehub-notes"]')?.textContent ?? ""), null, { timeout: 20000 }).catch(() => {});
  const shNotes = await text(page, "sharing-sondehub-notes");
  const shAfter = (await api("/api/sharing", VIEWER)).body?.sondehub;
  check("shared: an error in SondeHub's 202 is on the page, in /api/sharing and in the station's log",
    shNotes.includes("error: test fault: refused") && shAfter?.refused === 1 && shAfter.errors.some((e) => e.text.includes("test fault: refused"))
      && stationIo.err.includes("test fault: refused"),
    `page notes "${shNotes}"; station ${JSON.stringify(shAfter)}`);
  // The recovery page, on a viewer's phone with a GPS position, shares it as a chase car once ticked.
  const phoneAt = { latitude: 38.5412, longitude: -7.8801 };
  const rctx = await newContext("gonogo recovery", { viewport: { width: 400, height: 800 }, geolocation: phoneAt, permissions: ["geolocation"] });
  const phone = await rctx.newPage();
  watchErrors(phone, "gonogo recovery");
  await phone.goto(`${base}/recovery.html?token=${VIEWER}`);
  await phone.locator('[data-testid="rec-chase-share"]').check({ timeout: 10000 }).catch(() => {});
  const car = await until(async () => (await sondehub.received()).listeners.find((l) => l.mobile === true), (l) => l !== undefined, 20000, 300);
  await phone.waitForFunction(() => /^shared as /.test(document.querySelector('[data-testid="rec-chase-status"]')?.textContent ?? ""), null, { timeout: 15000 }).catch(() => {});
  const carStatus = await text(phone, "rec-chase-status");
  await page.waitForFunction(() => /chase car GONOGOTEST_CHASE/.test(document.querySelector('[data-testid="sharing-sondehub-listeners"]')?.textContent ?? ""), null, { timeout: 10000 }).catch(() => {});
  const carShown = await text(page, "sharing-sondehub-listeners");
  check("shared: a recovery phone that ticks the box is a chase car on SondeHub at its GPS position, and the panel says so",
    car?.uploader_callsign === "GONOGOTEST_CHASE" && Math.abs(car.uploader_position[0] - phoneAt.latitude) < 1e-6 && Math.abs(car.uploader_position[1] - phoneAt.longitude) < 1e-6
      && /^shared as GONOGOTEST_CHASE/.test(carStatus) && carShown.includes("chase car GONOGOTEST_CHASE at 38.54120, -7.88010"),
    `server ${JSON.stringify(car)}; phone "${carStatus}"; panel "${carShown}"`);
  await rctx.close();
  await page.locator('[data-testid="panel-sharing"]').screenshot({ path: join(out, "gonogo-sharing.png") });
  chaseEar.close();
  forwardEar.close();
  sondehub.close();

  // ---------------------------------------------------------------- the launch, with items open
  const atLaunch = await until(async () => (await api("/api/state")).body, (s) => s?.mission?.stage === "ascent", (ON_PAD_S / SPEED) * 1000 + 30000, 300);
  const launched = atLaunch?.readiness;
  const openNames = (launched?.launched_with_open ?? []);
  await viewer.waitForFunction(() => /^LAUNCHED WITH/.test(document.querySelector('[data-testid="hdr-readiness"]')?.textContent ?? ""), null, { timeout: 5000 }).catch(() => {});
  const badge = { text: await text(viewer, "hdr-readiness"), state: await attr(viewer, "hdr-readiness", "data-state") };
  const warned = (await api("/api/events", VIEWER)).body?.events?.filter((e) => /^LAUNCHED with/.test(e.text)) ?? [];
  check("launch with items open: every page's header names them, and one warning in the log says so",
    atLaunch?.mission?.stage === "ascent" && openNames.includes("Cutdown pyro armed, safe pin removed") && !openNames.includes("Round chute packed and its release tested")
      && badge.state === "launched_open" && badge.text.includes(`${openNames.length} CHECK`) && badge.text.includes("Cutdown pyro armed") && warned.length === 1 && warned[0].level === "warning",
    `open at launch: ${openNames.join("; ")}; viewer badge "${badge.text}"; log ${warned.map((e) => `${e.level}: ${e.text}`).join(" | ")}`);
  await viewer.screenshot({ path: join(out, "gonogo-launched.png") });
  await ctx.close();
  await vctx.close();
}

await runFlights(flight, ["ReadinessView", "TickBody", "ServerMessage:state", "StateMsg", "ErrorBody", "SharingBody", "ChaseCarBody", "SondehubView"]);
