"""Run the benchmarks: scaled mission families, both algorithms, time and peak memory.

Every measurement is a separate ``python -m mutrose_cp decompose`` process; its wall time and
peak resident memory are measured by this parent process (``os.wait4``).  Results go to
``benchmarks/results/<name>.json``; ``benchmarks/report.py`` turns them into
``docs/benchmarks.md`` and its plots.

    python benchmarks/run.py --quick          # CI smoke run, under two minutes
    python benchmarks/run.py                  # the full ladder, median of 3 runs per size, and
                                              # docs/benchmarks.md with its plots (about 20 min)
"""
from __future__ import annotations

import argparse
import json
import os
import platform
import shutil
import statistics
import subprocess
import sys
import tempfile
import time
from pathlib import Path

sys.path.insert(0, str(Path(__file__).resolve().parent))
from generate import REFERENCE, generate  # noqa: E402

from mutrose_cp.compare.measure import run_measured  # noqa: E402
from mutrose_cp.io.mission_files import find_mission_files  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
RESULTS = ROOT / "benchmarks" / "results"

# the original C++ tool, a benchmark peer where it is installed (never shipped, found by path)
ORIGINAL = Path(os.environ.get("MUTROSE_ORIGINAL", ROOT.parent / "shared" / "original" / "MutroseMissionDecomposer"))
# the largest n worth giving the original per family: it lists every decomposition in memory
ORIGINAL_MAX_N = {"delivery": 12, "pickup": 10, "vital-signs": None, "coupled": 12, "coupled-sequence": 12}

FULL_LADDER = [2, 3, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10000]
QUICK_LADDER = [2, 10, 100]

# (label, extra arguments, largest n worth running) per family; every run also gets
# ``-q --json-summary -o <tmp>``.
RUNS = {
    "delivery": [
        ("exploratory", ["--algorithm", "exploratory"], 12),
        ("cpsat", [], None),  # exact count + the first 1000 decompositions
        ("cpsat-all", ["--limit", "0"], 10),  # every decomposition written
        ("cpsat-optimize", ["--optimize"], None),
    ],
    "pickup": [
        ("exploratory", ["--algorithm", "exploratory"], 10),
        ("cpsat", [], None),
    ],
    "vital-signs": [
        ("exploratory", ["--algorithm", "exploratory"], None),
        ("cpsat", ["--limit", "1"], None),
    ],
    # one component coupled through a shared fact (2^(n+1) - 1 solutions): solved block by block,
    # the parallel conflict passed from delivery to delivery as a chain (solve/layered.py)
    "coupled": [
        ("count", ["count"], None),
        ("cpsat-optimize", ["--optimize"], None),
    ],
    # one component of tasks in sequence that share the kitchen's state (about 2.414^n solutions):
    # solved block by block as a layered graph, counted, listed and optimised without enumerating
    "coupled-sequence": [
        ("exploratory", ["--algorithm", "exploratory"], 12),
        ("count", ["count"], None),
        ("cpsat", [], None),
        ("cpsat-optimize", ["--optimize"], None),
    ],
}
EXTRA_SIZES = {"coupled": [12, 16, 19], "coupled-sequence": [12, 16, 19], "delivery": [9]}  # sizes the targets name

# the dissertation's own worlds (reference/scalability): index -> n
DISSERTATION = {
    "delivery": ("scalability/food-logistics-delivery", "configurationDelivery{i}.json", "FoodLogisticsDelivery.txt",
                 [2, 3, 5, 10, 11, 12, 15, 20]),
    "pickup": ("scalability/food-logistics-pickup", "configurationPickup{i}.json", "FoodLogisticsPickup.txt",
               [2, 3, 5, 10, 20, 50, 100, 200, 1000, 2000, 3000, 4000, 5000]),
    "vital-signs": ("scalability/vital-signs-monitoring", "configuration{i}.json", "VitalSignsMonitoring.txt",
                    [2, 3, 5, 10, 20, 50, 100, 200, 1000, 2000, 3000, 4000, 5000]),
}


