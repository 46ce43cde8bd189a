#!/usr/bin/env python3
"""Independent check of frames stx-link wrote: pymavlink (MAVLINK20=1) parses a byte stream,
verifying signatures with the given key when one is given, and prints a JSON summary.

Usage: MAVLINK20=1 python verify_stream.py STREAM_FILE [KEY_HEX TIMESTAMP_START]
"""

import json
import os
import sys

if os.environ.get("MAVLINK20") != "1":
    sys.exit("set MAVLINK20=1 so that pymavlink speaks MAVLink 2")

from pymavlink.dialects.v20 import common as m  # noqa: E402


def main():
    data = open(sys.argv[1], "rb").read()
    mav = m.MAVLink(None, srcSystem=255, srcComponent=190)
    mav.robust_parsing = True
    if len(sys.argv) > 3:
        mav.signing.secret_key = bytes.fromhex(sys.argv[2])
        mav.signing.timestamp = int(sys.argv[3])
        # Refuse unsigned frames: signing is on.
        mav.signing.allow_unsigned_callback = lambda _mav, _msgid: False
    names = []
    bad = 0
    for msg in mav.parse_buffer(data) or []:
        if msg.get_type() == "BAD_DATA":
            bad += 1
        else:
            names.append(msg.get_type())
    print(json.dumps({
        "messages": names,
        "bad": bad,
        "goodsig": mav.signing.goodsig_count,
        "badsig": mav.signing.badsig_count,
        "unsigned": mav.signing.unsigned_count,
        "rejected": mav.signing.reject_count,
    }))


if __name__ == "__main__":
    main()
