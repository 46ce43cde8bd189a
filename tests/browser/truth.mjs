#!/usr/bin/env node
// One truth on every screen, in a real browser: a whole `mission-short`, pad to landing, flown by
// `stx drone` (it knows the truth and prints it at the end, `--summary-json`) beside `stx serve`,
// with the dashboard open from the start. Every ~100 ms of real time the test reads what the page
// draws — the T+ clock, the header's landing badge, the map's final-course chip, planned-landing
// dot and flight-path badge — and afterwards holds it against the truth:
//  - the clock is the mission's (the drone's) at any speed: it reads the drone's stage starts, and
//    runs at the sim speed; the plots' time axis names its unit;
//  - "landing in" only once a landing is predicted (never on the pad or climbing), and under the
//    round chute it agrees with the map's unsteered landing;
//  - the final-course chip is the course the drone's guidance flew (within 5°), and shown only
//    while the parafoil flies a pattern;
//  - the planned dot from 200 to 50 m above the ground is the station's prediction, within 20 m
//    of where the drone touched down and within 5 m of the drone's own prediction's figure
//    (medians; the campaign's p95 is `stx bench agreement`'s);
//  - one landing figure, to 0.1 m, naming the body: header, map, event log, a viewer's page, the
//    recordings list of the next day's station and the flight's replay — and it is the drone's
//    real miss give or take its GPS error.
//
// Usage: node tests/browser/truth.mjs [path/to/stx]   (default target/release/stx)
// Env: CHROMIUM (default /usr/bin/chromium), TRUTH_SPEED (default 20; the sampling needs ≤ 40).

import { readdir, writeFile } from "node:fs/promises";
import { basename, join } from "node:path";
import {
  OPERATOR, VIEWER, out, sleep, check, newContext, distanceM, angleDiff, run, recordDir, startStation, freeUdpPort, apiOf, until, text, watchErrors, runFlights, cutShort,
} from "./harness.mjs";

const SPEED = Number(process.env.TRUTH_SPEED ?? 20);
const expected = ["ServerMessage:hello", "ServerMessage:state", "ServerMessage:history", "ServerMessage:event", "StateMsg", "RecordingsBody"];

/** "T+00:18:33.4" → 1113.4 s. */
function clockSeconds(t) {
  const m = /T([+−-])(\d+):(\d+):([\d.]+)/.exec(t ?? "");
  if (!m) return null;
  const s = Number(m[2]) * 3600 + Number(m[3]) * 60 + Number(m[4]);
  return m[1] === "+" ? s : -s;
}

/** "1 h 2 min", "9 min 43 s", "342 s" → seconds. */
function durationSeconds(t) {
  let s = 0;
  let any = false;
  for (const [, n, unit] of (t ?? "").matchAll(/([\d.]+)\s*(h|min|s)\b/g)) {
    any = true;
    s += Number(n) * (unit === "h" ? 3600 : unit === "min" ? 60 : 1);
  }
  return any ? s : null;
}

/** The figure in "… drone 2.3 m from the target" (`null`: none). */
const missFigure = (t) => /(\S+) ([\d.]+) m from the target/.exec(t ?? "")?.slice(1, 3).join(" ") ?? null;

/** What the page draws now. */
const shown = (page) => page.evaluate(() => {
  const q = (id) => document.querySelector(`[data-testid="${id}"]`);
  const vis = (id) => { const e = q(id); return e && !e.hidden ? e.textContent : null; };
  const dot = q("map-pred-planned");
  return {
    wall: Date.now(),
    clock: q("mission-clock")?.textContent ?? null,
    stage: q("hdr-stage")?.textContent ?? null,
    landing: q("hdr-landing")?.textContent ?? null,
    landingState: q("hdr-landing")?.dataset.state ?? null,
    final: vis("map-final"),
    path: vis("map-flight-path"),
    landed: vis("map-landed"),
    planned: dot?.isConnected && dot.dataset.lat ? { lat_deg: Number(dot.dataset.lat), lon_deg: Number(dot.dataset.lon) } : null,
    // The planned landings of the last state messages the page received, read in the same task
    // as the dot: the dot is checked against what the page was told, not against a later poll
    // of the API (under load the two are seconds of mission apart).
    told: [...(window.__told ?? [])],
  };
});

