"""One batch job run: a ``mutrose-cp`` command in a child process of its own, under its limits.

:func:`run_job` is what every engine calls, in a thread of the local pool or in a Ray worker, so
a job gives the same result wherever it runs.  Its argument and its result are plain, picklable
values: they are all that travels between a Ray driver and its workers.
"""
from __future__ import annotations

import dataclasses
import math
import os
import sys
import tempfile
import threading
from dataclasses import dataclass, field
from typing import Any

from ..measure import Measurement, run_measured
from .child import MEMORY_EXIT

# statuses of a finished job: the command succeeded; it exited with an error status of its own
# (bad input, no valid decomposition, an invalid output...); it was stopped at the time limit;
# it ran out of memory under its limit; it died otherwise (a signal, an uncaught exception)
OK, FAILED, TIMEOUT, MEMORY, CRASHED = "ok", "failed", "timeout", "memory", "crashed"
STATUSES = (OK, FAILED, TIMEOUT, MEMORY, CRASHED)

# how a native allocation failure shows in the stderr of a job that died of it
_OUT_OF_MEMORY_SIGNS = ("MemoryError", "std::bad_alloc", "Cannot allocate memory", "out of memory")
MEMORY_REACHED = 0.9  # a peak this close to the limit means the limit was hit


@dataclass(frozen=True)
class JobSpec:
    """What a worker needs to run one job: the command line (after ``mutrose-cp``), the folder it
    runs in and its limits (``time_limit`` in seconds, ``None`` for none; ``memory_mb`` 0 for
    none)."""

    argv: tuple[str, ...]
    cwd: str
    time_limit: float | None = None
    memory_mb: int = 0


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
    return [sys.executable, "-m", "mutrose_cp.batch.child", str(spec.memory_mb), str(os.getpid()), str(peak_fd),
            *spec.argv]


def run_job(spec: JobSpec, cancel: threading.Event | None = None) -> Outcome:
    """Run the job and classify how it ended (raises :class:`mutrose_cp.measure.Cancelled` when
    ``cancel`` is set meanwhile: an unfinished job has no outcome)."""
    limit = math.inf if spec.time_limit is None else spec.time_limit
    with tempfile.TemporaryFile() as peak:
        run = run_measured(child_command(spec, peak.fileno()), spec.cwd, limit, cancel=cancel,
                           pass_fds=(peak.fileno(),))
        peak.seek(0)
        reported = peak.read().strip()
    if reported.isdigit():  # the child's own peak, untouched by the memory of this process
        run = dataclasses.replace(run, peak_mb=int(reported) / 1024)
    status = classify(run, spec.memory_mb)
    return Outcome(status=status, exit_code=run.exit_status, seconds=round(run.seconds, 3),
                   peak_mb=round(run.peak_mb, 1), summary=run.summary,
                   problems=problems(run, status, spec))


def classify(run: Measurement, memory_mb: int) -> str:
    """The status of a finished run (see :data:`STATUSES`).

    A process short of memory does not always say so: Python raises ``MemoryError`` where it can,
    but an allocation that fails inside C code may surface as another exception, and one in
    native code aborts the process.  So a job under a memory limit that ended abnormally counts
    as out of memory when it said so, or when its peak memory reached the limit."""
    if run.timed_out:
        return TIMEOUT
    if run.exit_status == 0:
        return OK
    signalled = run.exit_status is not None and run.exit_status < 0
    abnormal = signalled or run.exit_status == MEMORY_EXIT or "Traceback (most recent call last)" in run.stderr
    if memory_mb and abnormal and (run.exit_status == MEMORY_EXIT or run.peak_mb >= MEMORY_REACHED * memory_mb
                                   or any(sign in run.stderr for sign in _OUT_OF_MEMORY_SIGNS)):
        return MEMORY
    return CRASHED if abnormal else FAILED


def problems(run: Measurement, status: str, spec: JobSpec) -> list[str]:
    """What went wrong, for the results: the command's own ``error:`` lines, or why the batch
    stopped it, or the end of what a crashed process printed."""
    errors = run.errors
    if status == TIMEOUT:
        return [f"stopped at the time limit of {spec.time_limit:g} s"]
    if status == MEMORY:
        return errors or [f"ran out of memory under the limit of {spec.memory_mb} MB"]
    if status == CRASHED:
        return [run.ending, *run.stderr.strip().splitlines()[-5:]]
    return errors or run.stderr.strip().splitlines()[-5:]  # a failure in its own words, whatever they are
