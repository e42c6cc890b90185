"""The allocation benchmark: deliveries on a grid of places, fleets of 5 to 50 robots.

Each instance is the item-delivery mission of ``examples/item-delivery`` (its domain, goal model
and configuration, read by path) with a generated world and fleet:

* a square grid of locations 20 m apart, with ``x``/``y`` coordinates; a seeded random third
  of them are staffed (an item is handed to a person there), the others have a drop box;
* ``n`` deliveries between random pickup points and destinations (seed 0), each one an OR
  between "one robot fetches the item and hands it over" and "staff load it, any robot hands
  it over" (4 task instances, 2 of them executed);
* ``r`` robots at random places of the grid, a third of each kind: pickers (manipulation),
  talkers (communication) and all-rounders (both), speeds 0.8 to 1.2 m/s.

Every size is one ``allocate`` run (``--workers 2``, the machine's cores) in a child process
that records the objective and the bounds whenever they improve; results go to
``benchmarks/results/allocation.json`` and ``docs/benchmarks-allocation.md``.

    python benchmarks/allocation.py                 # the full ladder (about 10 minutes)
    python benchmarks/allocation.py --quick         # one tiny instance (CI smoke test)
    python benchmarks/allocation.py --one N R S     # one instance, in this process (JSON line)
"""
from __future__ import annotations

import argparse
import json
import os
import random
import shutil
import subprocess
import sys
import tempfile
import time
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "item-delivery"
RESULTS = ROOT / "benchmarks" / "results"
DOC = ROOT / "docs" / "benchmarks-allocation.md"

# (deliveries, robots, time limit in seconds)
FULL = [(10, 5, 60), (40, 10, 60), (80, 10, 60), (200, 25, 60), (500, 50, 60)]
QUICK = [(4, 2, 10)]
SPACING = 20  # metres between neighbouring grid places
DURATIONS = {"navigate": 0, "pick-item": 30, "request-loading": 45, "give-item": 20, "drop-item": 10}


def grid_side(n: int) -> int:
    """Places per side: about one place per two deliveries, at least 3 x 3."""
    side = 3
    while side * side * 2 < n:
        side += 1
    return side


def generate(n: int, robots: int, folder: Path, seed: int = 0) -> tuple[Path, Path]:
    """Write the mission folder and its fleet file; returns (mission folder, fleet file)."""
    rng = random.Random(seed)
    mission = folder / f"deliveries-{n}-robots-{robots}"
    shutil.copytree(EXAMPLE, mission, ignore=shutil.ignore_patterns("output", "fleet.json"))
    side = grid_side(n)
    places = [(f"P{i}_{j}", i * SPACING, j * SPACING) for i in range(side) for j in range(side)]
    staffed = {name for name, _, _ in places if rng.random() < 1 / 3}
    lines = ["<?xml version='1.0' encoding='utf-8'?>", "<world_db>"]
    for name, x, y in places:
        lines.append(f"  <Location><name>{name}</name><x>{x}</x><y>{y}</y><reachable>True</reachable>"
                     f"<staffed>{name in staffed}</staffed><has_drop_box>{name not in staffed}</has_drop_box></Location>")
    for k in range(n):
        pickup, destination = rng.sample([p[0] for p in places], 2)
        lines.append(f"  <Delivery><name>D{k + 1}</name><item>Item {k + 1}</item><pickup>{pickup}</pickup>"
                     f"<destination>{destination}</destination><is_collected>False</is_collected>"
                     "<is_delivered>False</is_delivered></Delivery>")
    lines.append("</world_db>")
    (mission / "knowledge" / "world_db.xml").write_text("\n".join(lines) + "\n", encoding="utf-8")
    kinds = [["navigation", "manipulation"], ["navigation", "communication"],
             ["navigation", "manipulation", "communication"]]
    fleet = {"robots": [{"name": f"r{i + 1}", "capabilities": kinds[i % 3], "start": rng.choice(places)[0],
                         "speed": round(rng.uniform(0.8, 1.2), 2)} for i in range(robots)],
             "durations": {"default": 10, "actions": DURATIONS}}
    fleet_path = folder / f"fleet-{n}-{robots}.json"
    fleet_path.write_text(json.dumps(fleet, indent=1) + "\n", encoding="utf-8")
    return mission, fleet_path


