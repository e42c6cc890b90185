"""What every command-line front end (``mutrose-cp``, ``mutrose``) does around its command:
the settings a short-lived decomposition process runs best with, how a failure is told, and
how the process ends."""
from __future__ import annotations

import atexit
import gc
import os
import signal
import sys
from contextlib import contextmanager
from typing import Iterator

from ..errors import MissionError, Problem
from ..interrupt import Interrupted

Failure = Interrupted | MissionError | RecursionError | OSError  # what ends a command without a traceback


@contextmanager
def command_settings() -> Iterator[None]:
    """The cyclic garbage collector paused and big-integer printing unlimited, for the command
    only (both are restored for an embedding program).

    The pipeline allocates millions of small acyclic objects (vertices, edges, literals), which
    the collector would rescan over and over (up to 3x the run time on large missions); exact
    counts are big integers (3^10000 has 4772 digits, over Python's default limit for converting
    an int to text)."""
    collecting = gc.isenabled()
    gc.disable()
    digits = sys.get_int_max_str_digits()
    sys.set_int_max_str_digits(0)
    try:
        yield
    finally:
        sys.set_int_max_str_digits(digits)
        if collecting:
            gc.enable()


FAILURES = (Interrupted, MissionError, RecursionError, OSError)  # Failure, for ``except``


def prepare_process() -> None:
    """What both front ends set up first: a usable stderr, and writes over a file-size limit
    failing with EFBIG (a located error) instead of the signal killing the process."""
    usable_stderr()
    if hasattr(signal, "SIGXFSZ"):
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)


def usable_stderr() -> None:
    """Started with stderr closed, messages go nowhere rather than failing the command."""
    try:
        os.fstat(2)
    except OSError:
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115 - lives as long as the process
        return
    if sys.stderr is None:
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115


_kept: list[object] = []  # what a finished command leaves for the end of the process
_ends_with_command = False  # set by the console scripts


def process_ends_with_command() -> None:
    """Say that the process ends when the command returns (the console scripts; not a program
    that calls ``main``), so that :func:`keep_until_exit` may keep what the command made."""
    global _ends_with_command
    _ends_with_command = True


def keep_until_exit(*objects: object) -> None:
    """Keep a finished command's mission, Task Graph and decomposition space until the process
    ends, when it ends with the command: freeing millions of objects one by one takes a
    noticeable part of a large run (0.25 s of 5 s at 5000 vital-signs rooms), and the operating
    system takes the memory back at once when the process exits.  The objects are also moved
    out of the cyclic collector's reach, so that re-enabling it does not rescan them.  In a
    program that calls ``main``, nothing is kept."""
    if _ends_with_command:
        _kept.extend(objects)
        gc.freeze()


def exit_process(code: int) -> None:
    """End the process with ``code``.  After an interrupt everything is cleaned up already, and
    the process ends at once: a CP-SAT search stopped midway can leave native state whose
    teardown at interpreter exit aborts the process (status 134 instead of 130).  When a
    command kept its objects (:func:`keep_until_exit`), the process ends at once too, after the
    streams are flushed and the exit handlers run, as the interpreter would; a stream that
    cannot be flushed is left to the interpreter, which reports it as usual."""
    if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(code)
    if _kept:
        try:
            sys.stdout.flush()
            sys.stderr.flush()
        except (OSError, ValueError):
            sys.exit(code)
        atexit._run_exitfuncs()
        os._exit(code)
    sys.exit(code)


def failure_problems(err: Failure) -> list[Problem]:
    """Why a command stopped, as located problems (the front ends print them, ``--json-summary``
    lists them)."""
    match err:
        case MissionError(problems=problems):
            return list(problems)
        case Interrupted(during=during):
            return [Problem("", f"interrupted{' while ' + during if during else ''} ({err}): no output was written")]
        case RecursionError():
            return [Problem("", "the mission is nested too deeply to process")]
    assert isinstance(err, OSError)
    return [Problem(str(err.filename or ""), err.strerror or str(err))]


def failure_lines(err: Failure) -> list[str]:
    """The lines that tell why a command stopped: ``error: <problem>`` each, an interrupt as
    itself."""
    if isinstance(err, Interrupted):
        return [str(p) for p in failure_problems(err)]
    return [f"error: {p}" for p in failure_problems(err)]


def failure_status(err: Failure) -> int:
    """The exit status of a failed command: the error's own, else 2 (invalid input)."""
    return err.exit_code if isinstance(err, (Interrupted, MissionError)) else 2


def _to_devnull(fd: int) -> None:
    devnull = os.open(os.devnull, os.O_WRONLY)
    os.dup2(devnull, fd)
    os.close(devnull)


def reader_gone() -> int:
    """The reader of stdout went away (``… | head``): say so on stderr while it has a reader
    (``2>&1 | head`` closes both), send whatever is left to print nowhere, so that the exit does
    not fail a second time with a traceback; status 2."""
    _to_devnull(sys.stdout.fileno())
    try:
        print("error: standard output: the reader closed the pipe; the output was not written", file=sys.stderr)
        sys.stderr.flush()
    except OSError:
        _to_devnull(sys.stderr.fileno())
    return 2
