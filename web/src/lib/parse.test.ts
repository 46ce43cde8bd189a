import { describe, expect, it } from "vitest";
import { contract } from "../../scripts/contract.mjs";
import { decodeMessage, MessageStats, parseSession } from "./parse";

// The state example of API.md, with its elided values filled in: a message the contract accepts
// (checked below), so the fixture cannot drift from what the daemon sends.
const STATE = {
  type: "state", time_s: 123.25, mission_time_s: 1104.5, wall_ms: 1700000000000,
  link: { connected: true, stale: false, age_s: 0.21, rate_hz: 31.5, loss_percent: 0.4, crc_errors: 0, parse_errors: 0, signature_errors: 0,
    ages_s: { HEARTBEAT: 0.4, GPS_RAW_INT: 0.2, ATTITUDE: 0.2, SCALED_PRESSURE: 0.2, SERVO_OUTPUT_RAW: 0.2, WIND_COV: 0.2 },
    radios: [{ address: "udpin:127.0.0.1:14550", transmitting: true, stale: false, age_s: 0.2, rate_hz: 31.5, loss_percent: 0.4, duplicates: 0 }] },
  vehicle: {
    mode: "spiral_landing", stage: "parafoil", phase: "branch2", final_approaches: 0,
    gps: { fix: "fix3d", satellites: 11, lat_deg: 38.53, lon_deg: -7.88, alt_msl_m: 812.4, velocity_ned_mps: [5.1, -1.2, 2.9], h_acc_m: 1.5 },
    attitude: { time_boot_ms: 123456, roll_deg: -12.0, pitch_deg: -3.1, yaw_deg: 141.2 },
    air: { static_pressure_pa: 92000, differential_pressure_pa: 25.2, temperature_c: 11.2, airspeed_mps: 6.6 },
    servos: { main_line: 0.35, brake_right: 0.0, brake_left: 0.0 },
    power: { voltage_v: 11.9, current_a: 0.8, remaining_percent: 78 },
    onboard_wind_ned_mps: [-1.2, 0.4, 0.0],
    predicted_landing: { lat_deg: 38.5335, lon_deg: -7.8887, alt_msl_m: 245, age_s: 0.8, stale: false },
    age_s: 0.05, stale: false,
  },
  estimate: { lat_deg: 38.53, lon_deg: -7.88, alt_msl_m: 812.4, height_m: 567.4, velocity_ned_mps: [5.1, -1.2, 2.9], ground_speed_mps: 5.3, course_deg: -12.0,
    heading_deg: -10.5, heading_rate_dps: 2.1, airspeed_mps: 6.7, sink_rate_mps: 2.95, glide_ratio_air: 2.04, glide_ratio_ground: 1.8,
    wind_ned_mps: [-1.2, 0.4, 0.0], wind_speed_mps: 1.26, wind_from_deg: 341.6, wind_sigma_mps: 0.15, position_sigma_m: 1.8, gps_ok: true, age_s: 0.05, stale: false },
  stack: {
    bodies: [
      { body: "canopy", roll_deg: -8.1, pitch_deg: -6.0, yaw_deg: 141.0, position_enu_m: [-0.3, 0.2, 3.3], size_m: [0.9, 3.3, 0.82], source: "measured", age_s: 0.3 },
      { body: "drone", roll_deg: -12.0, pitch_deg: -3.1, yaw_deg: 141.2, position_enu_m: [0, 0, 0], size_m: [0.365, 0.155, 0.34], source: "measured", age_s: 0.05 },
      { body: "capsule", roll_deg: 0, pitch_deg: 0, yaw_deg: 141.2, position_enu_m: [0.03, -0.04, -3.15], size_m: [0.41, 0.41, 0.315], source: "rigging", age_s: null },
      { body: "transponder", roll_deg: 0, pitch_deg: 0, yaw_deg: 141.2, position_enu_m: [0.03, -0.04, -8.15], size_m: [0.32, 0.32, 0.158], source: "rigging", age_s: null },
    ],
    lines: [
      { line: "main_right", top_enu_m: [0.5, 0.6, 2.7], bottom_enu_m: [0.01, 0.02, 0.18] },
      { line: "main_left", top_enu_m: [-0.9, -0.5, 2.7], bottom_enu_m: [-0.02, -0.03, 0.18] },
      { line: "capsule", top_enu_m: [0.03, -0.04, -0.15], bottom_enu_m: [0.03, -0.04, -3.15] },
      { line: "transponder", top_enu_m: [0.03, -0.04, -3.15], bottom_enu_m: [0.03, -0.04, -8.15] },
    ],
  },
  guidance: { mode: "spiral_landing", phase: "branch2", target: { lat_deg: 38.5333, lon_deg: -7.8889, alt_msl_m: 245 }, target_source: "drone_plan",
    localizer: { point: [38.5333, -7.8889], course_deg: 80.0, glide_slope: 0.3 },
    pattern: { corners: [[38.531, -7.889], [38.532, -7.887], [38.534, -7.888], [38.533, -7.890]], final_entry: [38.531, -7.889], final_course_deg: 161.6,
      final_approach_height_m: 172.0, target_reachable: true, reach_ratio: 0.41 },
    learned: { brake: [0.0, 0.5, 1.0], airspeed_scale: [0.97, 0.97, 0.97], sink_scale: [1.08, 1.1, 1.12], learned_s: 84.0, turn_scale: 0.91, turn_learned_s: 36.5, flying: true, airspeed_sigma: 0.012, sink_sigma: 0.018, turn_sigma: 0.04 },
    commands: { main_line: 0.35, brake: 0.0 }, age_s: 0.05, stale: false,
    disagreement: { what: "phase", replica: "branch3", drone: "branch2", since_s: 1102.25, for_s: 2.25, resolved: false, adopted: false } },
  prediction: { planned: { lat_deg: 38.5334, lon_deg: -7.8888, time_to_land_s: 187.0, semi_major_m: 12.1, semi_minor_m: 6.0, major_axis_deg: 40.0 },
    uncontrolled: { lat_deg: 38.52, lon_deg: -7.87, time_to_land_s: 190.0, semi_major_m: 80, semi_minor_m: 40, major_axis_deg: 100 }, age_s: 0.6, stale: false },
  footprint: { computed_s: 800.0, age_s: 1.5, stale: false, height_m: 567.4, draws: 200, contours: [{ level: 0.5, polygons: [[[[38.52, -7.9], [38.54, -7.9], [38.54, -7.87], [38.52, -7.9]]]] }, { level: 0.95, polygons: [] }], zone_hits: [{ zone: "Pond", level: 0.95 }] },
  forecast_wind: [{ alt_msl_m: 300, speed_mps: 2.0, from_deg: 270 }, { alt_msl_m: 1000, speed_mps: 4, from_deg: 280 }],
  mission: { stage: "parafoil", cutdown_armed_until_s: null, landing: null },
  flight_path: null,
  keep_out_alarms: [{ prediction: "uncontrolled", zone: "Pond", since_s: 790.5 }],
  recording: { state: "on", file: "/var/lib/stx/recordings/stx-20261124T100000Z-001.mcap", bytes_written: 1200000, messages_written: 9000, messages_lost: 0, problem: null, failing_since_ms: null, next_try_in_s: null, failed_tries: 0, resumed_ms: null, resumed_after_s: null },
  readiness: {
    checks: [
      { id: "link", label: "Link up and signed", manual: false, status: "go", detail: "up and signed, 18 Hz", ticked_by: null, ticked_wall_ms: null },
      { id: "canopy", label: "Parafoil and lines inspected, folded and stowed", manual: true, status: "go", detail: "ticked by ops", ticked_by: "ops", ticked_wall_ms: 1764410000000 },
    ],
    open: 0, launched_with_open: [], checklist_error: null,
  },
  replay: null,
  surface_wind: {
    wind: { speed_mps: 3.2, from_deg: 275.0, source: "anemometer", age_s: 2.5 },
    operator: { speed_mps: 4.0, from_deg: 260.0, source: "operator", age_s: 310.0 },
    drone: "held", held: { speed_mps: 3.1, from_deg: 276.0, source: "anemometer", age_s: 4.0 }, drone_accepted_age_s: 1.5, last_error: null,
    anemometer: { address: "udpin:0.0.0.0:10110", sentences: 412, rejected: 3, last_error: null, heard_age_s: 0.9, in_mean: 10 },
  },
};
const SESSION = {
  role: "operator", name: "ops-1",
  station: { name: "STRAPLEX ground", origin: { lat_deg: 38.5333, lon_deg: -7.8889, alt_msl_m: 245 }, tile_url: "/tiles/{z}/{x}/{y}.png", tile_attribution: "©",
    offline_tiles: true, offline_tiles_error: null, tile_max_zoom: 16, tile_bounds: [-7.95, 38.5, -7.8, 38.58],
    modes: ["uncontrolled", "manual", "heading", "course", "localizer", "spiral_landing"], replay: false },
};
const j = (v: unknown): string => JSON.stringify(v);
const api = contract();

