#!/usr/bin/env python3
"""What ecCodes (the `eccodes` package from PyPI, ECMWF's decoder) reads from GRIB2 files: per
message its short name, level, step, grid and the values with their latitudes and longitudes.

    read_grib.py FILE...              every value of every message, as JSON on stdout
    read_grib.py --sample N FILE...   about N grid points per message (evenly spaced in the
                                      file's order, and the four corners)

The first is what the live peer test (tests/weather/eccodes_peer.rs) compares stx with; the
second is what make_fixtures.py commits beside the fixtures, so `cargo test` compares without
Python.
"""

import json
import sys

import eccodes


def messages(path: str):
    with open(path, "rb") as f:
        while True:
            h = eccodes.codes_grib_new_from_file(f)
            if h is None:
                return
            try:
                yield h
            finally:
                eccodes.codes_release(h)


def read(path: str, sample: int) -> list:
    out = []
    for h in messages(path):
        ni = eccodes.codes_get(h, "Ni")
        nj = eccodes.codes_get(h, "Nj")
        values = eccodes.codes_get_values(h)
        lats = eccodes.codes_get_array(h, "latitudes")
        lons = eccodes.codes_get_array(h, "longitudes")
        n = len(values)
        picks = range(n)
        if sample:
            stride = max(1, n // sample)
            picks = sorted({0, ni - 1, n - ni, n - 1} | set(range(stride // 2, n, stride)))
        out.append(
            {
                "short_name": eccodes.codes_get(h, "shortName"),
                "type_of_level": eccodes.codes_get(h, "typeOfLevel"),
                "level": eccodes.codes_get(h, "level"),
                "step_hours": eccodes.codes_get(h, "step"),
                "data_date": eccodes.codes_get(h, "dataDate"),
                "data_time": eccodes.codes_get(h, "dataTime"),
                "packing_type": eccodes.codes_get(h, "packingType"),
                "ni": ni,
                "nj": nj,
                "points": [[float(lats[k]), float(lons[k]), float(values[k])] for k in picks],
            }
        )
    return out


def main() -> None:
    args = sys.argv[1:]
    sample = int(args[1]) if args[:1] == ["--sample"] else 0
    files = args[2:] if sample else args
    print(
        json.dumps(
            {
                "eccodes": eccodes.codes_get_api_version(),
                "files": {path: read(path, sample) for path in files},
            }
        )
    )


if __name__ == "__main__":
    main()
