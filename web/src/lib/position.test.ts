import { describe, expect, it } from "vitest";
import { parsePosition, positionUnavailable } from "./position";

const ok = (t: string) => {
  const r = parsePosition(t);
  if (!r.ok) throw new Error(`${t}: ${r.error}`);
  return [r.value.lat_deg, r.value.lon_deg];
};

describe("parsePosition", () => {
  it("reads the forms people paste", () => {
    expect(ok("38.5333, -7.8889")).toEqual([38.5333, -7.8889]);
    expect(ok("38.5333,-7.8889")).toEqual([38.5333, -7.8889]);
    expect(ok("  38.5333 -7.8889 ")).toEqual([38.5333, -7.8889]);
    expect(ok("38,5333 -7,8889")).toEqual([38.5333, -7.8889]);
    expect(ok("38,5333; -7,8889")).toEqual([38.5333, -7.8889]);
    expect(ok("38.53000° N, 7.88890° W")).toEqual([38.53, -7.8889]);
    expect(ok("38.53 N 7.8889 W")).toEqual([38.53, -7.8889]);
    expect(ok("38.53S, 7.8889E")).toEqual([-38.53, 7.8889]);
    expect(ok("−33.9, 18.4")).toEqual([-33.9, 18.4]);
  });
  it("reads geo: URIs and map links", () => {
    expect(ok("geo:38.534672,-7.888292")).toEqual([38.534672, -7.888292]);
    expect(ok("geo:38.534672,-7.888292;u=5")).toEqual([38.534672, -7.888292]);
    expect(ok("https://www.google.com/maps/@38.5347,-7.8883,17z")).toEqual([38.5347, -7.8883]);
    expect(ok("https://maps.google.com/?q=38.5347,-7.8883")).toEqual([38.5347, -7.8883]);
    expect(ok("https://www.openstreetmap.org/?mlat=38.534672&mlon=-7.888292#map=17/38.534672/-7.888292")).toEqual([38.534672, -7.888292]);
    expect(ok("https://www.openstreetmap.org/#map=17/38.5/-7.9")).toEqual([38.5, -7.9]);
  });
  it("refuses what is not a position, saying what is expected", () => {
    for (const [t, msg] of [
      ["", /type or paste/],
      ["38.5", /two coordinates/],
      ["abc, def", /latitude "abc"/],
      ["38.5, 7.8 N", /longitude/],
      ["95, 7", /−90…90/],
      ["38, 190", /−180…180/],
      ["-38 N, 7 E", /latitude/],
      ["https://example.com/place", /no coordinates/],
    ] as const) {
      const r = parsePosition(t);
      expect(r.ok, t).toBe(false);
      if (!r.ok) expect(r.error).toMatch(msg);
    }
  });
});

describe("positionUnavailable", () => {
  const g = { secure: true, hasGeolocation: true, errorCode: null, origin: "http://10.0.0.5:8080" };
  it("null while the browser may give a position", () => {
    expect(positionUnavailable(g)).toBeNull();
  });
  it("names plain HTTP and the address to open instead", () => {
    expect(positionUnavailable({ ...g, secure: false })).toMatch(/plain HTTP \(http:\/\/10\.0\.0\.5:8080\).*https:\/\/10\.0\.0\.5:8080\/recovery\.html/);
  });
  it("says what to do for each refusal", () => {
    expect(positionUnavailable({ ...g, errorCode: 1 })).toMatch(/permission is denied/);
    expect(positionUnavailable({ ...g, errorCode: 2 })).toMatch(/cannot find its position/);
    expect(positionUnavailable({ ...g, errorCode: 3 })).toMatch(/too long/);
    expect(positionUnavailable({ ...g, hasGeolocation: false })).toMatch(/no geolocation/);
  });
});
