// Small pure helpers: backoff, token handling, time series, wind interpolation, recovery point,
// plan body, input validation.
import { describe, expect, it } from "vitest";
import { clockText } from "../ui/replayBar";
import { backoffMs, BACKOFF_MAX_MS, BACKOFF_MIN_MS } from "./backoff";
import { resolveToken, searchWithoutToken, TOKEN_KEY, withToken } from "./token";
import { breakWraps, MAX_GAP_S, Series, staleSpans } from "./series";
import { directionPieces, forecastAt, MeasuredProfile } from "./wind";
import { isLanded, landingBadge, phaseLabel, recoveryPoint } from "./recovery";
import { flightPathSummary } from "./flightPath";
import { planBody } from "./plan";
import { replicaAlarm } from "./replica";
import { all, parseLat, parseNumber } from "./inputs";
import { decodeMessage } from "./parse";
import type { State } from "./types";

describe("backoff", () => {
  it("doubles from the minimum to the cap, jitter ±20 %", () => {
    const mid = () => 0.5;
    expect(backoffMs(0, mid)).toBe(BACKOFF_MIN_MS);
    expect(backoffMs(1, mid)).toBe(2 * BACKOFF_MIN_MS);
    expect(backoffMs(50, mid)).toBe(BACKOFF_MAX_MS);
    expect(backoffMs(0, () => 0)).toBe(0.8 * BACKOFF_MIN_MS);
    expect(backoffMs(0, () => 0.999999)).toBeLessThanOrEqual(1.2 * BACKOFF_MIN_MS);
  });
});

describe("token", () => {
  const store = () => {
    const m = new Map<string, string>();
    return { getItem: (k: string) => m.get(k) ?? null, setItem: (k: string, v: string) => void m.set(k, v), m };
  };
  it("takes ?token=, stores it, and finds it again after a reload without it", () => {
    const s = store();
    expect(resolveToken("?token=op&x=1", s)).toBe("op");
    expect(s.m.get(TOKEN_KEY)).toBe("op");
    expect(resolveToken("", s)).toBe("op");
    expect(resolveToken("", store())).toBeNull();
  });
  it("strips the token from the address and adds it to socket/KML URLs", () => {
    expect(searchWithoutToken("?token=op&x=1")).toBe("?x=1");
    expect(searchWithoutToken("?token=op")).toBe("");
    expect(withToken("/kml", "a b")).toBe("/kml?token=a%20b");
    expect(withToken("/tiles/{z}/{x}/{y}.png?v=2", "op")).toBe("/tiles/{z}/{x}/{y}.png?v=2&token=op");
    expect(withToken("/kml", null)).toBe("/kml");
  });
});

describe("Series", () => {
  it("keeps a 10-minute window and drops repeats (history overlapping live data)", () => {
    const s = new Series(["a"], 600);
    for (let t = 0; t <= 900; t += 1) s.push(t, [t]);
    expect(s.t[0]).toBe(300);
    expect(s.t[s.t.length - 1]).toBe(900);
    expect(s.push(850, [1])).toBe(false);
    expect(s.push(900, [1])).toBe(false);
    expect(s.cols[0]).toHaveLength(s.t.length);
  });
  it("starts over when the mission clock restarts", () => {
    const s = new Series(["a"], 600);
    s.push(5000, [1]);
    expect(s.push(3, [2])).toBe(true);
    expect(s.t).toEqual([3]);
  });
  // Regression: while the link was stale the plots drew the last values on as a flat live line.
  it("stores stale samples as gaps and flags them", () => {
    const s = new Series(["a", "b"], 600);
    s.push(1, [1, 2]);
    s.push(1.25, [1, 2], true);
    s.push(1.5, [1, 2], true);
    s.push(1.75, [3, 4]);
    expect(s.cols[0]).toEqual([1, null, null, 3]);
    expect(s.cols[1]).toEqual([2, null, null, 4]);
    expect(s.kinds).toEqual(["live", "stale", "stale", "live"]);
    expect(staleSpans(s.t, s.kinds)).toEqual([[1, 1.75]]);
  });
  it("breaks the line over a silence (socket stalled) instead of joining across it", () => {
    const s = new Series(["a"], 600);
    s.push(10, [1]);
    s.push(10 + MAX_GAP_S, [1]); // a step of exactly the limit is still a line
    s.push(30, [1]);
    expect(s.cols[0]).toEqual([1, 1, null, 1]);
    expect(s.t[2]).toBeCloseTo((13 + 30) / 2);
    expect(staleSpans(s.t, s.kinds)).toEqual([[13, 30]]);
  });
  it("a stale run still going ends at the last sample", () => {
    expect(staleSpans([1, 2, 3], ["live", "stale", "stale"])).toEqual([[1, 3]]);
    expect(staleSpans([1, 2], ["stale", "live"])).toEqual([[1, 2]]);
    expect(staleSpans([], [])).toEqual([]);
  });
  it("breaks heading lines at the 360 → 0 wrap", () => {
    expect(breakWraps([350, 355, 2, 8, null, 10, -10])).toEqual([350, 355, null, 8, null, 10, null]);
  });
});

