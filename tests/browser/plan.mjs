#!/usr/bin/env node
// The Plan page in a real browser (issue 15 item 4): a station with the shipped config (no drone
// needed); the page is filled from the station's defaults; a uniform forecast whose answer is
// known in closed form (10 m/s from the west at every height, 5 m/s ascent to 20 km, no spread:
// the burst lies east of the launch by wind × climb / rate) is planned and the numbers shown are
// checked, with the points, ellipses, samples and region drawn on the map; the target's
// reachability is shown (none at the launch site, far upwind; all at the centre of the reach
// disc); a malformed box is named by the page, and a request the station refuses shows its reason.
// A GFS GRIB2 file sent from the page (issue 31, item 1) fills the forecast with its wind over the
// launch site (a file without HGT is refused, naming it), and the launch window over it (item 3)
// is drawn as a strip whose times, shares, ranks and best marks are the station's own answer.
// First the station's own defaults are planned as they come (a 35-km ascent whose wind spread
// carries the samples tens of kilometres apart): the region steering reaches is drawn in green
// with an area, the whole sample cloud is in view, every number has its unit, and the legend
// names each symbol in its colour.
//
// Usage: node tests/browser/plan.mjs [path/to/stx]   (default target/release/stx)

import { readFile } from "node:fs/promises";
import { join } from "node:path";
import { OPERATOR, VIEWER, root, out, check, newContext, startStation, apiOf, until, text, attr, watchErrors, runFlights, registerRest, legendAgainstMap, checkLegend, rad } from "./harness.mjs";

registerRest("GET", /^\/api\/plan\/defaults$/, null, "PreflightDefaults");
registerRest("POST", /^\/api\/plan$/, "PreflightBody", "PreflightReport");
registerRest("POST", /^\/api\/plan\/forecast$/, null, "ForecastUploadReport");
registerRest("POST", /^\/api\/plan\/window$/, "WindowBody", "WindowReport");

