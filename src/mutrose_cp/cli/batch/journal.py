"""The results file of a batch: an append-only journal of JSON lines, shared safely.

Several batches may share one results file (two manifests sent to one ``--results``, two
``--each`` runs in one folder), and any of them may be killed at any moment.  So:

* **one writer at a time**: every write holds an exclusive ``flock`` on the file itself (no lock
  file is left behind).  A batch that finds the file replaced or removed once it holds the lock
  reopens it, so it never writes to a file nobody will read;
* **append only while the jobs run**: a batch adds its own lines and never writes the file from
  what it holds in memory, so the lines of another batch (appended meanwhile, or before) are
  never lost.  When a job is run again (its inputs changed, a higher limit), its new line
  follows the old one: the last line for an input hash is the one that counts;
* **in order at the end**: so that the file does not depend on which worker finished first,
  the batch then puts the lines of its manifest's jobs first, in manifest order
  (:func:`in_order`).  It does so under the lock, from the file as it is on the disk, copying
  every other line byte for byte, and replaces the file atomically (``atomic_writer``); a
  batch that was waiting for the lock then finds the new file and appends there;
* **whole lines**: each line is written by one ``write`` call on a descriptor opened with
  ``O_APPEND``, so it lands after the others in one piece, and is on its way to the disk when
  the call returns (nothing is held in a buffer of this process).  A write that fails midway
  (a full disk) is cut back to where the file ended, and the batch stops.  A line cut short all
  the same (the machine stopped) has no newline at its end; before appending, the batch ends it
  with one, so that the next line is not glued to it, and reports it.  The cut line is then
  skipped when the file is read, and its job runs again;
* **checked lines**: a line that is not a result (cut short, edited by hand, a field of the
  wrong type) is reported with its line number and skipped, never trusted
  (:meth:`ResultLine.parse`).

The file is opened (and created, with its folder) before the first job runs, so a results path
that cannot be written stops the batch before any work, not after it.  A file this batch created
and left empty (the batch stopped before any job finished) is removed at the end, with the
folders made for it.
"""
from __future__ import annotations

import fcntl
import json
import os
from contextlib import contextmanager
from pathlib import Path
from typing import Iterable, Iterator

from ...errors import MissionError
from ...output.files import atomic_writer
from .inputs import kind_of
from .job import JobSpec
from .results import ResultLine

_FLAGS = os.O_RDWR | os.O_APPEND | os.O_NONBLOCK | getattr(os, "O_CLOEXEC", 0)