TIME = Path("/usr/bin/time")


def measure(cmd: list[str], cwd: Path, timeout: float) -> dict:
    """Run ``cmd`` as a child process (``mutrose_cp.compare.measure``); wall time, peak RSS (MB), exit
    status and the command's JSON summary.

    Linux records the forking parent's peak memory in the child's at ``exec``, so a 5 MB program
    forked from this 30 MB process would read as 30 MB.  Where ``/usr/bin/time`` is installed, the
    command is forked from that small process instead, and its reading (the command's peak, its
    waited-for children included) replaces the parent's."""
    with tempfile.NamedTemporaryFile(suffix=".rss") as rss:
        wrapped = [str(TIME), "-q", "-f", "%M", "-o", rss.name, *cmd] if TIME.is_file() else cmd
        run = run_measured(wrapped, cwd, timeout)
        peak_kb = Path(rss.name).read_text().strip()
    peak_mb = int(peak_kb) / 1024 if peak_kb.isdigit() else run.peak_mb
    if run.timed_out:
        return {"status": "timeout", "seconds": round(run.seconds, 3), "peak_mb": round(peak_mb, 1)}
    result = {"status": "ok" if run.succeeded else f"exit {run.exit_status}",
              "seconds": round(run.seconds, 3), "peak_mb": round(peak_mb, 1)}
    summary = run.summary
    if summary is not None:
        result.update(task_instances=summary.get("task_instances"), constraints=summary.get("constraints"),
                      mission_decompositions=summary.get("mission_decompositions"))
    elif not run.succeeded:
        result["error"] = run.stderr.strip().splitlines()[-1:] if run.stderr.strip() else []
    return result


def _digits(count: str | None) -> str | None:
    """Counts can have thousands of digits: keep them short in the results."""
    if count is None or len(count) <= 15:
        return count
    return f"{count[0]}.{count[1:4]}e{len(count) - 1}"


def summarize(family: str, n: int, label: str, samples: list[dict], accepted: tuple[str, ...] = ("ok",)) -> dict:
    """One result row from the repeated runs of a command: medians of the accepted runs, or the
    last run when none was accepted."""
    ok = [s for s in samples if s["status"] in accepted]
    row = {"family": family, "n": n, "algorithm": label, "runs": len(samples),
           "status": "ok" if len(ok) == len(samples) else samples[-1]["status"]}
    if ok:
        row.update(seconds=statistics.median(s["seconds"] for s in ok),
                   peak_mb=statistics.median(s["peak_mb"] for s in ok),
                   task_instances=ok[0].get("task_instances"), constraints=ok[0].get("constraints"),
                   mission_decompositions=_digits(ok[0].get("mission_decompositions")))
    else:
        row.update(seconds=samples[-1]["seconds"], peak_mb=samples[-1]["peak_mb"], error=samples[-1].get("error"))
    return row


def run_family(family: str, ladder: list[int], repeats: int, timeout: float, work: Path, log,
               extra_sizes: bool = True) -> list[dict]:
    rows = []
    stopped: set[str] = set()
    extra = EXTRA_SIZES.get(family, []) if extra_sizes else []
    for n in sorted(set(ladder) | {k for k in extra if k <= max(ladder)}):
        hddl, gm, cfg = generate(family, n, work / family)
        runs = list(RUNS[family])
        if original_installed() and family in ORIGINAL_MAX_N:
            cap = ORIGINAL_MAX_N[family]
            runs.append(("original", ["original"], cap if extra_sizes else min(cap or 2, 2)))  # quick: its smallest
        for label, extra, max_n in runs:
            if label in stopped or (max_n is not None and n > max_n):
                continue
            out = work / f"{family}-{n}-{label}.out"
            if extra == ["original"]:  # writes the configuration's output file (in the work folder)
                cmd = [str(ORIGINAL), str(hddl), str(gm), str(cfg)]
            elif extra[:1] == ["count"]:
                cmd = [sys.executable, "-m", "mutrose_cp", "count", str(hddl), str(gm), str(cfg), "-q", "--json-summary"]
            else:
                cmd = [sys.executable, "-m", "mutrose_cp", "decompose", str(hddl), str(gm), str(cfg), "-q",
                       "--json-summary", "-o", str(out), *extra]
            samples = []
            for _ in range(repeats):
                r = measure(cmd, ROOT, timeout)
                samples.append(r)
                if r["status"] != "ok":
                    break
            out.unlink(missing_ok=True)
            (work / family / f"{family}-{n}.out.json").unlink(missing_ok=True)
            row = summarize(family, n, label, samples)
            if "error" in row:
                stopped.add(label)  # no run succeeded: the ladder stops for this algorithm
            rows.append(row)
            log(f"{family:12} n={n:<6} {label:15} {row['status']:8} {row.get('seconds', 0):8.2f} s "
                f"{row.get('peak_mb', 0):8.1f} MB  decompositions={row.get('mission_decompositions')}")
    return rows


