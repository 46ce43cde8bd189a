// The surface wind on the live page (ui/surfaceWind.ts), for live.mjs's rehearsal: none at
// first; an operator types one in the Wind panel's form, the station sends it, the drone accepts
// it, and page and station agree; a typo never leaves the page; Clear withdraws it. And a
// viewer has no form, and the station refuses one.
//
// What is read is the station's own answer (`GET /api/state`) and the drone's acknowledgement
// as the station reports it, never the page's echo of what was typed.

import { join } from "node:path";
import { OPERATOR, VIEWER, angleDiff, check, out, text } from "./harness.mjs";

/** The three lines of the readout and the form's state, as the page shows them. */
const shown = (page) => page.evaluate(() => {
  const t = (id) => document.querySelector(`[data-testid="${id}"]`)?.textContent ?? null;
  const form = document.querySelector('[data-testid="surface-wind-form"]');
  return {
    wind: t("ro-surface-wind"), drone: t("ro-surface-drone"), error: t("surface-wind-error"),
    formOpen: form !== null && !form.hidden,
  };
});

/** The operator's page: none, a value typed and held by the drone, a typo refused, Clear. */
export async function surfaceWindFromPage(page, api) {
  const posts = [];
  page.on("request", (r) => {
    if (new URL(r.url()).pathname === "/api/surface_wind" && r.method() !== "GET") posts.push(r.method());
  });
  const station = async () => (await api("/api/state")).body?.surface_wind ?? null;

  // Nothing configured, nothing typed: no wind is sent, and the page says so.
  const first = await shown(page);
  const firstStation = await station();
  check("surface wind: none at first, on the page and at the station", first.wind === "none" && first.drone === "not sent" && firstStation?.wind === null && firstStation?.drone === "none",
    `page "${first.wind}" / "${first.drone}"; station ${JSON.stringify(firstStation)}`);

  // A typo stays in the page, and says which field.
  await page.click('[data-testid="surface-wind-toggle"]');
  await page.fill('[data-testid="surface-wind-speed"]', "61");
  await page.fill('[data-testid="surface-wind-from"]', "250");
  await page.click('[data-testid="surface-wind-set"]');
  const typo = await shown(page);
  check("surface wind: a speed beyond 60 m/s is refused in the page, nothing sent", typo.formOpen && /speed.*0…60/.test(typo.error ?? "") && posts.length === 0, `"${typo.error}", ${posts.length} requests`);
  await page.locator('[data-testid="panel-wind"]').screenshot({ path: join(out, "live-surface-wind-form.png") });

  // 4.3 m/s from −110°: the station takes it as from 250°, sends it, and the drone accepts it.
  await page.fill('[data-testid="surface-wind-speed"]', "4.3");
  await page.fill('[data-testid="surface-wind-from"]', "-110");
  await page.click('[data-testid="surface-wind-set"]');
  await page.waitForFunction(() => /^held/.test(document.querySelector('[data-testid="ro-surface-drone"]')?.textContent ?? "")
    && /· operator/.test(document.querySelector('[data-testid="ro-surface-wind"]')?.textContent ?? ""), null, { timeout: 15000 }).catch(() => {});
  const set = await shown(page);
  await page.locator('[data-testid="panel-wind"]').screenshot({ path: join(out, "live-surface-wind-held.png") });
  const held = await station();
  const w = held?.wind;
  const near = (r) => r != null && Math.abs(r.speed_mps - 4.3) <= 0.05 && angleDiff(r.from_deg, 250) <= 0.5;
  check("surface wind typed in the page: the readout shows it, from the operator, held by the drone; the form closes",
    /^4\.3 m\/s from 250° · operator \d+ s$/.test(set.wind ?? "") && /^held\b.* ago$/.test(set.drone ?? "") && !set.formOpen && posts.join(",") === "POST",
    `page "${set.wind}" / "${set.drone}", form ${set.formOpen ? "open" : "closed"}; requests ${posts.join(",")}`);
  // An older station does not say what the drone holds (`held`): then only that it holds one.
  check("surface wind: the station agrees (4.3 m/s within 0.05, from 250° within 0.5°, the operator's), and the drone holds it",
    near(w) && w.source === "operator" && near(held?.operator) && held?.drone === "held" && (held?.held === undefined || near(held.held)),
    JSON.stringify(held));

  // Clear withdraws it: no wind is sent any more.
  await page.click('[data-testid="surface-wind-toggle"]');
  await page.click('[data-testid="surface-wind-clear"]');
  await page.waitForFunction(() => document.querySelector('[data-testid="ro-surface-wind"]')?.textContent === "none", null, { timeout: 10000 }).catch(() => {});
  const cleared = { page: await shown(page), station: await station() };
  check("surface wind: Clear withdraws it, on the page and at the station", cleared.page.wind === "none" && !cleared.page.formOpen && cleared.station?.wind === null && cleared.station?.operator === null && posts.join(",") === "POST,DELETE",
    `page "${cleared.page.wind}"; station wind ${JSON.stringify(cleared.station?.wind)}, operator ${JSON.stringify(cleared.station?.operator)}; requests ${posts.join(",")}`);
  // The station's own refusal, as the page would show it (its reason names the field).
  const refused = await api("/api/surface_wind", OPERATOR, { method: "POST", body: JSON.stringify({ speed_mps: 4, from_deg: 400 }) });
  check("surface wind: the station refuses a direction beyond ±360° with 400 and says why", refused.status === 400 && /from_deg/.test(refused.body?.reason ?? ""), `${refused.status} ${JSON.stringify(refused.body)}`);
}

/** A viewer's page: the readout, no form; and the station refuses a viewer's value. */
export async function surfaceWindForViewer(vpage, api) {
  const toggle = await vpage.locator('[data-testid="surface-wind-toggle"]').evaluate((b) => ({ visible: b.offsetParent !== null, disabled: b.disabled }));
  const readout = await text(vpage, "ro-surface-wind");
  const refused = await api("/api/surface_wind", VIEWER, { method: "POST", body: JSON.stringify({ speed_mps: 4, from_deg: 250 }) });
  check("viewer: the surface wind is shown, without its form, and the station refuses a viewer's value (403)",
    readout !== "" && !toggle.visible && toggle.disabled && refused.status === 403, `readout "${readout}", toggle ${JSON.stringify(toggle)}, POST → ${refused.status}`);
}
