#!/usr/bin/env python3
"""Independent MAVLink peer for stx-link's tests: pymavlink (2.4.50, MAVLINK20=1) writes byte
streams of telemetry and command messages, with garbage, truncated frames and corrupted CRCs
mixed in, plus a JSON manifest of every valid frame (header, payload bytes, a few field values)
and of what was corrupted.

Usage: MAVLINK20=1 python make_streams.py OUT_DIR

Two streams:
- unsigned.bin: valid MAVLink 2 frames from two senders, with garbage, corrupted CRCs and
  truncated frames between them.
- signed.bin: frames signed with a known key, plus one unsigned frame, one replayed signed
  frame, one frame signed with another key and one MAVLink 1 frame (all to be refused when
  signing is on).

Deterministic: a seeded random generator; fixed signing timestamps.
"""

import json
import os
import random
import sys

if os.environ.get("MAVLINK20") != "1":
    sys.exit("set MAVLINK20=1 so that pymavlink speaks MAVLink 2")

from pymavlink.dialects.v20 import common as m  # noqa: E402

SIGNING_KEY = bytes(range(32))
OTHER_KEY = bytes([0xEE] * 32)
# 2026-01-01 00:00:00 UTC in 10 us units since 2015-01-01.
SIGNING_T0 = 34_715_520_000_000


class Sink:
    """File-like object collecting what pymavlink sends."""

    def __init__(self):
        self.frames = []

    def write(self, data):
        self.frames.append(bytes(data))


def link(sysid, compid, key=None, link_id=0, ts=SIGNING_T0):
    sink = Sink()
    mav = m.MAVLink(sink, srcSystem=sysid, srcComponent=compid)
    if key is not None:
        mav.signing.secret_key = key
        mav.signing.link_id = link_id
        mav.signing.timestamp = ts
        mav.signing.sign_outgoing = True
    return mav, sink


def telemetry_and_commands(mav, rng, i):
    """One message of each kind, values varying with i."""
    lat = 411_779_000 + rng.randint(-500_000, 500_000)
    lon = -85_977_000 + rng.randint(-500_000, 500_000)
    custom_mode = (i % 6) | ((i % 6) << 8) | ((i % 10) << 16)
    return [
        mav.heartbeat_encode(m.MAV_TYPE_PARAFOIL, m.MAV_AUTOPILOT_GENERIC, m.MAV_MODE_FLAG_CUSTOM_MODE_ENABLED, custom_mode, m.MAV_STATE_ACTIVE),
        mav.gps_raw_int_encode(1_000_000 * i, 3, lat, lon, 1_234_567 + i, 90, 120, 1234, 27_000 + i, 11, 0, 2500 + i, 4000, 0, 0, 0),
        mav.global_position_int_encode(100 * i, lat, lon, 1_200_000 + i, 1_100_000, -250 + i, 130, 480, 27_005),
        mav.attitude_encode(100 * i, 0.1 + 0.001 * i, -0.05, 2.5, 0.01, -0.02, 0.3),
        mav.scaled_pressure_encode(100 * i, 880.25 + 0.01 * i, 2.5, -1234, 1567),
        mav.vfr_hud_encode(14.5, 12.0 + 0.1 * i, 271, 0, 1200.5, -4.25),
        mav.servo_output_raw_encode(1000 * i, 0, 1500 + i, 1000 + 2 * i, 2000 - 2 * i, 0, 0, 0, 0, 0),
        mav.sys_status_encode(0x1, 0x1, 0x1, 250, 12_600 - i, 150, 0, 0, 0, 0, 0, 0, 87),
        mav.battery_status_encode(0, 0, 0, 2500, [12_600 - i] + [65535] * 9, 150, 1200, -1, 87),
        mav.statustext_encode(m.MAV_SEVERITY_INFO, ("stx stream frame %d" % i).encode()),
        mav.wind_cov_encode(1_000_000 * i, 3.5, -1.25, 0.1, 0.8, 0.2, 1500.0, 0.3, 0.1),
        mav.nav_controller_output_encode(-12.5, 0.0, 275, 280, 1500 + i, 3.5, 0.0, -7.25),
        mav.position_target_global_int_encode(100 * i, m.MAV_FRAME_GLOBAL, 0xDF8, lat + 1000, lon - 1000, 95.0, 0, 0, 0, 0, 0, 0, 0, 0),
        mav.command_long_encode(1, 1, m.MAV_CMD_DO_SET_MODE, i % 3, 1, 5, 0, 0, 0, 0, 0),
        mav.command_int_encode(1, 1, m.MAV_FRAME_GLOBAL, m.MAV_CMD_NAV_LAND, 0, 0, 0, 0, 0, float("nan"), lat, lon, 95.0),
        mav.command_ack_encode(m.MAV_CMD_DO_SET_MODE, m.MAV_RESULT_ACCEPTED, 0, 0, 255, 190),
        mav.manual_control_encode(1, -1000 + i, 500, 0, 250, 0x8001, 0x0002),
        mav.param_value_encode(b"HDG_KP", 0.8 + i, m.MAV_PARAM_TYPE_REAL32, 20, i % 20),
        mav.param_set_encode(1, 1, b"FLARE_ALT_M", 8.5, m.MAV_PARAM_TYPE_REAL32),
        mav.mission_item_int_encode(1, 1, i % 5, m.MAV_FRAME_GLOBAL, m.MAV_CMD_NAV_WAYPOINT, 0, 1, 0, 0, 0, 0, lat, lon, 300.0),
        mav.mission_count_encode(1, 1, 5),
    ]


