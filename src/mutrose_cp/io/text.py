"""Reading input files: regular files of bounded size, decoded as UTF-8, with located errors."""
from __future__ import annotations

import os
import stat
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Iterator

from ..errors import MissionError, Problem, located

MB = 1024 * 1024
DEFAULT_INPUT_LIMIT = 256 * MB
_input_limit: ContextVar[int] = ContextVar("input_limit", default=DEFAULT_INPUT_LIMIT)


@contextmanager
def input_limit(max_bytes: int) -> Iterator[None]:
    """Refuse input files larger than ``max_bytes`` while the block runs (``--max-input-mb``)."""
    token = _input_limit.set(max_bytes)
    try:
        yield
    finally:
        _input_limit.reset(token)


def read_bytes(path: str | os.PathLike[str], what: str, hint: str = "") -> bytes:
    """Read a whole input file.

    A missing or unreadable file, a path that is not a regular file (``/dev/zero``, a FIFO, a
    folder) and a file over the input limit are located errors, raised before anything is read:
    an input can never exhaust the memory.  ``hint`` says where the path came from."""
    source = os.fspath(path)
    limit = _input_limit.get()
    try:
        fd = os.open(source, os.O_RDONLY | os.O_NONBLOCK)  # opening a FIFO must not wait for a writer
    except OSError as exc:
        raise MissionError(Problem(source, f"cannot read {what} file: {exc.strerror or exc}", hint)) from None
    info = os.fstat(fd)
    if not stat.S_ISREG(info.st_mode):
        os.close(fd)
        raise MissionError(Problem(source, f"cannot read {what} file: it is not a regular file (a device, a FIFO "
                                           "or a folder)", hint or "Give the path of a file."))
    with os.fdopen(fd, "rb") as fh:
        if info.st_size > limit:
            raise MissionError(Problem(source, f"the {what} file is {info.st_size / MB:.1f} MB, over the input limit "
                                               f"of {limit / MB:g} MB", "Raise it with --max-input-mb if the file is "
                                               "really that large."))
        data = fh.read(limit + 1)
    if len(data) > limit:  # the file grew while it was read
        raise MissionError(Problem(source, f"the {what} file is over the input limit of {limit / MB:g} MB"))
    return data


def decode_utf8(data: bytes, source: str, what: str) -> str:
    """``data`` as text: UTF-8, with or without a byte-order mark (editors on Windows write one).

    A byte that is not UTF-8 is reported at ``file:line:col`` (the column counts characters
    before it on its line), which an editor can jump to."""
    try:
        return data.decode("utf-8-sig")
    except UnicodeDecodeError as exc:
        before = data[:exc.start]
        line = before.count(b"\n") + 1
        line_start = before.rfind(b"\n") + 1
        column = len(before[line_start:].decode("utf-8", errors="replace").removeprefix("\ufeff")) + 1
        raise MissionError(Problem(
            located(source, line, column),
            f"the {what} is not UTF-8 text: byte 0x{data[exc.start]:02x} cannot be decoded",
            "Save the file as UTF-8.",
        )) from None
