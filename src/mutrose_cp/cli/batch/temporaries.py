"""The temporary files a killed job leaves beside its outputs, removed by the batch.

The output layer writes a file ``NAME`` as ``.NAME.XXXXXXXX.tmp`` beside it and renames it into
place once complete (``output_file.atomic_writer``); an iHTN export builds its folder ``DIR`` as
``.DIR.XXXXXXXX.tmp`` beside it (``ihtn.write_ihtns``).  A job that fails cleans up after itself,
but one killed at its time limit (SIGKILL, to its whole process group), by the kernel, or on an
interrupt of the batch cannot: the batch, which knows every output of the job, removes them.
"""
from __future__ import annotations

import os
import re
import shutil
from pathlib import Path
from typing import Iterable

# what tempfile.mkstemp and mkdtemp add to the prefix ".NAME.": eight characters, then the suffix
TEMPORARY = r"\.[a-z0-9_]{8}\.tmp"


def remove_temporaries(cwd: str, outputs: Iterable[str], since: float) -> list[str]:
    """Remove the temporary files and folders of the ``outputs`` (files or folders, relative to
    ``cwd``) made since ``since`` (a second earlier, for the clock's resolution): older ones
    belong to someone else.  The names removed, relative to ``cwd``."""
    removed: list[str] = []
    for output in outputs:
        target = Path(os.path.realpath(Path(cwd) / output))
        pattern = re.compile(re.escape("." + target.name) + TEMPORARY)
        removed += [os.path.relpath(p, cwd) for p in _remove_matching(target.parent, pattern, since - 1)]
    return removed


def _remove_matching(folder: Path, pattern: re.Pattern[str], since: float) -> list[str]:
    """Remove the entries of ``folder`` whose name matches ``pattern``, made since ``since``
    (a link is never followed)."""
    removed = []
    try:
        entries = list(os.scandir(folder))
    except OSError:
        return []
    for entry in entries:
        try:
            if not pattern.fullmatch(entry.name) or entry.stat(follow_symlinks=False).st_mtime < since:
                continue
            if entry.is_dir(follow_symlinks=False):
                shutil.rmtree(entry.path)
            else:
                os.unlink(entry.path)
            removed.append(entry.path)
        except OSError:
            continue
    return removed
