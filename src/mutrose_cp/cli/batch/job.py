"""One batch job run: a ``mutrose-cp`` command in a child process of its own, under its limits.

:func:`run_job` is what every engine calls, in a thread of the local pool or in a Ray worker, so
a job gives the same result wherever it runs.  Its argument and its result are plain, picklable
values: they are all that travels between a Ray driver and its workers.

How the job ended becomes its status (:mod:`.statuses`).  A child that is killed cannot clean up
after itself, so the parent removes the temporary files it left beside its outputs
(:mod:`.temporaries`).
"""
from __future__ import annotations

import dataclasses
import math
import os
import sys
import tempfile
import threading
import time
from dataclasses import dataclass, field
from typing import Any

from ...compare.measure import run_measured
from .statuses import MemoryLimit, classify, problems
from .temporaries import remove_temporaries


@dataclass(frozen=True)
class JobSpec:
    """What a worker needs to run one job: the command line (after ``mutrose-cp``), the folder it
    runs in and its limits (``time_limit`` in seconds, ``None`` for none; ``memory_mb`` 0 for
    none); ``outputs``, the files and folders it writes (relative to ``cwd``), whose temporary
    files are removed when the job is killed."""

    argv: tuple[str, ...]
    cwd: str
    time_limit: float | None = None
    memory_mb: int = 0
    outputs: tuple[str, ...] = ()


@dataclass(frozen=True)
class Outcome:
    """How a job ended: its status, the command's exit status (None when it was stopped at the
    time limit), wall time and peak memory of its process, the command's ``--json-summary`` and
    the problems it reported."""

    status: str
    exit_code: int | None
    seconds: float
    peak_mb: float
    summary: dict[str, Any] | None = None
    problems: list[str] = field(default_factory=list)


def child_command(spec: JobSpec, peak_fd: int) -> list[str]:
    """The child's command line: the limiting wrapper, then the job's own command line."""
    return [sys.executable, "-m", "mutrose_cp.cli.batch.child", str(spec.memory_mb), str(os.getpid()), str(peak_fd),
            *spec.argv]


def run_job(spec: JobSpec, cancel: threading.Event | None = None) -> Outcome:
    """Run the job and classify how it ended (raises :class:`mutrose_cp.compare.measure.Cancelled` when
    ``cancel`` is set meanwhile: an unfinished job has no outcome)."""
    limit = math.inf if spec.time_limit is None else spec.time_limit
    started = time.time()
    with tempfile.TemporaryFile() as peak:
        try:
            run = run_measured(child_command(spec, peak.fileno()), spec.cwd, limit, cancel=cancel,
                               pass_fds=(peak.fileno(),))
        except BaseException:  # cancelled or interrupted: the child was killed before it could clean up
            remove_temporaries(spec.cwd, spec.outputs, started)
            raise
        peak.seek(0)
        reported = peak.read().strip()
    if reported.isdigit():  # the child's own peak, untouched by the memory of this process
        run = dataclasses.replace(run, peak_mb=int(reported) / 1024)
    removed = remove_temporaries(spec.cwd, spec.outputs, started) if run.exit_status != 0 else []
    memory = MemoryLimit.of(spec.memory_mb)
    status = classify(run, memory)
    notes = [f"removed the temporary file {name} it left" for name in removed]
    return Outcome(status=status, exit_code=run.exit_status, seconds=round(run.seconds, 3),
                   peak_mb=round(run.peak_mb, 1), summary=run.summary,
                   problems=problems(run, status, spec.time_limit, memory) + notes)