def run_one(n: int, robots: int, limit: float, workers: int) -> dict:
    """Allocate one instance in this process; the trace of (seconds, objective, bound)."""
    from mutrose_cp.allocate import AllocationOptions, Fleet
    from mutrose_cp.api import Mission, find_mission_files

    trace: list[tuple[float, float | None, float]] = []
    with tempfile.TemporaryDirectory() as tmp:
        folder, fleet_path = generate(n, robots, Path(tmp))
        started = time.perf_counter()
        mission = Mission.load(*find_mission_files(folder))
        fleet = Fleet.read(fleet_path)
        allocation = mission.allocate(fleet, AllocationOptions(time_limit=limit, workers=workers),
                                      lambda p: trace.append((round(p.seconds, 2), p.objective, p.bound)))
        total = time.perf_counter() - started
    return {"deliveries": n, "robots": robots, "time_limit": limit, "workers": workers,
            "jobs": len(allocation.problem.jobs), "status": allocation.status, "restricted": allocation.restricted,
            "objective": allocation.objective,
            "cp_bound": allocation.cp_bound, "lp_bound": allocation.lp_value, "gap": allocation.gap,
            "lp_gap": allocation.lp_gap, "lp_status": allocation.lp.status if allocation.lp else None,
            "load_bound": allocation.load_value, "load_gap": allocation.load_gap, "travel": allocation.schedule.travel,
            "seconds": {k: round(v, 2) for k, v in allocation.seconds.items()}, "total_seconds": round(total, 2),
            "trace": _thin(trace)}


def _thin(trace: list[tuple[float, float | None, float]]) -> list[tuple[float, float | None, float]]:
    """The points where the objective or the bound changed (a bound callback can repeat)."""
    out: list[tuple[float, float | None, float]] = []
    for point in trace:
        if not out or point[1:] != out[-1][1:]:
            out.append(point)
    return out


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="one tiny instance (CI smoke test)")
    parser.add_argument("--one", nargs=3, type=float, metavar=("N", "R", "S"), help="run one instance here")
    parser.add_argument("--workers", type=int, default=2)
    parser.add_argument("--report", action="store_true", help="only rewrite the report from the recorded results")
    args = parser.parse_args(argv)
    if args.report:
        report(json.loads((RESULTS / "allocation.json").read_text(encoding="utf-8")))
        return 0
    if args.one:
        n, r, s = args.one
        print(json.dumps(run_one(int(n), int(r), s, args.workers)))
        return 0
    rows = []
    for n, r, limit in QUICK if args.quick else FULL:
        run = subprocess.run([sys.executable, __file__, "--one", str(n), str(r), str(limit), "--workers",
                              str(args.workers)], capture_output=True, text=True, timeout=limit * 4 + 120)
        if run.returncode != 0:
            rows.append({"deliveries": n, "robots": r, "time_limit": limit, "error": run.stderr.strip()[-500:]})
        else:
            rows.append(json.loads(run.stdout.strip().splitlines()[-1]))
        row = rows[-1]
        print(f"{n:4} deliveries {r:3} robots: {row.get('status', 'ERROR'):8} objective {row.get('objective')} "
              f"bound {row.get('cp_bound')} LP {row.get('lp_bound')} load {row.get('load_bound')} gap {row.get('gap')}",
              flush=True)
    if args.quick:
        return 0 if all("error" not in r for r in rows) else 1
    RESULTS.mkdir(parents=True, exist_ok=True)
    data = {"date": time.strftime("%Y-%m-%d"), "cpus": os.cpu_count(), "rows": rows}
    (RESULTS / "allocation.json").write_text(json.dumps(data, indent=1) + "\n", encoding="utf-8")
    report(data)
    return 0


CHECKPOINTS = (5, 15, 30, 60)
TARGETS = """Targets (issue #14): 80 deliveries x 10 robots proven within 2 % in 60 s; 500 deliveries x 50
robots with a feasible schedule in 60 s and its gap reported.  The time limit is the whole
allocation's (load bound, LP bound, model and search); "total s" also counts reading the mission.
An LP that Clarabel did not solve within its share gives no bound ("not solved (MaxTime)")."""


def _gap(value: float | None) -> str:
    return "-" if value is None else f"{100 * value:.1f} %"


def _at(trace: list, seconds: float) -> str:
    """The objective and bound reached by ``seconds``."""
    seen = [p for p in trace if p[0] <= seconds]
    if not seen:
        return "-"
    _, objective, bound = seen[-1]
    return f"{'-' if objective is None else round(objective)} / {bound:g}"


