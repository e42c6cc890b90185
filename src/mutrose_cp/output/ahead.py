"""The head of the JSON output written by a second process while the decompositions are solved.

Most of a large output is its head: the actions, a task entry per decomposition and the
constraints (at 5000 vital-signs rooms, 95,000 entries and a million constraints, 300 of its
330 MB).  None of it depends on the solver's answer, only on the Task Graph.  So on a machine
with a second core, ``decompose`` forks once the graph and the constraints are made: the child
writes the head to the output's temporary file while the parent solves; the parent then waits
for it and writes the tail (the mission decompositions and the decomposition space) after it, on
the same open file, whose offset the two processes share.  The bytes are those of writing the
whole document in one process.

The child only formats and writes, then leaves with ``os._exit`` (nothing of the parent's is
flushed or cleaned up twice).  A failure in it (a write error, a predicate with no semantic
mapping) is sent to the parent through a pipe and raised there, as if the parent had written the
head; if the parent stops first (an error, an interrupt), the child is killed and reaped before
the temporary file is removed, so nothing is left running or written.

The head is written in the parent, after the solve, where forking is not available or not
worth it: one core, a small mission, standard output or another format; and where memory comes
first: on the largest missions, where the memory the child copies (``AHEAD_MAX_DECOMPOSITIONS``)
matters more than the time it saves, and under a memory limit (which holds for each process).
"""
from __future__ import annotations

import os
import pickle
import resource
import signal
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Callable, Iterable, Iterator, Mapping

from ..errors import MissionError
from .builder import OutputBuilder, OutputModel
from .formats import write_output
from .files import STDOUT, atomic_writer

# decompositions below which the head is written in the parent: forking a small process and
# waiting for it costs more than writing its head
AHEAD_MIN_DECOMPOSITIONS = 20_000
# and above which, too: the child copies the pages of the objects it reads (their reference
# counts change), up to 60 % more memory in all (vital signs at 5000 rooms: 410 + 260 MB; at
# 50,000 rooms 3.8 + 2.3 GB), and on the largest missions memory comes first
AHEAD_MAX_DECOMPOSITIONS = 250_000

Finish = Callable[[Iterable[list[int]], Mapping[str, object] | None], None]


def _ahead(model: OutputModel, path: Path | str, file_type: str, json_style: str, minimum: int) -> bool:
    """Whether the head is worth writing in a second process (module docstring)."""
    return (file_type == "json" and json_style == "boost" and os.fspath(path) != STDOUT and hasattr(os, "fork")
            and _cores() > 1 and not _memory_limited()
            and minimum <= len(model.tg.decompositions()) <= AHEAD_MAX_DECOMPOSITIONS)


def _memory_limited() -> bool:
    """Whether the process runs under a memory limit (``batch --memory-mb`` sets ``RLIMIT_DATA``):
    the limit holds for each process, so a second one could take the run past it."""
    return any(resource.getrlimit(limit)[0] != resource.RLIM_INFINITY
               for limit in (resource.RLIMIT_DATA, resource.RLIMIT_AS))


def _cores() -> int:
    """The cores this process may run on."""
    return len(os.sched_getaffinity(0)) if hasattr(os, "sched_getaffinity") else os.cpu_count() or 1


@contextmanager
def output_while_solving(model: OutputModel, path: Path | str, file_type: str, json_style: str = "boost",
                         minimum: int | None = None) -> Iterator[Finish]:
    """Start writing the output of ``model`` (whose decompositions and space are not known yet)
    to ``path``; the block solves, then calls the function it is given with the decompositions
    and the space section, which completes the output.  The output is replaced only if the
    block and that call succeed.  ``minimum``: the decompositions from which the head is written
    ahead (``AHEAD_MIN_DECOMPOSITIONS`` by default)."""
    if not _ahead(model, path, file_type, json_style, AHEAD_MIN_DECOMPOSITIONS if minimum is None else minimum):
        def finish_here(decompositions: Iterable[list[int]], space: Mapping[str, object] | None) -> None:
            model.decompositions, model.space = decompositions, space
            write_output(model, path, file_type, json_style)

        yield finish_here
        return
    builder = OutputBuilder(model)
    with atomic_writer(path) as fh, _head_written_beside(builder, fh, path) as join:
        def finish(decompositions: Iterable[list[int]], space: Mapping[str, object] | None) -> None:
            join()
            model.decompositions, model.space = decompositions, space
            builder.write_json_tail(fh)

        yield finish


@contextmanager
def _head_written_beside(builder: OutputBuilder, fh: IO[str], path: Path | str) -> Iterator[Callable[[], None]]:
    """Fork a child that writes the head of ``builder``'s document to ``fh``; yield the function
    that waits for it (raising its failure).  Leaving the block early kills the child."""
    fh.flush()  # nothing of the parent's may be buffered twice
    read_end, write_end = os.pipe()
    pid = os.fork()
    if pid == 0:  # the child: never returns
        os.close(read_end)
        _write_head(builder, fh, write_end)
    os.close(write_end)
    pipe = os.fdopen(read_end, "rb")
    done = False

    def join() -> None:
        nonlocal done
        report = pipe.read()  # until the child ends
        _, status = os.waitpid(pid, 0)
        done = True
        if report:
            raise pickle.loads(report)
        if status != 0:
            raise MissionError(f"cannot write the output: the process writing its task entries stopped "
                               f"({_status_text(status)})", os.fspath(path))

    try:
        yield join
    finally:
        pipe.close()
        if not done:
            try:
                os.kill(pid, signal.SIGKILL)
            finally:
                os.waitpid(pid, 0)


def _write_head(builder: OutputBuilder, fh: IO[str], report: int) -> None:
    """The child's whole life: write the head, send a failure to the parent, leave."""
    status = 0
    try:
        for s in (signal.SIGINT, signal.SIGTERM):
            signal.signal(s, signal.SIG_DFL)  # a signal to the process group ends the child at once
        builder.write_json_head(fh)
        fh.flush()
    except BaseException as err:  # noqa: BLE001 - every failure goes to the parent
        status = 1
        try:
            data = pickle.dumps(err)
        except Exception:  # noqa: BLE001 - an exception that does not pickle is told by its text
            data = pickle.dumps(MissionError(f"cannot write the output: {err}"))
        try:
            os.write(report, data)
        except OSError:
            pass
    finally:
        os._exit(status)


def _status_text(status: int) -> str:
    if os.WIFSIGNALED(status):
        return f"killed by {signal.Signals(os.WTERMSIG(status)).name}"
    return f"exit status {os.WEXITSTATUS(status)}"

