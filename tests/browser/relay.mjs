#!/usr/bin/env node
// The public relay (issue 30, item 3) in a real browser: `stx serve` with the simulated drone
// (the rehearsal at 5×), a relay on the station (`stx relay --upstream …?token=viewer-token`)
// and a second relay behind the first, delayed and coarsened. The public page, opened with no
// token, is held against the station's own track (the same mission second, within metres);
// the second relay's page against the first relay's state (later by its delay, on its grid);
// neither relay answers a command or the operators' state; the KML feed, the viewer count and
// the most-viewers limit do what they say. A screenshot of each public page is kept.
//
// Usage: node tests/browser/relay.mjs [path/to/stx]   (default target/release/stx)

import { join } from "node:path";
import { browser } from "./harness.mjs";
import { OPERATOR, VIEWER, out, check, newContext, startStation, freeUdpPort, apiOf, run, until, watchErrors, runFlights, distanceM, sleep, registerRest } from "./harness.mjs";

registerRest("GET", /^\/api\/relay$/, null, "RelayStatusBody");

const SPEED = 5;
const DELAY_S = 4;
const GRID_M = 500;

async function startRelay(args, label) {
  const io = run(["relay", "--listen", "127.0.0.1:0", ...args], label);
  for (let i = 0; i < 100 && !/open (http:\/\/\S+)\//.test(io.out); i++) await sleep(100);
  const base = /open (http:\/\/\S+)\//.exec(io.out)?.[1];
  if (!base) throw new Error(`${label} did not start:\n${io.out}\n${io.err}`);
  return base;
}

const getJson = async (url) => {
  const r = await fetch(url);
  return { status: r.status, body: await r.json().catch(() => null) };
};

/** What a public page shows now. */
const shown = (page) => page.evaluate(() => {
  const q = (id) => document.querySelector(`[data-testid="${id}"]`);
  const map = q("pub-map");
  return {
    lat: Number(map?.dataset.lat), lon: Number(map?.dataset.lon), missionS: Number(map?.dataset.missionTimeS),
    trackPoints: Number(map?.dataset.trackPoints ?? 0), stage: q("pub-stage")?.textContent, caveat: q("pub-caveat")?.textContent,
    fresh: q("pub-fresh")?.textContent, viewers: q("pub-viewers")?.textContent, payloadDot: !!q("pub-map-payload"),
  };
});

async function flight() {
  const port = await freeUdpPort();
  const { base } = await startStation(["--link", `udpin:127.0.0.1:${port}`]);
  const api = apiOf(base);
  run(["drone", "--connect", `udpout:127.0.0.1:${port}`, "--scenario", "rehearsal", "--speed", String(SPEED)], "stx drone");
  const relay1 = await startRelay(["--upstream", `${base}/?token=${VIEWER}`], "stx relay 1");
  const relay2 = await startRelay(["--upstream", `${relay1}/`, "--delay", String(DELAY_S), "--coarsen", String(GRID_M), "--max-viewers", "2"], "stx relay 2");

  // The first relay's page, with no token: the payload where the station has it.
  const ctx = await newContext("relay", { viewport: { width: 1280, height: 800 } }, "RelayMessage");
  const page = await ctx.newPage();
  watchErrors(page, "relay");
  await page.goto(`${relay1}/`);
  const first = await until(() => shown(page), (s) => s.payloadDot && Number.isFinite(s.missionS), 30000, 250);
  check("the public page opens with no token and shows the payload", first.payloadDot && Number.isFinite(first.lat), JSON.stringify(first));
  const misses = [];
  for (let i = 0; i < 8; i++) {
    await sleep(700);
    const s = await shown(page);
    const track = (await api("/api/track", OPERATOR)).body?.points ?? [];
    const same = track.reduce((best, p) => (best === null || Math.abs(p.mission_time_s - s.missionS) < Math.abs(best.mission_time_s - s.missionS) ? p : best), null);
    if (same && Math.abs(same.mission_time_s - s.missionS) <= 1.5) misses.push(distanceM({ lat_deg: s.lat, lon_deg: s.lon }, same));
  }
  const worst = Math.max(...misses);
  check("the page's payload is where the station's track has it at the same mission second (within 15 m)", misses.length >= 5 && worst < 15,
    `${misses.length} comparisons, worst ${worst.toFixed(1)} m: ${misses.map((m) => m.toFixed(1)).join(", ")}`);
  const st = (await api("/api/state", OPERATOR)).body;
  const ps = await shown(page);
  check("the page shows the station's stage", ps.stage === (st?.mission?.stage ?? "").replace(/_/g, " "), `page "${ps.stage}", station "${st?.mission?.stage}"`);
  check("the page draws the track from the relay's history and the states since", ps.trackPoints >= 5, `${ps.trackPoints} points`);

  // Nothing of the operators' on a relay, and no command route at all.
  const refused = [];
  for (const [method, path] of [["POST", "/api/commands/mode"], ["POST", "/api/cutdown/arm"], ["GET", "/api/state"], ["GET", "/api/params"], ["GET", "/api/session"], ["POST", "/api/params/SP_FLARE_H"]]) {
    const r = await fetch(`${relay1}${path}?token=${OPERATOR}`, { method, headers: { authorization: `Bearer ${OPERATOR}`, "content-type": "application/json" }, body: method === "POST" ? JSON.stringify({ mode: "heading", value: 1 }) : undefined });
    refused.push(`${method} ${path} → ${r.status}`);
  }
  check("a relay has no command route and no operators' state, even with an operator's token", refused.every((r) => r.endsWith("404")), refused.join("; "));
  const ws1 = await page.evaluate((u) => new Promise((res) => {
    const s = new WebSocket(u.replace("http", "ws") + "/api/ws");
    s.onmessage = (e) => { const t = JSON.parse(e.data).type; if (t === "public_state") { s.close(); res(Object.keys(JSON.parse(e.data)).sort().join(",")); } };
    setTimeout(() => res("no state"), 5000);
  }), relay1);
  check("the relay's socket carries the public state only (no link, vehicle, guidance, readiness)", ws1 === "coarsen_m,delay_s,landing,link_stale,mission_time_s,position,stage,target,type,wall_ms", ws1);

  // The second relay, behind the first: later by its delay, positions on its grid.
  const page2 = await ctx.newPage();
  watchErrors(page2, "relay 2");
  await page2.goto(`${relay2}/`);
  const s2 = await until(() => shown(page2), (s) => s.payloadDot && Number.isFinite(s.missionS), 30000, 250);
  const [a, b] = await Promise.all([getJson(`${relay1}/api/public/state`), getJson(`${relay2}/api/public/state`)]);
  const lagS = (a.body?.wall_ms - b.body?.wall_ms) / 1000;
  check(`a relay behind a relay shows the flight ${DELAY_S} s later and says so`, lagS > DELAY_S - 1 && lagS < DELAY_S + 1.5 && b.body?.delay_s === DELAY_S && /shown 4 s after the station/.test(s2.caveat ?? ""),
    `${lagS.toFixed(2)} s behind the first relay; delay_s ${b.body?.delay_s}; page: "${s2.caveat}"`);
  const dlat = GRID_M / 111320;
  const onGrid = (lat) => Math.abs(lat / dlat - Math.round(lat / dlat)) < 1e-6;
  const p2 = b.body?.position;
  const near = a.body?.position && p2 ? distanceM(p2, a.body.position) : NaN;
  check(`its positions are on its ${GRID_M} m grid, within a grid step of the true one, and the page says so`,
    onGrid(p2?.lat_deg) && onGrid(s2.lat) && b.body?.coarsen_m === GRID_M && near < GRID_M * 1.5 && /rounded to 500 m/.test(s2.caveat ?? ""),
    `lat ${p2?.lat_deg} (page ${s2.lat}); ${near.toFixed(0)} m from the first relay's newer point; "${s2.caveat}"`);
  const kml = await (await fetch(`${relay2}/kml/live`)).text();
  const kmlPayload = /<name>payload<\/name><Point>.*?<coordinates>([-\d.]+),([-\d.]+)/s.exec(kml);
  const nearGrid = (lat) => Math.abs(lat / dlat - Math.round(lat / dlat)) < 1e-3; // KML writes 7 decimals
  check("the relay's KML feed has the payload on the grid and the track", kmlPayload !== null && nearGrid(Number(kmlPayload[2])) && kml.includes("<name>track</name>"), kml.slice(0, 300));

  // The viewers: counted, and no more than the most allowed.
  await sleep(10500); // the page reads the count every 10 s
  const status2 = (await getJson(`${relay2}/api/relay`)).body;
  const viewers = await text2(page2);
  const probe = await (await browser.newContext()).newPage();
  await probe.goto(`${relay2}/api/relay`);
  const third = await probe.evaluate((u) => new Promise((res) => {
    const s = new WebSocket(u.replace("http", "ws") + "/api/ws");
    s.onopen = () => res("opened");
    s.onerror = () => res("refused");
    setTimeout(() => res("no answer"), 5000);
  }), relay2);
  check("a relay counts its viewers, the page shows the count, and a viewer beyond --max-viewers is refused",
    status2?.viewers === 1 && viewers === "1 watching" && status2?.upstream_connected === true && third === "opened", `status ${JSON.stringify(status2)}; page "${viewers}"; second viewer ${third}`);
  const fourth = await probe.evaluate((u) => new Promise((res) => {
    const s = new WebSocket(u.replace("http", "ws") + "/api/ws");
    s.onopen = () => res("opened");
    s.onerror = () => res("refused");
    setTimeout(() => res("no answer"), 5000);
  }), relay2);
  check("with --max-viewers 2 and two viewers on, the next is refused", fourth === "refused", fourth);
  // The audience travels up: relay 2's two pages and relay 1's one reach the station's panel.
  const opCtx = await newContext("relay-station", { viewport: { width: 1280, height: 800 } });
  const opPage = await opCtx.newPage();
  await opPage.goto(`${base}/?token=${OPERATOR}`);
  await opPage.click('[data-testid="tab-readiness"]');
  await opPage.waitForFunction(() => document.querySelector('[data-testid="sharing-relays"]')?.dataset.viewers === "3", null, { timeout: 20000 }).catch(() => {});
  const relaysText = await opPage.locator('[data-testid="sharing-relays"]').innerText();
  const sharing = (await api("/api/sharing", VIEWER)).body;
  const status1 = (await getJson(`${relay1}/api/relay`)).body;
  check("the station's Go/no-go tab counts the public pages of the whole relay tree",
    sharing?.relays?.length === 1 && sharing.relays[0].viewers === 3 && status1?.audience === 3 && /^3 public pages through 1 relay/.test(relaysText),
    `page "${relaysText}"; /api/sharing ${JSON.stringify(sharing?.relays)}; relay 1 audience ${status1?.audience}`);
  await opPage.screenshot({ path: join(out, "relay-station-sharing.png") });
  await opCtx.close();
  await page.screenshot({ path: join(out, "relay.png") });
  await page2.screenshot({ path: join(out, "relay-delayed.png") });
  await ctx.close();
}

const text2 = (page) => page.locator('[data-testid="pub-viewers"]').innerText();

await runFlights(flight, ["RelayMessage:public_history", "RelayMessage:public_state", "RelayStatusBody"]);
