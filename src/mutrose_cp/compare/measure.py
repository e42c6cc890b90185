"""Run a command as a child process and measure it: wall time, peak memory, exit status.

The parent does the measuring (``os.wait4`` returns the child's peak resident set size, and the
total memory of its process tree is sampled while it runs), so the numbers cover the whole
process, interpreter start-up and helper processes included, and the child need not cooperate.  ``compare``, ``batch`` and the benchmarks measure commands this way.

The child runs in a session of its own, hence its own process group: at the time limit the whole
group is killed, so no helper process it started outlives it.  A Ctrl-C at the terminal reaches
only the parent (the child is not in the terminal's foreground group); the parent's interrupt
then kills the group on its way out, so an interrupted parent leaves no child running either.
A parent that waits for several children in threads stops them through ``cancel``: the signal
reaches the main thread only, the event reaches every waiting thread.
"""
from __future__ import annotations

import json
import os
import resource
import signal
import subprocess
import sys
import tempfile
import threading
import time
from dataclasses import dataclass
from pathlib import Path
from typing import IO, Any, Mapping, Sequence

POLL_SECONDS = 0.01  # how often the parent looks whether the child has ended
FIRST_POLL_SECONDS = 0.0002  # the first look; the interval doubles up to POLL_SECONDS


class Cancelled(Exception):
    """The run was stopped through its ``cancel`` event; the child was killed, nothing measured."""


@dataclass(frozen=True)
class Measurement:
    """How one run of a command went.  ``exit_status`` is None when the run was killed at the
    time limit; it is negative (``-signal``) when a signal ended the child."""

    exit_status: int | None
    seconds: float
    peak_mb: float
    stdout: str
    stderr: str

    @property
    def timed_out(self) -> bool:
        """Killed at the time limit (or on a cancel): no exit status, no result."""
        return self.exit_status is None

    @property
    def succeeded(self) -> bool:
        return self.exit_status == 0

    @property
    def summary(self) -> dict[str, Any] | None:
        """The command's ``--json-summary``: the last line of stdout that is a JSON object."""
        for line in reversed(self.stdout.splitlines()):
            if line.startswith("{"):
                try:
                    value = json.loads(line)
                except json.JSONDecodeError:
                    continue
                if isinstance(value, dict):
                    return value
        return None

    @property
    def errors(self) -> list[str]:
        """The command's own ``error:`` lines, without the prefix."""
        return [line.removeprefix("error: ") for line in self.stderr.splitlines() if line.startswith("error: ")]

    @property
    def ending(self) -> str:
        """How the process ended: its exit status, or the signal that killed it."""
        status = self.exit_status
        if status is not None and status < 0:
            try:
                return f"killed by {signal.Signals(-status).name}"
            except ValueError:
                return f"killed by signal {-status}"
        return f"exit status {status}"


class _TreeMemory:
    """The largest total memory of a process and its descendants, sampled while it runs (Linux).

    The kernel's peak (``ru_maxrss``) is that of one process; a command that forks a helper
    (``decompose`` writes its output's head in a second process) uses the sum.  Each process's
    proportional set size (``Pss`` in ``smaps_rollup``: shared pages split between the processes
    sharing them) is summed.  Reading it walks the process's page tables, so samples are spaced
    by twenty times what the last one took (at least ``SAMPLE_SECONDS``): the measuring takes
    at most a twentieth of a core."""

    SAMPLE_SECONDS = 0.1

    def __init__(self, pid: int) -> None:
        self.pid = pid
        self.peak_kb = 0
        self.next = time.perf_counter() + self.SAMPLE_SECONDS
        self.available = os.path.exists(f"/proc/{pid}/smaps_rollup")

    def sample(self) -> None:
        now = time.perf_counter()
        if not self.available or now < self.next:
            return
        total = sum(_pss_kb(p) for p in _tree(self.pid))
        self.peak_kb = max(self.peak_kb, total)
        self.next = now + max(self.SAMPLE_SECONDS, 20 * (time.perf_counter() - now))