const WIND = 10;
const RATE = 5;
const BURST = 20000;
/** Reads "E 39510 m" and the like from a shown line. */
const shown = (line, key) => Number(new RegExp(`${key} (-?\\d+) m`).exec(line)?.[1] ?? NaN);
/** A position as the page writes it: "38.53330° N, 7.88890° W". */
const latLonText = (lat, lon) => `${Math.abs(lat).toFixed(5)}° ${lat >= 0 ? "N" : "S"}, ${Math.abs(lon).toFixed(5)}° ${lon >= 0 ? "E" : "W"}`;
/** The unit each box must show beside its label (the seed is a bare number). */
const UNITS = {
  launch_lat_deg: "°", launch_lon_deg: "°", launch_alt_msl_m: "m", ascent_rate_mps: "m/s", ascent_rate_sigma_mps: "m/s", burst_altitude_msl_m: "m",
  burst_altitude_sigma_m: "m", deploy_height_m: "m", default_wind_sigma_mps: "m/s", runs: "samples", target_lat_deg: "°", target_lon_deg: "°",
};
/** What the Plan map draws (ui/preflightMap.ts), as the page's elements show it. */
const PLAN_SYMBOLS = {
  launch: ['[data-testid="plan-mk-launch"]', "backgroundColor"], burst: ['[data-testid="plan-mk-burst"]', "backgroundColor"],
  deploy: ['[data-testid="plan-mk-deploy"]', "backgroundColor"], landing: ['[data-testid="plan-mk-landing"]', "backgroundColor"],
  sample: ["path.plan-sample", "stroke"], region: ["path.plan-region", "fill"], target: ['[data-testid="plan-mk-target"]', "backgroundColor"],
};
/** Distinct vertices and enclosed area of a ring of [x, y]. */
function ringShape(ring) {
  const distinct = new Set(ring.map(([x, y]) => `${x.toFixed(3)},${y.toFixed(3)}`)).size;
  let twice = 0;
  for (let i = 0; i < ring.length; i++) {
    const [a, b] = [ring[i], ring[(i + 1) % ring.length]];
    twice += a[0] * b[1] - b[0] * a[1];
  }
  return { distinct, area: Math.abs(twice) / 2 };
}

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
  // The page says "computing…" from the click until it has drawn the answer (or shown why not).
  const submit = async () => {
    await page.locator('[data-testid="plan-submit"]').click();
    await until(() => text(page, "plan-status"), (t) => !/computing/.test(t), 30000);
  };

  // ---- the station's defaults as they come: the spread is wider than the glide reaches
  const answer = page.waitForResponse((r) => r.url().endsWith("/api/plan"), { timeout: 30000 });
  await submit();
  const spread = await (await answer).json();
  // The answer's outline in metres about the launch (small-angle: tens of km).
  const regionM = spread.steered_region_lat_lon_deg.map(([la, lo]) => [(la - site.launch_lat_deg) * rad * 6371000, (lo - site.launch_lon_deg) * rad * 6371000 * Math.cos(site.launch_lat_deg * rad)]);
  const inAnswer = ringShape(regionM);
  const drawnRegion = await page.evaluate(() => {
    const p = document.querySelector("path.plan-region");
    if (!p) return null;
    const xy = (p.getAttribute("d") ?? "").match(/-?[\d.]+/g)?.map(Number) ?? [];
    const ring = [];
    for (let i = 0; i + 1 < xy.length; i += 2) ring.push([xy[i], xy[i + 1]]);
    const st = getComputedStyle(p);
    return { ring, stroke: st.stroke, fill: st.fill, fillOpacity: Number(st.fillOpacity) };
  });
  const onPage = drawnRegion ? ringShape(drawnRegion.ring) : { distinct: 0, area: 0 };
  const green = (c) => {
    const [r, g, b] = (c ?? "").match(/\d+/g)?.map(Number) ?? [0, 0, 0];
    return g >= 100 && g > r + 60 && g > b + 60;
  };
  check("plan, station defaults: the region steering reaches is a polygon with an area, drawn in green",
    inAnswer.distinct >= 3 && inAnswer.area > 1e6 && onPage.distinct >= 3 && onPage.area > 100 && green(drawnRegion?.stroke) && green(drawnRegion?.fill) && drawnRegion.fillOpacity > 0,
    `answer: ${inAnswer.distinct} distinct vertices, ${(inAnswer.area / 1e6).toFixed(0)} km², reached in ≥ ${(100 * spread.steered_region_probability).toFixed(1)} % (best ${(100 * spread.steered_region_best_probability).toFixed(1)} %); page: ${onPage.distinct} vertices, ${onPage.area.toFixed(0)} px², stroke ${drawnRegion?.stroke}, fill ${drawnRegion?.fill} at ${drawnRegion?.fillOpacity}`);
  const cloud = await page.evaluate(() => {
    const map = document.querySelector('[data-testid="plan-map"]').getBoundingClientRect();
    const dots = [...document.querySelectorAll("path.plan-sample")].map((e) => e.getBoundingClientRect());
    const out = dots.filter((r) => r.left < map.left || r.right > map.right || r.top < map.top || r.bottom > map.bottom).length;
    return { dots: dots.length, out, spanX: Math.max(...dots.map((r) => r.right)) - Math.min(...dots.map((r) => r.left)), mapW: map.width };
  });
  check("plan, station defaults: the map frames the whole sample cloud", cloud.dots === spread.landing_samples_lat_lon_deg.length && cloud.dots > 100 && cloud.out === 0 && cloud.spanX > 0.2 * cloud.mapW,
    `${cloud.out} of ${cloud.dots} samples outside the map; the cloud spans ${cloud.spanX.toFixed(0)} of ${cloud.mapW.toFixed(0)} px`);
  const labels = await page.evaluate((fields) => Object.fromEntries(fields.map((f) => [f, document.querySelector(`label[for="plan-${f}"]`)?.textContent ?? ""])), Object.keys(UNITS));
  const unitless = Object.entries(UNITS).filter(([f, u]) => !(/\(([^)]*)\)$/.exec(labels[f])?.[1].split(/[ ,]+/) ?? []).includes(u)).map(([f]) => `${f}: "${labels[f]}"`);
  const lines = { burst: await text(page, "plan-burst"), reach: await text(page, "plan-reach") };
  const pointLine = /^Burst: \d+\.\d{5}° [NS], \d+\.\d{5}° [EW], \d+ m MSL · N -?\d+ m, E -?\d+ m of launch · T\+\d+:\d\d:\d\d ±\d+ s · 1σ \d+ × \d+ m at \d+°$/;
  const reachLine = /^Steering reaches \d+ m around .* reached in \d+ % of the samples or more, no point in more than \d+ % \(\d+ landings drawn\)$/;
  check("plan: every box and every number shown has its unit", unitless.length === 0 && pointLine.test(lines.burst) && reachLine.test(lines.reach),
    `${unitless.join("; ") || "every label has its unit"} | ${lines.burst} | ${lines.reach}`);
  checkLegend("plan: the legend names each symbol on the map in its colour, and nothing else", await legendAgainstMap(page, "plan-legend", PLAN_SYMBOLS), ["launch", "burst", "deploy", "landing", "sample", "region"]);
  await page.locator(".plan-result").screenshot({ path: join(out, "plan-region.png") });
  await fill({
    forecast: `alt_msl_m,speed_mps,from_deg,sigma_mps\n0,${WIND},270,0`,
    ascent_rate_mps: RATE, ascent_rate_sigma_mps: 0, burst_altitude_msl_m: BURST, burst_altitude_sigma_m: 0,
    default_wind_sigma_mps: 0, runs: 50, seed: 3,
    // The launch site: 40 km upwind of the landing, out of any glide.
    target_lat_deg: site.launch_lat_deg, target_lon_deg: site.launch_lon_deg,
  });
  await submit();
  const burst = await text(page, "plan-burst");
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
  await submit();
  const reached = await text(page, "plan-target");
  check("plan: a target at the centre of the glide disc is reachable in every sample", /reachable in 100 %/.test(reached), reached);
  check("plan: the page shows the station's plan (the same landing as POST /api/plan)", (await text(page, "plan-landing")).includes(latLonText(l.lat_deg, l.lon_deg)), `${await text(page, "plan-landing")} vs ${l.lat_deg}, ${l.lon_deg}`);
  await page.screenshot({ path: join(out, "plan.png") });

  await launchWindow(page, api, fill, box);

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