describe("the fixtures are messages of the contract", () => {
  it("state, session, hello, event, command_result, params", () => {
    expect(api.check("StateMsg", STATE)).toBeNull();
    expect(api.check("Session", SESSION)).toBeNull();
    expect(api.check("ServerMessage", { type: "hello", session: SESSION, role: SESSION.role, name: SESSION.name })).toBeNull();
    expect(api.check("ServerMessage", { type: "event", time_s: 1, mission_time_s: 1180.5, wall_ms: 1700000000000, level: "info", source: "link", text: "ok" })).toBeNull();
    expect(api.check("ServerMessage", { type: "command_result", request_id: "r1", command: "set_param", outcome: "accepted", attempts: 2, detail: "HK1", value: 0.015 })).toBeNull();
    expect(api.check("StateMsg", { ...STATE, extra: 1 })).toMatch(/additional/);
  });
});

describe("decodeMessage: the API.md example", () => {
  it("reads a message of the contract as it is: nothing lost, nothing invented", () => {
    const d = decodeMessage(j(STATE));
    expect(d).toEqual({ ok: true, msg: STATE, dropped: 0 });
    expect(decodeMessage(j({ type: "hello", session: SESSION, role: "operator", name: "ops-1" }))).toEqual({ ok: true, msg: { type: "hello", session: SESSION }, dropped: 0 });
  });
  it("parses a full state", () => {
    const d = decodeMessage(j({ ...STATE, forecast_wind: [...STATE.forecast_wind].reverse() }));
    expect(d.ok).toBe(true);
    if (!d.ok || d.msg.type !== "state") throw new Error("not a state");
    const s = d.msg;
    expect(s.time_s).toBe(123.25);
    expect(s.link.ages_s.HEARTBEAT).toBe(0.4);
    expect(s.vehicle?.servos?.main_line).toBe(0.35);
    expect(s.estimate?.wind_from_deg).toBe(341.6);
    expect(s.guidance?.pattern?.corners).toHaveLength(4);
    expect(s.guidance?.pattern?.final_entry).toEqual([38.531, -7.889]);
    expect(s.guidance?.learned?.sink_scale).toEqual([1.08, 1.1, 1.12]);
    expect(s.guidance?.learned?.turn_scale).toBe(0.91);
    expect(s.prediction?.planned?.semi_major_m).toBe(12.1);
    // Forecast sorted by altitude for interpolation.
    expect(s.forecast_wind.map((f) => f.alt_msl_m)).toEqual([300, 1000]);
    expect(s.mission.cutdown_armed_until_s).toBeNull();
  });
  it("names the contract does not list become null", () => {
    const d = decodeMessage(j({ ...STATE, vehicle: { ...STATE.vehicle, mode: "warp", gps: { ...STATE.vehicle.gps, fix: "3d" } } }));
    if (!d.ok || d.msg.type !== "state") throw new Error("not a state");
    expect([d.msg.vehicle?.mode, d.msg.vehicle?.gps?.fix, d.msg.vehicle?.stage]).toEqual([null, null, "parafoil"]);
  });
  it("reads each radio and drops entries that are not objects", () => {
    const radios = [STATE.link.radios[0], 7, { address: "serial:/dev/ttyUSB1:57600", transmitting: false, stale: true, age_s: null, rate_hz: "x", duplicates: 12 }];
    const d = decodeMessage(j({ ...STATE, link: { ...STATE.link, radios } }));
    if (!d.ok || d.msg.type !== "state") throw new Error("not a state");
    expect(d.msg.link.radios).toHaveLength(2);
    expect(d.msg.link.radios[0]).toMatchObject({ transmitting: true, rate_hz: 31.5 });
    expect(d.msg.link.radios[1]).toMatchObject({ address: "serial:/dev/ttyUSB1:57600", stale: true, rate_hz: null, duplicates: 12 });
  });
  it("accepts null blocks before the first data", () => {
    const d = decodeMessage(j({ ...STATE, vehicle: null, estimate: null, guidance: null, prediction: null }));
    expect(d.ok && d.msg.type === "state" && d.msg.vehicle === null && d.msg.estimate === null).toBe(true);
  });
});

