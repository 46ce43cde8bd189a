#!/usr/bin/env node
// Where the stack can land, in a real browser (issue 15 items 1 and 2): `stx serve --sim` flies the
// `rehearsal` under the parafoil with the shipped station config (its sample keep-out zones). The
// map draws the reachable footprint (50 % and 95 % regions), which holds the predicted landing and
// is refreshed; the sample zones are drawn; a target inside a zone is refused naming it; a viewer
// may not change the zones; an operator's zone around the uncontrolled landing raises the alarm
// on the map and in the log, and the zones it set are what GET returns. The map's legend lists
// each symbol drawn, in the map's own colours, and nothing that is not.
//
// Usage: node tests/browser/footprint.mjs [path/to/stx]   (default target/release/stx)

import { readFile } from "node:fs/promises";
import { join } from "node:path";
import { OPERATOR, VIEWER, root, out, speed, check, newContext, startStation, apiOf, until, attr, text, watchErrors, runFlights, registerRest, fromNorthEast, configWithZoneCopy, legendAgainstMap, checkLegend, LIVE_SYMBOLS, zoomOut, inRing } from "./harness.mjs";

registerRest("PUT", /^\/api\/keep-out$/, "KeepOutBody", "KeepOutMsg");

const inPolygons = (polys, p) => polys.some(([outer, ...holes]) => inRing(outer, p) && !holes.some((h) => inRing(h, p)));

