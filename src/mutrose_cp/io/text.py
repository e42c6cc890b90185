"""Reading input files: regular files of bounded size, decoded as UTF-8, with located errors.

The JSON readers (configuration, goal model, decomposition output) share the problems of a
document that cannot be decoded at all: a syntax error and a nesting too deep to be read."""
from __future__ import annotations

import json
import os
import stat
from contextlib import contextmanager
from contextvars import ContextVar
from typing import Any, Iterator

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
        # a buffer the size of the file, not of the limit: under a memory limit (``batch
        # --memory-mb``) a 256 MB buffer for a 2 kB file would fail
        data = fh.read(info.st_size + 1)
        if len(data) > info.st_size:  # the file grew while it was read: read on up to the limit
            data += fh.read(limit + 1 - len(data))
    if len(data) > limit:
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


# ---------------------------------------------------------------------------------------------
# JSON documents that cannot be decoded


def parse_json(text: str, source: str, **options: Any) -> Any:
    """``json.loads(text, **options)`` with its failures as located problems: a syntax error at
    its ``file:line:col``, nesting too deep for the decoder at its deepest bracket."""
    try:
        return json.loads(text, **options)
    except json.JSONDecodeError as err:
        raise MissionError(json_syntax_problem(err, text, source)) from None
    except RecursionError:
        raise MissionError(json_depth_problem(text, source)) from None


def json_syntax_problem(err: json.JSONDecodeError, text: str, source: str) -> Problem:
    """``file:line:col: invalid JSON: <reason>``, saying so when the text simply stops early."""
    where = located(source, err.lineno, err.colno)
    rest = text[err.pos:]
    truncated = not rest.strip() or (err.msg.startswith("Unterminated string") and '"' not in rest[1:])
    if truncated:
        return Problem(
            where,
            f"invalid JSON: {err.msg}",
            "The text ends before the JSON document is complete: the file looks truncated; "
            "restore its end (every '{' and '[' needs its closing '}' and ']').",
        )
    return Problem(where, f"invalid JSON: {err.msg}")


def _outside_strings(text: str) -> Iterator[tuple[str, int, int]]:
    """Every character of ``text`` that is not inside a JSON string, with its line and column:
    brackets inside strings do not nest anything."""
    line, column = 1, 1
    in_string = escaped = False
    for char in text:
        if in_string:
            if escaped:
                escaped = False
            elif char == "\\":
                escaped = True
            elif char == '"':
                in_string = False
        elif char == '"':
            in_string = True
        else:
            yield char, line, column
        if char == "\n":
            line, column = line + 1, 1
        else:
            column += 1


def json_depth_problem(text: str, source: str) -> Problem:
    """The JSON nests too deeply to be read (Python's decoder recursed out): located at the
    first bracket of the deepest nesting."""
    depth = deepest = 0
    at = (1, 1)
    for char, line, column in _outside_strings(text):
        if char in "[{":
            depth += 1
            if depth > deepest:
                deepest, at = depth, (line, column)
        elif char in "]}":
            depth -= 1
    return Problem(
        located(source, *at),
        f"invalid JSON: arrays and objects are nested {deepest} levels deep, too deep to be read",
        "No mission file nests like this: the file is probably damaged.",
    )
