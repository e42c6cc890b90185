"""``mutrose-cp verify`` measured: one whole process per property, start-up included.

* the delivery family (the reference's food-logistics delivery, n deliveries in one world:
  ``benchmarks/generate.py``) at n = 100, 1000 and 5000, with ``never uses(action ...)``, a
  ``count uses(method ...)`` and a conjunction;
* the vital-signs family (the reference's vital-signs monitoring, n rooms of two patients each)
  at n = 100 and 5000, with ``before`` over every room and patient;
* the coupled-sequence family (n visits to one kitchen that each may mark it busy or free and
  test it: one layered component) at n = 30 and 200, with a count over a method and over the
  state it ends in;
* the bundled example examples/hospital-disinfection, with a property that holds (``before``
  per room), one that fails (with its witness written) and a count.

Each run is ``python -m mutrose_cp verify ... -q --json-summary``, measured by the parent as the
other benchmarks are (wall time and peak memory, ``benchmarks/run.py:measure``), with the
package's bytecode compiled first.  Results go to ``benchmarks/results/verify.json``; the table
is printed as Markdown for docs/benchmarks.md.

    python benchmarks/verify.py           # every size, median of 3 runs each (about three minutes)
    python benchmarks/verify.py --quick   # n = 100 and the example
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
EXAMPLE = ROOT / "examples" / "hospital-disinfection"
DELIVERY = ["never uses(action deliver-to-table)", "count uses(method fetch-meal-with-robot)",
            "some uses(method table-deliver) and uses(method fetch-deliver)"]
VITAL_SIGNS = ["always before(task EnterRoom(?r, ?rm), task ApproachPatient(?s, ?rm, ?p))"]
COUPLED = ["count uses(method food-pickup-mark)", "count finally(busy(Kitchen))"]
HOSPITAL = ["always before(task ClearRoom(?r, ?rm), task UVDisinfection(?u, ?rm))",
            "never uses(action open-door)", "count uses(task SprayDisinfection)"]


def run(inputs: list[str], prop: str, work: Path, repeats: int) -> dict:
    """The median of ``repeats`` runs (time and memory), with the slowest and fastest: on a
    shared machine one run can take a third longer than the next."""
    cmd = [sys.executable, "-m", "mutrose_cp", "verify", *inputs, "--property", prop, "-q", "--json-summary",
           "--witness-dir", str(work / "witnesses")]
    samples = [measure(cmd, ROOT, 600) for _ in range(repeats)]
    seconds = [s["seconds"] for s in samples]
    return {"property": prop, "seconds": statistics.median(seconds), "fastest": min(seconds), "slowest": max(seconds),
            "runs": repeats, "peak_mb": statistics.median(s["peak_mb"] for s in samples),
            "status": next((s["status"] for s in samples if s["status"] not in ("ok", "exit 1")), samples[-1]["status"])}


def main(argv: list[str] | None = None) -> int:
    quick = quick_run(__doc__, argv)
    repeats = 1 if quick else 3
    rows = []
    with tempfile.TemporaryDirectory() as folder:
        work = Path(folder)
        for n in ([100] if quick else [100, 1000, 5000]):
            hddl, gm, cfg = generate("delivery", n, work / f"delivery-{n}")
            for prop in DELIVERY:
                rows.append({"mission": f"delivery n={n}", **run([str(hddl), str(gm), str(cfg)], prop, work, repeats)})
        for n in ([100] if quick else [100, 5000]):
            hddl, gm, cfg = generate("vital-signs", n, work / f"vital-signs-{n}")
            for prop in VITAL_SIGNS:
                rows.append({"mission": f"vital signs n={n}", **run([str(hddl), str(gm), str(cfg)], prop, work, repeats)})
        for n in ([30] if quick else [30, 200]):
            hddl, gm, cfg = generate("coupled-sequence", n, work / f"coupled-sequence-{n}")
            for prop in COUPLED:
                rows.append({"mission": f"coupled sequence n={n}", **run([str(hddl), str(gm), str(cfg)], prop, work, repeats)})
        for prop in HOSPITAL:
            rows.append({"mission": "examples/hospital-disinfection", **run([str(EXAMPLE)], prop, work, repeats)})
    out = ROOT / "benchmarks" / "results" / ("verify-quick.json" if quick else "verify.json")
    out.write_text(json.dumps(rows, indent=1) + "\n")
    print("| mission | property | status | time (median) | fastest–slowest | peak memory |\n|---|---|---|---|---|---|")
    for r in rows:
        print(f"| {r['mission']} | `{r['property']}` | {r['status']} | {r['seconds']:.2f} s | "
              f"{r['fastest']:.2f}–{r['slowest']:.2f} s | {r['peak_mb']:.0f} MB |")
    return 0 if all(r["status"] in ("ok", "exit 1") for r in rows) else 1


if __name__ == "__main__":
    sys.exit(main())
