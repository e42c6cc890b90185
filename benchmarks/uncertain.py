"""Uncertain worlds measured: one whole process per command, start-up included.

The delivery family (the reference's food-logistics delivery, n deliveries in one world:
``benchmarks/generate.py``) with one uncertain fact per delivery, whether the patient can fetch
the meal (``Patient<i>.can_fetch``, true with probability 0.9), at n = 100, 1000 and 5000:
``count --robust``, ``count --possible``, ``decompose --most-likely`` (its output written) and
``explain``; and the bundled example examples/medication-round.

Facts the goal model reads expand the mission once per world: the vital-signs family (n rooms
of two patients) with whether Room0 and Room1 are occupied uncertain (the query of the rooms to
visit reads it: 4 worlds) and whether each patient is available (2n facts the domain reads), at
n = 100 and 1000; and examples/medication-round with knowledge/uncertain-orders.json (whether
Room204's dose is due: 2 worlds).

Each run is ``python -m mutrose_cp ... -q``, measured by the parent as the other benchmarks are
(wall time and peak memory, ``benchmarks/run.py:measure``), with the package's bytecode
compiled first.  Results go to ``benchmarks/results/uncertain.json``; the table is printed as
Markdown for docs/benchmarks.md.

    python benchmarks/uncertain.py           # every size, delivery n=5000 the median of 3 (about two minutes)
    python benchmarks/uncertain.py --quick   # n = 100 and the example
"""
from __future__ import annotations

import json
import statistics
import sys
import tempfile
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from generate import generate  # noqa: E402
from run import measure, quick_run  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "medication-round"
COMMANDS = {"count --robust": ["count", "--robust"], "count --possible": ["count", "--possible"],
            "decompose --most-likely": ["decompose", "--most-likely"], "explain": ["explain"]}


def uncertainty(n: int, path: Path) -> Path:
    """One uncertain fact per delivery: its patient can fetch the meal, with probability 0.9."""
    path.write_text(json.dumps({"uncertain": [{"entity": f"Patient{i}", "attribute": "can_fetch", "probability": 0.9}
                                              for i in range(1, n + 1)]}))
    return path


def occupancy(n: int, path: Path) -> Path:
    """Room0 and Room1 occupied or not (read by the goal model's query), and every patient
    available or not (read by the domain)."""
    rooms = [{"entity": "Room0", "attribute": "is_occupied", "probability": 0.7},
             {"entity": "Room1", "attribute": "is_occupied", "probability": 0.5}]
    patients = [{"entity": f"Patient{i}", "attribute": "available", "probability": 0.9} for i in range(1, 2 * n + 1)]
    path.write_text(json.dumps({"uncertain": rooms + patients}))
    return path


def run(inputs: list[str], name: str, work: Path, repeats: int = 1) -> dict:
    """The median of ``repeats`` runs (time and memory), with the fastest and slowest: one run
    on a shared machine can be a second off."""
    argv = COMMANDS[name]
    out = ["-o", str(work / "plan.json")] if argv[0] == "decompose" else []
    samples = [measure([sys.executable, "-m", "mutrose_cp", argv[0], *inputs, *argv[1:], *out, "-q"], ROOT, 600)
               for _ in range(repeats)]
    seconds = [s["seconds"] for s in samples]
    return {"command": name, "seconds": statistics.median(seconds), "fastest": min(seconds), "slowest": max(seconds),
            "runs": repeats, "peak_mb": statistics.median(s["peak_mb"] for s in samples),
            "status": "ok" if all(s["status"] == "ok" for s in samples) else samples[-1]["status"]}


def main(argv: list[str] | None = None) -> int:
    quick = quick_run(__doc__, argv)
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        for n in ([100] if quick else [100, 1000, 5000]):
            hddl, gm, cfg = generate("delivery", n, work / f"delivery-{n}")
            facts = uncertainty(n, work / f"delivery-{n}" / "uncertain.json")
            for name in COMMANDS:  # the target's sizes: the median of three runs
                inputs = [str(hddl), str(gm), str(cfg), "--uncertain", str(facts)]
                rows.append({"mission": f"delivery n={n}", "uncertain_facts": n,
                             **run(inputs, name, work, 3 if n == 5000 else 1)})
        for name in COMMANDS:
            rows.append({"mission": "examples/medication-round", "uncertain_facts": 2, **run([str(EXAMPLE)], name, work)})
        for n in ([100] if quick else [100, 1000]):
            hddl, gm, cfg = generate("vital-signs", n, work / f"vital-signs-{n}")
            facts = occupancy(n, work / f"vital-signs-{n}" / "uncertain.json")
            for name in COMMANDS:
                inputs = [str(hddl), str(gm), str(cfg), "--uncertain", str(facts)]
                rows.append({"mission": f"vital signs n={n}, 4 worlds", "uncertain_facts": 2 + 2 * n,
                             **run(inputs, name, work)})
        orders = EXAMPLE / "knowledge" / "uncertain-orders.json"
        for name in COMMANDS:
            rows.append({"mission": "examples/medication-round, 2 worlds", "uncertain_facts": 3,
                         **run([str(EXAMPLE), "--uncertain", str(orders)], name, work)})
    out = ROOT / "benchmarks" / "results" / ("uncertain-quick.json" if quick else "uncertain.json")
    out.write_text(json.dumps(rows, indent=1) + "\n")
    print("| mission | uncertain facts | command | status | time | peak memory |\n|---|---|---|---|---|---|")
    for r in rows:
        spread = f" ({r['fastest']:.2f}-{r['slowest']:.2f})" if r["runs"] > 1 else ""
        print(f"| {r['mission']} | {r['uncertain_facts']} | `{r['command']}` | {r['status']} | {r['seconds']:.2f} s"
              f"{spread} | {r['peak_mb']:.0f} MB |")
    return 0 if all(r["status"] == "ok" for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
