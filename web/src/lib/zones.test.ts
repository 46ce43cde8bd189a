import { describe, expect, it } from "vitest";
import { collectionOf, newZoneName, withZoneNames, openRing, polygonsOfLatLngs, ringProblem, zonesOf, zonesProblem } from "./zones";
import type { Ring, Zone } from "./types";

const pond = {
  type: "Feature",
  properties: { name: "Pond", kind: "water", note: "fenced" },
  geometry: { type: "Polygon", coordinates: [[[-7.89, 38.53], [-7.88, 38.53], [-7.88, 38.54], [-7.89, 38.53]]] },
};
const woods = {
  type: "Feature",
  properties: { name: "Woods" },
  geometry: {
    type: "MultiPolygon",
    coordinates: [
      [[[0, 0], [1, 0], [1, 1], [0, 0]]],
      [[[2, 0], [3, 0], [3, 1], [2, 0]], [[2.5, 0.1], [2.9, 0.1], [2.9, 0.5], [2.5, 0.1]]],
    ],
  },
};

describe("keep-out zones for editing", () => {
  it("reads named zones with their kind and other properties, rings open and [lat, lon]", () => {
    const zones = zonesOf({ type: "FeatureCollection", features: [pond, woods, { type: "Feature", properties: {}, geometry: { type: "Point", coordinates: [0, 0] } }] });
    expect(zones.map((z) => [z.name, z.kind, z.polygons.length])).toEqual([["Pond", "water", 1], ["Woods", "", 2]]);
    expect(zones[0]?.extra).toEqual({ note: "fenced" });
    expect(zones[0]?.polygons[0]?.[0]).toEqual([[38.53, -7.89], [38.53, -7.88], [38.54, -7.88]]);
    expect(zones[1]?.polygons[1]?.length).toBe(2);
  });

  it("writes back what it read: a round trip through the editor changes nothing", () => {
    const fc = { type: "FeatureCollection", features: [pond, woods] };
    expect(collectionOf(zonesOf(fc))).toEqual(fc);
  });

  it("writes a new zone as a closed Polygon with its name trimmed and degrees to 1e-7", () => {
    const z: Zone = { name: "  Test field ", kind: "", extra: {}, polygons: [[[[38.123456789, -7.5], [38.2, -7.5], [38.2, -7.4]]]] };
    expect(collectionOf([z]).features[0]).toEqual({
      type: "Feature",
      properties: { name: "Test field" },
      geometry: { type: "Polygon", coordinates: [[[-7.5, 38.1234568], [-7.5, 38.2], [-7.4, 38.2], [-7.5, 38.1234568]]] },
    });
  });

  it("takes Leaflet's latlngs of a ring, a polygon with a hole and a multi-polygon alike", () => {
    const ll = (lat: number, lng: number) => ({ lat, lng });
    const ring = [ll(0, 0), ll(0, 1), ll(1, 1)];
    const hole = [ll(0.2, 0.5), ll(0.2, 0.8), ll(0.4, 0.8)];
    expect(polygonsOfLatLngs(ring)).toEqual([[[[0, 0], [0, 1], [1, 1]]]]);
    expect(polygonsOfLatLngs([ring, hole])).toEqual([[[[0, 0], [0, 1], [1, 1]], [[0.2, 0.5], [0.2, 0.8], [0.4, 0.8]]]]);
    expect(polygonsOfLatLngs([[ring], [hole]]).length).toBe(2);
    expect(polygonsOfLatLngs([])).toEqual([]);
  });

  it("drops repeated points and the closing point", () => {
    expect(openRing([[0, 0], [0, 0], [0, 1], [1, 1], [0, 0]])).toEqual([[0, 0], [0, 1], [1, 1]]);
  });

  it("refuses rings that bound no area: too few points, crossing themselves, on one line, off the globe", () => {
    const square: Ring = [[0, 0], [0, 1], [1, 1], [1, 0]];
    expect(ringProblem(square)).toBeNull();
    expect(ringProblem([[0, 0], [0, 1]])).toMatch(/2 points: an area needs at least 3/);
    // A bow tie: the square with two corners swapped.
    expect(ringProblem([[0, 0], [1, 1], [0, 1], [1, 0]])).toBe("crosses itself");
    // An edge that runs back along another touches it.
    expect(ringProblem([[0, 0], [0, 2], [0, 1], [1, 1]])).toBe("crosses itself");
    expect(ringProblem([[0, 0], [0, 1], [0, 2]])).toMatch(/no area/);
    expect(ringProblem([[0, 0], [0, 1], [95, 1]])).toMatch(/off the globe/);
    expect(ringProblem([[0, 0], [0, Number.NaN], [1, 1]])).toMatch(/off the globe/);
  });

  it("names the zone and the ring at fault, and wants every zone named", () => {
    const ok: Zone = { name: "A", kind: "", extra: {}, polygons: [[[[0, 0], [0, 1], [1, 1]]]] };
    expect(zonesProblem([ok])).toBeNull();
    expect(zonesProblem([ok, { ...ok, name: "  " }])).toBe("zone 2 needs a name");
    expect(zonesProblem([{ ...ok, polygons: [[[[0, 0], [0, 1], [1, 1]], [[0, 0], [1, 1]]]] }])).toBe('zone "A": its hole 1 has 2 points: an area needs at least 3');
    expect(zonesProblem([{ ...ok, polygons: [] }])).toBe('zone "A" has no area');
  });

  it("names the zone the station's refusal counts by its place in the edit", () => {
    const z = (name: string): Zone => ({ name, kind: "", extra: {}, polygons: [] });
    expect(withZoneNames("keep-out feature 1: names are at most 80 characters", [z("Pond"), z(" Field ")])).toBe('keep-out feature 1 ("Field"): names are at most 80 characters');
    expect(withZoneNames("keep-out feature 7: ring 0 is not closed", [z("Pond")])).toBe("keep-out feature 7: ring 0 is not closed");
  });

  it("gives a new zone a name no zone has", () => {
    expect(newZoneName([])).toBe("Zone 1");
    expect(newZoneName(["Pond", "zone 1", "Zone 3"])).toBe("Zone 2");
  });
});
