"""Where an output goes, and how it gets there without harm.

* A regular file is replaced atomically: the text is written to a temporary file beside it,
  which is renamed into place only when complete, so an interrupted or failed run leaves the old
  file (and no temporary file).  A replaced file keeps its permission bits; a new one follows the
  umask.  A symbolic link stays a link: the file it points to is replaced.
* A character device or a FIFO (``/dev/null``, a named pipe) is written through, never replaced.
  A FIFO is opened without waiting: when no process reads it, the write fails at once.
* ``-`` is standard output.
* Every error names the path the user gave, never the temporary one.

:func:`refuse_unsafe_outputs` checks a command's outputs before it does any work: an output that
is one of its inputs, two outputs that are one file, an output that is a folder (or ends with
``/``), an empty path, a folder that cannot hold it; an output folder that holds an input.
:func:`staged_outputs` makes a command that writes several files replace them all or none, and
concurrent runs that write the same set write it in turn (:func:`written_together`).
"""
from __future__ import annotations

import errno
import fcntl
import os
import stat
import sys
import tempfile
from contextlib import AbstractContextManager, contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from pathlib import Path
from typing import IO, Any, Iterable, Iterator, Literal, cast, overload

from ..errors import MissionError
from .write_behind import WriteBehind

STDOUT = "-"


def _umask() -> int:
    mask = os.umask(0)
    os.umask(mask)
    return mask


def write_failure(path: str | os.PathLike[str], err: OSError) -> MissionError:
    """Why an output could not be written, located at the path the user gave."""
    reason = err.strerror or str(err)
    return MissionError(f"cannot write the output: {reason}", os.fspath(path))


@overload
def atomic_writer(path: str | os.PathLike[str], mode: Literal["w"] = "w", *,
                  behind: bool = False) -> AbstractContextManager[IO[str]]: ...


@overload
def atomic_writer(path: str | os.PathLike[str], mode: Literal["wb"], *,
                  behind: bool = False) -> AbstractContextManager[IO[bytes]]: ...


@contextmanager
def atomic_writer(path: str | os.PathLike[str], mode: str = "w", *, behind: bool = False) -> Iterator[IO[Any]]:
    """A file object for the output at ``path`` (see the module docstring).  With ``behind``,
    a replaced file's text is written by a second thread while the caller goes on formatting
    (:mod:`mutrose_cp.output.write_behind`): for the large outputs, written from one thread and not
    across a fork."""
    if os.fspath(path) == STDOUT:
        with _standard_output(mode) as stream:
            yield stream
        return
    target = Path(os.path.realpath(path))  # a link stays a link: replace what it points to
    existing = _existing(target, path)
    if existing is not None and not stat.S_ISREG(existing.st_mode):
        with _written_through(target, path, mode, stat.S_ISFIFO(existing.st_mode)) as fh:
            yield fh
        return
    stage = _STAGE.get()
    with _replaced(target, path, mode, existing, behind and "b" not in mode,
                   stage if stage is not None and stage.holds(target) else None) as fh:
        yield fh


def _text_options(mode: str) -> tuple[str | None, str | None]:
    """``open``'s encoding and newline: UTF-8 text with the newlines as written, or bytes."""
    return (None, None) if "b" in mode else ("utf-8", "")


@contextmanager
def _standard_output(mode: str) -> Iterator[IO[Any]]:
    """Standard output, flushed at the end, so that a write error is reported here (as the
    user's error) and not by the interpreter at exit."""
    stream: IO[Any] = sys.stdout.buffer if "b" in mode else sys.stdout
    try:
        yield stream
        stream.flush()
    except BrokenPipeError:
        # nothing more can reach the reader; keep the interpreter's final flush quiet
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        raise MissionError("cannot write the output: the reader closed the pipe", "standard output") from None
    except OSError as err:
        raise write_failure("standard output", err) from None


def _existing(target: Path, path: str | os.PathLike[str]) -> os.stat_result | None:
    """The status of the file to be replaced, ``None`` if there is none yet; a folder is refused
    here, before anything is written."""
    try:
        existing = os.stat(target)
    except FileNotFoundError:
        return None
    except OSError as err:
        raise write_failure(path, err) from None
    if stat.S_ISDIR(existing.st_mode):
        raise MissionError("cannot write the output: it is a folder; give a file name", os.fspath(path))
    return existing


