"""The ``batch`` sub-command: read the jobs, skip the settled ones, run the rest, report.

    mutrose-cp batch [options] MANIFEST
    mutrose-cp batch [options] --each GLOB [--mission DIR] [--output PATTERN] COMMAND [OPTION ...]

Exit status: 0 when every job ended with status ``ok``, 1 when some did not, 2 for a bad
manifest or usage, 130/143 when interrupted (the finished jobs are recorded: run the same
command again to finish the rest).
"""
from __future__ import annotations

import argparse
import os
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING

from ..option_types import count_option, seconds

if TYPE_CHECKING:  # the command line builds this parser for every command: the rest loads when batch runs
    from .job import Outcome
    from .manifest import Job
    from .results import InputHasher

BATCH_USAGE = ("mutrose-cp batch [options] MANIFEST\n"
               "       mutrose-cp batch [options] --each GLOB [--mission DIR] [--output PATTERN] COMMAND [OPTION ...]")


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def _batch_options(p: argparse.ArgumentParser) -> None:
    p.add_argument("--jobs", "-j", type=count_option(1), default=default_workers(), metavar="N",
                   help="run N jobs at a time (default: the number of cores); with --ray, the CPUs of the local "
                        "cluster it starts")
    p.add_argument("--ray", nargs="?", const="", metavar="ADDRESS",
                   help="run the jobs on Ray: alone, on a local cluster started for the batch; 'auto' or HOST:PORT "
                        "joins a running cluster (needs pip install 'mutrose-cp[ray]')")
    p.add_argument("--time-limit", type=seconds, metavar="S",
                   help="stop a job after S seconds (status timeout; default: no limit)")
    p.add_argument("--memory-mb", type=count_option(1), metavar="MB",
                   help="stop a job that needs more than MB megabytes (status memory; default: no limit)")
    p.add_argument("--results", metavar="FILE",
                   help="the results file (JSONL; default: MANIFEST with the suffix .results.jsonl, or "
                        "batch.results.jsonl with --each)")
    p.add_argument("--each", metavar="GLOB", help="one job per mission folder GLOB matches (or per world file, "
                                                  "with --mission)")
    p.add_argument("--mission", metavar="DIR", help="--each: run this mission on every world file GLOB matches")
    p.add_argument("--output", metavar="PATTERN", help="--each: each job's output file; {name} is the matched "
                                                       "folder's or world's name")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary on stderr")


def add_batch_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """Register ``batch`` on the command line's sub-command parsers."""
    p = sub.add_parser("batch", help="run many jobs (missions, worlds, commands) at once, locally or on Ray",
                       usage=BATCH_USAGE)
    _batch_options(p)
    p.add_argument("target", nargs=argparse.REMAINDER, metavar="MANIFEST | COMMAND [OPTION ...]",
                   help="a JSON or CSV manifest; with --each, the command to run and its options")
    p.set_defaults(func=cmd_batch, max_input_mb=256)


def _complete(args: argparse.Namespace) -> None:
    """Finish parsing: options written after the manifest (``batch ladder.json --jobs 2``), and a
    manifest taken for the address of ``--ray`` (``batch --ray ladder.json``)."""
    from ..errors import MissionError

    if args.ray and not args.target and ":" not in args.ray and args.ray != "auto":
        args.target, args.ray = [args.ray], ""
    if args.each is None and len(args.target) > 1:
        tail = argparse.ArgumentParser(prog="mutrose-cp batch", usage=BATCH_USAGE)
        _batch_options(tail)
        tail.parse_args(args.target[1:], namespace=args)
        args.target = args.target[:1]
    if args.each is None and (args.mission or args.output):
        raise MissionError("--mission and --output belong to the --each form", "batch")
    if not args.target:
        raise MissionError("expected a manifest (MANIFEST), or --each GLOB COMMAND", "batch")


def cmd_batch(args: argparse.Namespace) -> int:
    from ..errors import MissionError
    from ..interrupt import Interrupted, phase, signals_held
    from .engines import LocalPool, RayCluster
    from .job import OK, JobSpec
    from .manifest import check_jobs
    from .report import Progress, summary_table
    from .results import InputHasher, ResultLine, ResultsFile

    _complete(args)
    jobs, base, results_path = _jobs(args)
    engine = RayCluster(args.ray or None, args.jobs) if args.ray is not None else LocalPool(args.jobs)
    parsed = check_jobs(jobs, base)
    hashes = _hashes(jobs, parsed, InputHasher(base))
    specs = [JobSpec(job.command_line(), str(base), args.time_limit, args.memory_mb or 0) for job in jobs]
    results = ResultsFile(results_path)
    for note in results.ignored:
        print(f"warning: {note}", file=sys.stderr)
    lines: list[ResultLine | None] = [results.done(h, s) for h, s in zip(hashes, specs)]
    todo = [(i, spec) for i, (spec, line) in enumerate(zip(specs, lines)) if line is None]
    progress = Progress(len(jobs), len(jobs) - len(todo), not args.quiet)
    progress.draw()

    def report(i: int, outcome: Outcome) -> None:
        line = ResultLine.of(jobs[i], hashes[i], specs[i], outcome)
        with signals_held():  # a finished job is recorded whole, or (interrupted before) not at all
            results.record(line)
            lines[i] = line
        progress.finished(line.status)

    start = time.perf_counter()
    stopped: Interrupted | None = None
    try:
        with phase("running the jobs"):
            if todo:
                engine.run(todo, report)
    except Interrupted as err:
        stopped = err
    finally:
        progress.close()
        results.close(hashes)
    if not args.quiet:
        print(summary_table(jobs, lines, len(jobs) - len(todo), engine.describe(), time.perf_counter() - start),
              file=sys.stderr)
        print(f"results: {results_path}", file=sys.stderr)
    if stopped is not None:
        left = sum(line is None for line in lines)
        print(f"interrupted ({stopped}): {left} jobs not finished, none of them recorded; run the same command "
              "again to run only those", file=sys.stderr)
        return stopped.exit_code
    if any(line is None for line in lines):
        raise MissionError("some jobs have no result", str(results_path))
    return 0 if all(line is not None and line.status == OK for line in lines) else 1


def _jobs(args: argparse.Namespace) -> tuple[list[Job], Path, Path]:
    """The jobs, the folder they run in, and the results file: from the manifest (its folder, and
    ``MANIFEST.results.jsonl`` beside it), or from ``--each`` (the current folder)."""
    from .manifest import jobs_from_glob, read_manifest

    if args.each is not None:
        jobs = jobs_from_glob(args.each, args.target[0], args.target[1:], mission=args.mission, output=args.output)
        return jobs, Path.cwd(), Path(args.results or "batch.results.jsonl")
    manifest = Path(args.target[0])
    results = Path(args.results) if args.results else manifest.with_suffix(".results.jsonl")
    return read_manifest(manifest), manifest.resolve().parent, results


def _hashes(jobs: list[Job], parsed: list[argparse.Namespace], hasher: InputHasher) -> list[str]:
    """The input hash of every job; two jobs with the same hash are one job listed twice."""
    from ..errors import MissionError, Problem

    hashes: list[str] = []
    first: dict[str, Job] = {}
    problems: list[Problem] = []
    for job, args in zip(jobs, parsed):
        h = hasher.job_hash(job, args)
        if h in first:
            problems.append(Problem(job.where, f"job {job.id} repeats job {first[h].id} (same command, options, "
                                               "output and inputs)"))
        first.setdefault(h, job)
        hashes.append(h)
    if problems:
        raise MissionError(problems)
    return hashes
