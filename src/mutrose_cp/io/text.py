"""Decoding input files as UTF-8 text, with located errors."""
from __future__ import annotations

from ..errors import MissionError, Problem, located


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