async function flight() {
  const copy = await configWithZoneCopy();
  const sampleBefore = await readFile(join(root, "config/keep-out/sample.geojson"), "utf8");
  const { base } = await startStation(["--config", copy.file, "--sim", "--sim-scenario", "rehearsal", "--sim-speed", String(speed), "--link", "udpin:127.0.0.1:0"]);
  const api = apiOf(base);
  const ctx = await newContext("footprint", { viewport: { width: 1440, height: 900 } });
  const page = await ctx.newPage();
  watchErrors(page, "footprint");
  await page.goto(`${base}/?token=${OPERATOR}`);

  // The footprint, with a planned landing to hold.
  const first = (await until(() => api("/api/state"), (r) => r.body?.footprint?.contours?.length === 2 && r.body?.prediction?.planned, 60000)).body;
  const f = first?.footprint;
  const level = (fp, p) => fp?.contours.find((c) => Math.abs(c.level - p) < 1e-6)?.polygons ?? [];
  const landing = first?.prediction?.planned;
  const holds = landing ? inPolygons(level(f, 0.95), [landing.lat_deg, landing.lon_deg]) : false;
  check("footprint: the state carries the 50 % and 95 % regions, and the 95 % region holds the planned landing",
    f && level(f, 0.5).length > 0 && level(f, 0.95).length > 0 && holds,
    `${f?.draws} draws from ${f?.height_m?.toFixed(0)} m; 50 %: ${level(f, 0.5).length} polygon(s), 95 %: ${level(f, 0.95).length}; planned landing ${holds ? "inside" : "OUTSIDE"}`);
  const hits = f?.zone_hits ?? [];
  const hitBadge = await until(() => text(page, "map-footprint").catch(() => ""), (t) => /keep-out within reach: .*Pond/.test(t), 10000);
  check("footprint: the sample zones within reach are marked (the pond by the target), on the map too",
    hits.some((h) => h.zone === "Pond" && h.level >= 0.5) && /Pond/.test(hitBadge), `${JSON.stringify(hits)}; badge "${hitBadge}"`);
  const drawn = await until(() => page.locator("path.map-footprint-95, path.map-footprint-50").count(), (n) => n >= 2, 10000);
  const badge = await text(page, "map-footprint").catch(() => "");
  check("footprint: the map draws both regions with the age of the refresh", drawn >= 2 && /reach 50 % \/ 95 %/.test(badge), `${drawn} paths, badge "${badge}"`);
  // Two refreshes seen on the page, timed by the wall clock (the "at least every 5 s").
  const computed = () => attr(page, "map-footprint", "data-computed").then(Number);
  const c0 = await computed();
  const c1 = await until(computed, (t) => t > c0, 15000, 50);
  const w1 = Date.now();
  const c2 = await until(computed, (t) => t > c1, 15000, 50);
  const gapMs = Date.now() - w1;
  check("footprint: refreshed on the page at least every 5 s", c1 > c0 && c2 > c1 && gapMs <= 5000, `computed at ${c0}, ${c1}, ${c2} s of mission time; ${gapMs} ms between the last two on the page`);

  // The sample zones of the shipped config.
  const zones = (await api("/api/keep-out")).body;
  const shown = await until(() => page.locator("path.map-keep-out").count(), (n) => n >= (zones?.areas ?? 1), 10000);
  check("keep-out: the station's sample zones are drawn on the map", zones?.areas >= 3 && shown === zones.areas, `${zones?.areas} areas in force, ${shown} drawn`);

  // A target in the pond is refused, naming it.
  const pond = zones?.zones?.features?.find((z) => z.properties?.name === "Pond");
  const ring = pond?.geometry?.coordinates?.[0] ?? [];
  const centre = ring.slice(0, -1).reduce((a, p) => [a[0] + p[0] / (ring.length - 1), a[1] + p[1] / (ring.length - 1)], [0, 0]);
  const refused = await api("/api/commands/target", OPERATOR, { method: "POST", body: JSON.stringify({ lat_deg: centre[1], lon_deg: centre[0], alt_msl_m: 245 }) });
  check("keep-out: a target inside a zone is refused with the zone's name", refused.status === 400 && /Pond/.test(JSON.stringify(refused.body)), `${refused.status} ${JSON.stringify(refused.body)}`);

  // A viewer may not change the zones; an operator's zone around the uncontrolled landing alarms.
  const viewerPut = await api("/api/keep-out", VIEWER, { method: "PUT", body: JSON.stringify(zones.zones) });
  const st = (await api("/api/state")).body;
  const u = st?.prediction?.uncontrolled;
  const origin = { lat_deg: u?.lat_deg ?? 0, lon_deg: u?.lon_deg ?? 0 };
  const corner = (n, e) => { const p = fromNorthEast(origin, n, e); return [p.lon_deg, p.lat_deg]; };
  const square = [corner(-400, -400), corner(-400, 400), corner(400, 400), corner(400, -400), corner(-400, -400)];
  const added = { type: "FeatureCollection", features: [...zones.zones.features, { type: "Feature", properties: { name: "Test field" }, geometry: { type: "Polygon", coordinates: [square] } }] };
  const put = await api("/api/keep-out", OPERATOR, { method: "PUT", body: JSON.stringify(added) });
  check("keep-out: a viewer may not change the zones (403); an operator's edit is in force and read back",
    viewerPut.status === 403 && put.status === 200 && (await api("/api/keep-out")).body?.areas === zones.areas + 1,
    `viewer ${viewerPut.status}, operator ${put.status}`);
  const alarm = await until(() => page.locator('[data-testid="map-keep-out-alarm"]').isVisible().then(async (v) => (v ? text(page, "map-keep-out-alarm") : "")), (t) => /Test field/.test(t), 15000);
  const events = (await api("/api/events")).body?.events ?? [];
  const logged = events.some((e) => e.level === "warning" && /Test field/.test(e.text));
  check("keep-out: a landing predicted in a zone raises the alarm on the map and a warning in the log", /Test field/.test(alarm) && logged, `map "${alarm}", log ${logged ? "has" : "lacks"} the warning`);
  const onDisk = JSON.parse(await readFile(copy.zones, "utf8"));
  const sampleAfter = await readFile(join(root, "config/keep-out/sample.geojson"), "utf8");
  check("keep-out: the edit is kept in the configured file (a restart keeps it), and only there",
    onDisk.features?.some((z) => z.properties?.name === "Test field") && sampleAfter === sampleBefore,
    `${onDisk.features?.length} zones in the file; the repository's sample ${sampleAfter === sampleBefore ? "untouched" : "CHANGED"}`);
  await page.screenshot({ path: join(out, "footprint.png") });

  // The legend names what the map draws under the parafoil: the reach contours, the predicted
  // landings with their ellipses, the zones; not the ascent's flight path, which is not drawn.
  // Zoomed out, so no symbol drawn lies outside the view (Leaflet leaves those paths empty).
  await zoomOut(page, 2);
  const legend = await legendAgainstMap(page, "map-legend", LIVE_SYMBOLS);
  checkLegend("legend: every symbol on the live map is listed in its own colour, and nothing else", legend,
    ["vehicle", "track", "target", "planned", "uncontrolled", "reach-50", "reach-95", "keep-out", "grid"]);
  await page.screenshot({ path: join(out, "legend-live.png") });
  await ctx.close();
}

await runFlights(flight, ["ServerMessage:hello", "ServerMessage:state", "StateMsg", "KeepOutMsg", "ErrorBody", "EventsBody"]);
