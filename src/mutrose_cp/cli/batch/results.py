"""The results of a batch: one JSON line per finished job, and what a rerun can skip.

Each job gets an **input hash**: SHA-256 over the mutrose-cp version, the job's command line
(command, inputs, options, output) and the contents of every file it *reads*: the four mission
files (HDDL, goal model, configuration and the world the configuration or ``--world`` names,
resolved exactly as the command resolves them) and any other argument that names a file
(``--costs``, the output ``validate`` checks).  The files a job *writes* (``-o``, ``--schedule``,
``--gantt``, ``--ihtn``, ...) are never hashed: they change on every run, and a rerun would see a
new job each time.  A rerun skips a job whose line is present with the same hash: the same
command on the same bytes.  A job stopped at its time or memory limit is run again when the
rerun's limit is higher; one interrupted from outside the batch is always run again.

The results file itself is kept by :mod:`.journal`.  A line read from it is checked field by
field (:meth:`ResultLine.parse`): a line damaged by hand or by a crash is reported and skipped,
never trusted and never a traceback.
"""
from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import math
import os
from dataclasses import asdict, dataclass, fields
from pathlib import Path
from typing import Any, Callable

from ... import __version__
from .files import FileFinder, JobFiles
from .inputs import file_digest
from .job import JobSpec, Outcome
from .statuses import INTERRUPTED, MEMORY, STATUSES, TIMEOUT
from .manifest import Job


def _text(value: Any) -> bool:
    return isinstance(value, str)


def _texts(value: Any) -> bool:
    return isinstance(value, list) and all(isinstance(v, str) for v in value)


def _whole(value: Any) -> bool:
    return isinstance(value, int) and not isinstance(value, bool)


def _number(value: Any) -> bool:
    """A finite number (an integer too large for a float, 1e400 written out, is none)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return False
    try:
        return math.isfinite(value)
    except OverflowError:
        return False


def _or_null(check: Callable[[Any], bool]) -> Callable[[Any], bool]:
    return lambda value: value is None or check(value)


# each field's check and what it expects, for the message when a line does not pass
_FIELD_CHECKS: dict[str, tuple[Callable[[Any], bool], str]] = {
    "id": (_text, "a string"), "command": (_text, "a string"), "inputs": (_texts, "a list of strings"),
    "options": (_texts, "a list of strings"), "output": (_or_null(_text), "a string or null"),
    "input_hash": (_text, "a string"), "status": (lambda v: v in STATUSES, "one of " + ", ".join(STATUSES)),
    "exit_code": (_or_null(_whole), "a whole number or null"), "seconds": (_number, "a number"),
    "peak_mb": (_number, "a number"), "time_limit": (_or_null(_number), "a number or null"),
    "memory_mb": (_whole, "a whole number"), "summary": (_or_null(lambda v: isinstance(v, dict)), "an object or null"),
    "problems": (_texts, "a list of strings"),
}


@dataclass(frozen=True)
class ResultLine:
    """One line of the results file (the field order is the line's)."""

    id: str
    command: str
    inputs: list[str]
    options: list[str]
    output: str | None
    input_hash: str
    status: str
    exit_code: int | None
    seconds: float
    peak_mb: float
    time_limit: float | None
    memory_mb: int
    summary: dict[str, Any] | None
    problems: list[str]

    @classmethod
    def of(cls, job: Job, input_hash: str, spec: JobSpec, outcome: Outcome) -> "ResultLine":
        return cls(job.id, job.command, list(job.inputs), list(job.options), job.output, input_hash,
                   outcome.status, outcome.exit_code, outcome.seconds, outcome.peak_mb, spec.time_limit,
                   spec.memory_mb, outcome.summary, outcome.problems)

    @classmethod
    def parse(cls, text: str) -> "ResultLine":
        """The result a line of the results file holds; ``ValueError`` saying what is wrong with
        it (not JSON, a field missing, unknown or of the wrong type)."""
        try:
            data = json.loads(text)
        except RecursionError:  # [[[[...: not a result, whatever else it is
            raise ValueError("nested too deeply") from None
        if not isinstance(data, dict):
            raise ValueError("not a JSON object")
        names = [f.name for f in fields(cls)]
        missing = [n for n in names if n not in data]
        unknown = [k for k in data if k not in _FIELD_CHECKS]
        if missing or unknown:
            raise ValueError("; ".join([*(f"no field {n!r}" for n in missing[:3]),
                                        *(f"unknown field {k!r}" for k in unknown[:3])]))
        for name in names:
            check, expected = _FIELD_CHECKS[name]
            if not check(data[name]):
                raise ValueError(f"{name}: expected {expected}, found {json.dumps(data[name])[:60]}")
        return cls(**data)

    def text(self) -> str:
        return json.dumps(asdict(self), ensure_ascii=False) + "\n"

    def settles(self, spec: JobSpec) -> bool:
        """Whether this result stands for a run under ``spec``'s limits: any finished result does,
        except a time or memory stop when the limit is now higher, and an interruption."""
        if self.status == TIMEOUT:
            return _no_higher(spec.time_limit, self.time_limit)
        if self.status == MEMORY:
            return _no_higher(spec.memory_mb or None, self.memory_mb or None)
        return self.status != INTERRUPTED


def _no_higher(now: float | None, then: float | None) -> bool:
    """Whether the limit ``now`` is not above ``then`` (None: no limit, above every number)."""
    if now is None:
        return then is None
    return then is None or now <= then


# -- input hashes --------------------------------------------------------------------------------

class InputHasher:
    """Input hashes of the jobs of one batch; a file read by many jobs (a shared domain, a goal
    model) is hashed once."""

    def __init__(self, base: Path) -> None:
        self.base = base
        self.finder = FileFinder()
        self._digests: dict[tuple[str, int, int], str] = {}

    def files(self, job: Job, args: argparse.Namespace) -> JobFiles:
        """What ``job`` reads and writes, found from the jobs' folder (a FIFO or a device among
        its inputs: a located error)."""
        with contextlib.chdir(self.base):  # the job's paths are relative to where it runs
            return self.finder.job_files(job, args)

    def job_hash(self, job: Job, files: JobFiles) -> str:
        h = hashlib.sha256()
        h.update(json.dumps([__version__, job.command, job.inputs, job.options, job.output]).encode())
        with contextlib.chdir(self.base):
            for name in files.reads:
                h.update(f"\n{name}\0{self._digest(name)}".encode())
        if files.unresolved:
            h.update(f"\nunresolved\0{files.unresolved}".encode())
        return "sha256:" + h.hexdigest()

    def _digest(self, name: str) -> str:
        try:
            st = os.stat(name)
        except OSError as err:
            return f"unreadable: {err.strerror}"
        key = (os.path.realpath(name), st.st_size, st.st_mtime_ns)
        if key not in self._digests:
            self._digests[key] = file_digest(name)
        return self._digests[key]
