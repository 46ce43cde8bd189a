#!/usr/bin/env node
// Keep-out zones edited on the live map by an operator, with the mouse (issue 15 item 2), while
// `stx serve --sim` flies the `rehearsal` on a copy of the shipped config (an edit is written to
// the configured file). With the drone let go (mode uncontrolled, so that where it would land
// stays put: under guidance that prediction swings by a kilometre as the stack turns), a zone
// drawn by clicking its corners around the predicted uncontrolled landing is saved where it was clicked (in the API and in the file) and raises the landing
// alarm on the map and in the log; a corner dragged moves; a name the station refuses (and one
// this page refuses) is shown and the edit is kept; a change by another operator is announced
// during an edit and drawn after it; a deleted zone is gone; Cancel forgets an edit; a viewer has
// no edit controls.
//
// Where a click lands is computed here from the map's view (its centre and zoom, which the page
// writes on the map element) with Web Mercator's formulas, independently of Leaflet's code.
//
// Usage: node tests/browser/zones.mjs [path/to/stx]   (default target/release/stx)

import { readFile } from "node:fs/promises";
import { join } from "node:path";
import { OPERATOR, VIEWER, out, speed, check, newContext, startStation, apiOf, until, text, watchErrors, runFlights, registerRest, distanceM, sleep, configWithZoneCopy, settled, inRing } from "./harness.mjs";

registerRest("PUT", /^\/api\/keep-out$/, "KeepOutBody", "KeepOutMsg");

// ---- Web Mercator as Leaflet's default CRS has it: 256 px tiles, 2^zoom of them across.
const world = (z, p) => {
  const n = 256 * 2 ** z;
  const lat = Math.max(-85.0511287798, Math.min(85.0511287798, p.lat_deg)) * (Math.PI / 180);
  return { x: (n * (p.lon_deg + 180)) / 360, y: n * (0.5 - Math.log(Math.tan(Math.PI / 4 + lat / 2)) / (2 * Math.PI)) };
};
const fromWorld = (z, w) => {
  const n = 256 * 2 ** z;
  return { lat_deg: (Math.atan(Math.sinh(Math.PI * (1 - (2 * w.y) / n))) * 180) / Math.PI, lon_deg: (360 * w.x) / n - 180 };
};
/** The map's view: where its element is on the page, its centre and zoom. */
async function viewOf(page) {
  const el = page.locator('[data-testid="map"]');
  const box = await el.boundingBox();
  const [lat, lon] = (await el.getAttribute("data-center")).split(",").map(Number);
  return { box, zoom: Number(await el.getAttribute("data-zoom")), centre: { lat_deg: lat, lon_deg: lon } };
}
/** Page pixel of a position in a view. */
function pixelOf(v, p) {
  const c = world(v.zoom, v.centre);
  const w = world(v.zoom, p);
  return { x: v.box.x + v.box.width / 2 + (w.x - c.x), y: v.box.y + v.box.height / 2 + (w.y - c.y) };
}
/** Position under a page pixel in a view. */
function positionAt(v, px) {
  const c = world(v.zoom, v.centre);
  return fromWorld(v.zoom, { x: c.x + (px.x - v.box.x - v.box.width / 2), y: c.y + (px.y - v.box.y - v.box.height / 2) });
}
/** Ground metres per screen pixel at a latitude. */
const metresPerPixel = (v) => (40075016.686 * Math.cos((v.centre.lat_deg * Math.PI) / 180)) / (256 * 2 ** v.zoom);

/** The feature named `name` of a FeatureCollection, or of the `zones` of a `keep_out` message. */
const feature = (k, name) => (k?.zones ?? k)?.features?.find((f) => f.properties?.name === name);
/** A GeoJSON ring's corners (closing point dropped) as positions. */
const corners = (f) => (f?.geometry?.coordinates?.[0] ?? []).slice(0, -1).map(([lon, lat]) => ({ lat_deg: lat, lon_deg: lon }));
/** The largest distance between matching corners, m (Infinity when their counts differ). */
const worstM = (a, b) => (a.length === b.length && a.length > 0 ? Math.max(...a.map((p, i) => distanceM(p, b[i]))) : Infinity);

