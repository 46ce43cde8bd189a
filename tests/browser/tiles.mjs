#!/usr/bin/env node
// Offline maps in a real browser: the station serves a tile pack the test makes itself (an MBTiles
// file of flat tiles in a colour no real map has, written by make_tile_pack.py), and the live map
// and the recovery page's map both draw those tiles; a corrupt pack leaves both on their fallback
// and says why, naming the file. The station runs `rehearsal` with its simulated drone, so the
// recovery page has a predicted landing to show on its map.
//
// Usage: node tests/browser/tiles.mjs [path/to/stx]   (default target/release/stx)

import { spawnSync } from "node:child_process";
import { mkdtemp, readFile, writeFile } from "node:fs/promises";
import { tmpdir } from "node:os";
import { join } from "node:path";
import { OPERATOR, VIEWER, root, out, speed, check, newContext, startStation, stopChildren, until, text, attr, watchErrors, runFlights } from "./harness.mjs";

const PACK_RGB = [0x3c, 0xb4, 0xa0];
const dir = await mkdtemp(join(tmpdir(), "stx-browser-tiles-"));

/** The shipped station config with `tile_pack` set to `pack`, written next to it. */
async function configWithPack(name, pack) {
  const toml = await readFile(join(root, "config/station.toml"), "utf8");
  const file = join(dir, `${name}.toml`);
  await writeFile(file, `tile_pack = ${JSON.stringify(pack)}\n${toml}`);
  return file;
}

/** The colour of the middle pixel of every pack tile the page shows (loaded <img> from /tiles/). */
const tileColours = (page, selector) => page.evaluate((sel) => {
  const c = document.createElement("canvas");
  c.width = c.height = 1;
  const g = c.getContext("2d", { willReadFrequently: true });
  return Array.from(document.querySelectorAll(`${sel} img.leaflet-tile`))
    .filter((i) => i.complete && i.naturalWidth > 0 && new URL(i.src).pathname.startsWith("/tiles/"))
    .map((i) => {
      g.clearRect(0, 0, 1, 1);
      g.drawImage(i, 128, 128, 1, 1, 0, 0, 1, 1);
      return Array.from(g.getImageData(0, 0, 1, 1).data.slice(0, 3));
    });
}, selector);
const isPack = (rgb) => rgb.every((v, i) => Math.abs(v - PACK_RGB[i]) <= 2);

async function withPack() {
  const pack = join(dir, "field.mbtiles");
  const made = spawnSync("python3", [join(root, "tests/browser/make_tile_pack.py"), pack, "38.5333", "-7.8889", "4000", "10", "16"], { encoding: "utf8" });
  if (made.status !== 0) throw new Error(`make_tile_pack.py failed: ${made.stderr}`);
  const { base } = await startStation(["--config", await configWithPack("pack", pack), "--sim", "--sim-scenario", "rehearsal", "--sim-speed", String(speed), "--link", "udpin:127.0.0.1:0"]);
  console.log(`tile pack of ${made.stdout.trim()} tiles; station at ${base}`);
  const ctx = await newContext("tiles", { viewport: { width: 1440, height: 900 } });
  const page = await ctx.newPage();
  watchErrors(page, "tiles live");
  await page.goto(`${base}/?token=${OPERATOR}`);
  await until(() => attr(page, "map-tiles-status", "data-state"), (s) => s === "ok", 20000);
  const colours = await until(() => tileColours(page, '[data-testid="map"]'), (c) => c.length > 0 && c.every(isPack), 20000);
  check("offline map: the live map draws the station's tile pack (every /tiles/ tile the pack's colour)",
    (await attr(page, "map-tiles-status", "data-state")) === "ok" && colours.length > 0 && colours.every(isPack),
    `badge "${await text(page, "map-tiles-status")}", ${colours.length} tiles, first ${JSON.stringify(colours[0])}`);
  await page.screenshot({ path: join(out, "tiles-live.png") });

  // The recovery page, on a phone: its map on the same pack, with the point to drive to.
  const phone = await newContext("tiles phone", { viewport: { width: 390, height: 844 }, deviceScaleFactor: 2, isMobile: true, hasTouch: true });
  const rec = await phone.newPage();
  watchErrors(rec, "tiles recovery");
  await rec.goto(`${base}/recovery.html?token=${VIEWER}`);
  await until(() => rec.locator('[data-testid="rec-map-point"]').count(), (n) => n === 1, 30000);
  await rec.locator('[data-testid="rec-map"]').scrollIntoViewIfNeeded();
  const recColours = await until(() => tileColours(rec, '[data-testid="rec-map"]'), (c) => c.length > 0 && c.every(isPack), 20000);
  const marker = await rec.locator('[data-testid="rec-map-point"]').boundingBox();
  const mapBox = await rec.locator('[data-testid="rec-map"]').boundingBox();
  const inside = marker !== null && mapBox !== null && marker.x >= mapBox.x && marker.x + marker.width <= mapBox.x + mapBox.width && marker.y >= mapBox.y && marker.y + marker.height <= mapBox.y + mapBox.height;
  check("offline map: the recovery page's map draws the pack, with the point to drive to in view",
    recColours.length > 0 && recColours.every(isPack) && inside && (await attr(rec, "rec-map-tiles", "data-state")) === "ok",
    `${recColours.length} tiles, point ${inside ? "inside" : "outside"} the map, badge "${await text(rec, "rec-map-tiles")}"`);
  await rec.screenshot({ path: join(out, "tiles-recovery.png"), fullPage: true });
  await phone.close();
  await ctx.close();
  stopChildren();
}

async function corruptPack() {
  const pack = join(dir, "broken.mbtiles");
  await writeFile(pack, "this is not an SQLite file, nor any map");
  const { base } = await startStation(["--config", await configWithPack("broken", pack), "--sim", "--sim-scenario", "rehearsal", "--sim-speed", String(speed), "--link", "udpin:127.0.0.1:0"]);
  const ctx = await newContext("broken pack", { viewport: { width: 1440, height: 900 } });
  const page = await ctx.newPage();
  watchErrors(page, "broken pack live");
  await page.goto(`${base}/?token=${OPERATOR}`);
  await until(() => attr(page, "map-tiles-status", "data-state"), (s) => s === "pack-failed", 15000);
  const note = await text(page, "map-tiles-error").catch(() => "");
  check("offline map: a corrupt pack leaves the live map on its metric grid and says why, naming the file",
    (await attr(page, "map-tiles-status", "data-state")) === "pack-failed" && note.includes("broken.mbtiles") && (await page.locator('[data-testid="map"] .map-grid, [data-testid="map"] path').count()) > 0,
    `badge "${await text(page, "map-tiles-status")}", note "${note}"`);
  const rec = await ctx.newPage();
  watchErrors(rec, "broken pack recovery");
  await rec.goto(`${base}/recovery.html?token=${VIEWER}`);
  await until(() => rec.locator('[data-testid="rec-map-pack-error"]').isVisible().catch(() => false), (v) => v, 15000);
  const recNote = await text(rec, "rec-map-pack-error").catch(() => "");
  check("offline map: the recovery page says the same, and its map still places the points on a scale",
    recNote.includes("broken.mbtiles") && (await attr(rec, "rec-map-tiles", "data-state")) === "pack-failed",
    `note "${recNote}", badge "${await text(rec, "rec-map-tiles").catch(() => "")}"`);
  await ctx.close();
  stopChildren();
}

await runFlights(async () => {
  await withPack();
  await corruptPack();
}, ["ServerMessage:hello", "ServerMessage:state", "Session", "StateMsg"]);
