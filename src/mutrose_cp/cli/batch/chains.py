"""Jobs that read what other jobs of the batch write (``validate`` after ``decompose``).

A batch has no order of its own between jobs (run such a pair with ``--jobs 1``, in manifest
order), but its results file must not go stale over them: a reader's input hash covers the file
another job writes, and that file changes when its writer runs.  So:

* a reader runs whenever one of its writers runs (and so on, along a chain), even when its own
  line is present: the file it reads is about to change;
* a reader's hash is taken again when it is recorded, from the file as it read it, so that the
  next run, which finds that file unchanged, skips it.
"""
from __future__ import annotations

import os
from pathlib import Path

from .files import JobFiles


def writers_of(files: list[JobFiles], base: Path) -> list[frozenset[int]]:
    """For each job, the other jobs that write a file it reads (paths compared resolved, since
    the files may not exist yet)."""
    written: dict[str, set[int]] = {}
    for j, found in enumerate(files):
        for w in found.writes:
            written.setdefault(os.path.realpath(base / w.path), set()).add(j)
    return [frozenset(j for name in found.reads for j in written.get(os.path.realpath(base / name), ()) if j != i)
            for i, found in enumerate(files)]


def must_run(settled: list[bool], writers: list[frozenset[int]]) -> list[bool]:
    """Which jobs run: those not settled, and every reader of a job that runs."""
    run = [not s for s in settled]
    changed = True
    while changed:
        changed = False
        for i, ws in enumerate(writers):
            if not run[i] and any(run[j] for j in ws):
                run[i] = changed = True
    return run