def run_dissertation(family: str, repeats: int, timeout: float, log, quick: bool) -> list[dict]:
    folder, template, gm_name, sizes = DISSERTATION[family]
    src = REFERENCE / folder
    hddl = next((src / "hddl").glob("*.hddl"))
    rows = []
    stopped: set[str] = set()
    for i, n in enumerate(sizes):
        if quick and n > 3:
            break
        cfg = src / "configuration" / template.format(i=i)
        if not cfg.exists():
            continue
        for label, extra in (("exploratory", ["--algorithm", "exploratory"]), ("cpsat", [])):
            if label in stopped:
                continue
            with tempfile.TemporaryDirectory() as tmp:
                # --lenient-xml: the dissertation's delivery world 5 leaves <Location> Location12
                # unclosed; it is read as the original reads it (the patients nest inside it)
                cmd = [sys.executable, "-m", "mutrose_cp", "decompose", str(hddl), str(src / "gm" / gm_name),
                       str(cfg), "-q", "--lenient-xml", "--json-summary", "-o", str(Path(tmp) / "out.json"), *extra]
                samples = []
                for _ in range(repeats):
                    samples.append(measure(cmd, src, timeout))
                    if samples[-1]["status"] != "ok":
                        break
            if samples[-1]["status"] == "timeout":
                stopped.add(label)
            row = summarize(f"dissertation-{family}", n, label, samples)
            rows.append(row)
            log(f"{row['family']:24} n={n:<6} {label:12} {row['status']:8} {row.get('seconds', 0):8.2f} s "
                f"tasks={row.get('task_instances')} decompositions={row.get('mission_decompositions')}")
    return rows


def run_small_missions(repeats: int, timeout: float, log) -> list[dict]:
    """Every reference mission and configuration as a user runs it, whole process (start-up
    included), with both algorithms; and the floor: ``python -c pass``."""
    floor = [measure([sys.executable, "-c", "pass"], ROOT, timeout) for _ in range(max(repeats, 3))]
    rows = [{**summarize("small", 0, "floor", floor), "mission": "python -c pass"}]
    runs = [(mission, cfg) for mission in sorted((REFERENCE / "missions").iterdir())
            for cfg in sorted((mission / "configuration").glob("*"))]
    for n, (mission, cfg) in enumerate(runs, start=1):  # n numbers the runs (the family has no size)
        labels = [("exploratory", ["--algorithm", "exploratory"]), ("cpsat", [])]
        if original_installed():
            labels.append(("original", []))
        for label, extra in labels:
            with tempfile.TemporaryDirectory() as tmp:
                if label == "original":  # inside a copy of the mission: it writes the configured output there
                    work = Path(tmp) / mission.name
                    shutil.copytree(mission, work)
                    hddl, gm, _ = find_mission_files(mission, cfg.name)
                    cmd = [str(ORIGINAL), str(hddl.relative_to(mission)), str(gm.relative_to(mission)),
                           str(cfg.relative_to(mission))]
                    samples = [measure(cmd, work, timeout) for _ in range(repeats)]
                else:
                    cmd = [sys.executable, "-m", "mutrose_cp", "decompose", str(mission), "--config", cfg.name,
                           "-q", "--json-summary", "-o", str(Path(tmp) / "out"), *extra]
                    samples = [measure(cmd, mission, timeout) for _ in range(repeats)]
            # exit 3 (nothing valid, as the original says too) is a finished run
            row = {**summarize("small", n, label, samples, accepted=("ok", "exit 3")), "mission": f"{mission.name}/{cfg.name}"}
            rows.append(row)
            log(f"small        {row['mission']:50} {label:12} {row['status']:8} {row.get('seconds', 0):6.2f} s "
                f"{row.get('peak_mb', 0):7.1f} MB")
    return rows


