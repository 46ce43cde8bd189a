"""Writes a MAVLink telemetry log the way MAVProxy does (8-byte big-endian microseconds, then
the frame) with pymavlink's own encoder, reads it back with pymavlink's tlog reader, and
prints what pymavlink found as JSON: the test compares `stx import` with it.

Its first NO_FIX seconds are an ArduPilot vehicle's on the pad before its GPS has a fix:
GPS_RAW_INT with fix type 0 or 1 and GLOBAL_POSITION_INT, both with zeros for coordinates.
`gps_positions` counts the GPS_RAW_INT pymavlink reads back with a fix (type >= 2) elsewhere
than 0, 0.

    write_tlog.py OUT.tlog
"""

import json
import struct
import sys
from collections import Counter

from pymavlink import mavutil
from pymavlink.dialects.v20 import common as mavlink2

T0_US = 1_795_576_246_000_000
NO_FIX = 3


def main(path):
    mav = mavlink2.MAVLink(None, srcSystem=1, srcComponent=1)
    messages = []
    for i in range(10):
        t = i * 250_000
        messages.append((t, mav.heartbeat_encode(mavlink2.MAV_TYPE_PARAFOIL, mavlink2.MAV_AUTOPILOT_GENERIC, 0, 0, mavlink2.MAV_STATE_ACTIVE)))
        fixed = i >= NO_FIX
        lat, lon = (int((38.5 + i * 1e-5) * 1e7), int(-7.9 * 1e7)) if fixed else (0, 0)
        messages.append((t + 1000, mav.global_position_int_encode(i * 250, lat, lon, 900_000 - i * 100 if fixed else 0, 655_000, 300, 200, 310, 9000)))
        messages.append((t + 2000, mav.attitude_encode(i * 250, 0.1, -0.05, 1.2 + i * 0.01, 0.0, 0.0, 0.02)))
        fix_type = 3 if fixed else i % 2
        messages.append((t + 3000, mav.gps_raw_int_encode(T0_US + t, fix_type, lat, lon, 900_000 if fixed else 0, 65535, 65535, 700, 4500, 11 if fixed else 0)))
        if i % 5 == 0:
            messages.append((t + 4000, mav.statustext_encode(mavlink2.MAV_SEVERITY_INFO, b"spiral branch 2")))
            messages.append((t + 5000, mav.system_time_encode(T0_US + t, i * 250)))
    with open(path, "wb") as f:
        for t, msg in messages:
            f.write(struct.pack(">Q", T0_US + t))
            f.write(msg.pack(mav))
    # pymavlink's own reading of the file.
    log = mavutil.mavlink_connection(path)
    seen = Counter()
    ids = {}
    first_time = None
    gps_positions = 0
    while True:
        m = log.recv_match()
        if m is None:
            break
        if m.get_type() == "BAD_DATA":
            continue
        if m.get_type() == "GPS_RAW_INT" and m.fix_type >= 2 and (m.lat, m.lon) != (0, 0):
            gps_positions += 1
        seen[m.get_type()] += 1
        ids[m.get_type()] = m.get_msgId()
        if first_time is None:
            first_time = round(m._timestamp * 1e6)
    print(json.dumps({"counts": dict(seen), "ids": ids, "first_time_us": first_time, "gps_positions": gps_positions}))


if __name__ == "__main__":
    main(sys.argv[1])
