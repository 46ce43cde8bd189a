#!/usr/bin/env node
// The Plan page in a real browser (issue 15 item 4): a station with the shipped config (no drone
// needed); the page is filled from the station's defaults; a uniform forecast whose answer is
// known in closed form (10 m/s from the west at every height, 5 m/s ascent to 20 km, no spread:
// the burst lies east of the launch by wind × climb / rate) is planned and the numbers shown are
// checked, with the points, ellipses, samples and region drawn on the map; the target's
// reachability is shown (none at the launch site, far upwind; all at the centre of the reach
// disc); a malformed box is named by the page, and a request the station refuses shows its reason.
//
// Usage: node tests/browser/plan.mjs [path/to/stx]   (default target/release/stx)

import { join } from "node:path";
import { OPERATOR, VIEWER, out, check, newContext, startStation, apiOf, until, text, attr, watchErrors, runFlights, registerRest } from "./harness.mjs";

registerRest("GET", /^\/api\/plan\/defaults$/, null, "PreflightDefaults");
registerRest("POST", /^\/api\/plan$/, "PreflightBody", "PreflightReport");

const WIND = 10;
const RATE = 5;
const BURST = 20000;
/** Reads "E 39510 m" and the like from a shown line. */
const shown = (line, key) => Number(new RegExp(`${key} (-?\\d+) m`).exec(line)?.[1] ?? NaN);