SPOT_FIELDS = {
    "HEARTBEAT": ["custom_mode"],
    "GPS_RAW_INT": ["lat", "lon", "alt", "cog", "h_acc"],
    "GLOBAL_POSITION_INT": ["lat", "lon", "alt", "vx", "hdg"],
    "ATTITUDE": ["roll", "yaw"],
    "SCALED_PRESSURE": ["press_abs", "temperature", "temperature_press_diff"],
    "VFR_HUD": ["groundspeed", "heading", "climb"],
    "SERVO_OUTPUT_RAW": ["servo1_raw", "servo2_raw", "servo3_raw"],
    "SYS_STATUS": ["voltage_battery", "battery_remaining"],
    "WIND_COV": ["wind_x", "wind_alt"],
    "NAV_CONTROLLER_OUTPUT": ["target_bearing", "wp_dist", "xtrack_error"],
    "POSITION_TARGET_GLOBAL_INT": ["lat_int", "lon_int", "alt"],
    "COMMAND_LONG": ["param2", "confirmation"],
    "COMMAND_INT": ["x", "y", "z"],
    "MANUAL_CONTROL": ["x", "buttons", "buttons2"],
    "PARAM_VALUE": ["param_value", "param_index"],
    "MISSION_ITEM_INT": ["seq", "x", "z"],
}


def describe(msg, frame):
    d = msg.to_dict()
    name = d["mavpackettype"]
    plen = frame[1]
    spot = {k: d[k] for k in SPOT_FIELDS.get(name, [])}
    if name == "STATUSTEXT":
        spot["text"] = d["text"]
    if name == "PARAM_VALUE":
        spot["param_id"] = d["param_id"]
    return {
        "name": name,
        "msgid": msg.get_msgId(),
        "sysid": frame[5],
        "compid": frame[6],
        "seq": frame[4],
        "signed": bool(frame[2] & 1),
        "payload_hex": frame[10 : 10 + plen].hex(),
        "spot": spot,
    }


def garbage(rng, n):
    # No 0xFD / 0xFE: garbage must not start frame candidates, so the counts below are exact.
    return bytes(rng.choice([b for b in range(256) if b not in (0xFD, 0xFE)]) for _ in range(n))


def unsigned_stream(rng):
    out = bytearray()
    valid = []
    counts = {"corrupted_crc": 0, "truncated": 0, "garbage_bytes": 0}
    senders = [link(1, 1), link(42, 200)]
    for i in range(60):
        mav, sink = senders[i % 2]
        for msg in telemetry_and_commands(mav, rng, i):
            mav.send(msg)
            frame = sink.frames.pop()
            roll = rng.random()
            if roll < 0.06:
                bad = bytearray(frame)
                pos = rng.randrange(10, len(bad))  # a payload or CRC byte
                bad[pos] ^= 1 << rng.randrange(8)
                out += bad
                counts["corrupted_crc"] += 1
            elif roll < 0.09:
                out += frame[: rng.randrange(1, len(frame) - 1)]
                counts["truncated"] += 1
            else:
                out += frame
                valid.append(describe(msg, frame))
            if rng.random() < 0.1:
                g = garbage(rng, rng.randrange(1, 40))
                out += g
                counts["garbage_bytes"] += len(g)
    return bytes(out), valid, counts


def signed_stream(rng):
    out = bytearray()
    valid = []
    mav, sink = link(1, 1, SIGNING_KEY, link_id=3)
    plain, plain_sink = link(1, 1)
    other, other_sink = link(1, 1, OTHER_KEY, link_id=3, ts=SIGNING_T0 + 10_000_000)
    first_signed = None
    for i in range(20):
        for msg in telemetry_and_commands(mav, rng, i):
            mav.send(msg)
            frame = sink.frames.pop()
            if first_signed is None:
                first_signed = frame
            out += frame
            valid.append(describe(msg, frame))
        if i == 5:
            plain.send(plain.attitude_encode(1, 0, 0, 0, 0, 0, 0))
            out += plain_sink.frames.pop()
        if i == 8:
            out += first_signed  # replay
        if i == 11:
            other.send(other.attitude_encode(2, 0, 0, 0, 0, 0, 0))
            out += other_sink.frames.pop()
        if i == 14:
            plain.send(plain.attitude_encode(3, 0, 0, 0, 0, 0, 0), force_mavlink1=True)
            out += plain_sink.frames.pop()
    expect = {"unsigned_refused": 1, "replays_refused": 1, "bad_signatures": 1, "v1_refused": 1}
    return bytes(out), valid, expect


def main():
    out_dir = sys.argv[1]
    os.makedirs(out_dir, exist_ok=True)
    rng = random.Random(0x5717)
    u_bytes, u_valid, u_counts = unsigned_stream(rng)
    s_bytes, s_valid, s_expect = signed_stream(rng)
    with open(os.path.join(out_dir, "unsigned.bin"), "wb") as f:
        f.write(u_bytes)
    with open(os.path.join(out_dir, "signed.bin"), "wb") as f:
        f.write(s_bytes)
    manifest = {
        "generator": "pymavlink",
        "unsigned": {"file": "unsigned.bin", "frames": u_valid, **u_counts},
        "signed": {
            "file": "signed.bin",
            "frames": s_valid,
            "key_hex": SIGNING_KEY.hex(),
            "timestamp_start": SIGNING_T0,
            "expect": s_expect,
        },
    }
    with open(os.path.join(out_dir, "manifest.json"), "w") as f:
        json.dump(manifest, f, indent=1, allow_nan=True)
    print("unsigned: %d valid, %s; signed: %d valid" % (len(u_valid), u_counts, len(s_valid)))


if __name__ == "__main__":
    main()
