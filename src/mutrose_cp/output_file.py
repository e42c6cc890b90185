"""Where an output goes, and how it gets there without harm.

* A regular file is replaced atomically: the text is written to a temporary file beside it,
  which is renamed into place only when complete, so an interrupted or failed run leaves the old
  file (and no temporary file).  A replaced file keeps its permission bits; a new one follows the
  umask.  A symbolic link stays a link: the file it points to is replaced.
* A character device or a FIFO (``/dev/null``, a named pipe) is written through, never replaced.
* ``-`` is standard output.
* Every error names the path the user gave, never the temporary one.
"""
from __future__ import annotations

import os
import stat
import sys
import tempfile
from contextlib import contextmanager
from pathlib import Path
from typing import IO, Iterator

from .errors import MissionError

STDOUT = "-"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def _failure(path: str | os.PathLike, err: OSError) -> MissionError:
    reason = err.strerror or str(err)
    return MissionError(f"cannot write the output: {reason}", os.fspath(path))


@contextmanager
def atomic_writer(path: str | os.PathLike, mode: str = "w") -> Iterator[IO]:
    """A file object for the output at ``path`` (see the module docstring)."""
    if os.fspath(path) == STDOUT:
        stream = sys.stdout.buffer if "b" in mode else sys.stdout
        try:
            yield stream
            stream.flush()
        except BrokenPipeError:
            # nothing more can reach the reader; keep the interpreter's final flush quiet
            os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
            raise MissionError("cannot write the output: the reader closed the pipe", "standard output") from None
        except OSError as err:
            raise _failure("standard output", err) from None
        return
    target = Path(os.path.realpath(path))  # a link stays a link: replace what it points to
    try:
        existing = os.stat(target)
    except FileNotFoundError:
        existing = None
    except OSError as err:
        raise _failure(path, err) from None
    if existing is not None and stat.S_ISDIR(existing.st_mode):
        raise MissionError("cannot write the output: it is a folder; give a file name", os.fspath(path))
    encoding = None if "b" in mode else "utf-8"
    newline = None if "b" in mode else ""
    if existing is not None and not stat.S_ISREG(existing.st_mode):
        try:  # a device or a FIFO: write through, never replace it
            with open(target, mode, encoding=encoding, newline=newline) as fh:
                yield fh
        except OSError as err:
            raise _failure(path, err) from None
        return
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as err:
        raise _failure(path, err) from None
    try:
        os.fchmod(fd, stat.S_IMODE(existing.st_mode) if existing is not None else 0o666 & ~_umask())
        with os.fdopen(fd, mode, encoding=encoding, newline=newline) as fh:
            yield fh
        os.replace(tmp, target)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise _failure(path, exc) from None
        raise