async function flight() {
  const { base } = await startStation(["--link", "udpin:127.0.0.1:0"]);
  const api = apiOf(base);
  const defaults = (await api("/api/plan/defaults", VIEWER)).body;
  const ctx = await newContext("plan", { viewport: { width: 1440, height: 1000 } });
  const page = await ctx.newPage();
  watchErrors(page, "plan");

  // The live page links to it.
  await page.goto(`${base}/?token=${OPERATOR}`);
  const href = await until(() => attr(page, "plan-link", "href"), (h) => /plan\.html/.test(h ?? ""), 15000);
  check("plan: the live page's header links to the Plan page", /^plan\.html\?token=/.test(href ?? ""), href);

  // A viewer plans: it commands nothing.
  await page.goto(`${base}/plan.html?token=${VIEWER}`);
  const box = (f) => page.locator(`[data-testid="plan-in-${f}"]`);
  const lat = await until(() => box("launch_lat_deg").inputValue(), (v) => v !== "", 15000);
  const forecast = await box("forecast").inputValue();
  check("plan: the form starts from the station's launch site and forecast",
    Number(lat) === defaults.request.launch_lat_deg && Number(await box("launch_lon_deg").inputValue()) === defaults.request.launch_lon_deg
      && forecast.split("\n").length === defaults.request.forecast.length + 1 && /^alt_msl_m,speed_mps,from_deg/.test(forecast),
    `${lat}, forecast:\n${forecast}`);
  const site = defaults.request;
  const fill = async (values) => { for (const [f, v] of Object.entries(values)) await box(f).fill(String(v)); };
  await fill({
    forecast: `alt_msl_m,speed_mps,from_deg,sigma_mps\n0,${WIND},270,0`,
    ascent_rate_mps: RATE, ascent_rate_sigma_mps: 0, burst_altitude_msl_m: BURST, burst_altitude_sigma_m: 0,
    default_wind_sigma_mps: 0, runs: 50, seed: 3,
    // The launch site: 40 km upwind of the landing, out of any glide.
    target_lat_deg: site.launch_lat_deg, target_lon_deg: site.launch_lon_deg,
  });
  await page.locator('[data-testid="plan-submit"]').click();
  const burst = await until(() => text(page, "plan-burst").catch(() => ""), (t) => /^Burst/.test(t), 30000);
  const climb = (BURST - site.launch_alt_msl_m) / RATE;
  const east = shown(burst, "E");
  check("plan: the burst is east of the launch by wind × climb time (within 0.5 %), on the launch's latitude",
    Math.abs(east - WIND * climb) <= 0.005 * WIND * climb && Math.abs(shown(burst, "N")) <= 1 && / 1σ 0 × 0 m/.test(burst),
    `${burst} (expected E ${(WIND * climb).toFixed(0)} m)`);
  const deploy = await text(page, "plan-deploy");
  const landing = await text(page, "plan-landing");
  check("plan: deploy and the unsteered landing lie further downwind", shown(deploy, "E") > east && shown(landing, "E") > shown(deploy, "E"), `${deploy} | ${landing}`);
  const target = await text(page, "plan-target");
  check("plan: the target's reachability is shown (the launch site, far upwind: 0 %)", /reachable in 0 % of the samples/.test(target), target);
  const count = (sel) => page.locator(sel).count();
  const drawn = { samples: await count("path.plan-sample"), region: await count("path.plan-region"), ellipses: await count("path.plan-ellipse"),
    markers: await Promise.all(["launch", "burst", "deploy", "landing", "target"].map((m) => page.locator(`[data-testid="plan-mk-${m}"]`).isVisible())) };
  check("plan: the map draws the points, their ellipses, the 50 landing samples and the steered region",
    drawn.samples === 50 && drawn.region === 1 && drawn.ellipses === 3 && drawn.markers.every(Boolean), JSON.stringify(drawn));

  // The centre of the reach disc: one glide radius upwind (west) of the unsteered landing.
  const plan = (await api("/api/plan", VIEWER, { method: "POST", body: JSON.stringify({ request: { ...site, forecast: [{ alt_msl_m: 0, speed_mps: WIND, from_deg: 270, sigma_mps: 0 }], ascent_rate_mps: RATE, ascent_rate_sigma_mps: 0, burst_altitude_msl_m: BURST, burst_altitude_sigma_m: 0, default_wind_sigma_mps: 0, runs: 50, seed: 3, target_lat_lon_deg: null } }) })).body;
  const l = plan.landing_unsteered;
  const radius = plan.steered_reach_radius_m;
  const centreLon = l.lon_deg - (radius / (6378137 * Math.cos((l.lat_deg * Math.PI) / 180))) * (180 / Math.PI);
  await fill({ target_lat_deg: l.lat_deg, target_lon_deg: centreLon });
  await page.locator('[data-testid="plan-submit"]').click();
  const reached = await until(() => text(page, "plan-target"), (t) => /reachable in 100 %/.test(t), 30000);
  check("plan: a target at the centre of the glide disc is reachable in every sample", /reachable in 100 %/.test(reached), reached);
  check("plan: the page shows the station's plan (the same landing as POST /api/plan)", (await text(page, "plan-landing")).includes(`${l.lat_deg.toFixed(5)}, ${l.lon_deg.toFixed(5)}`), `${await text(page, "plan-landing")} vs ${l.lat_deg}, ${l.lon_deg}`);
  await page.screenshot({ path: join(out, "plan.png") });

  // A box that is no number is named by the page; a rule the station enforces comes back as its reason.
  await fill({ ascent_rate_mps: "fast" });
  await page.locator('[data-testid="plan-submit"]').click();
  const local = await until(() => text(page, "plan-error").catch(() => ""), (t) => t !== "", 5000);
  check("plan: a box that is no number is named before sending", /ascent_rate_mps is not a number/.test(local) && (await box("ascent_rate_mps").getAttribute("aria-invalid")) === "true", local);
  await fill({ ascent_rate_mps: RATE, runs: 0 });
  await page.locator('[data-testid="plan-submit"]').click();
  const remote = await until(() => text(page, "plan-error").catch(() => ""), (t) => /400/.test(t), 15000);
  check("plan: a request the station refuses shows its reason, naming the field", /400 bad_request: request: `runs` = 0 is invalid: must be in 1…5000/.test(remote), remote);
  await ctx.close();
}

await runFlights(flight, ["Session", "PreflightDefaults", "RecordingsBody", "PreflightReport", "ErrorBody"]);