// ==================================================================== the whole mission, live
async function wholeMission() {
  const port = await freeUdpPort();
  const { io: station, base } = await startStation(["--link", `udpin:127.0.0.1:${port}`]);
  const api = apiOf(base);
  const ctx = await newContext("truth", { viewport: { width: 1440, height: 900 } });
  await ctx.addInitScript(() => {
    window.__told = [];
    const Native = window.WebSocket;
    window.WebSocket = class extends Native {
      constructor(...args) {
        super(...args);
        this.addEventListener("message", (e) => {
          try {
            const m = JSON.parse(e.data);
            const p = m.type === "state" ? m.prediction?.planned : null;
            if (p) window.__told = [...window.__told.slice(-9), { lat_deg: p.lat_deg, lon_deg: p.lon_deg }];
          } catch {}
        });
      }
    };
  });
  const page = await ctx.newPage();
  watchErrors(page, "truth");
  await page.goto(`${base}/?token=${OPERATOR}`);
  await page.waitForFunction(() => document.querySelector('[data-testid="conn-status"]')?.textContent === "CONNECTED", null, { timeout: 15000 });
  const drone = run(["drone", "--connect", `udpout:127.0.0.1:${port}`, "--scenario", "mission-short", "--speed", String(SPEED), "--summary-json", "--linger", "3"], "stx drone");
  const exited = new Promise((r) => drone.proc.once("exit", r));
  let done = false;
  exited.then(() => (done = true));
  console.log(`truth: station at ${base}, mission-short at ${SPEED}× real time`);

  // Sample the page (and, for the height above the ground only, the station's estimate) until
  // the drone has landed and lingered.
  const samples = [];
  const t0 = Date.now();
  while (!done && Date.now() - t0 < 600_000) {
    const [s, st] = await Promise.all([shown(page), api("/api/state")]);
    s.alt_msl_m = st.body?.estimate?.alt_msl_m ?? null;
    s.apiStage = st.body?.mission?.stage ?? null;
    s.apiPlanned = st.body?.prediction?.planned ?? null;
    s.onboard = st.body?.vehicle?.predicted_landing ?? null;
    s.apiTime = st.body?.mission_time_s ?? null;
    // Under the parafoil the whole state is kept: a departure of the station's picture from the
    // drone's is then diagnosable from tests/output/browser/truth-samples.json alone.
    if (s.apiStage === "parafoil") s.state = st.body;
    samples.push(s);
    await sleep(50);
  }
  await exited;
  await writeFile(join(out, "truth-samples.json"), JSON.stringify(samples));
  await writeFile(join(out, "truth-events.json"), JSON.stringify((await api("/api/events")).body));
  const truth = JSON.parse(drone.out.trim().split("\n").pop() || "null");
  check("the drone flew mission-short to a landing and said so", truth?.landing?.miss_m != null && truth?.final_course_deg != null,
    truth?.landing ? `landed at ${truth.landing.time_s.toFixed(1)} s, ${truth.landing.miss_m.toFixed(1)} m from the target` : drone.err.slice(-300));
  if (!truth?.landing) return { station, page, ctx, base };
  const start = (stage) => truth.stages.find((s) => s.stage === stage)?.start_s ?? null;

  // ---------------------------------------------------------------- one clock: the mission's
  // The stage's start must fall between the clock of the last sample still showing the stage
  // before and that of the first showing it (the page's clock then, give or take 1 s, the few
  // mission seconds telemetry takes to reach the page, and what the clock ran ahead through a
  // silence): whatever the sampling interval.
  // The telemetry's way to the page is a wall-clock delay: at SPEED× it is SPEED times as many
  // mission seconds (half a second of it on a loaded machine, at least 5 mission seconds).
  const lagS = Math.max(5, 0.5 * SPEED);
  // Through a silence of the link (a stalled process on a loaded machine) the clock is carried
  // forward at the sim speed and can get ahead of the drone's; it then stands still until the
  // drone's catches up (crates/stx-station/src/core/mission_clock.rs). How long the last clock
  // before the change went on standing, at the sim speed, is how far ahead it was.
  const aheadOf = (i) => {
    let k = i;
    while (k + 1 < samples.length && samples[k + 1].clock === samples[i].clock) k++;
    return (SPEED * (samples[k].wall - samples[i].wall)) / 1000;
  };
  const clockChecks = ["round_chute", "parafoil"].map((stage) => {
    const i = samples.findIndex((s) => s.stage === stage.replace(/_/g, " "));
    const before = i > 0 ? clockSeconds(samples[i - 1].clock) : null;
    const ahead = i > 0 ? aheadOf(i - 1) : 0;
    const at = i >= 0 ? clockSeconds(samples[i].clock) : null;
    const t = start(stage);
    return { stage, truth: t, before, ahead, page: at, ok: at !== null && before !== null && t !== null && at >= t - 1 && before <= t + lagS + ahead };
  });
  const ticking = samples.filter((s) => clockSeconds(s.clock) !== null && s.apiStage !== "landed");
  const a = ticking[0];
  const b = ticking[ticking.length - 1];
  const rate = a && b ? (clockSeconds(b.clock) - clockSeconds(a.clock)) / ((b.wall - a.wall) / 1000) : NaN;
  check("the T+ clock is the drone's: each stage is first shown between the clocks around the drone's start of it, and it runs at the sim speed",
    clockChecks.every((c) => c.ok) && Math.abs(rate / SPEED - 1) < 0.2,
    `${clockChecks.map((c) => `${c.stage}: drone ${c.truth?.toFixed(1)} s, page ${c.before?.toFixed(1)} → ${c.page?.toFixed(1)} s${c.ahead > 0 ? ` (the clock before stood ${c.ahead.toFixed(1)} s ahead)` : ""}`).join("; ")}; ${rate.toFixed(1)} s of mission per s at ${SPEED}×`);
  const axis = await page.evaluate(() => document.querySelector('[data-testid="plot-altitude"]')?.uplot?.axes?.[0]?.label ?? null);
  check("the plots' time axis is the mission's, with its unit", axis === "mission time, s", `x axis "${axis}"`);

  // ---------------------------------------------------------------- "landing in" only with a prediction
  // Before the round chute by the station and by the page alike: the two are read in parallel,
  // and at the release the page can already show the round chute the API's answer came before.
  const early = samples.filter((s) => ["pre_launch", "ascent"].includes(s.apiStage) && ["pre launch", "ascent"].includes(s.stage));
  const countdownEarly = early.filter((s) => /landing in/.test(s.landing ?? ""));
  check("no \"landing in\" on the pad or climbing", early.length > 20 && countdownEarly.length === 0,
    `${early.length} samples before the round chute, ${countdownEarly.length} with a countdown: ${countdownEarly[0]?.landing ?? ""}`);
  const chute = samples.filter((s) => s.apiStage === "round_chute" && /landing in/.test(s.landing ?? "") && /unsteered landing in/.test(s.path ?? ""));
  const chuteOff = chute.map((s) => Math.abs(durationSeconds(s.landing.replace(/^.*landing in/, "")) - durationSeconds(s.path.replace(/^.*landing in/, ""))));
  check("under the round chute the header's countdown is the map's unsteered landing (within 2 s)", chute.length > 3 && chuteOff.every((d) => d <= 2),
    `${chute.length} samples, largest difference ${Math.max(...chuteOff).toFixed(0)} s; e.g. "${chute[0]?.landing}" / "${chute[0]?.path}"`);

  // ---------------------------------------------------------------- the final course the drone flew
  const beforeLanding = samples.filter((s) => s.apiStage !== "landed");
  const chips = beforeLanding.filter((s) => s.final !== null);
  const lastChip = chips[chips.length - 1]?.final ?? null;
  const chipDeg = Number(/final (\d+)°/.exec(lastChip ?? "")?.[1]);
  const chipEarly = samples.filter((s) => s.final !== null && ["pad", "ascent", "round_chute"].includes(s.apiStage));
  check("the map's final-course chip is the course the drone's guidance flew (within 5°), and only under the parafoil",
    Number.isFinite(chipDeg) && angleDiff(chipDeg, truth.final_course_deg) <= 5 && chipEarly.length === 0,
    `page "${lastChip}", drone ${truth.final_course_deg.toFixed(1)}°; chip before the parafoil ${chipEarly.length} times`);

  // ---------------------------------------------------------------- the planned dot converges
  const st = (await until(() => api("/api/state"), (r) => r.body?.mission?.landing != null, 10000)).body;
  const ground = st?.mission?.landing?.position?.alt_msl_m ?? null;
  const touchdown = { lat_deg: truth.landing.lat_deg, lon_deg: truth.landing.lon_deg };
  // One flight, sampled every ~2 s of its clock: where a sample falls against the turn onto final
  // (in this band) and against the station's once-a-second prediction moves its figure by a few
  // metres (medians of 3.5–5.8 m over six runs, the drone's own 3.3–5.7 m). So: the median over
  // 200–50 m within 20 m — the issue's page drew it 70–100 m off — no more than 5 m beyond the
  // drone's own at the same instants — a replica updated once per telemetry burst was 7–14 m
  // beyond it in three runs of six — and the dot exactly on the station's prediction. The
  // campaign's statistics (p95 within 15 m, never worse than the drone's own by over 5 m) are
  // `stx bench agreement`'s and the short test's.
  const band = beforeLanding.filter((s) => s.apiStage === "parafoil" && s.planned && s.alt_msl_m !== null && ground !== null && Math.abs(s.alt_msl_m - ground - 125) <= 75);
  const median = (xs) => (xs.length ? [...xs].sort((x, y) => x - y)[Math.floor(xs.length / 2)] : NaN);
  const offs = band.map((s) => distanceM(s.planned, touchdown));
  const onboardOffs = band.filter((s) => s.onboard).map((s) => distanceM(s.onboard, touchdown));
  // The dot against the nearest of the last ten predictions the page was sent (the map may draw
  // a message or two after it arrives); the drone's own prediction is metres away from these.
  const drawn = median(band.filter((s) => s.told.length).map((s) => Math.min(...s.told.map((p) => distanceM(s.planned, p)))));
  check("the planned dot from 200 to 50 m above the ground is the station's prediction, within 20 m of the drone's touchdown and within 5 m of the drone's own prediction's figure (medians)",
    offs.length >= 5 && median(offs) <= 20 && median(offs) <= median(onboardOffs) + 5 && drawn < 1,
    `${offs.length} samples: the dot ${offs.map((o) => o.toFixed(1)).join(", ")} m from the touchdown (median ${median(offs).toFixed(1)} m; the drone's own prediction at the same instants: median ${median(onboardOffs).toFixed(1)} m); the dot from the station's prediction the page was last sent: median ${drawn.toFixed(2)} m`);

  // ---------------------------------------------------------------- one landing figure, live
  await page.waitForFunction(() => document.querySelector('[data-testid="hdr-landing"]')?.dataset.state === "landed" && !/measuring/.test(document.querySelector('[data-testid="hdr-landing"]').textContent), null, { timeout: 10000 }).catch(() => {});
  const viewerCtx = await newContext("truth-viewer", { viewport: { width: 1280, height: 800 } });
  const viewer = await viewerCtx.newPage();
  watchErrors(viewer, "truth viewer");
  await viewer.goto(`${base}/?token=${VIEWER}`);
  await viewer.waitForFunction(() => document.querySelector('[data-testid="hdr-landing"]')?.dataset.state === "landed", null, { timeout: 15000 }).catch(() => {});
  const logText = await page.locator('[data-testid="event-item"]').evaluateAll((els) => els.map((e) => e.textContent).filter((t) => / from the target/.test(t)));
  const figures = {
    header: missFigure(await text(page, "hdr-landing")),
    map: missFigure(await text(page, "map-landed")),
    log: missFigure(logText[logText.length - 1]),
    viewer: missFigure(await text(viewer, "hdr-landing")),
  };
  const stationMiss = st?.mission?.landing?.miss_m ?? NaN;
  const one = new Set(Object.values(figures));
  check("one landing figure live: header, map, event log and a viewer's page read the same, to 0.1 m, naming the body",
    one.size === 1 && figures.header === `drone ${stationMiss.toFixed(1)}`, `${JSON.stringify(figures)}; station ${stationMiss.toFixed(2)} m; log "${logText[logText.length - 1] ?? ""}"`);
  check("the figure is the drone's real miss, give or take its GPS error (≤ 8 m)", Math.abs(stationMiss - truth.landing.miss_m) <= 8,
    `station ${stationMiss.toFixed(1)} m (the drone's GPS), truth ${truth.landing.miss_m.toFixed(1)} m (its ground contact)`);
  // On the ground there is no glide, and the height above the origin's ground is not a height.
  const landedReadouts = { glideAir: await text(page, "ro-glide-air"), glideGround: await text(page, "ro-glide-ground"), height: await text(page, "ro-height") };
  check("landed: no glide ratio, and the height reads \"landed\"",
    landedReadouts.glideAir === "—" && landedReadouts.glideGround === "—" && landedReadouts.height === "landed", JSON.stringify(landedReadouts));
  // What the flight learned of the canopy stays on the page after the landing, as the station keeps it.
  const learnedAfter = (await api("/api/state")).body?.guidance?.learned ?? null;
  const learnedRows = await page.evaluate(() => [...document.querySelectorAll('[data-testid="learned-polar"] tr')].map((tr) => [...tr.querySelectorAll("th, td")].map((c) => c.textContent)));
  check("landed: the learned polar stays, headed \"at landing\", the page's airspeed row the station's",
    learnedAfter?.flying === false && learnedRows[0]?.[0] === "at landing"
      && learnedAfter.learned_s > 0 && learnedAfter.airspeed_scale.every((v, i) => learnedRows[1]?.[i + 1] === `${Math.round(v * 100)} %${Math.abs(Math.round(v * 100) - 100) > 15 ? "!" : ""}`),
    `page ${JSON.stringify(learnedRows)}; station ${JSON.stringify(learnedAfter)}`);
  // The wind chart's height axis stops at the ground: the landing's own altitude, give or take its GPS.
  const axisMin = Number(await page.locator('[data-testid="wind-axis-min"]').textContent());
  check("landed: the wind chart's height axis does not run below the ground", ground !== null && axisMin >= ground - 10, `axis from ${axisMin} m MSL, the landing at ${ground?.toFixed(0)} m MSL`);
  const cut = await cutShort(page);
  check("landed, link stale: no readout is cut short", cut.length === 0, cut.join(" | ") || "none");
  await page.screenshot({ path: join(out, "truth-landed.png") });
  await viewerCtx.close();
  return { station, page, ctx, base, figure: figures.header, truth };
}