@contextmanager
def _written_through(target: Path, path: str | os.PathLike[str], mode: str, fifo: bool) -> Iterator[IO[Any]]:
    """A device or a FIFO is opened and written in place: replacing it would break whoever
    reads it (``/dev/null``, a named pipe).  A FIFO is opened without waiting for a reader
    (``O_NONBLOCK``, which fails at once when there is none) and then written as usual."""
    encoding, newline = _text_options(mode)
    try:
        fd = os.open(target, os.O_WRONLY | (os.O_NONBLOCK if fifo else 0))
    except OSError as err:
        if err.errno == errno.ENXIO:
            raise MissionError("cannot write the output: no process is reading this FIFO", os.fspath(path)) from None
        raise write_failure(path, err) from None
    if fifo:
        fcntl.fcntl(fd, fcntl.F_SETFL, fcntl.fcntl(fd, fcntl.F_GETFL) & ~os.O_NONBLOCK)
    try:
        with os.fdopen(fd, mode, encoding=encoding, newline=newline) as fh:
            yield fh
    except OSError as err:
        raise write_failure(path, err) from None


@contextmanager
def _replaced(target: Path, path: str | os.PathLike[str], mode: str,
              existing: os.stat_result | None, behind: bool = False,
              stage: "_Stage | None" = None) -> Iterator[IO[Any]]:
    """A temporary file beside ``target``, renamed over it only once the whole text is written;
    on any failure (or interruption) the temporary file is removed and ``target`` is left as
    it was.  ``behind``: written by a second thread (:class:`WriteBehind`).  Within a
    ``stage``, the rename waits for the stage's other files (:func:`staged_outputs`)."""
    encoding, newline = _text_options(mode)
    try:
        target.parent.mkdir(parents=True, exist_ok=True)
        fd, tmp = tempfile.mkstemp(prefix=f".{target.name}.", suffix=".tmp", dir=target.parent)
    except OSError as err:
        raise write_failure(path, err) from None
    try:
        os.fchmod(fd, stat.S_IMODE(existing.st_mode) if existing is not None else 0o666 & ~_umask())
        if behind:
            with _written_behind(fd) as fh:
                yield fh
        else:
            with os.fdopen(fd, mode, encoding=encoding, newline=newline) as fh:
                yield fh
        if stage is not None:
            stage.written.append((tmp, target, path))
        else:
            os.replace(tmp, target)
    except BaseException as exc:
        try:
            os.unlink(tmp)
        except OSError:
            pass
        if isinstance(exc, OSError):
            raise write_failure(path, exc) from None
        raise


@contextmanager
def _written_behind(fd: int) -> Iterator[IO[str]]:
    """``fd`` as a :class:`WriteBehind`: closed (all written) when the block ends, abandoned
    (the rest dropped) when it fails."""
    fh = WriteBehind(fd)
    try:
        yield cast(IO[str], fh)  # a TextIOBase: what the writers use of IO[str]
    except BaseException:
        fh.abandon()
        raise
    fh.close()


Pathlike = str | os.PathLike[str]


def _identity(path: Pathlike) -> tuple[object, ...]:
    """What makes two paths one file: its device and inode when it exists (links, hard links),
    else the path with every link of its folders resolved."""
    try:
        st = os.stat(path)
    except OSError:
        return ("new", os.path.realpath(path))
    return ("file", st.st_dev, st.st_ino)


def refuse_unsafe_outputs(outputs: Iterable[Pathlike | None], inputs: Iterable[Pathlike | None],
                          folders: Iterable[Pathlike | None] = ()) -> None:
    """Refuse, before any work, the outputs that would destroy or lose something, each located at
    the output as the user gave it: one that is an input (it would be overwritten), one that is
    the same file as an earlier output (the later one would replace it), one that is a folder
    or ends with ``/``, an empty path, and one whose folder cannot hold it (a file stands where
    a folder should be, or the folder is not writable).  ``folders`` are output folders (a
    file per decomposition): each must be a folder, or creatable, and hold no input.  ``None``
    and ``-`` (standard output) are skipped."""
    read: dict[tuple[object, ...], Pathlike] = {}
    for path in inputs:
        if path is not None and os.fspath(path) != STDOUT and os.path.exists(path):
            read.setdefault(_identity(path), path)
    for folder in folders:
        if folder is not None:
            _refuse_output_folder(folder, read)
    written: dict[tuple[object, ...], Pathlike] = {}
    for path in outputs:
        if path is None or os.fspath(path) == STDOUT:
            continue
        _refuse_unwritable(path)
        _existing(Path(os.path.realpath(path)), path)  # a folder is refused
        identity = _identity(path)
        if identity in read:
            raise MissionError(f"the output would overwrite the input {os.fspath(read[identity])}: choose another "
                               "output file", os.fspath(path))
        if identity in written:
            raise MissionError(f"the outputs {os.fspath(written[identity])} and {os.fspath(path)} are one file, "
                               "which the later would replace: give each output a file of its own", os.fspath(path))
        written[identity] = path


