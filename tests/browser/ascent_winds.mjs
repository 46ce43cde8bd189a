#!/usr/bin/env node
// Ascent winds in a real browser: the station flies `mission-short` with its simulated drone (a
// pad wait, then a balloon ascent at about 5 m/s to a burst at 3 km MSL), measures the wind from
// the balloon's drift band by band, and the wind panel draws the bands beside the forecast. The
// bands must agree with the scenario's mean wind (config/scenarios/mission-short.toml, gusts of
// 0.2 m/s on top), and the panel must show as many bands as the station measured. During the
// ascent the map draws the predicted burst, deploy point and unsteered landing flown in those
// bands, and its legend names them; the last burst predicted before the burst must lie where the
// balloon burst.
//
// Usage: node tests/browser/ascent_winds.mjs [path/to/stx]   (default target/release/stx)
// Env: ASCENT_SIM_SPEED (default 20).

import { readFile } from "node:fs/promises";
import { join } from "node:path";
import { VIEWER, root, out, check, newContext, startStation, apiOf, until, text, watchErrors, runFlights, distanceM, legendAgainstMap, checkLegend, LIVE_SYMBOLS, zoomOut } from "./harness.mjs";

const SPEED = Number(process.env.ASCENT_SIM_SPEED ?? 20);

/** The scenario's site altitude and mean wind rows `[altitude above the site m, speed m/s, from °]`. */
async function scenarioWind() {
  const toml = await readFile(join(root, "config/scenarios/mission-short.toml"), "utf8");
  const site = Number(/\[site\][^[]*?alt_msl_m\s*=\s*([\d.]+)/.exec(toml)[1]);
  const rows = JSON.parse(/^rows\s*=\s*(\[.*\])\s*$/m.exec(toml)[1]);
  return { site, rows };
}

/** North and east of the mean wind (where the air goes) at `alt` m above the site: components interpolated linearly, the end rows held. */
function windAt(rows, alt) {
  const ne = ([, s, from]) => [-s * Math.cos((from * Math.PI) / 180), -s * Math.sin((from * Math.PI) / 180)];
  if (alt <= rows[0][0]) return ne(rows[0]);
  for (let i = 1; i < rows.length; i++) {
    if (alt <= rows[i][0]) {
      const f = (alt - rows[i - 1][0]) / (rows[i][0] - rows[i - 1][0]);
      const [a, b] = [ne(rows[i - 1]), ne(rows[i])];
      return [a[0] * (1 - f) + b[0] * f, a[1] * (1 - f) + b[1] * f];
    }
  }
  return ne(rows[rows.length - 1]);
}

async function flight() {
  const { site, rows } = await scenarioWind();
  const { base } = await startStation(["--sim", "--sim-speed", String(SPEED), "--link", "udpin:127.0.0.1:0"]);
  const api = apiOf(base);
  const ctx = await newContext("ascent winds", { viewport: { width: 1440, height: 900 } });
  const page = await ctx.newPage();
  watchErrors(page, "ascent winds");
  await page.goto(`${base}/?token=${VIEWER}`);
  const diamonds = () => page.locator('[data-testid="wind-chart"] [data-testid="wind-ascent-speed"]').count();

  // During the ascent: the first bands appear while the balloon still rises.
  const during = await until(async () => ({ n: await diamonds(), stage: (await api("/api/state")).body?.mission?.stage }), (x) => x.n >= 1 || x.stage === "round_chute", 120000, 500);
  check("during the ascent the wind panel draws measured bands", during.n >= 1 && during.stage === "ascent", `${during.n} band(s) drawn at stage ${during.stage}`);
  // Its legend names what is drawn, and under the balloon nothing is a descent.
  const legendItems = await page.locator('[data-testid="wind-chart"] [data-testid="wind-legend-item"]').allTextContents();
  check("during the ascent the wind legend names the ascent's bands and no descent", legendItems.includes("ascent ±2σ") && !legendItems.includes("descent"), legendItems.join(", "));

  // The flight path on the map while the balloon rises, and the last burst it predicted
  // against where the balloon burst. The predictions are polled by a loop of their own, beside
  // the page's checks: on a loaded machine the legend check below took long enough (15 s, 300 s
  // of flight at 20x) that the last prediction seen was minutes old. Where the balloon burst is
  // the highest point of the station's track (one point per second of flight), not the first
  // state seen under the round chute, which a slow poll reads a kilometre lower and drifted.
  let lastBurst = null;
  const watchAscent = (async () => {
    for (const deadline = Date.now() + 150000; Date.now() < deadline; ) {
      const s = (await api("/api/state")).body;
      if (s?.mission?.stage === "ascent" && s.flight_path?.burst) lastBurst = { ...s.flight_path.burst, at_s: s.mission_time_s };
      else if (s?.mission?.stage === "round_chute") return true;
      await new Promise((r) => setTimeout(r, 250));
    }
    return false;
  })();
  let marks = null;
  for (const deadline = Date.now() + 120000; marks === null && Date.now() < deadline; ) {
    const s = (await api("/api/state")).body;
    if (s?.mission?.stage !== "ascent") break;
    if (s.flight_path?.burst && (await page.locator('[data-testid="map-burst"]').count()) === 1) {
      const alt = async (id) => Number(await page.locator(`[data-testid="${id}"]`).getAttribute("data-alt"));
      marks = { burst: await alt("map-burst"), deploy: await alt("map-deploy"), landing: await page.locator('[data-testid="map-unsteered-landing"]').count(), badge: await text(page, "map-flight-path") };
      // The legend names the ascent's symbols (✷ ◆ ✕ ○, the path and its reach), zoomed out
      // so that none of them lies outside the view; and not the descent's, not drawn yet.
      await zoomOut(page, 2);
      checkLegend("legend: during the ascent every symbol on the map is listed in its own colour and glyph, and nothing else",
        await legendAgainstMap(page, "map-legend", LIVE_SYMBOLS), ["vehicle", "burst", "deploy", "unsteered", "chute", "path", "path-reach", "grid"]);
      await page.screenshot({ path: join(out, "legend-ascent.png") });
    }
    await new Promise((r) => setTimeout(r, 250));
  }
  const burstSeen = await watchAscent;
  const track = burstSeen ? ((await api("/api/track?every_s=0")).body?.points ?? []) : [];
  const burstAt = track.reduce((top, p) => (top === null || p.alt_msl_m > top.alt_msl_m ? p : top), null);
  check("during the ascent the map draws the predicted burst (3 km), deploy point (1200 m above the site) and unsteered landing, and says when",
    marks !== null && Math.abs(marks.burst - 3000) < 5 && Math.abs(marks.deploy - (site + 1200)) < 15 && marks.landing === 1 && /burst in .* · deploy in/.test(marks.badge),
    JSON.stringify(marks));
  const miss = lastBurst && burstAt ? distanceM(lastBurst, burstAt) : NaN;
  check("the last burst predicted during the ascent lies within 60 m of where the balloon burst", miss < 60,
    `${miss.toFixed(0)} m (predicted ${lastBurst?.in_s?.toFixed(0)} s ahead, at ${lastBurst?.at_s?.toFixed(0)} s; burst at ${burstAt?.mission_time_s?.toFixed(0)} s, ${burstAt?.alt_msl_m?.toFixed(0)} m MSL, the track's highest point)`);

  // After the burst: the whole ascent, and the panel agrees with the station.
  const done = await until(() => api("/api/ascent_wind"), (r) => r.body?.ascent_over === true, 180000, 1000);
  const bands = done.body?.bands ?? [];
  await until(diamonds, (n) => n === bands.length, 10000);
  const drawn = await diamonds();
  check("after the ascent: the station has measured the bands up to the burst, and the panel draws each", done.body?.ascent_over === true && bands.length >= 5 && drawn === bands.length,
    `${bands.length} bands measured, ${drawn} drawn, ascent over ${done.body?.ascent_over}`);

  let worst = 0;
  let sumSq = 0;
  let outside = 0;
  const lines = [];
  for (const b of bands) {
    const [n, e] = windAt(rows, b.alt_msl_m - site);
    const [dn, de] = [b.wind_north_mps - n, b.wind_east_mps - e];
    worst = Math.max(worst, Math.abs(dn), Math.abs(de));
    sumSq += dn * dn + de * de;
    outside += Number(Math.abs(dn) > 2 * b.sigma_north_mps) + Number(Math.abs(de) > 2 * b.sigma_east_mps);
    lines.push(`${(b.alt_msl_m - site).toFixed(0)} m: ${b.wind_north_mps.toFixed(2)}±${(2 * b.sigma_north_mps).toFixed(2)}, ${b.wind_east_mps.toFixed(2)}±${(2 * b.sigma_east_mps).toFixed(2)} vs ${n.toFixed(2)}, ${e.toFixed(2)}`);
  }
  const rms = bands.length > 0 ? Math.sqrt(sumSq / (2 * bands.length)) : NaN;
  console.log(`bands (above the site; measured N, E ± 2σ vs simulated mean):\n  ${lines.join("\n  ")}`);
  check("the measured bands agree with the simulated wind (each component within 0.4 m/s, at most 2 of them outside 2σ)", bands.length > 0 && worst < 0.4 && outside <= 2,
    `RMS ${rms.toFixed(3)} m/s, worst ${worst.toFixed(3)} m/s, ${outside} of ${2 * bands.length} components outside 2σ`);
  const readout = await text(page, "ro-wind-ascent");
  const legend = await page.locator('[data-testid="wind-chart"] [data-testid="wind-legend"]').count();
  check("the panel's Ascent readout and legend", /\d+ bands?|m\/s/.test(readout) && legend === 1, `readout "${readout}", legend ${legend}`);
  await page.locator('[data-testid="panel-wind"]').screenshot({ path: join(out, "ascent-winds.png") });
  await ctx.close();
}

await runFlights(flight, ["ServerMessage:ascent_wind", "AscentWindMsg", "ServerMessage:state"]);
