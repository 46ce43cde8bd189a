"""pymavlink, an independent MAVLink implementation, against the simulated drone (`stx drone`).

Usage: test_drone_pymavlink.py STX_BINARY [SCENARIO]

Listens with `udpin` on a free loopback port, starts `stx drone --connect udpout:…` at real
time, and, as a ground station would:
  1. reads HEARTBEAT (a parafoil, custom mode = mode | stage << 8 | phase << 16), GPS_RAW_INT,
     ATTITUDE and the rest of the telemetry, and measures each message's rate over a window
     (the other bodies' ATTITUDE from their own components, apart);
  2. lists the parameters (PARAM_REQUEST_LIST → every PARAM_VALUE, by index), sets one and reads
     it back (the PARAM_SET echo and a PARAM_REQUEST_READ), and checks an out-of-range set, and
     one within its range that breaks a rule between parameters, are answered only with the
     value in force;
  3. sends COMMAND_LONG DO_SET_MODE (heading mode) and gets COMMAND_ACK ACCEPTED, timing it,
     and sees the mode in the next HEARTBEAT;
  4. sends an unsupported command and a cutdown under the parafoil and gets non-ACCEPTED ACKs.

Prints one JSON object (the measured figures) on stdout; any failed check raises. Needs
MAVLINK20=1 in the environment (the Rust test sets it) so pymavlink speaks MAVLink 2.
"""

import json
import os
import signal
import subprocess
import sys
import time

from pymavlink import mavutil

STX = sys.argv[1]
SCENARIO = sys.argv[2] if len(sys.argv) > 2 else "rehearsal"

assert os.environ.get("MAVLINK20") == "1", "run with MAVLINK20=1 (MAVLink 2)"

MODE_HEADING = 2
MAV_MODE_FLAG_CUSTOM_MODE_ENABLED = 1
RATE_WINDOW_S = 8.0


def main():
    conn = mavutil.mavlink_connection("udpin:127.0.0.1:0", source_system=255, source_component=190)
    port = conn.port.getsockname()[1]
    drone = subprocess.Popen(
        [STX, "drone", "--connect", f"udpout:127.0.0.1:{port}", "--scenario", SCENARIO, "--speed", "1",
         "--summary-json"],
        stdout=subprocess.PIPE,
        stderr=subprocess.PIPE,
    )
    try:
        report = exercise(conn)
    finally:
        drone.send_signal(signal.SIGINT)
        try:
            out, err = drone.communicate(timeout=20)
        except subprocess.TimeoutExpired:
            drone.kill()
            out, err = drone.communicate()
    report["drone_exit_code"] = drone.returncode
    assert drone.returncode == 0, f"stx drone exited {drone.returncode}: {err.decode(errors='replace')[-2000:]}"
    summary = json.loads(out.decode().strip().splitlines()[-1])
    report["drone_interrupted"] = summary["interrupted"]
    print(json.dumps(report))


def recv(conn, types, timeout=5.0, cond=lambda m: True):
    """The next message of one of `types` satisfying `cond`, answering nothing else."""
    deadline = time.monotonic() + timeout
    while time.monotonic() < deadline:
        m = conn.recv_match(type=types, blocking=True, timeout=max(0.01, deadline - time.monotonic()))
        if m is not None and m.get_srcSystem() == 1 and cond(m):
            return m
    raise AssertionError(f"no {types} within {timeout} s")


def heartbeat(conn):
    conn.mav.heartbeat_send(mavutil.mavlink.MAV_TYPE_GCS, mavutil.mavlink.MAV_AUTOPILOT_INVALID, 0, 0, 0)


