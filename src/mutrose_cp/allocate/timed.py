"""A computation that cannot be stopped midway, run within a deadline: in a child process.

Clarabel's time limit holds for its iterations, not for its setup (ordering and factoring the
LP's system), which on a large LP takes longer than the LP's whole share of the time limit.  A
thread would not do: one left behind at the deadline runs on, and ends the process with an abort
if the interpreter exits first.  So the computation runs in a forked child, which sends its
result back through a pipe (pickled) and leaves with ``os._exit``; a child still running at the
deadline is killed and reaped, and the caller gets nothing.  An interrupt in the parent kills the
child too.  Where ``fork`` is missing the computation runs here, to its end.
"""
from __future__ import annotations

import os
import pickle
import select
import signal
import time
from typing import Any, Callable


def run_within(run: Callable[[], Any], seconds: float) -> tuple[bool, Any]:
    """``(True, run())`` when it returns within ``seconds``, ``(False, None)`` otherwise; an
    exception of ``run`` is raised here (when it pickles; else a ``RuntimeError`` with its text)."""
    if not hasattr(os, "fork"):
        return True, run()
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        os.close(read_end)
        _child(run, write_end)
    os.close(write_end)
    ended = False
    try:
        data = _read_until(read_end, time.monotonic() + max(0.0, seconds))
        if data is None:
            return False, None
        os.waitpid(pid, 0)
        ended = True
        done, value = pickle.loads(data)
        if not done:
            raise value
        return True, value
    finally:
        os.close(read_end)
        if not ended:
            try:
                os.kill(pid, signal.SIGKILL)
            except ProcessLookupError:
                pass
            os.waitpid(pid, 0)


def _read_until(fd: int, deadline: float) -> bytes | None:
    """Everything the child writes to ``fd`` until it closes it, or None at the ``deadline``."""
    chunks: list[bytes] = []
    while True:
        left = deadline - time.monotonic()
        if left <= 0:
            return None
        readable, _, _ = select.select([fd], [], [], left)
        if not readable:
            return None
        chunk = os.read(fd, 1 << 16)
        if not chunk:
            return b"".join(chunks)
        chunks.append(chunk)


def _child(run: Callable[[], Any], report: int) -> None:
    """The child's whole life: run, send the result or the failure to the parent, leave."""
    status = 0
    try:
        for s in (signal.SIGINT, signal.SIGTERM):
            signal.signal(s, signal.SIG_DFL)  # a signal to the process group ends the child at once
        try:
            data = pickle.dumps((True, run()))
        except BaseException as err:  # noqa: BLE001 - every failure goes to the parent
            status = 1
            try:
                data = pickle.dumps((False, err))
            except Exception:  # noqa: BLE001 - an exception that does not pickle is told by its text
                data = pickle.dumps((False, RuntimeError(f"{type(err).__name__}: {err}")))
        view = memoryview(data)
        while view:
            view = view[os.write(report, view):]
    finally:
        os._exit(status)