async function drag(page, from, to) {
  await page.mouse.move(from.x, from.y);
  await page.mouse.down();
  for (let i = 1; i <= 8; i++) await page.mouse.move(from.x + ((to.x - from.x) * i) / 8, from.y + ((to.y - from.y) * i) / 8);
  await page.mouse.up();
  // Leaflet swallows a click that comes right after a drag (it takes it for the drag's end).
  await sleep(300);
}

const whole = (p) => ({ x: Math.round(p.x), y: Math.round(p.y) });
const sameView = (a, b) => JSON.stringify(a) === JSON.stringify(b);
/** The map's view once it has stopped moving (the same for 300 ms; at most 5 s). */
async function settledView(page) {
  let last = await viewOf(page);
  for (let still = 0, t = 0; still < 3 && t < 50; t++) {
    await sleep(100);
    const now = await viewOf(page);
    still = sameView(now, last) ? still + 1 : 0;
    last = now;
  }
  return last;
}
/** Where to click for a position on the map as it is now: the whole pixel, the position under it, the view. */
async function aim(page, q) {
  const view = await viewOf(page);
  const exact = pixelOf(view, q);
  const px = whole(exact);
  return { px, exact, at: positionAt(view, px), view };
}
/**
 * Drags the map so that what is at `from` comes to `to` (page pixels); false if it is there
 * already. The drag starts at `to`, a point of the map clear of its controls (`from` may be at
 * an edge, under the edit bar), and moves by as much. The mouse rests before it is released,
 * so Leaflet adds no inertia.
 */
async function panTo(page, from, to) {
  const [dx, dy] = [to.x - from.x, to.y - from.y];
  if (Math.hypot(dx, dy) < 20) return false;
  await page.mouse.move(to.x, to.y);
  await page.mouse.down();
  for (let i = 1; i <= 10; i++) await page.mouse.move(to.x + (dx * i) / 10, to.y + (dy * i) / 10);
  await sleep(200);
  await page.mouse.up();
  await sleep(300);
  return true;
}

/**
 * The first point of a 40 px grid over `area` (page px) where the points of `shape` (offsets,
 * px) around it are all on bare map: no zone, marker, line or control under any of them.
 */
async function clearSpot(page, shape, area) {
  return page.evaluate(({ shape, area }) => {
    const bare = (x, y) => {
      const el = document.elementFromPoint(x, y);
      return el !== null && el.closest('[data-testid="map"]') !== null && el.closest(".leaflet-interactive, .leaflet-marker-icon, .leaflet-control, .marker-icon, [data-testid='map-overlay'], [data-testid='zone-editor']") === null;
    };
    for (let y = area.top; y <= area.bottom; y += 40) {
      for (let x = area.left; x <= area.right; x += 40) {
        if (shape.every(([dx, dy]) => bare(x + dx, y + dy))) return { x, y };
      }
    }
    return null;
  }, { shape, area });
}

