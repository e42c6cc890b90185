"""The checks that keep a batch's files safe, made before any job runs.

A batch writes many files from many processes, hours apart; a mistake in a manifest found after
the first job is found too late.  So before anything runs, every file the batch or its jobs
write is compared with every file that must survive, by identity (device and inode, so links
and hard links count as the file they reach):

* the results file is a file the batch can write: not ``-``, not a folder, a FIFO or a device,
  its folder not a file; and it is not the manifest, nor any file a job reads or writes, nor in
  a folder a job writes files into;
* no job writes the manifest or the results file, nor one of its own inputs;
* no two jobs write one file, whichever options name it (``-o``, ``--schedule``, ``--gantt``,
  ``--problem-out``, ``--plot``, any option typed as an output) or default to it
  (``schedule.json`` beside ``-o``, the configuration's output path); no two jobs write into one
  folder (``--ihtn``), and no job writes a file into another job's folder.  Running one job
  after the other would not help: the later replaces the earlier's output.

A job may read what another job writes (``validate`` after ``decompose``): that is how a batch
chains commands.  Each problem names the job (its place in the manifest and its id) and the
option, or ``--results``; all of them are reported at once (exit 2).
"""
from __future__ import annotations

import os
import stat
from dataclasses import dataclass
from pathlib import Path

from ...errors import MissionError, Problem
from ...output.files import STDOUT, refuse_unsafe_outputs
from .files import JobFiles, Written
from .inputs import identity, kind_of
from .manifest import Job


@dataclass(frozen=True)
class BatchFiles:
    """The batch's own files: the manifest (None with ``--each``), the results file (absolute)
    and its path as the user gave it (``named``; ``given``: with ``--results``), and the jobs'
    folder."""

    manifest: Path | None
    results: Path
    named: str
    given: bool
    base: Path

    @property
    def results_where(self) -> str:
        """Where a problem with the results file is located: ``--results FILE``, or the
        default path."""
        return f"--results {self.named}" if self.given else self.named


@dataclass(frozen=True)
class _Writer:
    """A job and one file or folder it writes."""

    job: Job
    written: Written


def refuse_unsafe_writes(batch: BatchFiles, jobs: list[Job], files: list[JobFiles]) -> None:
    """Every problem with what the batch and its jobs write (module docstring), at once."""
    refuse_unusable_results(batch)
    problems = (_job_writes(batch, jobs, files) + _own_inputs(batch, jobs, files)
                + _results_problems(batch, jobs, files))
    if problems:
        raise MissionError(problems)


def refuse_unusable_results(batch: BatchFiles) -> None:
    """A results path the batch cannot keep a journal in: standard output (the file is read back
    on every rerun), the manifest, a folder, a FIFO or a device, a path whose folder is a file or
    not writable."""
    where = batch.results_where
    if batch.named == STDOUT:
        raise MissionError("the results file is read again when the batch is run again: give a file, not -", where)
    if batch.manifest is not None and identity(batch.manifest) == identity(batch.results):
        raise MissionError(f"the results file would overwrite the input {batch.manifest}, the manifest: give "
                           "another results file", where)
    try:
        mode: int | None = os.stat(batch.results).st_mode
    except (FileNotFoundError, NotADirectoryError):  # no file yet, or a file where a folder should be (below)
        mode = None
    except OSError as err:
        raise MissionError(f"cannot write the results file: {err.strerror or err}", where) from None
    if mode is not None and not stat.S_ISREG(mode):
        raise MissionError(f"the results file is {kind_of(mode)}: give the path of a regular file", where)
    try:
        refuse_unsafe_outputs([batch.results], [])  # a file where its folder should be, an unwritable folder
    except MissionError as err:
        raise MissionError([Problem(where, p.message.replace("the output", "the results file"))
                            for p in err.problems]) from None


def _job_writes(batch: BatchFiles, jobs: list[Job], files: list[JobFiles]) -> list[Problem]:
    """A job writing the manifest or the results file, two jobs (or two options of one job)
    writing one file or into one folder, a job writing into another's folder."""
    guarded = {identity(batch.results): "the results file"}
    if batch.manifest is not None:
        guarded[identity(batch.manifest)] = "the manifest"
    problems = []
    writers: dict[tuple[object, ...], _Writer] = {}
    for job, found in zip(jobs, files):
        for written in found.writes:
            key = identity(batch.base / written.path)
            if key in guarded:
                problems.append(Problem(job.where, f"job {job.id} writes {guarded[key]} {written.path}"
                                                   f"{_named(written)}: give it another file"))
            elif key in writers:
                problems.append(_twice(_Writer(job, written), writers[key]))
            else:
                writers[key] = _Writer(job, written)
    return problems + _into_folders(batch, list(writers.values()))


def _twice(now: _Writer, before: _Writer) -> Problem:
    """Two writers of one file or folder."""
    job, written = now.job, now.written
    what = "into " if written.folder else ""
    return Problem(job.where, f"job {job.id} writes {what}{written.path}{_named(written)}, as job {before.job.id} "
                              f"does{_named(before.written)}: give each job its own output")


def _into_folders(batch: BatchFiles, writers: list[_Writer]) -> list[Problem]:
    """A file written directly into a folder another job writes its files into (an export may
    replace any file there), and the results file in such a folder."""
    folders = {os.path.realpath(batch.base / w.written.path): w for w in writers if w.written.folder}
    problems = []
    for writer in writers:
        parent = os.path.dirname(os.path.realpath(batch.base / writer.written.path))
        owner = folders.get(parent)
        if owner is not None and owner.job is not writer.job and not writer.written.folder:
            job = writer.job
            problems.append(Problem(job.where, f"job {job.id} writes {writer.written.path}{_named(writer.written)} "
                                               f"into {owner.written.path}, the folder job {owner.job.id} writes its "
                                               f"files into ({owner.written.option}): give it another folder"))
    owner = folders.get(os.path.dirname(os.path.realpath(batch.results)))
    if owner is not None:
        problems.append(Problem(batch.results_where, f"the results file is in {owner.written.path}, the folder job "
                                                     f"{owner.job.id} writes its files into ({owner.written.option}): "
                                                     "give another results file"))
    return problems


def _named(written: Written) -> str:
    """How a job names an output, for messages: nothing for ``-o``, the option otherwise."""
    return "" if written.option == "-o" else f" ({written.option})"


def _own_inputs(batch: BatchFiles, jobs: list[Job], files: list[JobFiles]) -> list[Problem]:
    """A job writing one of its own inputs (the command would refuse it when its turn comes:
    refused here, before the batch starts)."""
    problems = []
    for job, found in zip(jobs, files):
        reads = {identity(batch.base / name): name for name in found.reads}
        for written in found.writes:
            read = reads.get(identity(batch.base / written.path))
            if read is not None and not written.folder:
                problems.append(Problem(job.where, f"job {job.id} writes {written.path}{_named(written)}, which is "
                                                   f"its input {read}: give the output another file"))
    return problems


def _results_problems(batch: BatchFiles, jobs: list[Job], files: list[JobFiles]) -> list[Problem]:
    """The results file being a file some job reads."""
    results = identity(batch.results)
    problems = []
    for job, found in zip(jobs, files):
        read = next((name for name in found.reads if identity(batch.base / name) == results), None)
        if read is not None:
            problems.append(Problem(batch.results_where, f"the results file would overwrite the input {read} of "
                                                         f"job {job.id} ({job.where}): give another results file"))
    return problems