def report(data: dict) -> None:
    """Write ``docs/benchmarks-allocation.md`` from the recorded results."""
    workers = sorted({r["workers"] for r in data["rows"] if "workers" in r})
    command = "python benchmarks/allocation.py" + "".join(f" --workers {w}" for w in workers if w != 2)
    lines = ["# Allocation benchmark", "",
             f"Generated by `{command}` on {data['date']} ({data['cpus']} cores, shared with "
             "other work while it ran: times are indicative). " + __doc__.split("\n\n")[1].replace("\n", " "), "",
             TARGETS, "",
             "| deliveries | robots | jobs | status | makespan | CP-SAT bound | LP bound | load bound | gap (CP-SAT) "
             "| gap (LP) | gap (load) | load s | warm start s | LP s | model s | search s | total s |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        if "error" in r:
            lines.append(f"| {r['deliveries']} | {r['robots']} | | error: {r['error'][-120:]} |" + " |" * 13)
            continue
        sec = r["seconds"]
        bound = "-" if r["cp_bound"] is None else f"{r['cp_bound']:g}"
        lp = f"not solved ({r.get('lp_status')})" if r["lp_bound"] is None else f"{r['lp_bound']:.1f}"
        load = "-" if r.get("load_bound") is None else f"{r['load_bound']:g}"
        lines.append(f"| {r['deliveries']} | {r['robots']} | {r['jobs']} | {r['status']}"
                     f"{' (restricted)' if r.get('restricted') else ''} | {r['objective']} | {bound} | {lp} | {load} | "
                     f"{_gap(r['gap'])} | {_gap(r['lp_gap'])} | {_gap(r.get('load_gap'))} | {sec.get('load', 0):.1f} | "
                     f"{sec.get('warm', 0):.1f} | "
                     f"{sec.get('lp', 0):.1f} | {sec.get('model', 0):.1f} | {sec.get('search', 0):.1f} | "
                     f"{r.get('total_seconds', 0):.1f} |")
    lines += ["", "Objective / CP-SAT bound over time (seconds of search):", "",
              "| deliveries x robots | " + " | ".join(f"{t} s" for t in CHECKPOINTS) + " |",
              "|---|" + "---|" * len(CHECKPOINTS)]
    for r in data["rows"]:
        if "error" not in r:
            lines.append(f"| {r['deliveries']} x {r['robots']} | " + " | ".join(_at(r["trace"], t) for t in CHECKPOINTS)
                         + " |")
    limits = RESULTS / "allocation-limits.json"
    if limits.exists():
        lines += limits_lines(json.loads(limits.read_text(encoding="utf-8")))
    DOC.write_text("\n".join(lines) + "\n", encoding="utf-8")


def limits_lines(data: dict) -> list[str]:
    """The section of ``benchmarks/allocation_limits.py``'s runs: the time limit on large inputs."""
    lines = ["", "## The time limit on large inputs", "",
             f"Generated by `python benchmarks/allocation_limits.py` on {data['date']} ({data['machine'].get('cpus')} "
             "cores, bytecode compiled first). Ten deliveries of the grid above, `allocate --time-limit "
             f"{data['rows'][0]['time_limit']:g}` in a process of its own (its wall time and peak memory, start-up, "
             "reading the fleet and writing the schedule included); the time limit counts from the start of the "
             "command. Each phase is done, cut by its share of the limit, or skipped when no time is left for it "
             "(`--json-summary` key `phases`). Before the phases were budgeted, the same command took 54 s on "
             "the 3,000 robots, more than 420 s on the 110,000 (stopped there) and 66 s on the road network.", "",
             "| instance | exit | wall s | peak MB | status | makespan | problem | load | warm start | LP | model "
             "| search |",
             "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for r in data["rows"]:
        phases = {p["phase"]: p for p in r.get("phases", [])}
        cells = [f"{phases[n]['status']} {phases[n]['seconds']:.2f}" if n in phases else "-"
                 for n in ("problem", "load", "warm", "lp", "model", "search")]
        lines.append(f"| {r['instance']} | {r['exit']} | {r['seconds']:.2f} | {r['peak_mb']:.0f} | "
                     f"{r.get('status', r.get('error', '-'))} | {r.get('objective', '-')} | " + " | ".join(cells) + " |")
    return lines


if __name__ == "__main__":
    sys.exit(main())
