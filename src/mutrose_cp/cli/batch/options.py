"""The ``batch`` sub-command's options, registered on the command line's parser (which builds
them for every command: nothing else of the batch loads until it runs)."""
from __future__ import annotations

import argparse
import os
from typing import NoReturn

from ...errors import MissionError
from ..option_types import count_option, input_file, output_file, seconds


BATCH_USAGE = ("mutrose-cp batch [options] MANIFEST\n"
               "       mutrose-cp batch [options] --each GLOB [--mission DIR] [--output PATTERN] COMMAND [OPTION ...]")


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:  # not on Linux
        return os.cpu_count() or 1


def batch_options(p: argparse.ArgumentParser) -> None:
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
    p.add_argument("--results", metavar="FILE", type=output_file,
                   help="the results file (JSONL; default: MANIFEST with the suffix .results.jsonl, or "
                        "batch.results.jsonl with --each)")
    p.add_argument("--each", metavar="GLOB", help="one job per mission folder GLOB matches (or per world file, "
                                                  "with --mission)")
    p.add_argument("--mission", metavar="DIR", type=input_file, help="--each: run this mission on every world file GLOB matches")
    p.add_argument("--output", metavar="PATTERN", help="--each: each job's output file; {name} is the matched "
                                                       "folder's or world's name")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress bar and no summary on stderr")


def add_batch_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """Register ``batch`` on the command line's sub-command parsers."""
    p = sub.add_parser("batch", help="run many jobs (missions, worlds, commands) at once, locally or on Ray",
                       usage=BATCH_USAGE)
    batch_options(p)
    p.add_argument("target", nargs=argparse.REMAINDER, metavar="MANIFEST | COMMAND [OPTION ...]",
                   help="a JSON or CSV manifest; with --each, the command to run and its options")
    p.set_defaults(max_input_mb=256)


class TailParser(argparse.ArgumentParser):
    """The batch options written after the manifest.  Its usage errors are raised as errors of
    the batch (exit 2, as the main parser's), not as an exit: the main parser's own error
    handling is over by the time it runs, and a program that calls ``main`` gets a status back."""

    def error(self, message: str) -> NoReturn:
        raise MissionError(message, "batch")

