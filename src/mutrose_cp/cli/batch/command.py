"""The ``batch`` sub-command: read the jobs, skip the settled ones, run the rest, report.

    mutrose-cp batch [options] MANIFEST
    mutrose-cp batch [options] --each GLOB [--mission DIR] [--output PATTERN] COMMAND [OPTION ...]

Exit status: 0 when every job ended with status ``ok``, 1 when some did not, 2 for a bad
manifest or usage, 130/143 when interrupted (the finished jobs are recorded: run the same
command again to finish the rest).
"""
from __future__ import annotations

import argparse
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from .options import BATCH_USAGE, TailParser, batch_options

if TYPE_CHECKING:  # the command line builds this parser for every command: the rest loads when batch runs
    from ...interrupt import Interrupted
    from .engines import Engine
    from .job import Outcome
    from .manifest import Job
    from .plan import Plan
    from .results import ResultLine
    from .safety import BatchFiles











def _complete(args: argparse.Namespace) -> None:
    """Finish parsing: options written after the manifest (``batch ladder.json --jobs 2``), and a
    manifest taken for the address of ``--ray`` (``batch --ray ladder.json``)."""
    from ...errors import MissionError

    if args.ray and not args.target and ":" not in args.ray and args.ray != "auto":
        args.target, args.ray = [args.ray], ""
    if args.each is None and len(args.target) > 1:
        tail = TailParser(prog="mutrose-cp batch", usage=BATCH_USAGE)
        batch_options(tail)
        tail.parse_args(args.target[1:], namespace=args)
        args.target = args.target[:1]
    if args.each is None and (args.mission or args.output):
        raise MissionError("--mission and --output belong to the --each form", "batch")
    if not args.target:
        raise MissionError("expected a manifest (MANIFEST), or --each GLOB COMMAND", "batch")


def cmd_batch(args: argparse.Namespace) -> int:
    from .engines import LocalPool, RayCluster
    from .plan import make_plan

    _complete(args)
    jobs, base, results_path, manifest = _jobs(args)
    engine = RayCluster(args.ray or None, args.jobs) if args.ray is not None else LocalPool(args.jobs)
    # every check before any job runs, and before the results file is touched
    plan = make_plan(jobs, _batch_files(args, manifest, results_path, base), args.time_limit, args.memory_mb or 0)
    return _run(args, engine, plan)


def _run(args: argparse.Namespace, engine: Engine, plan: Plan) -> int:
    """Open the results file, run the jobs it does not settle, record each as it finishes, and
    report; the exit status."""
    from ...interrupt import Interrupted, phase, signals_held
    from .journal import ResultsFile
    from .report import Progress, summary_table
    from .results import ResultLine

    results = ResultsFile(plan.batch.results, plan.batch.results_where)
    results.open()  # an unwritable results file stops the batch here, before the first job
    shown = _warn(results.notes, 0)
    lines: list[ResultLine | None] = [results.done(h, s) for h, s in zip(plan.hashes, plan.specs)]
    todo = plan.to_run(lines)
    for i in todo:
        lines[i] = None
    progress = Progress(len(lines), len(lines) - len(todo), not args.quiet)
    progress.draw()

    def report(i: int, outcome: Outcome) -> None:
        line = ResultLine.of(plan.jobs[i], plan.recorded_hash(i), plan.specs[i], outcome)
        with signals_held():  # a finished job is recorded whole, or (interrupted before) not at all
            results.record(line)
            lines[i] = line
        progress.finished(line.status)

    start = time.perf_counter()
    stopped: Interrupted | None = None
    try:
        with phase("running the jobs"):
            if todo:
                engine.run([(i, plan.specs[i]) for i in todo], report)
    except Interrupted as err:
        stopped = err
    finally:
        progress.close()
        results.close(plan.hashes)
        _warn(results.notes, shown)
    if not args.quiet:
        print(summary_table(plan.jobs, lines, len(lines) - len(todo), engine.describe(), time.perf_counter() - start),
              file=sys.stderr)
        print(f"results: {plan.batch.named}", file=sys.stderr)
    return _ending(plan, lines, stopped)


def _ending(plan: Plan, lines: list[ResultLine | None], stopped: Interrupted | None) -> int:
    """The exit status, and what an interrupted batch left to do."""
    from ...errors import MissionError
    from .statuses import OK

    if stopped is not None:
        left = sum(line is None for line in lines)
        print(f"interrupted ({stopped}): {left} jobs not finished, none of them recorded; run the same command "
              "again to run only those", file=sys.stderr)
        return stopped.exit_code
    if any(line is None for line in lines):
        raise MissionError("some jobs have no result", str(plan.batch.results))
    return 0 if all(line is not None and line.status == OK for line in lines) else 1


def _warn(notes: list[str], shown: int) -> int:
    """Print the notes from ``shown`` on as warnings; how many are printed now."""
    for note in notes[shown:]:
        print(f"warning: {note}", file=sys.stderr)
    return len(notes)


def _batch_files(args: argparse.Namespace, manifest: Path | None, results: Path, base: Path) -> BatchFiles:
    """The batch's own files, the results file named as the user named it (for messages)."""
    from .safety import BatchFiles

    return BatchFiles(None if manifest is None else manifest.absolute(), results.absolute(), str(results),
                      bool(args.results), base)


def _jobs(args: argparse.Namespace) -> tuple[list[Job], Path, Path, Path | None]:
    """The jobs, the folder they run in, the results file and the manifest: from the manifest
    (its folder, and ``MANIFEST.results.jsonl`` beside it), or from ``--each`` (the current
    folder, no manifest)."""
    from .manifest import jobs_from_glob, read_manifest

    if args.each is not None:
        jobs = jobs_from_glob(args.each, args.target[0], args.target[1:], mission=args.mission, output=args.output)
        return jobs, Path.cwd(), Path(args.results or "batch.results.jsonl"), None
    manifest = Path(args.target[0])
    results = Path(args.results) if args.results else manifest.with_suffix(".results.jsonl")
    return read_manifest(manifest), manifest.resolve().parent, results, manifest