async function flight() {
  const copy = await configWithZoneCopy();
  // At most 2× real time the stack is still flying when the alarm is awaited on a slow machine
  // (at 5× it lands about 60 s after the start).
  const simSpeed = Math.min(speed, 2);
  const { base } = await startStation(["--config", copy.file, "--sim", "--sim-scenario", "rehearsal", "--sim-speed", String(simSpeed), "--link", "udpin:127.0.0.1:0"]);
  const api = apiOf(base);
  const ctx = await newContext("zones", { viewport: { width: 1440, height: 900 } });

  // A viewer sees the zones and no way to edit them.
  const viewer = await ctx.newPage();
  watchErrors(viewer, "zones viewer");
  await viewer.goto(`${base}/?token=${VIEWER}`);
  await until(() => viewer.locator("path.map-keep-out").count(), (n) => n >= 3, 10000);
  const viewerControls = await viewer.locator('[data-testid^="zones-"]').evaluateAll((els) => els.filter((e) => e.getClientRects().length > 0).map((e) => e.dataset.testid));
  check("zones: a viewer sees the zones but no edit controls", (await viewer.locator("path.map-keep-out").count()) >= 3 && viewerControls.length === 0, `visible: ${JSON.stringify(viewerControls)}`);
  await viewer.close();

  const page = await ctx.newPage();
  watchErrors(page, "zones");
  await page.goto(`${base}/?token=${OPERATOR}`);
  const zonesAtStart = (await api("/api/keep-out")).body;
  await until(() => page.locator("path.map-keep-out").count(), (n) => n === zonesAtStart.areas, 10000);
  // A flight with a predicted uncontrolled landing, framed by the map (it follows until an edit
  // begins). The operator lets the drone go, and waits for the prediction to settle.
  await until(() => api("/api/state"), (r) => r.body?.prediction?.uncontrolled, 60000);
  await page.click('[data-testid="mode-uncontrolled"]');
  await until(() => api("/api/state"), (r) => r.body?.vehicle?.mode === "uncontrolled", 20000);
  const heard = [];
  await until(async () => {
    heard.push({ at: Date.now(), point: (await api("/api/state")).body?.prediction?.uncontrolled ?? null });
    return settled(heard);
  }, (ok) => ok, 30000);
  const bar = page.locator('[data-testid="zone-editor"]');
  const tb = (id) => page.locator(`[data-testid="${id}"]`);

  // ---- draw a zone around the predicted landing with the mouse
  await tb("zones-edit").click();
  await until(() => bar.getAttribute("data-editing"), (e) => e === "true", 3000);
  let v = await settledView(page); // the last framing move (if any) has ended
  const u = (await api("/api/state")).body.prediction.uncontrolled;
  // A square of ±90 px around the landing, kept clear of the badges along the top (with room for
  // a row more: the alarm comes) and of the bar (bottom left).
  const badges = await page.locator('[data-testid="map-overlay"]').boundingBox();
  const top = badges.y + badges.height + 60;
  const barTop = (await bar.boundingBox()).y - 20;
  const side = 90;
  const cx = Math.min(Math.max(pixelOf(v, u).x, v.box.x + side + 60), v.box.x + v.box.width - side - 20);
  const cy = Math.min(Math.max(pixelOf(v, u).y, top + side), barTop - side);
  // Framed at an edge, the landing would fall outside the square: the operator drags it to the
  // square's centre first (the map has stopped following for the edit).
  const panned = await panTo(page, pixelOf(v, u), { x: cx, y: cy });
  if (panned) v = await settledView(page);
  const pu = pixelOf(v, u);
  const square = [[-1, -1], [1, -1], [1, 1], [-1, 1]].map(([dx, dy]) => positionAt(v, { x: cx + dx * side, y: cy + dy * side }));
  await tb("zones-draw").click();
  // Each click where the corner is on the screen at that moment, as an operator aims: a
  // layout shift (a banner, the header wrapping) between clicks moves the map under the mouse.
  const shifts = [];
  const clicked = [];
  const wanted = [];
  for (const q of [...square, square[0]]) { // the first corner again closes the zone
    const { px: p, at, view } = await aim(page, q);
    if (!sameView(view, v)) shifts.push(view);
    await page.mouse.click(p.x, p.y);
    if (clicked.length < 4) {
      clicked.push(p);
      wanted.push(at);
    }
    await sleep(80);
  }
  const named = await until(() => tb("zones-name").inputValue(), (n) => n !== "", 3000);
  await tb("zones-name").fill("Test field");
  await tb("zones-kind").selectOption("people");
  await tb("zones-save").click();
  await until(() => bar.getAttribute("data-editing"), (e) => e === "false", 5000);
  const tol = metresPerPixel(v) + 0.1;
  const saved = (await api("/api/keep-out")).body;
  const got = feature(saved, "Test field");
  const err1 = worstM(corners(got), wanted);
  const viewNote = `${panned ? "map dragged to put the landing in the square; " : ""}${shifts.length ? `the map moved under the mouse during the drawing (${JSON.stringify(shifts[0])} from ${JSON.stringify(v)}); ` : ""}`;
  check("zones: an operator draws a zone with four clicks; the station has it where it was clicked, named, with its kind",
    named === "Zone 1" && got?.properties?.kind === "people" && err1 <= tol && saved.areas === zonesAtStart.areas + 1,
    `new zone first named "${named}"; corners within ${err1.toFixed(2)} m of the clicks (tolerance 1 px = ${tol.toFixed(2)} m at zoom ${v.zoom}); ${saved.areas} areas; ${viewNote}the predicted landing ${(pu.x - cx).toFixed(0)}, ${(pu.y - cy).toFixed(0)} px off the square's centre`);
  const onDisk = JSON.parse(await readFile(copy.zones, "utf8"));
  check("zones: the drawn zone is written to the configured file", worstM(corners(feature(onDisk, "Test field")), wanted) <= tol, `${onDisk.features?.length} features in ${copy.zones}`);
  // Where the drone would land meanwhile: in the zone or not, and still flying.
  const since = Date.now();
  const meanwhile = [];
  const alarm = await until(async () => {
    const s = (await api("/api/state")).body;
    meanwhile.push({ stage: s?.mission?.stage, inside: s?.prediction?.uncontrolled ? inRing(got?.geometry?.coordinates?.[0] ?? [], [s.prediction.uncontrolled.lon_deg, s.prediction.uncontrolled.lat_deg]) : null });
    return (await page.locator('[data-testid="map-keep-out-alarm"]').isVisible()) ? text(page, "map-keep-out-alarm") : "";
  }, (t) => /Test field/.test(t), 15000);
  const whereNote = `; the predicted uncontrolled landing in the zone at ${meanwhile.filter((a) => a.inside).length} of ${meanwhile.length} polls over ${((Date.now() - since) / 1000).toFixed(1)} s, outside at ${meanwhile.filter((a) => a.inside === false).length}, stage at the end ${meanwhile.at(-1)?.stage}`;
  const logged = ((await api("/api/events")).body?.events ?? []).some((e) => e.level === "warning" && /inside keep-out zone 'Test field'/.test(e.text));
  const onPage = (await page.locator('[data-testid="event-item"]').allTextContents()).some((t) => /inside keep-out zone 'Test field'/.test(t));
  check("zones: the landing predicted in the drawn zone raises the alarm on the map and in the log (station and page)", /Test field/.test(alarm) && logged && onPage, `map "${alarm}"; station log ${logged}; page log ${onPage}${whereNote}`);
  await page.screenshot({ path: join(out, "zones-drawn.png") });

  // ---- drag one corner, add one at a midpoint and drag it out, delete one by a right-click
  await tb("zones-edit").click();
  await until(() => bar.getAttribute("data-editing"), (e) => e === "true", 3000);
  const drawn = corners(got);
  // Leaflet drags a corner by the mouse's travel from where it was pressed: the corner should
  // end 40 px right and 30 px down of where it was (to its marker's whole pixel).
  const dragged = await aim(page, drawn[2]);
  await drag(page, dragged.px, { x: dragged.px.x + 40, y: dragged.px.y + 30 });
  const draggedTo = positionAt(dragged.view, { x: dragged.exact.x + 40, y: dragged.exact.y + 30 });
  // The handle halfway along the first edge becomes a corner when clicked; then it is dragged out.
  const v2 = await viewOf(page);
  const mid = { x: (pixelOf(v2, drawn[0]).x + pixelOf(v2, drawn[1]).x) / 2, y: (pixelOf(v2, drawn[0]).y + pixelOf(v2, drawn[1]).y) / 2 };
  await page.mouse.click(whole(mid).x, whole(mid).y);
  await sleep(200);
  await drag(page, whole(mid), { x: whole(mid).x, y: whole(mid).y - 30 });
  const midTo = positionAt(v2, { x: mid.x, y: mid.y - 30 });
  const deleted = await aim(page, drawn[3]);
  await page.mouse.click(deleted.px.x, deleted.px.y, { button: "right" });
  await sleep(100);
  await tb("zones-save").click();
  await until(() => bar.getAttribute("data-editing"), (e) => e === "false", 5000);
  const moved = corners(feature((await api("/api/keep-out")).body, "Test field"));
  const movedWanted = [wanted[0], midTo, wanted[1], draggedTo];
  const px = drawn.map((p) => pixelOf(v2, p));
  const err2 = worstM(moved, movedWanted);
  check("zones: a corner dragged, one added at a midpoint and dragged out, one deleted by a right-click: saved so, the others unchanged", err2 <= tol,
    `${moved.length} corners (4 wanted) at ${JSON.stringify(moved.map((p) => whole(pixelOf(v2, p))))} px (drawn at ${JSON.stringify(px.map(whole))}), within ${err2.toFixed(2)} m of where they should be; the dragged one moved ${distanceM(corners(got)[2] ?? u, moved[3] ?? u).toFixed(0)} m`);

  // ---- a refused edit is shown and kept
  await tb("zones-edit").click();
  await until(() => bar.getAttribute("data-editing"), (e) => e === "true", 3000);
  // Inside the zone (convex): the mean of its corners.
  const inside = moved.map((p) => pixelOf(v2, p)).reduce((a, p) => ({ x: a.x + p.x / moved.length, y: a.y + p.y / moved.length }), { x: 0, y: 0 });
  await page.mouse.click(inside.x, inside.y);
  const selected = await until(() => tb("zones-name").inputValue(), (n) => n === "Test field", 3000);
  const long = "Long ".repeat(17); // 85 characters: the station takes at most 80
  await tb("zones-name").fill(long);
  await tb("zones-save").click();
  const serverSaid = await until(() => tb("zones-error").isVisible().then((s) => (s ? tb("zones-error").innerText() : "")), (t) => t !== "", 5000);
  const kept = (await bar.getAttribute("data-editing")) === "true" && (await tb("zones-name").inputValue()) === long;
  const unchanged = feature((await api("/api/keep-out")).body, "Test field") !== undefined;
  check("zones: a name the station refuses is shown with its reason, the edit stays on the map, the zones in force are unchanged",
    /at most 80 characters/.test(serverSaid) && kept && unchanged, `"${serverSaid}"; still editing with the name: ${kept}; in force unchanged: ${unchanged}`);
  await page.screenshot({ path: join(out, "zones-refused.png") });
  await tb("zones-name").fill("");
  await tb("zones-save").click();
  const pageSaid = await until(() => tb("zones-error").innerText(), (t) => /needs a name/.test(t), 3000);
  check("zones: a zone left unnamed is refused by the page before sending, the edit kept", /needs a name/.test(pageSaid) && (await bar.getAttribute("data-editing")) === "true", `"${pageSaid}"`);

  // ---- another operator's change: announced during the edit, drawn after it
  const theirs = (await api("/api/keep-out")).body;
  const farAway = [[0, 0], [0.001, 0], [0.001, 0.001], [0, 0]].map(([a, b]) => [corners(got)[0].lon_deg + 0.02 + a, corners(got)[0].lat_deg + 0.02 + b]);
  const other = { type: "Feature", properties: { name: "Other field" }, geometry: { type: "Polygon", coordinates: [farAway] } };
  const putOther = await api("/api/keep-out", OPERATOR, { method: "PUT", body: JSON.stringify({ type: "FeatureCollection", features: [...theirs.zones.features, other] }) });
  const note = await until(() => tb("zones-note").isVisible().then((s) => (s ? tb("zones-note").innerText() : "")), (t) => t !== "", 5000);
  const drawnDuring = await page.locator("path.map-keep-out").count();
  check("zones: another operator's change during an edit is announced, not drawn over the edit", putOther.status === 200 && /changed the zones/.test(note) && drawnDuring === zonesAtStart.areas + 1, `"${note}"; ${drawnDuring} zones drawn`);

  // ---- delete the zone and save: the edit replaces every zone
  await tb("zones-delete").click();
  await tb("zones-save").click();
  await until(() => bar.getAttribute("data-editing"), (e) => e === "false", 5000);
  const after = (await api("/api/keep-out")).body;
  const fileAfter = JSON.parse(await readFile(copy.zones, "utf8"));
  const drawnAfter = await until(() => page.locator("path.map-keep-out").count(), (n) => n === zonesAtStart.areas, 5000);
  check("zones: a zone deleted on the map is gone from the station, the file and the map (the save replaced the other operator's zones with this edit)",
    !feature(after, "Test field") && !feature(after, "Other field") && !feature(fileAfter, "Test field") && after.areas === zonesAtStart.areas && drawnAfter === zonesAtStart.areas,
    `${after.areas} areas in force, ${fileAfter.features?.length} in the file, ${drawnAfter} drawn`);
  const putAgain = await api("/api/keep-out", OPERATOR, { method: "PUT", body: JSON.stringify({ type: "FeatureCollection", features: [...after.zones.features, other] }) });
  const follows = await until(() => page.locator("path.map-keep-out").count(), (n) => n === zonesAtStart.areas + 1, 5000);
  check("zones: out of editing, the map follows another operator's change", putAgain.status === 200 && follows === zonesAtStart.areas + 1, `${follows} zones drawn`);

  // ---- Cancel forgets an edit: a zone drawn, then cancelled
  const beforeCancel = (await api("/api/keep-out")).body;
  await tb("zones-edit").click();
  await until(() => bar.getAttribute("data-editing"), (e) => e === "true", 3000);
  await tb("zones-draw").click();
  // On bare map: a click on another zone's corner handle, a marker or a control adds no corner.
  const shape = [[0, -60], [60, 40], [-60, 40], [0, -60]];
  const box = (await viewOf(page)).box;
  const tc = (await clearSpot(page, shape, { left: box.x + 80, right: box.x + box.width - 80, top: top + 70, bottom: barTop - 50 })) ?? { x: cx, y: cy };
  const tri = shape.map(([dx, dy]) => ({ x: Math.round(tc.x + dx), y: Math.round(tc.y + dy) }));
  for (const p of tri) {
    await page.mouse.click(p.x, p.y);
    await sleep(80);
  }
  const drawnEditing = await until(() => page.locator("path.map-keep-out").count(), (n) => n === zonesAtStart.areas + 2, 3000);
  await tb("zones-cancel").click();
  const drawnCancelled = await until(() => page.locator("path.map-keep-out").count(), (n) => n === zonesAtStart.areas + 1, 3000);
  const afterCancel = (await api("/api/keep-out")).body;
  check("zones: Cancel forgets the edit (a zone drawn is gone) and sends nothing",
    drawnEditing === zonesAtStart.areas + 2 && drawnCancelled === zonesAtStart.areas + 1 && JSON.stringify(afterCancel.zones) === JSON.stringify(beforeCancel.zones),
    `${drawnEditing} zones drawn while editing, ${drawnCancelled} after Cancel; in force ${afterCancel.areas}`);
  await page.screenshot({ path: join(out, "zones-final.png") });
  await ctx.close();
}

await runFlights(flight, ["ServerMessage:hello", "ServerMessage:state", "ServerMessage:keep_out", "StateMsg", "KeepOutMsg", "KeepOutBody", "ErrorBody", "EventsBody"]);