describe("decodeMessage: malformed input never throws", () => {
  const cases: [string, unknown][] = [
    ["not JSON", "{not json"],
    ["truncated frame", j(STATE).slice(0, 200)],
    ["an array", "[1,2,3]"],
    ["a number", "42"],
    ["null", "null"],
    ["no type", j({ time_s: 1 })],
    ["state without time_s", j({ type: "state" })],
    ["state with a string time", j({ ...STATE, time_s: "12" })],
    ["event without text", j({ type: "event", level: "info" })],
    ["command_result without request_id", j({ type: "command_result", outcome: "accepted" })],
    ["command_result with an unknown outcome", j({ type: "command_result", request_id: "r", outcome: "maybe" })],
    ["params without an array", j({ type: "params", params: 3 })],
    ["history with nothing", j({ type: "history" })],
    ["hello without station", j({ type: "hello", role: "operator" })],
    ["binary frame", new ArrayBuffer(4)],
  ];
  for (const [name, raw] of cases) {
    it(`rejects ${name}`, () => {
      const d = decodeMessage(raw);
      expect(d.ok).toBe(false);
      if (!d.ok) expect(d.error.length).toBeGreaterThan(0);
    });
  }

  it("wrong-typed leaves become null, not garbage", () => {
    const bad = { ...STATE, estimate: { ...STATE.estimate, airspeed_mps: "fast", lat_deg: 200, wind_ned_mps: [1, 2] }, link: { ...STATE.link, ages_s: { HEARTBEAT: "x", GPS_RAW_INT: 0.2 } } };
    const d = decodeMessage(j(bad));
    if (!d.ok || d.msg.type !== "state") throw new Error("should parse");
    expect(d.msg.estimate?.airspeed_mps).toBeNull();
    expect(d.msg.estimate?.lat_deg).toBeNull();
    expect(d.msg.estimate?.wind_ned_mps).toBeNull();
    expect(d.msg.link.ages_s).toEqual({ GPS_RAW_INT: 0.2 });
  });

  it("a state without a link block is stale, never fresh", () => {
    const { link: _drop, ...noLink } = STATE;
    const d = decodeMessage(j(noLink));
    expect(d.ok && d.msg.type === "state" && d.msg.link.stale).toBe(true);
  });

  it("learned scales that are not three numbers read as unknown, and no block as null", () => {
    const d = decodeMessage(j({ ...STATE, guidance: { ...STATE.guidance, learned: { ...STATE.guidance.learned, sink_scale: [1.0, "x", 1.2] } } }));
    expect(d.ok && d.msg.type === "state" && d.msg.guidance?.learned?.sink_scale).toBeNull();
    expect(d.ok && d.msg.type === "state" && d.msg.guidance?.learned?.airspeed_scale).toEqual([0.97, 0.97, 0.97]);
    const { learned: _drop, ...noLearned } = STATE.guidance;
    const n = decodeMessage(j({ ...STATE, guidance: noLearned }));
    expect(n.ok && n.msg.type === "state" && n.msg.guidance?.learned).toBeNull();
  });

  it("surface wind: a full block as sent; none from an older station or recording; garbled leaves null", () => {
    const parsed = (surface_wind: unknown) => {
      const d = decodeMessage(j({ ...STATE, surface_wind }));
      if (!d.ok || d.msg.type !== "state") throw new Error("should parse");
      return d.msg.surface_wind;
    };
    expect(parsed(STATE.surface_wind)).toEqual(STATE.surface_wind);
    const { surface_wind: _drop, ...old } = STATE;
    const d = decodeMessage(j(old));
    expect(d.ok && d.msg.type === "state" && d.msg.surface_wind).toBeNull();
    for (const garbled of [null, "3 m/s", 7, [1, 2]]) expect(parsed(garbled)).toBeNull();
    const sw = STATE.surface_wind;
    const bad = parsed({
      ...sw,
      // A reading without its speed, a negative speed or an unknown source says nothing: dropped.
      wind: { ...sw.wind, source: "windsock" },
      operator: { ...sw.operator, speed_mps: -1 },
      held: { ...sw.held, from_deg: "west" },
      drone: "maybe", drone_accepted_age_s: "1.5", last_error: 12,
      anemometer: { address: null, sentences: "many", rejected: 3, last_error: "bad checksum", heard_age_s: null, in_mean: Infinity },
    });
    expect(bad).toEqual({
      wind: null, operator: null, held: null, drone: null, drone_accepted_age_s: null, last_error: null,
      anemometer: { address: "?", sentences: null, rejected: 3, last_error: "bad checksum", heard_age_s: null, in_mean: null },
    });
    expect(parsed({ ...sw, wind: { speed_mps: 2, from_deg: 90, source: "operator" } })?.wind).toEqual({ speed_mps: 2, from_deg: 90, source: "operator", age_s: null });
    expect(parsed({ ...sw, wind: null, anemometer: "udp" })).toMatchObject({ wind: null, anemometer: null, drone: "held" });
  });

  it("pattern corners out of range are dropped", () => {
    const d = decodeMessage(j({ ...STATE, guidance: { ...STATE.guidance, pattern: { ...STATE.guidance.pattern, corners: [[38.5, -7.8], [95, 0], "x", [1]] } } }));
    expect(d.ok && d.msg.type === "state" && d.msg.guidance?.pattern?.corners.length).toBe(1);
  });

  it("unknown types are ignored, not errors (a newer daemon may add some)", () => {
    const d = decodeMessage(j({ type: "video_frame" }));
    expect(d).toEqual({ ok: true, msg: { type: "unknown", raw_type: "video_frame" }, dropped: 0 });
  });

  it("an unknown event level is kept, as a warning", () => {
    const d = decodeMessage(j({ type: "event", level: "critical", source: "vehicle", text: "x" }));
    expect(d.ok && d.msg.type === "event" && d.msg.level).toBe("warning");
  });
});