def original_installed() -> bool:
    return ORIGINAL.is_file() and os.access(ORIGINAL, os.X_OK)


def plugin_calls() -> list[tuple[Path, Path]]:
    """The missions whose ``-p`` output the corpus records (``reference/console``), with their
    configuration: the editor plug-in's call, on every edit."""
    calls = []
    for stdout in sorted((REFERENCE / "console").glob("*/*.p.stdout")):
        mission = REFERENCE / "missions" / stdout.parent.name
        cfg = mission / "configuration" / (stdout.name.removesuffix(".p.stdout") + ".json")
        if cfg.is_file():
            calls.append((mission, cfg))
    return calls


def run_plugin_calls(repeats: int, timeout: float, log) -> list[dict]:
    """``mutrose HDDL GM CONFIG -p`` (the drop-in) beside the original tool given the same
    command line, each run inside a temporary copy of the mission folder as the plug-in runs it
    (the original writes the configuration's output file there).  The original is measured only
    where it is installed (``MUTROSE_ORIGINAL``)."""
    dropin = [sys.executable, "-c", "import sys; from mutrose_cp.cli.dropin import entry; sys.argv[0] = 'mutrose'; entry()"]
    tools = [("mutrose -p", dropin)]
    if original_installed():
        tools.append(("original -p", [str(ORIGINAL)]))
    rows = []
    for n, (mission, cfg) in enumerate(plugin_calls(), start=1):
        hddl, gm, _ = find_mission_files(mission, cfg.name)
        for label, tool in tools:
            with tempfile.TemporaryDirectory() as tmp:
                work = Path(tmp) / mission.name
                shutil.copytree(mission, work)
                cmd = [*tool, str(hddl.relative_to(mission)), str(gm.relative_to(mission)),
                       str(cfg.relative_to(mission)), "-p"]
                samples = [measure(cmd, work, timeout) for _ in range(repeats)]
            row = {**summarize("plugin", n, label, samples), "mission": f"{mission.name}/{cfg.name}"}
            rows.append(row)
            log(f"plugin       {row['mission']:50} {label:12} {row['status']:8} {row.get('seconds', 0):6.3f} s "
                f"{row.get('peak_mb', 0):7.1f} MB")
    return rows


def quick_run(doc: str | None, argv: list[str] | None) -> bool:
    """A benchmark script's command line (``--quick``: its smallest sizes), read with the
    package's bytecode compiled (:func:`compile_bytecode`)."""
    parser = argparse.ArgumentParser(description=(doc or "").split("\n\n")[0])
    parser.add_argument("--quick", action="store_true", help="the smallest sizes and the example only")
    quick: bool = parser.parse_args(argv).quick
    compile_bytecode()
    return quick


def compile_bytecode() -> None:
    """Compile the package's bytecode first, as ``pip install`` does for a regular install: an
    editable install run with ``PYTHONDONTWRITEBYTECODE`` would otherwise compile every module
    on every run (about 0.08 s of a small mission's 0.2 s), which no installed user pays."""
    import compileall
    import importlib.util

    spec = importlib.util.find_spec("mutrose_cp")
    if spec is not None and spec.submodule_search_locations:
        for folder in spec.submodule_search_locations:
            compileall.compile_dir(folder, quiet=1)