def exercise(conn):
    report = {}
    hb = recv(conn, "HEARTBEAT", timeout=20.0)
    assert hb.type == mavutil.mavlink.MAV_TYPE_PARAFOIL, hb
    assert hb.base_mode & MAV_MODE_FLAG_CUSTOM_MODE_ENABLED
    assert conn.mavlink20(), "the drone must speak MAVLink 2"
    mode, stage, phase = hb.custom_mode & 0xFF, (hb.custom_mode >> 8) & 0xFF, (hb.custom_mode >> 16) & 0xFF
    report["first_heartbeat"] = {"mode": mode, "stage": stage, "phase": phase}
    assert mode <= 5 and stage <= 5 and phase <= 9, hb
    heartbeat(conn)

    # 1. Telemetry and its rates (wall clock: the drone flies at real time here).
    counts = {}
    latest = {}
    start = time.monotonic()
    last_hb = start
    while time.monotonic() - start < RATE_WINDOW_S:
        m = conn.recv_match(blocking=True, timeout=0.2)
        if time.monotonic() - last_hb > 1.0:
            heartbeat(conn)
            last_hb = time.monotonic()
        if m is None or m.get_srcSystem() != 1:
            continue
        t = m.get_type()
        if m.get_srcComponent() != 1:
            # Another body's own IMU (stx_types::stack::BodyImu): its stream, counted apart.
            t = f"{t}@{m.get_srcComponent()}"
        now = time.monotonic()
        n, t_first, _ = counts.get(t, (0, now, now))
        counts[t] = (n + 1, t_first, now)
        latest[t] = m
    # Rate = arrivals after the first over the time they took (no edge effect of the window).
    rates = {
        t: round((n - 1) / (t_last - t_first), 2)
        for t, (n, t_first, t_last) in sorted(counts.items())
        if n >= 3 and t_last > t_first
    }
    report["rates_hz"] = rates
    for t in ("HEARTBEAT", "GPS_RAW_INT", "ATTITUDE", "SCALED_PRESSURE", "GLOBAL_POSITION_INT",
              "VFR_HUD", "SERVO_OUTPUT_RAW", "SYS_STATUS", "BATTERY_STATUS", "WIND_COV"):
        assert t in rates, f"no {t} in {rates}"
    assert 0.8 <= rates["HEARTBEAT"] <= 1.25, rates
    for t in ("GPS_RAW_INT", "ATTITUDE", "SCALED_PRESSURE", "GLOBAL_POSITION_INT", "VFR_HUD",
              "SERVO_OUTPUT_RAW"):
        assert 3.5 <= rates[t] <= 4.5, (t, rates)
    for t in ("SYS_STATUS", "BATTERY_STATUS", "WIND_COV"):
        assert 0.8 <= rates[t] <= 1.25, (t, rates)
    # Under the parafoil the canopy, capsule and transponder IMUs (MAV_COMP_ID_IMU, _2, _3)
    # send their attitudes at 2 Hz; nothing else comes from another component.
    for c in (200, 201, 202):
        assert 1.6 <= rates.get(f"ATTITUDE@{c}", 0) <= 2.4, (c, rates)
    assert all(t.startswith("ATTITUDE@20") for t in rates if "@" in t), rates
    gps = latest["GPS_RAW_INT"]
    assert gps.fix_type == mavutil.mavlink.GPS_FIX_TYPE_3D_FIX, gps
    # Near Évora (the rehearsal's site), a few hundred metres from its origin.
    assert abs(gps.lat / 1e7 - 38.5333) < 0.05 and abs(gps.lon / 1e7 + 7.8889) < 0.05, gps
    att = latest["ATTITUDE"]
    assert abs(att.roll) < 3.2 and abs(att.pitch) < 1.6 and abs(att.yaw) < 3.2, att
    press = latest["SCALED_PRESSURE"]
    assert 850 < press.press_abs < 1013, press  # hPa, a few hundred metres up
    report["gps_fix"] = {"lat": gps.lat / 1e7, "lon": gps.lon / 1e7, "alt_m": gps.alt / 1000}

    # 2. Parameters: list, set, read back, refuse out of range.
    conn.mav.param_request_list_send(1, 1)
    params = {}
    count = None
    deadline = time.monotonic() + 10
    while (count is None or len(params) < count) and time.monotonic() < deadline:
        m = conn.recv_match(type="PARAM_VALUE", blocking=True, timeout=1.0)
        if m is None:
            continue
        count = m.param_count
        params[m.param_index] = (m.param_id, m.param_value)
    assert count and len(params) == count, f"{len(params)} of {count} parameters"
    assert sorted(params) == list(range(count))
    names = {name: value for name, value in params.values()}
    report["param_count"] = count
    # A control-law gain: HK1 (main line per radian of heading error).
    name = next(n for n in names if n.endswith("HK1"))
    old = names[name]
    new = round(old * 1.5 + 0.001, 5)
    t0 = time.monotonic()
    conn.mav.param_set_send(1, 1, name.encode(), new, mavutil.mavlink.MAV_PARAM_TYPE_REAL32)
    echo = recv(conn, "PARAM_VALUE", cond=lambda m: m.param_id == name)
    report["param_set_ms"] = round((time.monotonic() - t0) * 1000, 2)
    assert abs(echo.param_value - new) < 1e-6, (echo, new)
    conn.mav.param_request_read_send(1, 1, name.encode(), -1)
    back = recv(conn, "PARAM_VALUE", cond=lambda m: m.param_id == name)
    assert abs(back.param_value - new) < 1e-6, back
    conn.mav.param_set_send(1, 1, name.encode(), 1e6, mavutil.mavlink.MAV_PARAM_TYPE_REAL32)
    refused = recv(conn, "PARAM_VALUE", cond=lambda m: m.param_id == name)
    assert abs(refused.param_value - new) < 1e-6, f"out-of-range set changed {name}: {refused}"
    report["param_set"] = {"name": name, "old": old, "new": new}
    # Within its range but against a rule between parameters (the shortest final approach
    # longer than the longest): the only answer is the value in force — never the value asked
    # for first and the old one after it.
    rule_name = "SP_MIN_FINAL"
    in_force = names[rule_name]
    assert in_force < 1500.0 and names["SP_MAX_FINAL"] < 1500.0, names  # 1500 breaks the rule
    conn.mav.param_set_send(1, 1, rule_name.encode(), 1500.0, mavutil.mavlink.MAV_PARAM_TYPE_REAL32)
    answers = []
    deadline = time.monotonic() + 2.0
    while time.monotonic() < deadline:
        m = conn.recv_match(type=["PARAM_VALUE", "STATUSTEXT"], blocking=True, timeout=0.2)
        if m is None or m.get_srcSystem() != 1:
            continue
        if m.get_type() == "PARAM_VALUE" and m.param_id == rule_name:
            answers.append(m.param_value)
        elif m.get_type() == "STATUSTEXT" and rule_name in m.text:
            report["rule_refusal_text"] = m.text
    assert answers and all(abs(a - in_force) < 1e-6 for a in answers), (
        f"{rule_name} = 1500 answered {answers}, in force {in_force}")
    report["rule_refusal"] = {"name": rule_name, "asked": 1500.0, "answered": answers}

    # 3. A mode change, acknowledged; the heartbeat follows.
    t0 = time.monotonic()
    conn.mav.command_long_send(1, 1, mavutil.mavlink.MAV_CMD_DO_SET_MODE, 0,
                               MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, MODE_HEADING, 0, 0, 0, 0, 0)
    ack = recv(conn, "COMMAND_ACK", cond=lambda m: m.command == mavutil.mavlink.MAV_CMD_DO_SET_MODE)
    report["set_mode_ack_ms"] = round((time.monotonic() - t0) * 1000, 2)
    assert ack.result == mavutil.mavlink.MAV_RESULT_ACCEPTED, ack
    hb = recv(conn, "HEARTBEAT", timeout=3.0, cond=lambda m: (m.custom_mode & 0xFF) == MODE_HEADING)
    report["mode_after"] = hb.custom_mode & 0xFF

    # 4. Commands the drone must refuse, each with its own ACK.
    t0 = time.monotonic()
    conn.mav.command_long_send(1, 1, mavutil.mavlink.MAV_CMD_NAV_TAKEOFF, 0, 0, 0, 0, 0, 0, 0, 100)
    ack = recv(conn, "COMMAND_ACK", cond=lambda m: m.command == mavutil.mavlink.MAV_CMD_NAV_TAKEOFF)
    report["unsupported_ack_ms"] = round((time.monotonic() - t0) * 1000, 2)
    assert ack.result == mavutil.mavlink.MAV_RESULT_UNSUPPORTED, ack
    conn.mav.command_long_send(1, 1, mavutil.mavlink.MAV_CMD_DO_FLIGHTTERMINATION, 0, 1, 0, 0, 0, 0, 0, 0)
    ack = recv(conn, "COMMAND_ACK", cond=lambda m: m.command == mavutil.mavlink.MAV_CMD_DO_FLIGHTTERMINATION)
    assert ack.result == mavutil.mavlink.MAV_RESULT_DENIED, f"cutdown under the parafoil: {ack}"
    conn.mav.command_long_send(1, 1, mavutil.mavlink.MAV_CMD_DO_SET_MODE, 0,
                               MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, 42, 0, 0, 0, 0, 0)
    ack = recv(conn, "COMMAND_ACK", cond=lambda m: m.command == mavutil.mavlink.MAV_CMD_DO_SET_MODE)
    assert ack.result != mavutil.mavlink.MAV_RESULT_ACCEPTED, f"unknown mode 42 accepted: {ack}"
    report["refusals"] = "ok"

    # 5. What the drone is, as QGroundControl and MAVProxy ask on connecting: the message by
    # MAV_CMD_REQUEST_MESSAGE, and by the older MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES.
    versions = []
    for cmd, p1 in ((mavutil.mavlink.MAV_CMD_REQUEST_MESSAGE, 148),
                    (mavutil.mavlink.MAV_CMD_REQUEST_AUTOPILOT_CAPABILITIES, 1)):
        conn.mav.command_long_send(1, 1, cmd, 0, p1, 0, 0, 0, 0, 0, 0)
        ack = recv(conn, "COMMAND_ACK", cond=lambda m, cmd=cmd: m.command == cmd)
        assert ack.result == mavutil.mavlink.MAV_RESULT_ACCEPTED, ack
        versions.append(recv(conn, "AUTOPILOT_VERSION"))
    v = versions[0]
    caps = v.capabilities
    names = [n for n, bit in (
        ("MAVLINK2", mavutil.mavlink.MAV_PROTOCOL_CAPABILITY_MAVLINK2),
        ("PARAM_ENCODE_C_CAST", mavutil.mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_C_CAST),
        ("PARAM_ENCODE_BYTEWISE", mavutil.mavlink.MAV_PROTOCOL_CAPABILITY_PARAM_ENCODE_BYTEWISE),
        ("COMMAND_INT", mavutil.mavlink.MAV_PROTOCOL_CAPABILITY_COMMAND_INT),
        ("MISSION_INT", mavutil.mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_INT),
        ("MISSION_FENCE", mavutil.mavlink.MAV_PROTOCOL_CAPABILITY_MISSION_FENCE),
        ("FLIGHT_TERMINATION", mavutil.mavlink.MAV_PROTOCOL_CAPABILITY_FLIGHT_TERMINATION),
    ) if caps & bit]
    sw = v.flight_sw_version
    report["autopilot_version"] = {
        "capabilities": names,
        "flight_sw_version": f"{sw >> 24}.{(sw >> 16) & 0xFF}.{(sw >> 8) & 0xFF} type {sw & 0xFF}",
        "same_answer_twice": versions[1].capabilities == caps and versions[1].flight_sw_version == sw,
    }
    return report


if __name__ == "__main__":
    main()