describe("history, hello, command_result", () => {
  it("history keeps good items and counts the bad", () => {
    const d = decodeMessage(j({
      type: "history",
      track: [{ time_s: 1, lat_deg: 38.5, lon_deg: -7.8, alt_msl_m: 900 }, { time_s: "x" }, null],
      events: [{ type: "event", level: "info", source: "link", text: "ok" }, { level: "info" }],
      states: [STATE, { type: "state" }],
    }));
    if (!d.ok || d.msg.type !== "history") throw new Error("should parse");
    expect(d.msg.track).toHaveLength(1);
    expect(d.msg.events).toHaveLength(1);
    expect(d.msg.states).toHaveLength(1);
    expect(d.dropped).toBe(4);
  });
  it("hello, nested (as the station sends it) or flattened", () => {
    const session = { role: "viewer", name: "v", station: { name: "s", origin: { lat_deg: 1, lon_deg: 2, alt_msl_m: 3 }, tile_url: "/t/{z}/{x}/{y}.png", modes: ["manual", 7] } };
    for (const msg of [{ type: "hello", ...session }, { type: "hello", session }]) {
      const d = decodeMessage(j(msg));
      expect(d.ok && d.msg.type === "hello" && d.msg.session.role).toBe("viewer");
      expect(d.ok && d.msg.type === "hello" && d.msg.session.station.modes).toEqual(["manual"]);
    }
  });
  it("command_result with the read-back value", () => {
    const d = decodeMessage(j({ type: "command_result", request_id: "r1", command: "set_param", outcome: "accepted", attempts: 2, detail: "HK1", value: 0.015 }));
    expect(d.ok && d.msg.type === "command_result" && [d.msg.attempts, d.msg.value]).toEqual([2, 0.015]);
  });
  it("a station's tile pack fields: kept when sound, null when garbled", () => {
    const station = (extra: object) => ({ role: "viewer", name: "v", station: { name: "s", origin: { lat_deg: 1, lon_deg: 2 }, ...extra } });
    const ok = parseSession(station({ offline_tiles_error: "tile pack x.mbtiles: no such file", tile_max_zoom: 15, tile_bounds: [-8, 38, -7, 39] }));
    expect(ok.ok && [ok.value.station.offline_tiles_error, ok.value.station.tile_max_zoom, ok.value.station.tile_bounds]).toEqual([
      "tile pack x.mbtiles: no such file", 15, [-8, 38, -7, 39]]);
    for (const tile_bounds of [[-7, 38, -8, 39], [-8, 38, -7], [-8, 95, -7, 96], "w,s,e,n"]) {
      const p = parseSession(station({ tile_bounds }));
      expect(p.ok && p.value.station.tile_bounds).toBeNull();
    }
    const none = parseSession(station({}));
    expect(none.ok && [none.value.station.offline_tiles_error, none.value.station.tile_max_zoom]).toEqual([null, null]);
  });
  it("sessions with an unknown role are refused", () => {
    expect(parseSession({ role: "admin", station: { origin: { lat_deg: 0, lon_deg: 0 } } }).ok).toBe(false);
  });
});