class ResultsFile:
    """The results of earlier runs (by input hash) and the journal of this one.  ``where``
    names the file in messages (``--results FILE``, or the default path)."""

    def __init__(self, path: Path, where: str = "") -> None:
        self.path = path
        self.where = where or str(path)
        self.lines: dict[str, ResultLine] = {}
        self.notes: list[str] = []  # what was found wrong with the file, for the user
        self.recorded = 0
        self._fd: int | None = None
        self._created = False
        self._made_folders: list[Path] = []

    # -- opening and reading ------------------------------------------------------------------

    def open(self) -> None:
        """Open the file for appending (creating it and its folder), then read the results it
        holds, with its last line repaired first; a path that cannot be a results file is a
        located error (exit 2)."""
        self._made_folders = self._make_folder(self.path.parent)
        self._fd = self._open()
        with self._locked() as fd:
            try:
                self._repair(fd)
            except OSError as err:  # a full disk, a read-only file system
                raise MissionError(f"cannot write the results file: {err.strerror or err}", self.where) from None
            self._read(fd)

    def _make_folder(self, folder: Path) -> list[Path]:
        missing = []
        current = folder
        while not os.path.lexists(current):
            missing.append(current)
            current = current.parent
        try:
            folder.mkdir(parents=True, exist_ok=True)
        except OSError as err:
            raise MissionError(f"cannot write the results file: cannot make its folder {folder}: "
                               f"{err.strerror or err}", self.where) from None
        return missing  # the deepest first

    def _open(self) -> int:
        """A descriptor on the file; ``_created`` says whether this batch made it."""
        try:
            try:
                fd = os.open(self.path, _FLAGS | os.O_CREAT | os.O_EXCL, 0o666)
                self._created = True
            except FileExistsError:
                fd = os.open(self.path, _FLAGS)
        except OSError as err:
            raise MissionError(f"cannot write the results file: {err.strerror or err}", self.where) from None
        kind = kind_of(os.fstat(fd).st_mode)
        if kind is not None:
            os.close(fd)
            raise MissionError(f"the results file is {kind}: give the path of a regular file", self.where)
        return fd

    def _read(self, fd: int) -> None:
        data = _read_all(fd)
        for number, raw in enumerate(data.split(b"\n")[:-1], start=1):  # the repaired file ends with a newline
            try:
                line = ResultLine.parse(raw.decode("utf-8"))
            except (ValueError, UnicodeDecodeError) as err:
                reason = "not UTF-8" if isinstance(err, UnicodeDecodeError) else str(err)
                self.notes.append(f"{self.path}:{number}: not a result line ({reason}): skipped; its job runs again")
                continue
            self.lines[line.input_hash] = line

    def _repair(self, fd: int) -> None:
        """End a last line that was cut short (no newline at its end), so that nothing is
        appended to it."""
        size = os.fstat(fd).st_size
        if size == 0 or os.pread(fd, 1, size - 1) == b"\n":
            return
        number = _read_all(fd).count(b"\n") + 1
        _write_all(fd, b"\n")
        self.notes.append(f"{self.path}:{number}: the last line was cut short (no newline at its end: a run stopped "
                          "while writing it): ended with a newline so that no result is appended to it")

    # -- appending ----------------------------------------------------------------------------

    def done(self, input_hash: str, spec: JobSpec) -> ResultLine | None:
        """The result that settles the job with this hash under ``spec``'s limits, if present."""
        line = self.lines.get(input_hash)
        return line if line is not None and line.settles(spec) else None

    def record(self, line: ResultLine) -> None:
        """Append one finished job's line, whole, under the lock."""
        if self._fd is None:
            self.open()
        data = line.text().encode("utf-8")
        with self._locked() as fd:
            size = os.fstat(fd).st_size
            try:
                self._repair(fd)
                _write_all(fd, data)
            except OSError as err:
                _cut_back(fd, size)
                raise MissionError(f"cannot write the results file: {err.strerror or err}; the jobs that finished "
                                   "before are recorded", self.where) from None
        self.lines[line.input_hash] = line
        self.recorded += 1

    @contextmanager
    def _locked(self) -> Iterator[int]:
        """Hold the exclusive lock on the file at ``path``: when it was replaced or removed
        while this batch waited (a batch that created it and stopped empty removes it), the
        new file is opened and locked instead."""
        while True:
            assert self._fd is not None
            fcntl.flock(self._fd, fcntl.LOCK_EX)
            if self._still_the_file(self._fd):
                break
            os.close(self._fd)  # releases the lock
            self._created = False
            self._fd = self._open()
        try:
            yield self._fd
        finally:
            fcntl.flock(self._fd, fcntl.LOCK_UN)

    def _still_the_file(self, fd: int) -> bool:
        try:
            st = os.stat(self.path)
        except FileNotFoundError:
            return False
        held = os.fstat(fd)
        return (st.st_dev, st.st_ino) == (held.st_dev, held.st_ino)

    def close(self, order: Iterable[str] = ()) -> None:
        """Close the journal, its lines put in order (``order``: the input hashes of the
        manifest's jobs; see :func:`in_order`).  A file this batch created and nothing was
        written to is removed instead, with the folders made for it.  Both under the lock:
        another batch may have appended meanwhile."""
        if self._fd is None:
            return
        try:
            with self._locked() as fd:
                data = _read_all(fd)
                if self._created and not data:
                    self._remove()
                elif (ordered := in_order(data, order)) != data:
                    with atomic_writer(self.path, "wb") as fh:
                        fh.write(ordered)
        except (MissionError, OSError) as err:  # the appended lines are all there: only their order is lost
            self.notes.append(f"{self.where}: the lines stay in the order the jobs finished: cannot rewrite the "
                              f"file in manifest order ({err})")
        finally:
            os.close(self._fd)
            self._fd = None

    def _remove(self) -> None:
        os.unlink(self.path)
        for folder in self._made_folders:
            try:
                os.rmdir(folder)
            except OSError:
                break


def in_order(data: bytes, order: Iterable[str]) -> bytes:
    """The lines of a results file with the manifest's jobs first, in its order (``order``: their
    input hashes), each by its last line; then every other line as it was, in the order found.

    The lines are those on the disk, read under the lock, never those this batch holds in
    memory: a line another batch appended is copied byte for byte, and so is a line that is
    JSON but no result (edited by hand: it was reported when the file was read).  Left out are
    only the earlier lines of the manifest's own jobs (a newer line of the same job, same
    inputs, replaces them) and the pieces of lines cut short, which are not JSON at all."""
    lines = data.split(b"\n")[:-1]  # what follows the last newline is not a whole line
    hashes = [_hash_of(raw) for raw in lines]
    last = {h: i for i, h in enumerate(hashes) if isinstance(h, str)}
    wanted = [h for h in dict.fromkeys(order) if h in last]
    first = set(wanted)
    rest = [raw for raw, h in zip(lines, hashes) if h is not _BROKEN and h not in first]
    return b"".join(raw + b"\n" for raw in [*(lines[last[h]] for h in wanted), *rest])


_BROKEN = object()  # a line that is not JSON at all


def _hash_of(raw: bytes) -> str | None | object:
    """The input hash of a result line; None for a JSON line that is no result (kept as it
    is); _BROKEN for a line that is not JSON (a piece of a line cut short)."""
    try:
        return ResultLine.parse(raw.decode("utf-8")).input_hash
    except (ValueError, UnicodeDecodeError):
        pass
    try:
        json.loads(raw)
    except (ValueError, RecursionError):
        return _BROKEN
    return None


def _read_all(fd: int) -> bytes:
    chunks = []
    offset = 0
    while chunk := os.pread(fd, 1 << 20, offset):
        chunks.append(chunk)
        offset += len(chunk)
    return b"".join(chunks)


def _cut_back(fd: int, size: int) -> None:
    """Remove what a failed append wrote (a full disk takes part of a line): the file ends with
    its last whole line again.  If even that fails, the next batch repairs the cut line."""
    try:
        os.ftruncate(fd, size)
    except OSError:
        pass


def _write_all(fd: int, data: bytes) -> None:
    """Write ``data`` with one ``write`` call; a short write (a full disk) goes on where it
    stopped, still under the caller's lock, so no other batch's line can come between."""
    view = memoryview(data)
    while view:
        view = view[os.write(fd, view):]