describe("forecastAt", () => {
  const p = [
    { alt_msl_m: 300, speed_mps: 2, from_deg: 350 },
    { alt_msl_m: 1300, speed_mps: 6, from_deg: 30 },
  ];
  it("interpolates speed linearly and direction the short way round", () => {
    const w = forecastAt(p, 800)!;
    expect(w.speed_mps).toBeCloseTo(4);
    expect(w.from_deg).toBeCloseTo(10);
  });
  it("holds the end values outside the profile", () => {
    expect(forecastAt(p, 0)).toEqual({ speed_mps: 2, from_deg: 350 });
    expect(forecastAt(p, 5000)).toEqual({ speed_mps: 6, from_deg: 30 });
    expect(forecastAt([], 100)).toBeNull();
  });
});

describe("wind profiles (speed and direction)", () => {
  it("the measured profile averages per level, directions as vectors", () => {
    const m = new MeasuredProfile(25);
    m.add(1000, 3, 350);
    m.add(1005, 5, 10);
    m.add(500, 2, 270);
    m.add(Number.NaN, 2, 270);
    const pts = m.points();
    expect(pts.map((p) => p.alt_msl_m)).toEqual([500, 1000]);
    expect(pts[1]!.speed_mps).toBeCloseTo(4);
    expect(Math.min(pts[1]!.from_deg, 360 - pts[1]!.from_deg)).toBeLessThan(1e-9);
    expect(pts[0]!.from_deg).toBeCloseTo(270);
  });
  it("a direction profile is cut where it crosses north, and at missing directions", () => {
    const pieces = directionPieces([
      { alt_msl_m: 0, from_deg: 340 },
      { alt_msl_m: 100, from_deg: 355 },
      { alt_msl_m: 200, from_deg: 5 },
      { alt_msl_m: 300, from_deg: null },
      { alt_msl_m: 400, from_deg: -90 },
    ]);
    expect(pieces.map((p) => p.map((q) => q.from_deg))).toEqual([[340, 355], [5], [270]]);
  });
});

