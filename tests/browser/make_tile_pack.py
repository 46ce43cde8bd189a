#!/usr/bin/env python3
"""Writes a small MBTiles pack for the browser test of offline maps (tests/browser/tiles.mjs).

Usage: make_tile_pack.py OUT.mbtiles LAT LON RADIUS_M MINZOOM MAXZOOM

Every tile covering the square of RADIUS_M around (LAT, LON) at each zoom is one flat PNG of a
colour no real map has (#3cb4a0), so the test can tell the pack's tiles from anything else. Only
the standard library: sqlite3 is the format, and a flat PNG is a few zlib-compressed rows.
"""

import math
import sqlite3
import struct
import sys
import zlib

COLOUR = (0x3C, 0xB4, 0xA0)


def png(width, height, rgb):
    def chunk(kind, data):
        body = kind + data
        return struct.pack(">I", len(data)) + body + struct.pack(">I", zlib.crc32(body) & 0xFFFFFFFF)

    row = b"\x00" + bytes(rgb) * width
    return (
        b"\x89PNG\r\n\x1a\n"
        + chunk(b"IHDR", struct.pack(">IIBBBBB", width, height, 8, 2, 0, 0, 0))
        + chunk(b"IDAT", zlib.compress(row * height))
        + chunk(b"IEND", b"")
    )


def tile_xy(lat, lon, z):
    n = 2**z
    x = int((lon + 180.0) / 360.0 * n)
    lat_r = math.radians(lat)
    y = int((1.0 - math.asinh(math.tan(lat_r)) / math.pi) / 2.0 * n)
    return x, y


def main():
    out, lat, lon, radius, zmin, zmax = sys.argv[1:7]
    lat, lon, radius, zmin, zmax = float(lat), float(lon), float(radius), int(zmin), int(zmax)
    dlat = radius / 111_320.0
    dlon = radius / (111_320.0 * math.cos(math.radians(lat)))
    tile = png(256, 256, COLOUR)
    db = sqlite3.connect(out)
    db.executescript(
        "CREATE TABLE metadata (name TEXT, value TEXT);"
        "CREATE TABLE tiles (zoom_level INTEGER, tile_column INTEGER, tile_row INTEGER, tile_data BLOB);"
    )
    meta = {
        "name": "stx browser test pack",
        "format": "png",
        "minzoom": str(zmin),
        "maxzoom": str(zmax),
        "bounds": f"{lon - dlon},{lat - dlat},{lon + dlon},{lat + dlat}",
        "attribution": "stx test pack",
    }
    db.executemany("INSERT INTO metadata VALUES (?, ?)", meta.items())
    count = 0
    for z in range(zmin, zmax + 1):
        x0, y0 = tile_xy(lat + dlat, lon - dlon, z)
        x1, y1 = tile_xy(lat - dlat, lon + dlon, z)
        for x in range(x0, x1 + 1):
            for y in range(y0, y1 + 1):
                # MBTiles stores TMS rows: counted from the south.
                db.execute("INSERT INTO tiles VALUES (?, ?, ?, ?)", (z, x, 2**z - 1 - y, tile))
                count += 1
    db.commit()
    db.close()
    print(count)


if __name__ == "__main__":
    main()
