"""pymavlink encodes a keep-out fence upload as a ground station would send it: MISSION_COUNT
(mission type FENCE) then one MISSION_ITEM_INT per vertex, MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION
with param1 the polygon's vertex count; two polygons, a square and a triangle.

Usage: fence_upload.py OUT_FILE. Writes the frames' bytes to OUT_FILE and prints the vertices
(JSON: a list of [vertex_count, lat_degE7, lon_degE7]) on stdout.
"""

import json
import sys

from pymavlink.dialects.v20 import common as mavlink2

POLYGONS = [
    [(411500000, -85500000), (411505000, -85500000), (411505000, -85494000), (411500000, -85494000)],
    [(411510000, -85510000), (411514000, -85510000), (411512000, -85505000)],
]


class Sink:
    def __init__(self):
        self.data = bytearray()

    def write(self, b):
        self.data += b


def main():
    sink = Sink()
    mav = mavlink2.MAVLink(sink, srcSystem=255, srcComponent=190)
    vertices = [(len(p), lat, lon) for p in POLYGONS for (lat, lon) in p]
    fence = mavlink2.MAV_MISSION_TYPE_FENCE
    mav.send(mav.mission_count_encode(1, 1, len(vertices), fence))
    for seq, (n, lat, lon) in enumerate(vertices):
        mav.send(mav.mission_item_int_encode(
            1, 1, seq, mavlink2.MAV_FRAME_GLOBAL,
            mavlink2.MAV_CMD_NAV_FENCE_POLYGON_VERTEX_EXCLUSION, 0, 0,
            float(n), 0, 0, 0, lat, lon, 0.0, fence))
    with open(sys.argv[1], "wb") as f:
        f.write(sink.data)
    print(json.dumps(vertices))


main()