/** A GFS file from the page, then the launch window over it, against the station's own answers. */
async function launchWindow(page, api, fill, box) {
  const testdata = (name) => join(root, "crates/stx-weather/testdata", name);
  const read = async (file) => {
    await page.locator('[data-testid="plan-file"]').setInputFiles(testdata(file));
    await page.locator('[data-testid="plan-file-read"]').click();
    return until(() => text(page, "plan-file-status"), (t) => /GFS run|sounding|\d{3} /.test(t), 30000);
  };
  const refused = await read("no_hgt.grib2");
  check("plan: a GRIB2 file without HGT is refused, naming what it lacks", /^400 bad_request: no HGT on isobaric levels/.test(refused), refused);
  const said = await read("gfs_0p25_subset.grib2");
  // The station's answer for the same file, asked directly.
  const site = `lat=${await box("launch_lat_deg").inputValue()}&lon=${await box("launch_lon_deg").inputValue()}`;
  const up = (await api(`/api/plan/forecast?${site}`, VIEWER, { method: "POST", body: await readFile(testdata("gfs_0p25_subset.grib2")), headers: { "content-type": "application/octet-stream" } })).body;
  const shown = (await box("forecast").inputValue()).split("\n");
  const line = (r) => [r.alt_msl_m, r.speed_mps, r.from_deg].join(",");
  check("plan: the GFS file's wind over the launch site becomes the forecast rows (the station's answer for the file)",
    up?.kind === "gfs" && up.rows.length === 11 && shown.length === 12 && up.rows.every((r, k) => shown[k + 1] === line(r)) && said.includes("GFS run 2026-11-30T06:00:00Z"),
    `${said} | ${shown.slice(0, 3).join(" / ")}`);
  const windowBoxes = { from: await page.locator('[data-testid="plan-window-from"]').inputValue(), to: await page.locator('[data-testid="plan-window-to"]').inputValue() };
  check("plan: the window starts as the file's forecast hours", windowBoxes.from === "2026-11-30T06:00:00Z" && windowBoxes.to === "2026-11-30T12:00:00Z", JSON.stringify(windowBoxes));
  await fill({ runs: 40, burst_altitude_msl_m: 20000, burst_altitude_sigma_m: 1000, default_wind_sigma_mps: 1.5, target_lat_deg: 38.37, target_lon_deg: -6.17 });
  await page.locator('[data-testid="plan-window-every"]').fill("1.5");
  const sent = page.waitForRequest((r) => r.url().endsWith("/api/plan/window"), { timeout: 30000 });
  await page.locator('[data-testid="plan-window-submit"]').click();
  const asked = (await sent).postDataJSON();
  await until(() => text(page, "plan-window-status"), (t) => !/computing/.test(t), 120000);
  // The same window asked of the API directly: the page must show the station's answer.
  const report = (await api("/api/plan/window", VIEWER, { method: "POST", body: JSON.stringify(asked) })).body;
  const strip = await page.locator('[data-testid="window-row"]').evaluateAll((els) => els.map((e) => ({
    time: e.dataset.time, rank: Number(e.dataset.rank), share: Number(e.dataset.share), best: e.dataset.best === "true",
    bar: e.querySelector(".plan-strip-bar").getBoundingClientRect().width / e.getBoundingClientRect().width, weight: getComputedStyle(e).fontWeight, text: e.innerText,
  })));
  const launches = report?.launches ?? [];
  const mismatch = launches.map((l, k) => {
    const r = strip[k];
    const ok = r && r.time === l.launch_time && r.rank === l.rank && r.best === l.best && Math.abs(r.share - 100 * l.reach_share) < 1e-3
      && Math.abs(r.bar - l.reach_share) < 0.02 && (r.best ? r.weight === "700" && r.text.includes("★") : !r.text.includes("★"));
    return ok ? null : `${l.launch_time}: page ${JSON.stringify(r)} vs station rank ${l.rank}, share ${l.reach_share}, best ${l.best}`;
  }).filter((m) => m !== null);
  const uploadId = Number(await page.locator('[data-testid="plan-window-source"]').inputValue());
  check("plan: the window strip shows every launch time with its share as a bar, rank and best mark, as the station answers the page's request",
    asked.forecast?.upload === uploadId && launches.length === 5 && strip.length === 5 && mismatch.length === 0 && strip.filter((r) => r.best).length === 3
      && new Set(launches.map((l) => l.reach_share)).size > 1,
    `${strip.length} rows of ${launches.length}; ${mismatch.join("; ") || strip.map((r) => `${r.time.slice(11, 16)} ${r.share.toFixed(0)} % #${r.rank}${r.best ? "★" : ""}`).join(", ")}`);
  await page.locator(".plan-result").screenshot({ path: join(out, "plan-window.png") });
}

await runFlights(flight, ["Session", "PreflightDefaults", "RecordingsBody", "PreflightReport", "ErrorBody", "ForecastUploadReport", "WindowReport"]);
