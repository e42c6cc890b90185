"""The results of a batch: one JSON line per finished job, and what a rerun can skip.

Each job gets an **input hash**: SHA-256 over the mutrose-cp version, the job's command line
(command, inputs, options, output) and the contents of every file it reads: the four mission
files (HDDL, goal model, configuration and the world the configuration or ``--world`` names,
resolved exactly as the command resolves them) and any other argument that names a file
(``--costs``, the output ``validate`` checks).  A rerun skips a job whose line is present with
the same hash: the same command on the same bytes.  A job stopped at its time or memory limit is
run again when the rerun's limit is higher.

The file is written as a journal while the batch runs (one whole line per finished job, appended
and flushed at once, so an interrupt loses no finished job and records no unfinished one), then
rewritten atomically in manifest order at the end, so its order does not depend on which worker
finished first.  The fields of a line are always in the order of :class:`ResultLine`.
"""
from __future__ import annotations

import argparse
import contextlib
import hashlib
import json
import os
from dataclasses import asdict, dataclass
from pathlib import Path
from typing import IO, Any, Callable, Iterable

from .. import __version__
from ..errors import MissionError
from ..output_file import atomic_writer
from .job import MEMORY, TIMEOUT, JobSpec, Outcome
from .manifest import Job


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

    def text(self) -> str:
        return json.dumps(asdict(self), ensure_ascii=False) + "\n"

    def settles(self, spec: JobSpec) -> bool:
        """Whether this result stands for a run under ``spec``'s limits: any finished result does,
        except a time or memory stop when the limit is now higher."""
        if self.status == TIMEOUT:
            return _no_higher(spec.time_limit, self.time_limit)
        if self.status == MEMORY:
            return _no_higher(spec.memory_mb or None, self.memory_mb or None)
        return True


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
        self._digests: dict[tuple[str, int, int], str] = {}
        self._worlds: dict[tuple[str, int, int, bool], Path] = {}  # a configuration read by many jobs: read once

    def job_hash(self, job: Job, args: argparse.Namespace) -> str:
        h = hashlib.sha256()
        h.update(json.dumps([__version__, job.command, job.inputs, job.options, job.output]).encode())
        with contextlib.chdir(self.base):  # the job's paths are relative to where it runs
            for name, digest in self._files(job, args):
                h.update(f"\n{name}\0{digest}".encode())
        return "sha256:" + h.hexdigest()

    def _files(self, job: Job, args: argparse.Namespace) -> list[tuple[str, str]]:
        named = [a for a in (*job.inputs, *job.options) if os.path.isfile(a)]
        try:
            mission = [str(p) for p in mission_files(job, args, self._world)]
        except (MissionError, OSError) as err:  # the job will fail on it: the reason stands in for the files
            return [(name, self._digest(name)) for name in named] + [("unresolved", str(err))]
        return [(name, self._digest(name)) for name in sorted(set(named) | set(mission))]

    def _world(self, config: Path, lenient: bool) -> Path:
        """The world file ``config`` names (as the command resolves it from here)."""
        from ..io.config import load_configuration
        from ..mission import resolve_config_path

        def read() -> Path:
            return resolve_config_path(load_configuration(config, lenient=lenient).world_db.path, config)

        try:
            st = os.stat(config)
        except OSError:  # the reader says what is wrong with it
            return read()
        key = (os.path.realpath(config), st.st_size, st.st_mtime_ns, lenient)
        if key not in self._worlds:
            self._worlds[key] = read()
        return self._worlds[key]

    def _digest(self, name: str) -> str:
        try:
            st = os.stat(name)
        except OSError as err:
            return f"unreadable: {err.strerror}"
        key = (os.path.realpath(name), st.st_size, st.st_mtime_ns)
        if key not in self._digests:
            with open(name, "rb") as fh:
                self._digests[key] = hashlib.file_digest(fh, "sha256").hexdigest()
        return self._digests[key]


def mission_files(job: Job, args: argparse.Namespace, world_of: Callable[[Path, bool], Path]) -> list[Path]:
    """The HDDL, goal model, configuration and world a job reads, found as the command finds them
    (``find_mission_files``, ``--world`` or the configuration's world path, which ``world_of``
    reads).  Empty for a job whose inputs are not a mission."""
    from ..mission import find_mission_files

    first = Path(job.inputs[0])
    if first.is_dir():
        hddl, gm, config = find_mission_files(first, getattr(args, "config", None),
                                              hddl_name=getattr(args, "hddl", None), gm_name=getattr(args, "gm", None))
    elif len(job.inputs) >= 3:
        hddl, gm, config = (Path(p) for p in job.inputs[:3])
    else:
        return []
    world = getattr(args, "world", None)
    if world is None:
        world = world_of(config, getattr(args, "lenient_xml", False))
    return [hddl, gm, config, Path(world)]


# -- the results file ----------------------------------------------------------------------------

class ResultsFile:
    """The results of earlier runs (by input hash) and the journal of this one."""

    def __init__(self, path: Path) -> None:
        self.path = path
        self.lines: dict[str, ResultLine] = {}
        self.ignored: list[str] = []  # lines that are not results (a write cut short by a crash)
        self._journal: IO[str] | None = None
        if path.exists():
            self._read()

    def _read(self) -> None:
        with open(self.path, encoding="utf-8") as fh:
            for number, text in enumerate(fh, start=1):
                try:
                    line = ResultLine(**json.loads(text))
                except (ValueError, TypeError):
                    self.ignored.append(f"{self.path}:{number}: not a result line: ignored, its job runs again")
                    continue
                self.lines[line.input_hash] = line

    def done(self, input_hash: str, spec: JobSpec) -> ResultLine | None:
        """The result that settles the job with this hash under ``spec``'s limits, if present."""
        line = self.lines.get(input_hash)
        return line if line is not None and line.settles(spec) else None

    def record(self, line: ResultLine) -> None:
        """Append one finished job's line to the journal at once."""
        if self._journal is None:
            self.path.parent.mkdir(parents=True, exist_ok=True)
            self._journal = open(self.path, "a", encoding="utf-8")  # noqa: SIM115 - closed by close()
        self._journal.write(line.text())
        self._journal.flush()
        self.lines[line.input_hash] = line

    def close(self, order: Iterable[str]) -> None:
        """End the journal and rewrite the file atomically: the lines of the manifest's jobs in its
        order (``order``: their input hashes), then the lines of jobs it no longer lists."""
        if self._journal is not None:
            self._journal.close()
            self._journal = None
        if not self.lines:
            return
        ordered = [h for h in dict.fromkeys(order) if h in self.lines]
        listed = set(ordered)
        rest = [h for h in self.lines if h not in listed]
        with atomic_writer(self.path) as fh:
            for h in (*ordered, *rest):
                fh.write(self.lines[h].text())
