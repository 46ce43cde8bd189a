#!/usr/bin/env node
// The Lab page in a real browser, against `stx serve --sim` (the drone flies `rehearsal`, so
// live telemetry flows while the Lab works): the vehicle editor refuses a bad value on its row
// with the model's rule; a scenario runs and its plots draw; a Monte Carlo batch shows its
// progress and is cancelled part-way, keeping the runs it flew; the stability analysis draws its
// eigenvalues beside the seed's; a second job while one runs is 409 and a viewer's start 403;
// the viewer's page shows the results without the controls. Compare/identify on a recording is
// not in the Lab yet (see the report of issue 16 item 3).
//
// Usage: node tests/browser/lab.mjs [path/to/stx]   (default target/release/stx)

import { mkdtemp, readdir } from "node:fs/promises";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { OPERATOR, VIEWER, out, speed, check, newContext, startStation, until, text, apiOf, registerRest, watchErrors, runFlights } from "./harness.mjs";

registerRest("GET", /^\/api\/lab$/, null, "LabStatusBody");
registerRest("POST", /^\/api\/lab\/jobs$/, "LabJobBody", "LabStartedBody");
registerRest("POST", /^\/api\/lab\/cancel$/, null, "LabStatusBody");
registerRest("GET", /^\/api\/lab\/vehicle$/, null, "VehicleFieldsBody");
registerRest("POST", /^\/api\/lab\/vehicle\/check$/, "LabVehicleBody", "VehicleFieldsBody");
registerRest("POST", /^\/api\/lab\/vehicle\/save$/, "LabVehicleBody", "LabSavedBody");
registerRest("GET", /^\/api\/lab\/gains$/, null, "LabGainsListBody");
registerRest("POST", /^\/api\/lab\/gains\/(save|send)$/, "LabGainsBody", "LabSavedBody");

const labDir = await mkdtemp(join(tmpdir(), "stx-browser-lab-"));
const outcome = (page) => text(page, "job-outcome").catch(() => "");

