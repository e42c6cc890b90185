"""Interrupts: SIGINT and SIGTERM end a command cleanly, never with a partial result.

The command line installs :func:`signal_handlers` for the duration of a command.  A signal then
raises :class:`Interrupted` in the main thread, wherever it is: every ``finally`` and
``except BaseException`` on the way out runs, so temporary files are removed and no output is
replaced.  Long native calls (CP-SAT) run in a worker thread that the main thread waits for, so
the signal is handled at once and the solver is told to stop (:mod:`mutrose_cp.solve.run`).

:func:`phase` names what the command is doing, for the message ("interrupted while solving").
"""
from __future__ import annotations

import importlib
import os
import signal
import threading
from contextlib import contextmanager
from types import ModuleType
from typing import Iterator

FAULT_ENV = "MUTROSE_CP_FAULT"  # "<phase>:<INT|TERM>[:<delay seconds>]", used by the fault tests

_phase: list[str] = []


class Interrupted(BaseException):
    """The command was stopped by a signal; its exit status is 128 + the signal number."""

    def __init__(self, signum: int, during: str = "") -> None:
        super().__init__(signal.Signals(signum).name)
        self.signum = signum
        self.during = during  # the phase the command was in

    @property
    def exit_code(self) -> int:
        return 128 + self.signum


def _raise(signum: int, _frame: object) -> None:
    # a second Ctrl-C while the first unwinds (outputs removed, the reason printed) is ignored:
    # the command is already stopping, and must not stop halfway through its cleaning up
    for s in (signal.SIGINT, signal.SIGTERM):
        signal.signal(s, signal.SIG_IGN)
    raise Interrupted(signum, current_phase())


@contextmanager
def signal_handlers() -> Iterator[None]:
    """Turn SIGINT and SIGTERM into :class:`Interrupted` while the block runs (main thread only)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    previous = {s: signal.signal(s, _raise) for s in (signal.SIGINT, signal.SIGTERM)}
    try:
        yield
    finally:
        for s, handler in previous.items():
            signal.signal(s, handler)


@contextmanager
def signals_held() -> Iterator[None]:
    """Hold SIGINT and SIGTERM back while the block runs; they are delivered when it ends.  For
    work that must not be cut midway: a native module's initialisation (an exception raised
    inside it aborts the process) and the stopping of a solver thread."""
    held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
    try:
        yield
    finally:
        signal.pthread_sigmask(signal.SIG_SETMASK, held)


def native_import(name: str) -> ModuleType:
    """Import the native module ``name`` with interrupts held back (see :func:`signals_held`)."""
    with signals_held():
        return importlib.import_module(name)


def current_phase() -> str:
    return _phase[-1] if _phase else ""


@contextmanager
def phase(name: str) -> Iterator[None]:
    """Run a block as a named phase of the command (for messages and fault injection)."""
    _phase.append(name)
    _inject_fault(name)
    try:
        yield
    finally:
        _phase.pop()


def _inject_fault(name: str) -> None:
    """Send this process a signal when the phase named in ``$MUTROSE_CP_FAULT`` starts, after an
    optional delay: how the tests interrupt each phase at a known point."""
    spec = os.environ.get(FAULT_ENV, "")
    if not spec:
        return
    parts = spec.split(":")
    if parts[0] != name:
        return
    signum = signal.Signals["SIG" + (parts[1] if len(parts) > 1 else "INT")]
    delay = float(parts[2]) if len(parts) > 2 else 0.0
    if delay <= 0:
        os.kill(os.getpid(), signum)
    else:
        timer = threading.Timer(delay, os.kill, (os.getpid(), signum))
        timer.daemon = True
        timer.start()
