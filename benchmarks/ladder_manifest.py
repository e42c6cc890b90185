"""Write the benchmark ladder of one family, or the dissertation's experiment, as a
``mutrose-cp batch`` manifest.

The missions are generated as ``benchmarks/run.py`` generates them (``generate.py``), and the
manifest lists the same runs: every size of the ladder, every decomposer setting of the family
(``RUNS``), each up to its largest useful size.  Each job writes its own output file, so the
same manifest run alone, on the local pool or on Ray can be compared file by file.

``dissertation`` lists the runs of the dissertation's scalability table (Table 5.2) on its own
worlds (the reference corpus's ``scalability/``): both algorithms on every configuration of the
three families.

    python benchmarks/ladder_manifest.py delivery ladder/ --quick    # sizes 2, 10, 100
    python benchmarks/ladder_manifest.py delivery ladder/            # the full ladder
    mutrose-cp batch ladder/delivery.json --time-limit 120           # or: --ray [ADDRESS]
    python benchmarks/ladder_manifest.py dissertation table/
    mutrose-cp batch table/dissertation.json --time-limit 1200 --memory-mb 16000
"""
from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from generate import REFERENCE, generate  # noqa: E402
from run import DISSERTATION, EXTRA_SIZES, FULL_LADDER, QUICK_LADDER, RUNS  # noqa: E402


def ladder_jobs(family: str, sizes: list[int], folder: Path) -> list[dict]:
    """The jobs of the ladder, with paths relative to ``folder`` (where the manifest is written)
    for the generated files and absolute ones for the reference domain and goal model."""
    jobs = []
    for n in sizes:
        hddl, gm, cfg = generate(family, n, folder / "missions")
        inputs = [str(p.resolve()) if not p.resolve().is_relative_to(folder.resolve())
                  else str(p.resolve().relative_to(folder.resolve())) for p in (hddl, gm, cfg)]
        for label, extra, max_n in RUNS[family]:
            if max_n is not None and n > max_n:
                continue
            job = {"id": f"{family}-{n}-{label}"}
            if extra[:1] == ["count"]:
                job.update(command="count", inputs=inputs, options=extra[1:])
            else:
                job.update(command="decompose", inputs=inputs, options=extra, output=f"out/{family}-{n}-{label}.json")
            jobs.append(job)
    return jobs


def dissertation_jobs() -> list[dict]:
    """Both algorithms on every configuration of the dissertation's scalability folders, read
    as the benchmarks read them (``--lenient-xml``: one delivery world leaves a record open)."""
    jobs = []
    for family, (folder, template, _gm, sizes) in DISSERTATION.items():
        mission = REFERENCE / folder
        for i, n in enumerate(sizes):
            if not (mission / "configuration" / template.format(i=i)).exists():
                continue
            for label, extra in (("exploratory", ["--algorithm", "exploratory"]), ("cpsat", [])):
                jobs.append({"id": f"{family}-{n}-{label}", "command": "decompose", "inputs": [str(mission)],
                             "options": ["--config", template.format(i=i), "--lenient-xml", *extra],
                             "output": f"out/{family}-{n}-{label}.json"})
    return jobs


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("family", choices=[*RUNS, "dissertation"])
    parser.add_argument("folder", type=Path, help="where the missions and the manifest FAMILY.json are written")
    parser.add_argument("--quick", action="store_true", help="the quick ladder (2, 10, 100), as run.py --quick")
    parser.add_argument("--sizes", type=int, nargs="+", help="these sizes instead of a ladder")
    parser.add_argument("--max-n", type=int, help="stop the ladder at this size")
    args = parser.parse_args(argv)
    args.folder.mkdir(parents=True, exist_ok=True)
    manifest = args.folder / f"{args.family}.json"
    if args.family == "dissertation":
        jobs = dissertation_jobs()
    else:
        jobs = ladder_jobs(args.family, _sizes(args), args.folder)
    manifest.write_text(json.dumps({"jobs": jobs}, indent=1) + "\n", encoding="utf-8")
    print(manifest)
    return 0


def _sizes(args: argparse.Namespace) -> list[int]:
    if args.sizes:
        sizes = sorted(set(args.sizes))
    else:
        ladder = QUICK_LADDER if args.quick else FULL_LADDER
        extra = [] if args.quick else EXTRA_SIZES.get(args.family, [])
        sizes = sorted(set(ladder) | {k for k in extra if k <= max(ladder)})
    return [n for n in sizes if args.max_n is None or n <= args.max_n]


if __name__ == "__main__":
    sys.exit(main())
