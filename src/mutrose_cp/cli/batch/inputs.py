"""Reading a job's inputs to hash them, without ever waiting on one.

A batch reads each input whole before any job runs (its input hash).  A FIFO would make that
read wait for a writer forever (``open`` itself blocks on a FIFO with no writer), a character
device such as ``/dev/zero`` never ends, and a socket cannot be opened at all.  So every input is
opened with ``O_NONBLOCK`` and refused unless it is a regular file, as the commands refuse it
(:func:`mutrose_cp.io.text.read_bytes`), before the batch spends any time on the jobs.
"""
from __future__ import annotations

import hashlib
import os
import stat

from ...errors import MissionError, Problem

_KINDS = ((stat.S_ISFIFO, "a FIFO (named pipe)"), (stat.S_ISCHR, "a character device"),
          (stat.S_ISBLK, "a block device"), (stat.S_ISSOCK, "a socket"), (stat.S_ISDIR, "a folder"))
_HINT = "a batch reads each input whole to hash it: give a regular file"


def kind_of(mode: int) -> str | None:
    """What a file that is not a regular file is (``a FIFO``...), None for a regular file."""
    return next((name for test, name in _KINDS if test(mode)), None)


def identity(path: str | os.PathLike[str]) -> tuple[object, ...]:
    """What makes two paths one file: device and inode when it exists (links, hard links), else
    the path with every link of its folders resolved."""
    try:
        st = os.stat(path)
    except (OSError, ValueError):
        return ("new", os.path.realpath(path))
    return ("file", st.st_dev, st.st_ino)


def refuse_special_input(name: str) -> None:
    """Refuse an input that is a FIFO, a device or a socket; a folder, a regular file, or no
    file at all (the job reports that itself) passes."""
    try:
        mode = os.stat(name).st_mode
    except (OSError, ValueError):
        return
    kind = kind_of(mode)
    if kind is not None and not stat.S_ISDIR(mode):
        raise MissionError(Problem(name, f"the input is {kind}, not a regular file: {_HINT}"))


def file_digest(name: str) -> str:
    """SHA-256 of the regular file ``name``, read without blocking; for a file that cannot be
    opened, why (the job then fails on it, and the reason stands in for its bytes)."""
    try:
        fd = os.open(name, os.O_RDONLY | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0))
    except OSError as err:
        return f"unreadable: {err.strerror or err}"
    kind = kind_of(os.fstat(fd).st_mode)
    if kind is not None:  # replaced by a FIFO since it was checked
        os.close(fd)
        raise MissionError(Problem(name, f"the input is {kind}, not a regular file: {_HINT}"))
    with os.fdopen(fd, "rb") as fh:
        return hashlib.file_digest(fh, "sha256").hexdigest()
