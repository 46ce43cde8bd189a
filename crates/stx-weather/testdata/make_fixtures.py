#!/usr/bin/env python3
"""Writes the GRIB2 fixtures of stx-weather's tests with ecCodes (the `eccodes` package from
PyPI), and what ecCodes reads back from them (`eccodes_reads.json`), so `cargo test` compares
stx's decoding with ecCodes' without Python.

    .venv/bin/python crates/stx-weather/testdata/make_fixtures.py             # the fixtures
    .venv/bin/python crates/stx-weather/testdata/make_fixtures.py --bench OUT # the benchmark's file
    .venv/bin/python crates/stx-weather/testdata/make_fixtures.py --window-bench OUT # the window's

The fields are made up but shaped like GFS: geopotential height near the standard atmosphere's
at each pressure level, winds growing to a jet near 200 hPa, a little deterministic noise so the
packing's rounding matters. The files are cut as NOMADS' filter cuts GFS:

- `gfs_0p25_subset.grib2`: 0.25°, 17 × 21 points (36–40° N, 350–355° E: longitudes 0–360 as
  GFS writes them), 11 isobaric levels down to 0.4 hPa (40 Pa, an `isobaricInPa` level),
  forecast hours 0, 3 and 6, UGRD, VGRD and HGT in GFS' complex packing with spatial
  differencing, scanned north to south as GFS scans;
- `gfs_0p50_simple.grib2`: 0.5°, 9 × 11 points scanned south to north with negative
  longitudes, simple packing, 4 levels, hours 0 and 6;
- `no_hgt.grib2`: UGRD and VGRD only (a subset cut without HGT: refused).

Every byte is deterministic for a given ecCodes version; the committed files were made with the
version in `eccodes_reads.json`.
"""

import json
import math
import os
import random
import subprocess
import sys

import eccodes

HERE = os.path.dirname(os.path.abspath(__file__))

# Parameter (discipline 0): category and number in GRIB2 code table 4.2.
PARAMS = {"u": (2, 2), "v": (2, 3), "gh": (3, 5)}


def isa_geopotential_m(p_pa: float) -> float:
    """Geopotential height of a pressure in the standard atmosphere (isothermal above 11 km,
    which is close enough for made-up fields)."""
    if p_pa >= 22632.0:
        return 44330.8 * (1.0 - (p_pa / 101325.0) ** 0.190263)
    return 11000.0 + 6341.6 * math.log(22632.0 / p_pa)


def field(name: str, p_pa: float, step: int, lat: float, lon: float, rng: random.Random) -> float:
    z = isa_geopotential_m(p_pa)
    wave = math.sin(math.radians(3.0 * lat)) * math.cos(math.radians(4.0 * lon))
    noise = rng.uniform(-0.3, 0.3)
    jet = 35.0 * math.exp(-(((z - 12000.0) / 5000.0) ** 2))
    if name == "gh":
        return z + 40.0 * wave + 8.0 * step + 30.0 * noise
    if name == "u":
        return 4.0 + jet + 6.0 * wave + 0.5 * step + noise
    return -2.0 + 0.3 * jet - 5.0 * wave - 0.4 * step + noise


def write(path, *, lats, lons, levels_pa, steps, names, packing, seed):
    rng = random.Random(seed)
    sample = eccodes.codes_grib_new_from_samples("GRIB2")
    with open(path, "wb") as out:
        for step in steps:
            for p_pa in levels_pa:
                for name in names:
                    h = eccodes.codes_clone(sample)
                    lon_first, lon_last = lons[0], lons[-1]
                    keys = {
                        "centre": 7,  # NCEP, as GFS
                        "dataDate": 20261130,
                        "dataTime": 600,
                        "gridType": "regular_ll",
                        "Ni": len(lons),
                        "Nj": len(lats),
                        "latitudeOfFirstGridPointInDegrees": lats[0],
                        "longitudeOfFirstGridPointInDegrees": lon_first,
                        "latitudeOfLastGridPointInDegrees": lats[-1],
                        "longitudeOfLastGridPointInDegrees": lon_last,
                        "iDirectionIncrementInDegrees": abs(lons[1] - lons[0]),
                        "jDirectionIncrementInDegrees": abs(lats[1] - lats[0]),
                        "jScansPositively": 1 if lats[1] > lats[0] else 0,
                        "discipline": 0,
                        "parameterCategory": PARAMS[name][0],
                        "parameterNumber": PARAMS[name][1],
                        "typeOfFirstFixedSurface": 100,
                        "scaleFactorOfFirstFixedSurface": 0,
                        "scaledValueOfFirstFixedSurface": int(p_pa),
                        "stepUnits": 1,
                        "forecastTime": step,
                    }
                    for k, v in keys.items():
                        eccodes.codes_set(h, k, v)
                    values = [
                        field(name, p_pa, step, lat, lon, rng) for lat in lats for lon in lons
                    ]
                    eccodes.codes_set(h, "packingType", packing)
                    # 16 bits, ecCodes choosing the binary scale: finer than 0.01 m/s.
                    eccodes.codes_set(h, "bitsPerValue", 16)
                    eccodes.codes_set_values(h, values)
                    eccodes.codes_write(h, out)
                    eccodes.codes_release(h)
    eccodes.codes_release(sample)