async function lab() {
  const { base } = await startStation(["--sim", "--sim-scenario", "rehearsal", "--sim-speed", String(speed), "--link", "udpin:127.0.0.1:0", "--lab-dir", labDir]);
  const api = apiOf(base);
  const ctx = await newContext("lab", { viewport: { width: 1440, height: 1000 } });
  const page = await ctx.newPage();
  watchErrors(page, "lab");
  await page.goto(`${base}/lab.html?token=${OPERATOR}`);
  await page.locator('[data-testid="vehicle-canopy.mass_kg"]').waitFor({ timeout: 15000 });

  // The vehicle editor: a value the model refuses is marked on its row with the rule.
  const seedMass = await page.locator('[data-testid="vehicle-canopy.mass_kg"]').inputValue();
  await page.fill('[data-testid="vehicle-canopy.mass_kg"]', "-1");
  await page.click('[data-testid="vehicle-check"]');
  const rule = await until(() => text(page, "vehicle-error-canopy.mass_kg").catch(() => ""), (t) => t !== "", 5000);
  check("vehicle editor: a negative canopy mass is refused on its row with the model's rule",
    rule.includes("> 0") && (await page.locator('tr.invalid[data-field="canopy.mass_kg"]').count()) === 1, `"${rule}" (seed ${seedMass} kg)`);
  await page.fill('[data-testid="vehicle-canopy.mass_kg"]', "0.8");
  await page.click('[data-testid="vehicle-check"]');
  const valid = await until(() => text(page, "vehicle-msg"), (t) => t.startsWith("valid"), 5000);
  await page.fill('[data-testid="vehicle-name"]', "heavier");
  await page.click('[data-testid="vehicle-save"]');
  const saved = await until(() => text(page, "vehicle-msg"), (t) => t.startsWith("saved"), 5000);
  const files = await readdir(labDir);
  check("vehicle editor: an accepted vehicle is saved as a file in the Lab's directory", valid.includes("1 changed") && saved.includes("heavier.toml") && files.includes("heavier.toml"), `"${valid}", "${saved}", ${files.join(",")}`);

  // A scenario with the edited vehicle, and its plots.
  await page.selectOption('[data-testid="job-kind"]', "scenario");
  await page.selectOption('[data-testid="job-scenario"]', "spiral-exit");
  await page.click('[data-testid="job-start"]');
  const scen = await until(() => outcome(page), (t) => /scenario.*: (done|failed)/.test(t), 120000, 500);
  await page.locator('[data-testid="plot-height"] canvas').first().waitFor({ timeout: 5000 }).catch(() => {});
  const plots = await page.locator('[data-testid="lab-results"] .uplot').count();
  check("scenario: spiral-exit runs in the background and its four plots draw (height, attitude, speeds, position)", scen.includes("done") && plots === 4, `"${scen}", ${plots} plots`);
  await page.screenshot({ path: join(out, "lab-scenario.png") });

  // A Monte Carlo batch: progress as runs finish, then a cancel keeps the runs flown.
  await page.selectOption('[data-testid="job-kind"]', "monte_carlo");
  await page.fill('[data-testid="mc-runs"]', "40");
  await page.click('[data-testid="job-start"]');
  const label = await until(() => text(page, "job-progress-label"), (t) => /^[1-9]\d*\/40 runs/.test(t), 120000, 300);
  const fraction = await page.locator('[data-testid="job-progress"]').evaluate((p) => p.value);
  const second = await api("/api/lab/jobs", OPERATOR, { method: "POST", body: JSON.stringify({ kind: "stability", altitude_m: 100 }) });
  const viewerStart = await api("/api/lab/jobs", VIEWER, { method: "POST", body: JSON.stringify({ kind: "stability", altitude_m: 100 }) });
  check("Monte Carlo: the progress bar and label follow the runs while the batch runs", fraction > 0 && fraction < 1, `"${label}", bar ${fraction}`);
  check("one job at a time: a second start is 409 busy; a viewer's start is 403", second.status === 409 && viewerStart.status === 403, `${second.status} ${second.body?.reason}; viewer ${viewerStart.status}`);
  await page.click('[data-testid="job-cancel"]');
  const cancelled = await until(() => outcome(page), (t) => /monte_carlo.*cancelled/.test(t), 120000, 300);
  const mc = await until(() => text(page, "mc-result").catch(() => ""), (t) => /of 40 runs flown/.test(t), 5000);
  const flown = Number(/(\d+) of 40 runs flown/.exec(mc)?.[1] ?? "NaN");
  check("Monte Carlo: a cancel stops the batch and the runs it flew are shown with their statistics", /cancelled/.test(cancelled) && flown >= 1 && flown < 40 && (await page.locator('[data-testid="mc-landings"] circle').count()) === flown,
    `"${cancelled}", ${flown} flown`);
  await page.screenshot({ path: join(out, "lab-montecarlo.png") });

  // The stability analysis: eigenvalues beside the seed's, ranks.
  await page.selectOption('[data-testid="job-kind"]', "stability");
  await page.click('[data-testid="job-start"]');
  const stab = await until(() => outcome(page), (t) => /stability.*: (done|failed)/.test(t), 120000, 500);
  const ours = await page.locator('[data-testid="eigen-plot"] circle.point').count();
  const seeds = await page.locator('[data-testid="eigen-plot"] circle.seed-point').count();
  const ranks = await text(page, "stability-ranks").catch(() => "");
  check("stability: the eigenvalue plot shows ours and the seed's 31, with the ranks beside the seed's", stab.includes("done") && ours > 20 && seeds === 31 && /controllability rank\s+\d+\s+29/.test(ranks),
    `"${stab}", ${ours} ours, ${seeds} seed's; ${ranks.replace(/\s+/g, " ").slice(0, 160)}`);
  await page.screenshot({ path: join(out, "lab-stability.png") });

  // A viewer sees the last result, without the controls.
  const vctx = await newContext("lab viewer", { viewport: { width: 1200, height: 900 } });
  const vpage = await vctx.newPage();
  watchErrors(vpage, "lab viewer");
  await vpage.goto(`${base}/lab.html?token=${VIEWER}`);
  await vpage.locator('[data-testid="eigen-plot"]').waitFor({ timeout: 10000 }).catch(() => {});
  check("viewer: the Lab page shows the last result read-only (Run disabled)",
    (await vpage.locator('[data-testid="eigen-plot"] circle.point').count()) === ours && (await vpage.locator('[data-testid="job-start"]').isDisabled()), `${await text(vpage, "lab-role")}`);
  await vctx.close();
  await ctx.close();
}

await runFlights(lab, ["Session", "LabStatusBody", "LabStartedBody", "VehicleFieldsBody", "LabSavedBody"]);
