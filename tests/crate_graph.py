#!/usr/bin/env python3
"""The crate graph, checked: every workspace crate's normal and build dependencies on other
workspace crates are among those the table below allows it (dev-dependencies are free: a test
may fly the simulator or talk over the link to check a crate from outside).

Why: the layers only stay apart if a `use` of the wrong crate fails CI. The onboard guidance
must not carry the simulator's physics, nor the MAVLink link guidance, and what several crates
share lives at the bottom in `stx-types`. The graph comes from `cargo metadata --no-deps`
(declared dependencies, not what the code happens to use), so a dependency left in a
Cargo.toml after its last `use` is gone still counts.

Run from the repository root: `python3 tests/crate_graph.py`; exits 1 naming every edge that is
not allowed, and every crate the table does not place.
"""

import json
import subprocess
import sys

# Crate -> the stx crates it may depend on, each rule with why.
ALLOWED: dict[str, set[str]] = {
    # The shared vocabulary (mission enums, frame, zones, plan points, controls, angles, air):
    # at the bottom, so anything may use it and it uses nothing of ours.
    "stx-types": set(),
    # The MCAP recorder writes JSON it is handed: it needs no stx type to do so.
    "stx-record": set(),
    # Forecast files (GFS GRIB2, soundings) to wind levels: plain numbers out, so no stx type;
    # its callers make their forecast rows of them.
    "stx-weather": set(),
    # The 14-DOF flight model: physics over the shared types, nothing onboard or on the link.
    "stx-dynamics": {"stx-types"},
    # Onboard guidance, navigation and control: runs on the drone, so no simulator physics.
    "stx-gnc": {"stx-types"},
    # The sans-io MAVLink link: carries modes and plan points, so no guidance behind them.
    "stx-link": {"stx-types"},
    # The link's tokio adapter: puts stx-link on sockets and serial ports, nothing more.
    "stx-link-tokio": {"stx-link"},
    # The simulated drone: the flight model as truth, onboard GNC, and the link to a station.
    "stx-sim": {"stx-types", "stx-dynamics", "stx-gnc", "stx-link", "stx-link-tokio"},
    # Offline analysis of flights: flies the model and the simulator; reads recordings as
    # files, not through the link.
    "stx-analysis": {"stx-types", "stx-dynamics", "stx-gnc", "stx-sim"},
    # The ground station: GNC replica and estimator, the link and its adapter, the recorder, and
    # the flight model's vehicle file (the Lab edits it); the simulated drone only in its tests.
    "stx-station": {
        "stx-types", "stx-dynamics", "stx-gnc", "stx-link", "stx-link-tokio", "stx-record",
        "stx-weather",
    },
    # Station beside simulated drone, checked against truth: needs both sides.
    "stx-agreement": {
        "stx-types", "stx-dynamics", "stx-gnc", "stx-link", "stx-sim", "stx-station",
    },
    # The Lab's jobs: the station's Lab decides, this flies the simulator and the analysis for
    # it, and reads the recordings it compares and identifies from.
    "stx-lab": {
        "stx-types", "stx-dynamics", "stx-gnc", "stx-sim", "stx-analysis", "stx-station",
        "stx-record",
    },
    # The measurements behind `stx bench`: drives the daemon, the simulated drone and the Lab
    # from outside, and flies the agreement campaign.
    "stx-bench": {
        "stx-types", "stx-gnc", "stx-link-tokio", "stx-sim", "stx-station", "stx-agreement",
        "stx-lab",
    },
    # The command-line binary at the top: it wires every crate together.
    "stx": {
        "stx-types", "stx-dynamics", "stx-gnc", "stx-link", "stx-link-tokio", "stx-sim",
        "stx-station", "stx-record", "stx-analysis", "stx-agreement", "stx-lab", "stx-bench",
        "stx-weather",
    },
}


def workspace_edges() -> dict[str, set[str]]:
    out = subprocess.run(
        ["cargo", "metadata", "--format-version", "1", "--no-deps"],
        check=True,
        capture_output=True,
        text=True,
    ).stdout
    packages = json.loads(out)["packages"]
    members = {p["name"] for p in packages}
    return {
        p["name"]: {
            d["name"]
            for d in p["dependencies"]
            # kind: None for normal, "build", or "dev".
            if d["name"] in members and d["kind"] != "dev" and d["name"] != p["name"]
        }
        for p in packages
    }


def problems(edges: dict[str, set[str]]) -> list[str]:
    found = []
    for crate in sorted(edges):
        if crate not in ALLOWED:
            found.append(
                f"{crate} is not in tests/crate_graph.py's table: add it with the stx crates "
                "it may depend on and why"
            )
            continue
        for dep in sorted(edges[crate] - ALLOWED[crate]):
            allowed = ", ".join(sorted(ALLOWED[crate])) or "no stx crate"
            found.append(f"{crate} → {dep} is not allowed ({crate} may depend on {allowed})")
    return found


def main() -> int:
    found = problems(workspace_edges())
    for p in found:
        print(p, file=sys.stderr)
    if found:
        print(
            "the crate graph has edges it must not have (above); see tests/crate_graph.py "
            "for why each crate may depend on what it may",
            file=sys.stderr,
        )
        return 1
    print(f"crate graph: {len(ALLOWED)} crates, every edge allowed")
    return 0


if __name__ == "__main__":
    sys.exit(main())