def axis(first: float, step: float, count: int) -> list:
    return [round(first + step * k, 6) for k in range(count)]


def fixtures() -> None:
    hpa = [1000, 850, 700, 500, 300, 200, 100, 50, 10, 1, 0.4]
    # name: latitudes, longitudes, levels (Pa), hours, variables, packing
    files = {
        "gfs_0p25_subset.grib2": (
            axis(40.0, -0.25, 17), axis(350.0, 0.25, 21), [p * 100 for p in hpa], [0, 3, 6],
            ["u", "v", "gh"], "grid_complex_spatial_differencing",
        ),
        "gfs_0p50_simple.grib2": (
            axis(36.0, 0.5, 9), axis(-10.0, 0.5, 11), [100000, 50000, 10000, 1000], [0, 6],
            ["u", "v", "gh"], "grid_simple",
        ),
        "no_hgt.grib2": (
            axis(36.0, 0.5, 3), axis(-10.0, 0.5, 3), [100000, 50000], [0], ["u", "v"],
            "grid_simple",
        ),
    }
    for seed, (name, (lats, lons, levels_pa, steps, names, packing)) in enumerate(files.items()):
        write(
            os.path.join(HERE, name),
            lats=lats,
            lons=lons,
            levels_pa=levels_pa,
            steps=steps,
            names=names,
            packing=packing,
            seed=seed + 1,
        )
    reads = {}
    # A dozen points of each made-up message; a thousand of the real GFS one (a 0.25° global
    # field from NOMADS: see README.md here).
    for sample, names in [
        (12, ["gfs_0p25_subset.grib2", "gfs_0p50_simple.grib2"]),
        (1000, ["gdas.t12z.pgrb2.0p25.f000.12"]),
    ]:
        out = subprocess.run(
            [sys.executable, os.path.join(HERE, "../tests/peers/read_grib.py"), "--sample",
             str(sample)] + names,
            cwd=HERE,
            check=True,
            capture_output=True,
            text=True,
        ).stdout
        read = json.loads(out)
        reads["eccodes"] = read["eccodes"]
        reads.setdefault("files", {}).update(read["files"])
    with open(os.path.join(HERE, "eccodes_reads.json"), "w") as f:
        json.dump(reads, f, indent=0)


# GFS' isobaric levels from 1000 to 3 hPa.
GFS_LEVELS_HPA = [
    1000, 975, 950, 925, 900, 850, 800, 750, 700, 650, 600, 550, 500, 450, 400, 350, 300,
    250, 200, 150, 100, 70, 50, 40, 30, 20, 15, 10, 7, 5, 3,
]


def gfs_subset(path: str, north: float, west: float, points: int, hours: list, seed: int) -> None:
    """A 0.25° subset of `points` × `points` from `north`, `west`, on GFS' 31 levels, at
    `hours`, in GFS' complex packing."""
    write(
        path,
        lats=axis(north, -0.25, points),
        lons=axis(west, 0.25, points),
        levels_pa=[p * 100 for p in GFS_LEVELS_HPA],
        steps=hours,
        names=["u", "v", "gh"],
        packing="grid_complex_spatial_differencing",
        seed=seed,
    )


def bench(path: str) -> None:
    """The benchmark's subset: 50 × 50 points at 0.25°, 31 levels, 20 forecast hours."""
    gfs_subset(path, 50.0, 0.0, 50, list(range(0, 60, 3)), seed=4)


def window_bench(path: str) -> None:
    """The launch window benchmark's subset: 20 × 20 points at 0.25°, 31 levels, forecast hours
    0 to 75 every 3 (a 72-hour window and the hours around it)."""
    gfs_subset(path, 46.0, 3.0, 20, list(range(0, 78, 3)), seed=5)


if __name__ == "__main__":
    if sys.argv[1:2] == ["--bench"]:
        bench(sys.argv[2])
    elif sys.argv[1:2] == ["--window-bench"]:
        window_bench(sys.argv[2])
    else:
        fixtures()
