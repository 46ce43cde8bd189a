import { describe, expect, it } from "vitest";
import type * as Wire from "../generated/api";
import { buildWindow, stripRows, utcText } from "./launchWindow";

const request: Wire.PlanRequestInput = { launch_lat_deg: 38, launch_lon_deg: -8, forecast: [{ alt_msl_m: 0, speed_mps: 1, from_deg: 0 }], target_lat_lon_deg: [38, -7.5] };

describe("launch window", () => {
  it("reads datetime-local boxes as UTC and keeps RFC 3339 text", () => {
    expect(utcText("2026-11-30T06:00")).toBe("2026-11-30T06:00:00Z");
    expect(utcText("2026-11-30T06:00:00+01:00")).toBe("2026-11-30T06:00:00+01:00");
    expect(utcText("noon")).toBeNull();
    expect(utcText("")).toBeNull();
  });

  it("builds the body with the step in seconds and no forecast rows, or names the bad box", () => {
    const b = buildWindow(request, "2026-11-30T06:00", "2026-11-30T12:00", "1.5", { upload: 3 });
    expect(b).toEqual({ ok: true, body: { request: { ...request, forecast: [] }, window: { from: "2026-11-30T06:00:00Z", to: "2026-11-30T12:00:00Z", every_s: 5400 }, forecast: { upload: 3 } } });
    expect(buildWindow(request, "x", "2026-11-30T12:00", "1", "configured")).toEqual({ ok: false, error: 'window from: not a time: "x"' });
    expect(buildWindow(request, "2026-11-30T06:00", "2026-11-30T12:00", "0", "configured").ok).toBe(false);
    expect(buildWindow({ ...request, target_lat_lon_deg: null }, "2026-11-30T06:00", "2026-11-30T12:00", "1", "configured")).toEqual({ ok: false, error: "a launch window needs a target: fill in the target's latitude and longitude" });
  });

  it("makes a row per launch with its share, rank and best mark", () => {
    const p = { lat_deg: 38.1, lon_deg: -7.9, alt_msl_m: 20000, time_s: 4000 };
    const launch = (t: string, share: number, rank: number): Wire.WindowLaunch => ({ launch_time: t, burst: p, landing_unsteered: p, landing_sigma_m: 100, reach_share: share, target_from_landing_m: 2500, rank, best: rank <= 3 });
    const report = { launches: [launch("2026-11-30T06:00:00Z", 0.25, 4), launch("2026-11-30T07:00:00Z", 0.5, 1)] } as Wire.WindowReport;
    const rows = stripRows(report);
    expect(rows.map((r) => [r.sharePct, r.rank, r.best])).toEqual([[25, 4, false], [50, 1, true]]);
    expect(rows[1]!.text).toBe("2026-11-30 07:00Z · reach 50 % · landing 38.1000, -7.9000 (2.5 km from target) · burst 38.1000, -7.9000 at 20.0 km · #1 ★");
  });
});