// ==================================================================== the recording, the next day
async function theDayAfter({ station, ctx, figure }) {
  await ctx.close();
  const exited = new Promise((r) => station.proc.once("exit", r));
  station.proc.kill("SIGINT");
  await Promise.race([exited, sleep(10000)]);
  const files = (await readdir(recordDir)).filter((f) => f.endsWith(".mcap")).sort();
  const file = join(recordDir, files[files.length - 1]);

  // The recordings list of a new station.
  const { base } = await startStation(["--link", "udpin:127.0.0.1:0"]);
  const lctx = await newContext("truth-recordings", { viewport: { width: 1440, height: 900 } });
  const list = await lctx.newPage();
  watchErrors(list, "truth recordings");
  await list.goto(`${base}/?token=${OPERATOR}`);
  await list.click('[data-testid="tab-recordings"]');
  const row = `[data-testid="recording-row"][data-name="${basename(file)}"] [data-testid="recording-landing"]`;
  await list.waitForSelector(row, { timeout: 10000 }).catch(() => {});
  const listed = missFigure(await list.locator(row).textContent().catch(() => ""));
  await lctx.close();

  // The flight's replay, sought to its end.
  const io = run(["replay", file, "--listen", "127.0.0.1:0"], "stx replay");
  for (let i = 0; i < 100 && !/open (http:\/\/\S+)\/\?token=/.test(io.out); i++) await sleep(100);
  const rbase = /open (http:\/\/\S+)\/\?token=/.exec(io.out)?.[1];
  if (!rbase) throw new Error(`stx replay did not start:\n${io.out}\n${io.err}`);
  const rctx = await newContext("truth-replay", { viewport: { width: 1440, height: 900 } });
  const replay = await rctx.newPage();
  watchErrors(replay, "truth replay");
  await replay.goto(`${rbase}/?token=${OPERATOR}`);
  await replay.waitForFunction(() => document.querySelector('[data-testid="replay-bar"]')?.hidden === false, null, { timeout: 15000 }).catch(() => {});
  await replay.locator('[data-testid="replay-seek"]').evaluate((el) => {
    el.value = el.max;
    el.dispatchEvent(new Event("input"));
    el.dispatchEvent(new Event("change"));
  });
  await replay.waitForFunction(() => document.querySelector('[data-testid="hdr-landing"]')?.dataset.state === "landed" && / from the target/.test(document.querySelector('[data-testid="hdr-landing"]').textContent), null, { timeout: 30000 }).catch(() => {});
  const replayed = missFigure(await text(replay, "hdr-landing"));
  const replayState = (await apiOf(rbase)("/api/state")).body;
  check("one landing figure after the flight: the recordings list and the replay read the live figure, to 0.1 m",
    figure !== null && listed === figure && replayed === figure,
    `live "${figure}", recordings list "${listed}", replay "${replayed}" (replay station ${replayState?.mission?.landing?.miss_m?.toFixed(2)} m)`);
  await replay.screenshot({ path: join(out, "truth-replay.png") });
  await rctx.close();
}

await runFlights(async () => {
  const flown = await wholeMission();
  await theDayAfter(flown);
}, expected);
