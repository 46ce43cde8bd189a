import { describe, expect, it } from "vitest";
import { judgeStaleness, linkStale, messageAges } from "./staleness";
import type { Link } from "./types";

const link = (over: Partial<Link> = {}): Link => ({
  connected: true, stale: false, age_s: 0.2, rate_hz: 30, loss_percent: 0.4, crc_errors: 0, parse_errors: 0, signature_errors: 0,
  ages_s: { HEARTBEAT: 0.4, GPS_RAW_INT: 0.2 }, radios: [], ...over,
});
const T = 1_000_000;

describe("judgeStaleness", () => {
  it("fresh when the station says so and the state is recent", () => {
    const v = judgeStaleness({ socketOpen: true, link: link(), receivedAtMs: T, nowMs: T + 300 });
    expect(v).toMatchObject({ freshness: "fresh", stale: false });
    expect(v.age_s).toBeCloseTo(0.5);
  });
  it("stale when the station flags the link stale", () => {
    const v = judgeStaleness({ socketOpen: true, link: link({ stale: true }), receivedAtMs: T, nowMs: T });
    expect(v.stale).toBe(true);
    expect(v.reasons.join()).toContain("station reports the link stale");
  });
  it("stale when the last message is old even if the flag says fresh", () => {
    const v = judgeStaleness({ socketOpen: true, link: link({ age_s: 2.5 }), receivedAtMs: T, nowMs: T });
    expect(v.freshness).toBe("stale");
  });
  it("ages grow while nothing arrives: the page notices a silent station by itself", () => {
    expect(judgeStaleness({ socketOpen: true, link: link(), receivedAtMs: T, nowMs: T + 1500 }).stale).toBe(false);
    const v = judgeStaleness({ socketOpen: true, link: link(), receivedAtMs: T, nowMs: T + 2500 });
    expect(v.stale).toBe(true);
    expect(v.age_s).toBeCloseTo(2.7);
    expect(v.reasons.join()).toContain("no update from the station");
  });
  it("disconnected socket wins over everything", () => {
    expect(judgeStaleness({ socketOpen: false, link: link(), receivedAtMs: T, nowMs: T }).freshness).toBe("disconnected");
    expect(judgeStaleness({ socketOpen: false, link: null, receivedAtMs: null, nowMs: T }).freshness).toBe("disconnected");
  });
  it("no data yet is stale, never current", () => {
    expect(judgeStaleness({ socketOpen: true, link: null, receivedAtMs: null, nowMs: T })).toMatchObject({ freshness: "no_data", stale: true });
  });
  it("unknown age is not taken as fresh", () => {
    expect(judgeStaleness({ socketOpen: true, link: link({ age_s: null }), receivedAtMs: T, nowMs: T }).stale).toBe(true);
  });
});

describe("messageAges", () => {
  it("flags old messages with per-type limits, oldest first, grown by the time since arrival", () => {
    const ages = messageAges(link({ ages_s: { HEARTBEAT: 2.5, GPS_RAW_INT: 1.5, ATTITUDE: 0.1 } }), T, T + 600);
    // HEARTBEAT comes at 1 Hz: 3.1 s is within its 3.5 s; GPS at 2.1 s is past the 2 s limit.
    expect(ages.map((a) => [a.name, a.old])).toEqual([["HEARTBEAT", false], ["GPS_RAW_INT", true], ["ATTITUDE", false]]);
    expect(ages[0]!.age_s).toBeCloseTo(3.1);
  });
  it("one-shot answers (PARAM_VALUE, MISSION_ACK) are never OLD and come after the streams", () => {
    const ages = messageAges(link({ ages_s: { PARAM_VALUE: 40, MISSION_ACK: 95, ATTITUDE: 2.5 } }), T, T);
    expect(ages.map((a) => [a.name, a.old, a.limit_s])).toEqual([["ATTITUDE", true, 2], ["MISSION_ACK", false, null], ["PARAM_VALUE", false, null]]);
  });
});

describe("linkStale", () => {
  it("a sample is stale when the station says so, the link is down, or its age is over the limit or unknown", () => {
    expect(linkStale(link({}))).toBe(false);
    expect(linkStale(link({ stale: true }))).toBe(true);
    expect(linkStale(link({ connected: false }))).toBe(true);
    expect(linkStale(link({ age_s: 2.5 }))).toBe(true);
    expect(linkStale(link({ age_s: null }))).toBe(true);
  });
});