describe("recoveryPoint", () => {
  const base = (over: Record<string, unknown>): State => {
    const d = decodeMessage(JSON.stringify({
      type: "state", time_s: 1, link: { connected: true, stale: false, age_s: 0.1, ages_s: {} },
      vehicle: { mode: "spiral_landing", stage: "parafoil" },
      estimate: { lat_deg: 38.6, lon_deg: -7.9, position_sigma_m: 2 },
      guidance: { mode: "spiral_landing" },
      prediction: { planned: { lat_deg: 38.5, lon_deg: -7.8, time_to_land_s: 100, semi_major_m: 10 }, uncontrolled: { lat_deg: 38.4, lon_deg: -7.7, time_to_land_s: 110, semi_major_m: 50 } },
      mission: { stage: "parafoil" }, ...over,
    }));
    if (!d.ok || d.msg.type !== "state") throw new Error("bad fixture");
    return d.msg;
  };
  it("guided: the planned prediction", () => {
    expect(recoveryPoint(base({}))).toMatchObject({ kind: "planned", lat_deg: 38.5 });
  });
  it("uncontrolled or manual: the uncontrolled prediction", () => {
    expect(recoveryPoint(base({ guidance: { mode: "uncontrolled" } }))).toMatchObject({ kind: "uncontrolled", lat_deg: 38.4 });
    expect(recoveryPoint(base({ guidance: { mode: "manual" } }))?.kind).toBe("uncontrolled");
  });
  it("landed: where the vehicle is", () => {
    const s = base({ mission: { stage: "landed" } });
    expect(isLanded(s)).toBe(true);
    expect(recoveryPoint(s)).toMatchObject({ kind: "actual", lat_deg: 38.6, lon_deg: -7.9 });
  });
  it("falls back to what exists, or null", () => {
    expect(recoveryPoint(base({ prediction: { planned: null, uncontrolled: { lat_deg: 1, lon_deg: 2 } } }))?.kind).toBe("uncontrolled");
    expect(recoveryPoint(base({ prediction: null }))).toBeNull();
  });

  it("landing badge: a live countdown under the parafoil", () => {
    expect(landingBadge(base({}), false, 0.2)).toEqual({ state: "live", text: "landing in 1 min 40 s" });
    expect(landingBadge(base({ guidance: { mode: "uncontrolled" } }), false, 0.2).text).toBe("landing in 1 min 50 s (uncontrolled)");
    expect(landingBadge(null, false, null).state).toBe("none");
  });
  // Regression: a stale link left "landing in N s" in the header as if it were current.
  it("landing badge: stale data say so and how old they are", () => {
    expect(landingBadge(base({}), true, 12)).toEqual({ state: "stale", text: "landing in 1 min 40 s as of 12 s ago — STALE" });
  });
  // Regression: "landing in 342 s" while the balloon climbed at 988 m.
  it("landing badge: no countdown on the pad or under the balloon, whatever the station predicted", () => {
    for (const stage of ["pre_launch", "ascent"]) {
      expect(landingBadge(base({ mission: { stage }, vehicle: { stage } }), false, 0.2)).toEqual({ state: "none", text: "landing —" });
    }
    // A silent link while climbing: still no countdown, but the badge says the data are old.
    expect(landingBadge(base({ mission: { stage: "ascent" }, vehicle: { stage: "ascent" } }), true, 12)).toEqual({ state: "stale", text: "landing — · data 12 s old — STALE" });
  });
  // Regression: "landing in 938 s" under the round chute beside the map's "unsteered landing in 9 min 43 s".
  it("landing badge: under the round chute, the map's unsteered landing counted down on the mission clock", () => {
    const path = {
      computed_s: 30, computed_mission_s: 600, stage: "round_chute", burst: null,
      deploy: { lat_deg: 38.5, lon_deg: -7.8, alt_msl_m: 1445, in_s: 200 },
      landing: { lat_deg: 38.51, lon_deg: -7.81, alt_msl_m: 245, in_s: 613 },
      round_chute_landing: { lat_deg: 38.52, lon_deg: -7.82, alt_msl_m: 245, in_s: 500 },
      reach_centre_lat_lon_deg: [38.51, -7.81], reach_radius_m: 2000, measured_bands: 3, measured_to_msl_m: 3000,
      burst_source: "drone", ascent_rate_source: "drone",
    };
    // 30 s of flight since the path was computed (at 20×, 1.5 s of the station's clock).
    const s = base({ mission: { stage: "round_chute" }, vehicle: { stage: "round_chute" }, mission_time_s: 630, flight_path: path });
    expect(landingBadge(s, false, 0.2)).toEqual({ state: "live", text: "landing in 9 min 43 s (unsteered)" });
    expect(s.flight_path && flightPathSummary(s.flight_path, s.mission_time_s)).toContain("unsteered landing in 9 min 43 s");
  });
  // Regression: four screens showed 1, 2, 3 and 10 m for one landing, each working it out itself.
  it("landed: the badge shows the station's one figure, the phase says landed", () => {
    const landing = { time_s: 1180.25, body: "drone", position: { lat_deg: 38.6, lon_deg: -7.9, alt_msl_m: 245 }, target: { lat_deg: 38.6, lon_deg: -7.9001, alt_msl_m: 245 }, miss_m: 2.34 };
    const s = base({ mission: { stage: "landed", landing }, guidance: { mode: "spiral_landing", phase: "flare", target: { lat_deg: 38.6, lon_deg: -7.9002 } } });
    const b = landingBadge(s, false, 0.1);
    expect(b.state).toBe("landed");
    expect(b.text).toBe("LANDED · drone 2.3 m from the target");
    expect(recoveryPoint(s)).toMatchObject({ kind: "actual", lat_deg: 38.6, lon_deg: -7.9 });
    expect(phaseLabel(s)).toBe("landed");
    expect(phaseLabel(base({ vehicle: { phase: "branch2" }, guidance: { phase: "flare" } }))).toBe("branch2");
    expect(landingBadge(base({ mission: { stage: "landed" } }), false, 0.1).text).toBe("LANDED · measuring the touchdown");
  });
});