def _tree(pid: int) -> list[int]:
    """``pid`` and its descendants (those that still run)."""
    found, stack = [], [pid]
    while stack:
        p = stack.pop()
        found.append(p)
        try:
            with open(f"/proc/{p}/task/{p}/children", encoding="ascii") as fh:
                stack.extend(int(c) for c in fh.read().split())
        except OSError:
            continue
    return found


def _pss_kb(pid: int) -> int:
    try:
        with open(f"/proc/{pid}/smaps_rollup", encoding="ascii") as fh:
            for line in fh:
                if line.startswith("Pss:"):
                    return int(line.split()[1])
    except (OSError, ValueError):
        pass
    return 0


def _peak_mb(usage: resource.struct_rusage) -> float:
    """``ru_maxrss`` in megabytes: Linux counts kilobytes, macOS bytes."""
    return usage.ru_maxrss / (1024 * 1024 if sys.platform == "darwin" else 1024)


def _kill_group(pid: int) -> None:
    try:
        os.killpg(pid, signal.SIGKILL)
    except ProcessLookupError:  # the group is already gone
        pass


def _wait(pid: int, deadline: float, cancel: threading.Event | None,
          memory: _TreeMemory | None = None) -> tuple[int, resource.struct_rusage] | None:
    """The child's wait status and resource usage once it ends; None at the deadline.

    The first polls come quickly and then slow down to ``POLL_SECONDS``: a run of a few
    milliseconds (the original tool on a small mission) is timed to the millisecond, a long
    one costs no more polling than before."""
    interval = FIRST_POLL_SECONDS
    while True:
        done, status, usage = os.wait4(pid, os.WNOHANG)
        if done:
            return status, usage
        if memory is not None:
            memory.sample()
        if cancel is not None and cancel.is_set():
            raise Cancelled()
        remaining = deadline - time.perf_counter()
        if remaining <= 0:
            return None
        time.sleep(min(interval, remaining))
        interval = min(2 * interval, POLL_SECONDS)


def _text(stream: IO[bytes]) -> str:
    stream.seek(0)
    return stream.read().decode("utf-8", errors="replace")


def run_measured(command: Sequence[str], cwd: str | os.PathLike[str], time_limit: float,
                 env: Mapping[str, str] | None = None, cancel: threading.Event | None = None,
                 pass_fds: Sequence[int] = ()) -> Measurement:
    """Run ``command`` in ``cwd`` with at most ``time_limit`` seconds of wall time.

    Standard output and error are collected in temporary files (a pipe could fill up and stall
    the child), standard input is empty; ``pass_fds`` are left open in the child.  Setting
    ``cancel`` kills the child and raises :class:`Cancelled`.

    The peak memory is the larger of the kernel's (the largest resident set the child had,
    counting the parent's own when it was started: ``fork`` copies it, so it is exact for a
    small parent only) and the largest total of the child's process tree, sampled
    (:class:`_TreeMemory`)."""
    start = time.perf_counter()
    with tempfile.TemporaryFile() as out, tempfile.TemporaryFile() as err:
        child = subprocess.Popen(list(command), cwd=Path(cwd), stdin=subprocess.DEVNULL, stdout=out, stderr=err,
                                 env=None if env is None else dict(env), start_new_session=True,
                                 pass_fds=tuple(pass_fds))
        ended = None
        memory = _TreeMemory(child.pid)
        try:
            ended = _wait(child.pid, start + time_limit, cancel, memory)
        finally:
            if ended is None:  # the time limit, a cancel, or the parent was interrupted: end the whole group
                _kill_group(child.pid)
                _, status, usage = os.wait4(child.pid, 0)
                child.returncode = os.waitstatus_to_exitcode(status)
        seconds = time.perf_counter() - start
        if ended is not None:
            status, usage = ended
            child.returncode = os.waitstatus_to_exitcode(status)
        return Measurement(exit_status=None if ended is None else child.returncode,
                           seconds=seconds, peak_mb=max(_peak_mb(usage), memory.peak_kb / 1024),
                           stdout=_text(out), stderr=_text(err))