def _refuse_unwritable(path: Pathlike) -> None:
    """An output path that names no file, or a file that its folder cannot take."""
    text = os.fspath(path)
    if not text:
        raise MissionError("cannot write the output: the path is empty; give a file name", "''")
    if text.endswith(os.sep):
        raise MissionError("cannot write the output: the path ends with /, so it names a folder; give a file name "
                           "(for example " + text + "out.json)", text)
    _refuse_unusable_folder(Path(os.path.realpath(path)).parent, text)


def _refuse_unusable_folder(folder: Path, where: str) -> None:
    """``folder`` must be a folder, or be creatable: its nearest existing ancestor a writable
    folder (a file where a folder should be is found here, before any work)."""
    current = folder
    while not os.path.lexists(current):
        current = current.parent
    if not current.is_dir():
        raise MissionError(f"cannot write the output: {current} is a file, not a folder", where)
    if not os.access(current, os.W_OK | os.X_OK):
        raise MissionError(f"cannot write the output: the folder {current} is not writable", where)


def _refuse_output_folder(folder: Pathlike, read: dict[tuple[object, ...], Pathlike]) -> None:
    """An output folder: a folder or none yet (then creatable), holding none of the inputs."""
    text = os.fspath(folder)
    if not text:
        raise MissionError("cannot write the output: the folder path is empty", "''")
    real = Path(os.path.realpath(folder))
    if os.path.lexists(real) and not real.is_dir():
        raise MissionError("cannot write the output files: it is a file; give a folder", text)
    _refuse_unusable_folder(real, text)
    for path in read.values():
        if Path(os.path.realpath(path)).parent == real:
            raise MissionError(f"the output folder holds the input {os.fspath(path)}, which a file written there "
                               "could replace: choose another folder", text)


_STAGE: ContextVar["_Stage | None"] = ContextVar("output_stage", default=None)


@dataclass
class _Stage:
    """The files of one :func:`staged_outputs` block: the targets, and the temporary files
    written for them so far (renamed into place when the block ends)."""

    targets: frozenset[Path]
    written: list[tuple[str, Path, Pathlike]] = field(default_factory=list)  # (temporary, target, as given)

    def holds(self, target: Path) -> bool:
        return target in self.targets

    def discard(self) -> None:
        for tmp, _target, _given in self.written:
            try:
                os.unlink(tmp)
            except OSError:
                pass
        self.written.clear()

    def commit(self) -> None:
        """Rename every temporary file into place (renames within a checked folder, which
        do not fail for want of space)."""
        while self.written:
            tmp, target, given = self.written.pop(0)
            try:
                os.replace(tmp, target)
            except OSError as err:
                self.discard()
                raise write_failure(given, err) from None


@contextmanager
def staged_outputs(paths: Iterable[Pathlike | None]) -> Iterator[None]:
    """Replace the regular files among ``paths`` all together or not at all.

    Inside the block, :func:`atomic_writer` writes each of them to a temporary file beside it,
    as always, but renames none until the block ends without failure: then all are renamed.
    A failure or an interruption anywhere in the block (a full disk on the last file, Ctrl-C)
    removes every temporary file and leaves every old file as it was.  A FIFO or device among
    them is written through when its writer runs (it cannot be taken back).  The block holds
    :func:`written_together`'s lock, so two runs writing the same set write it in turn."""
    kept = [p for p in paths if p is not None and os.fspath(p) != STDOUT]
    stage = _Stage(frozenset(Path(os.path.realpath(p)) for p in kept))
    with written_together(kept):
        token = _STAGE.set(stage)
        try:
            yield
        except BaseException:
            stage.discard()
            raise
        finally:
            _STAGE.reset(token)
        stage.commit()


@contextmanager
def written_together(paths: Iterable[Pathlike | None]) -> Iterator[None]:
    """Hold a lock on the folders of ``paths`` while a command writes them one after the other.

    Each file is replaced atomically anyway; the lock makes two runs that write the same set
    (``allocate``'s decomposition, schedule and chart; ``export-hddl``'s domain and problem)
    write it in turn, so the set ends up all from one run, never a mixture.  The folders are
    the locks (``flock``, in a fixed order): nothing is left behind.  ``None`` and ``-`` are
    skipped; a folder that cannot be created or opened is left to the write to report."""
    folders = sorted({os.path.dirname(os.path.realpath(p)) for p in paths if p is not None and os.fspath(p) != STDOUT})
    held: list[int] = []
    try:
        for folder in folders:
            try:
                os.makedirs(folder, exist_ok=True)
                fd = os.open(folder, os.O_RDONLY)
            except OSError:
                continue
            held.append(fd)
            fcntl.flock(fd, fcntl.LOCK_EX)
        yield
    finally:
        for fd in held:
            os.close(fd)  # releases the lock