describe("plan and inputs", () => {
  it("plan body: waypoints then exactly one land item, last", () => {
    const land = { kind: "land" as const, lat_deg: 1, lon_deg: 2, alt_msl_m: 245 };
    const r = planBody([{ kind: "waypoint", lat_deg: 1.1, lon_deg: 2.1, alt_msl_m: 600 }], land);
    expect(r.ok && r.body.items.map((i) => i.kind)).toEqual(["waypoint", "land"]);
    expect(r.ok && r.body.items[1]).toMatchObject({ kind: "land", approach_course_deg: null });
    expect(planBody([], null).ok).toBe(false);
  });
  it("validates typed numbers, naming the field", () => {
    expect(parseNumber(" 12,5 ", "x", 0, 20)).toEqual({ ok: true, value: 12.5 });
    expect(parseNumber("", "heading (°)", 0, 1)).toEqual({ ok: false, error: "heading (°): required" });
    expect(parseNumber("abc", "x", 0, 1).ok).toBe(false);
    expect(parseLat("91").ok).toBe(false);
    const a = all(parseLat("38.5"), parseNumber("7", "n", 0, 10));
    expect(a.ok && a.values).toEqual([38.5, 7]);
    expect(all(parseLat("38.5"), parseLat("x")).ok).toBe(false);
  });
});


describe("the replay bar's clock", () => {
  it("shows minutes and seconds, hours when there are", () => {
    expect(clockText(0)).toBe("0:00");
    expect(clockText(61_999)).toBe("1:01");
    expect(clockText(3 * 3600_000 + 5_000)).toBe("3:00:05");
    expect(clockText(-5)).toBe("0:00");
  });
});

describe("replica alarm", () => {
  const d = { what: "phase" as const, replica: "branch3", drone: "final_approach", since_s: 812.4, for_s: 1.6, resolved: false, adopted: false };
  it("says which value, each side's, for how long and since when on the mission clock", () => {
    expect(replicaAlarm(d)).toBe("REPLICA ≠ DRONE: phase (station branch3, drone final approach) for 1.6 s, since T+00:13:32.4");
  });
  it("says how a resolved one ended", () => {
    expect(replicaAlarm({ ...d, for_s: 2, resolved: true, adopted: true })).toBe("replica and drone disagreed on the phase for 2.0 s (station branch3, drone final approach, since T+00:13:32.4): the replica took the drone's");
    expect(replicaAlarm({ ...d, resolved: true })).toMatch(/: they agree again$/);
  });
});