describe("MessageStats", () => {
  it("counts received, bad (including dropped items) and ignored; remembers the last error", () => {
    const st = new MessageStats();
    for (const raw of [j(STATE), "{oops", j({ type: "future" }), j({ type: "history", track: [null, null] })]) st.record(decodeMessage(raw));
    expect([st.received, st.bad, st.ignored]).toEqual([4, 3, 1]);
    expect(st.lastError).toContain("history");
  });
});

describe("the reachable footprint in a state", () => {
  const ring = [[38.53, -7.89], [38.54, -7.89], [38.54, -7.88], [38.53, -7.89]];
  const fp = (contours: unknown) => ({ computed_s: 812.5, age_s: 1.2, stale: false, height_m: 640, draws: 200, contours, zone_hits: [{ zone: "Pond", level: 0.5 }, { level: 0.95 }] });
  const parsed = (footprint: unknown) => {
    const d = decodeMessage(j({ ...STATE, footprint }));
    return d.ok && d.msg.type === "state" ? d.msg.footprint : undefined;
  };

  it("keeps each level's polygons, outer ring then holes, as Leaflet's [lat, lon]", () => {
    const f = parsed(fp([{ level: 0.5, polygons: [[ring]] }, { level: 0.95, polygons: [[ring, ring], [ring]] }]));
    expect(f?.computed_s).toBe(812.5);
    // A hit without its zone's name says nothing: left out.
    expect(f?.zone_hits).toEqual([{ zone: "Pond", level: 0.5 }]);
    expect(f?.contours.map((c) => [c.level, c.polygons.length, c.polygons[0]?.length])).toEqual([[0.5, 1, 1], [0.95, 2, 2]]);
    expect(f?.contours[0]?.polygons[0]?.[0]?.[1]).toEqual([38.54, -7.89]);
  });

  it("leaves out a polygon with a point off the globe or a ring too short, not the whole footprint", () => {
    const f = parsed(fp([{ level: 0.5, polygons: [[[[95, 0], [38, -7], [38.1, -7]]], [ring.slice(0, 2)], [ring]] }]));
    expect(f?.contours[0]?.polygons.length).toBe(1);
  });

  it("is null when absent or without its time", () => {
    expect(parsed(null)).toBeNull();
    expect(parsed({ contours: [] })).toBeNull();
  });
});

