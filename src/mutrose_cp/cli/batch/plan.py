"""What a batch settles before its first job runs: every job's files, the checks of what they
write, their input hashes, what each worker is given, and which jobs read what others write.

All of it is done before the results file is opened, so that a problem found here (a FIFO among
the inputs, two jobs writing one file) stops the batch with nothing written at all.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass

from ...errors import MissionError, Problem
from .chains import must_run, writers_of
from .files import JobFiles
from .job import JobSpec
from .manifest import Job, check_jobs
from .results import InputHasher, ResultLine
from .safety import BatchFiles, refuse_unsafe_writes


@dataclass
class Plan:
    """The jobs of a batch and what is known of each before any runs; ``writers[i]``: the jobs
    that write what job ``i`` reads (:mod:`.chains`)."""

    jobs: list[Job]
    files: list[JobFiles]
    hashes: list[str]
    specs: list[JobSpec]
    writers: list[frozenset[int]]
    hasher: InputHasher
    batch: BatchFiles

    def to_run(self, found: list[ResultLine | None]) -> list[int]:
        """The jobs to run, given the result ``found`` for each (None: not settled): the
        unsettled ones, and the readers of what those write."""
        return [i for i, run in enumerate(must_run([line is not None for line in found], self.writers)) if run]

    def recorded_hash(self, i: int) -> str:
        """The hash to record for job ``i`` once it has run: a reader's is taken again, from the
        files as it read them (what another job wrote meanwhile)."""
        if self.writers[i]:
            self.hashes[i] = self.hasher.job_hash(self.jobs[i], self.files[i])
        return self.hashes[i]


def make_plan(jobs: list[Job], batch: BatchFiles, time_limit: float | None, memory_mb: int) -> Plan:
    """Check the jobs and their files (every problem at once, exit 2) and plan them."""
    parsed = check_jobs(jobs, batch.base)
    hasher = InputHasher(batch.base)
    files = _files(jobs, parsed, hasher)
    refuse_unsafe_writes(batch, jobs, files)
    specs = [JobSpec(job.command_line(), str(batch.base), time_limit, memory_mb,
                     outputs=tuple(w.path for w in found.writes)) for job, found in zip(jobs, files)]
    return Plan(jobs, files, _hashes(jobs, files, hasher), specs, writers_of(files, batch.base), hasher, batch)


def _files(jobs: list[Job], parsed: list[argparse.Namespace], hasher: InputHasher) -> list[JobFiles]:
    """What every job reads and writes; an input that cannot be read whole (a FIFO, a device)
    is a problem located at its job."""
    found: list[JobFiles] = []
    problems: list[Problem] = []
    for job, args in zip(jobs, parsed):
        try:
            found.append(hasher.files(job, args))
        except MissionError as err:
            problems.extend(Problem(f"{job.where}: job {job.id}", str(p)) for p in err.problems)
    if problems:
        raise MissionError(problems)
    return found


def _hashes(jobs: list[Job], files: list[JobFiles], hasher: InputHasher) -> list[str]:
    """The input hash of every job; two jobs with the same hash are one job listed twice."""
    hashes: list[str] = []
    first: dict[str, Job] = {}
    problems: list[Problem] = []
    for job, found in zip(jobs, files):
        h = hasher.job_hash(job, found)
        if h in first:
            problems.append(Problem(job.where, f"job {job.id} repeats job {first[h].id} (same command, options, "
                                               "output and inputs)"))
        first.setdefault(h, job)
        hashes.append(h)
    if problems:
        raise MissionError(problems)
    return hashes
