"""The same point as stx sent, uploaded by pysondehub (`sondehub` on PyPI, 0.3.2), the
SondeHub-Amateur project's own Python uploader, to the test server: what stx sends is held
against what it sends (field names, JSON types, the datetime format, the headers).

Usage: sondehub_pysondehub.py BASE_URL POINT_JSON. POINT_JSON is one point as the test server
kept it from stx. Uploads it with `sondehub.amateur.Uploader` (its endpoint pointed at
BASE_URL), then the uploader's station position as a chase car (`mobile=True`), and exits once
both were sent.
"""

import json
import sys
import time

from sondehub.amateur import Uploader


def main():
    base, point = sys.argv[1], json.loads(sys.argv[2])
    up = Uploader(
        point["uploader_callsign"],
        uploader_position=point.get("uploader_position"),
        software_name="pysondehub-peer",
        software_version="0.3.2",
        upload_rate=1,
    )
    up.SONDEHUB_AMATEUR_URL = f"{base}/amateur/telemetry"
    up.SONDEHUB_AMATEUR_STATION_POSITION_URL = f"{base}/amateur/listeners"
    optional = {k: point[k] for k in ["sats", "batt", "temp", "pressure", "vel_h", "vel_v",
                                      "heading"] if k in point}
    up.add_telemetry(point["payload_callsign"], point["datetime"], point["lat"], point["lon"],
                     point["alt"], time_received=point["time_received"], **optional)
    # Its thread uploads what it holds once a second.
    time.sleep(2.5)
    up.close()
    position = point.get("uploader_position") or [point["lat"], point["lon"], point["alt"]]
    up.upload_station_position(point["uploader_callsign"] + "_CHASE", position, mobile=True)


if __name__ == "__main__":
    main()