def machine() -> dict:
    info = {"python": platform.python_version(), "platform": platform.platform(), "cpus": os.cpu_count()}
    try:
        for line in Path("/proc/cpuinfo").read_text().splitlines():
            if line.startswith("model name"):
                info["cpu"] = line.split(":", 1)[1].strip()
                break
        for line in Path("/proc/meminfo").read_text().splitlines():
            if line.startswith("MemTotal"):
                info["memory_gb"] = round(int(line.split()[1]) / 1024 / 1024, 1)
    except OSError:
        pass
    return info


def main(argv: list[str] | None = None) -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--quick", action="store_true", help="small ladder, one run per size (CI smoke test)")
    parser.add_argument("--families", nargs="*", default=list(RUNS), choices=list(RUNS))
    parser.add_argument("--max-n", type=int, help="stop the ladder at this size")
    parser.add_argument("--repeats", type=int, help="runs per size (median); default 3, 1 with --quick")
    parser.add_argument("--timeout", type=float, help="per-run time limit in seconds (default 120, 30 with --quick)")
    parser.add_argument("--no-dissertation", action="store_true", help="skip the dissertation's own worlds")
    parser.add_argument("--no-small", action="store_true", help="skip the reference missions run whole")
    parser.add_argument("--small-only", action="store_true",
                        help="only the reference missions run whole and the editor plug-in's call, beside the "
                             "original (results/small.json; docs/benchmarks.md shows them in place of the full "
                             "run's)")
    args = parser.parse_args(argv)
    ladder = QUICK_LADDER if args.quick else FULL_LADDER
    if args.max_n:
        ladder = [n for n in ladder if n <= args.max_n]
    repeats = args.repeats or (1 if args.quick else 3)
    timeout = args.timeout or (30.0 if args.quick else 120.0)
    name = "quick" if args.quick else "small" if args.small_only else "full"
    if args.small_only:
        args.families = []
    started = time.time()
    rows: list[dict] = []
    compile_bytecode()
    with tempfile.TemporaryDirectory(prefix="mutrose-bench-") as tmp:
        if not args.no_small:
            rows += run_small_missions(repeats, timeout, lambda m: print(m, flush=True))
            rows += run_plugin_calls(max(repeats, 5) if not args.quick else 1, timeout,
                                     lambda m: print(m, flush=True))
        for family in args.families:
            rows += run_family(family, ladder, repeats, timeout, Path(tmp), lambda m: print(m, flush=True),
                               extra_sizes=not args.quick)
            if not args.no_dissertation and family in DISSERTATION:
                rows += run_dissertation(family, repeats, timeout, lambda m: print(m, flush=True), args.quick)
    RESULTS.mkdir(parents=True, exist_ok=True)
    result = {"name": name, "machine": machine(), "repeats": repeats, "timeout_s": timeout,
              "date": time.strftime("%Y-%m-%d", time.gmtime(started)),
              "elapsed_s": round(time.time() - started, 1), "rows": rows}
    if args.quick:  # the allocation benchmark's tiny instance (its full ladder: benchmarks/allocation.py)
        smoke = subprocess.run([sys.executable, str(ROOT / "benchmarks" / "allocation.py"), "--quick"], cwd=ROOT)
        if smoke.returncode != 0:
            rows.append({"family": "allocation", "n": 4, "algorithm": "allocate", "status": "failed"})
    path = RESULTS / f"{name}.json"
    path.write_text(json.dumps(result, indent=1) + "\n", encoding="utf-8")
    # the original's own aborts (exit 134 on inputs it cannot take) are its results, not failures here
    failed = [r for r in rows if r["status"] not in ("ok", "timeout") and not r["algorithm"].startswith("original")]
    print(f"wrote {path} ({len(rows)} measurements, {result['elapsed_s']} s); "
          f"{len(failed)} failed runs", flush=True)
    if not args.quick:  # the full run (or the small missions' rerun) regenerates docs/benchmarks.md
        import report

        report.main(["full"])
    return 1 if failed else 0


if __name__ == "__main__":
    sys.exit(main())