describe("keep-out zones", () => {
  const square = [[-7.89, 38.53], [-7.88, 38.53], [-7.88, 38.54], [-7.89, 38.53]];
  const msg = (features: unknown[]) => decodeMessage(j({ type: "keep_out", time_s: 12, areas: features.length, changed_by: null, file: null, load_error: null, zones: { type: "FeatureCollection", features } }));
  it("reads named Polygons and each polygon of a MultiPolygon, as the map's [lat, lon]", () => {
    const d = msg([
      { type: "Feature", properties: { name: "Pond" }, geometry: { type: "Polygon", coordinates: [square] } },
      { type: "Feature", properties: { name: "Woods" }, geometry: { type: "MultiPolygon", coordinates: [[square], [square, square]] } },
    ]);
    expect(d.ok && d.msg.type === "keep_out" ? d.msg.areas.map((a) => [a.name, a.rings.length]) : null).toEqual([["Pond", 1], ["Woods", 1], ["Woods", 2]]);
    expect(d.ok && d.msg.type === "keep_out" ? d.msg.areas[0]?.rings[0]?.[1] : null).toEqual([38.53, -7.88]);
  });
  it("leaves out a geometry it cannot draw (a point, a ring off the globe)", () => {
    const d = msg([
      { type: "Feature", properties: { name: "Mast" }, geometry: { type: "Point", coordinates: [-7.89, 38.53] } },
      { type: "Feature", properties: { name: "Bad" }, geometry: { type: "Polygon", coordinates: [[[0, 95], [1, 1], [2, 2]]] } },
    ]);
    expect(d.ok && d.msg.type === "keep_out" ? d.msg.areas : null).toEqual([]);
  });
});
