"""The allocation's time limit on large inputs: `allocate --time-limit 5` on large fleets and a large road network.

Each instance is ten deliveries of the allocation benchmark (``benchmarks/allocation.py``: the
item-delivery mission on a generated grid of places) with

* a fleet of 3,000 robots;
* a fleet of 110,000 robots;
* 600 robots, each starting at its own junction of a road network of 600 junctions (a grid of
  roads in ``travel.times``, every place of the world joined to two junctions).

Each is one ``python -m mutrose_cp allocate ... --time-limit 5`` process, measured by this
parent (wall time and peak memory, ``mutrose_cp.compare.measure``), with the package's bytecode compiled
first as an installed package has it.  The phases the command reports (``--json-summary``:
done, cut by their share of the limit, or skipped) are recorded with the times.  Results go to
``benchmarks/results/allocation-limits.json`` and ``docs/benchmarks-allocation.md``.

    python benchmarks/allocation_limits.py            # the three instances (about a minute)
    python benchmarks/allocation_limits.py --limit 2  # another time limit
"""
from __future__ import annotations

import argparse
import json
import random
import re
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
import allocation  # noqa: E402
from run import compile_bytecode, machine  # noqa: E402

from mutrose_cp.compare.measure import Measurement, run_measured  # noqa: E402

LIMITS = allocation.RESULTS / "allocation-limits.json"
DELIVERIES = 10
JUNCTIONS = 600


def road_network(mission: Path, fleet_path: Path, junctions: int, seed: int = 1) -> None:
    """Replace the fleet's travel by a grid of roads between ``junctions`` junctions (5 to 20
    time units each), every world place joined to two of them, and start each robot at a
    junction of its own (in turn, when there are more robots)."""
    rng = random.Random(seed)
    data = json.loads(fleet_path.read_text(encoding="utf-8"))
    places = re.findall(r"<Location><name>([^<]+)</name>", (mission / "knowledge" / "world_db.xml").read_text())
    side = max(1, int(junctions ** 0.5))
    names = [f"J{k}" for k in range(junctions)]
    times: dict[str, dict[str, int]] = {}
    for k, name in enumerate(names):
        if (k + 1) % side and k + 1 < junctions:
            times.setdefault(name, {})[names[k + 1]] = rng.randint(5, 20)
        if k + side < junctions:
            times.setdefault(name, {})[names[k + side]] = rng.randint(5, 20)
    for place in places:
        times[place] = {junction: rng.randint(5, 20) for junction in rng.sample(names, 2)}
    data["travel"] = {"times": times}
    for k, robot in enumerate(data["robots"]):
        robot["start"] = names[k % junctions]
    fleet_path.write_text(json.dumps(data), encoding="utf-8")


def instances(folder: Path) -> list[tuple[str, Path, Path]]:
    """(label, mission folder, fleet file) of each instance, written in ``folder``."""
    out = []
    for robots in (3_000, 110_000):
        mission, fleet = allocation.generate(DELIVERIES, robots, folder / f"robots-{robots}")
        out.append((f"{robots:,} robots", mission, fleet))
    mission, fleet = allocation.generate(DELIVERIES, JUNCTIONS, folder / "junctions")
    road_network(mission, fleet, JUNCTIONS)
    out.append((f"{JUNCTIONS} junctions, {JUNCTIONS} robots", mission, fleet))
    return out


def run_instance(label: str, mission: Path, fleet: Path, limit: float, folder: Path) -> dict:
    """One measured ``allocate`` process; its row of results."""
    cmd = [sys.executable, "-m", "mutrose_cp", "allocate", str(mission), "--fleet", str(fleet), "-o",
           str(folder / "out.json"), "--schedule", str(folder / "schedule.json"), "--time-limit", str(limit), "-q",
           "--json-summary"]
    measured = run_measured(cmd, allocation.ROOT, limit * 20 + 60)
    row = {"instance": label, "time_limit": limit, **measure_fields(measured)}
    summary = measured.summary or {}
    if "objective" in summary:
        row.update(status=summary["objective"]["status"], objective=summary["objective"]["value"],
                   phases=summary.get("phases", []), command_seconds=summary.get("seconds"))
    elif measured.stderr.strip():
        row["error"] = measured.stderr.strip().splitlines()[-1][:300]
    return row


def measure_fields(measured: Measurement) -> dict:
    return {"exit": measured.exit_status, "seconds": round(measured.seconds, 2), "peak_mb": round(measured.peak_mb, 1)}


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--limit", type=float, default=5.0, help="the time limit of each run (default 5 s)")
    args = parser.parse_args(argv)
    compile_bytecode()  # an installed package has its bytecode; this machine may not write it
    rows = []
    with tempfile.TemporaryDirectory(prefix="mutrose-limits-") as tmp:
        for label, mission, fleet in instances(Path(tmp)):
            rows.append(run_instance(label, mission, fleet, args.limit, Path(tmp)))
            row = rows[-1]
            print(f"{label:28} exit {row['exit']} {row['seconds']:6.2f} s {row['peak_mb']:7.1f} MB "
                  f"{row.get('status', row.get('error'))}", flush=True)
    allocation.RESULTS.mkdir(parents=True, exist_ok=True)
    data = {"date": time.strftime("%Y-%m-%d"), "machine": machine(), "rows": rows}
    LIMITS.write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    allocation.report(json.loads((allocation.RESULTS / "allocation.json").read_text(encoding="utf-8")))
    return 0 if all(r["exit"] == 0 for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
