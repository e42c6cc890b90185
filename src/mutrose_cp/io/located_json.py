"""JSON documents whose values know where they are: ``file:line:col`` for every key and value.

Python's ``json`` module reads the values (and reports syntax errors at ``file:line:col``), but
forgets where each value was.  A file a user writes by hand, such as a fleet, needs its
*semantic* errors located too ("speed must be positive" at the speed's line), so
:class:`LocatedJson` maps each path (``("robots", 0, "speed")``) to the position of its value
and of its key.

The positions are found only when a message asks for one, by one pass of a tokenizer over the
text (which the decoder has already found to be valid JSON): a fleet of 100,000 robots is read
at the decoder's speed, and only a fleet with a mistake pays for the positions.  A key given
twice in one object is noticed while decoding (``json.loads`` would keep the last value
silently), and located the same way.
"""
from __future__ import annotations

import bisect
import json
import os
import re
from dataclasses import dataclass, field
from functools import cached_property
from typing import Any

from ..errors import MissionError, Problem, located
from .text import decode_utf8, parse_json, read_bytes

Path = tuple[str | int, ...]

# one token after optional blanks: a string, a bracket or separator, or a bare scalar
_TOKEN = re.compile(r'[ \t\r\n]*(?:("(?:[^"\\]|\\.)*")|([{}\[\]:,])|([^ \t\r\n{}\[\]:,"]+))')


def _constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number")


MAX_DIGITS = 4000  # an integer's digits, at most (Python converts up to 4300 of them, then fails)


@dataclass(frozen=True)
class OutOfRangeNumber:
    """A JSON integer of thousands of digits, which Python does not convert (JSON sets no
    limit): kept as its text, so that the reader of the document reports it where it is, as out
    of range."""

    text: str

    def __str__(self) -> str:
        return f"{self.text[:8]}... ({sum(c.isdigit() for c in self.text)} digits)"


def _integer(text: str) -> int | OutOfRangeNumber:
    return int(text) if len(text) <= MAX_DIGITS else OutOfRangeNumber(text)


@dataclass(frozen=True)
class Positions:
    """Where each value and key of a document is: ``(line, column)`` by path, and the keys
    given a second time in one object (with the position of the repetition)."""

    values: dict[Path, tuple[int, int]]
    keys: dict[Path, tuple[int, int]]
    repeated: list[tuple[Path, tuple[int, int]]]


@dataclass(frozen=True)
class LocatedJson:
    """A decoded JSON document, and the ``(line, column)`` of each value and key by path
    (:attr:`positions`, found on first use)."""

    source: str
    data: Any
    text: str = field(repr=False)

    @cached_property
    def positions(self) -> Positions:
        return scan_positions(self.text)

    def at(self, path: Path, *, key: bool = False) -> str:
        """``file:line:col`` of the value at ``path`` (of its key with ``key``); a path that is
        not in the document (a missing key) is located at its nearest enclosing value."""
        values, keys = self.positions.values, self.positions.keys
        for cut in range(len(path), -1, -1):
            position = (keys if key else values).get(path[:cut]) if cut == len(path) else values.get(path[:cut])
            if position is not None:
                return located(self.source, *position)
        return self.source


def read_located_json(path: str | os.PathLike[str], what: str) -> LocatedJson:
    """Read a JSON file (``what`` names it in messages: "fleet") with its positions."""
    source = os.fspath(path)
    return parse_located_json(decode_utf8(read_bytes(source, what), source, what), source)


def parse_located_json(text: str, source: str) -> LocatedJson:
    """Decode ``text``; ``NaN`` and ``Infinity``, which are not JSON, are syntax errors, and so
    is a key given twice in one object; a number too large for Python is an
    :class:`OutOfRangeNumber`."""
    repeated = False

    def pairs(items: list[tuple[str, Any]]) -> dict[str, Any]:
        nonlocal repeated
        out = dict(items)
        repeated = repeated or len(out) < len(items)
        return out

    try:
        data = parse_json(text, source, parse_constant=_constant, object_pairs_hook=pairs)
    except ValueError as err:
        if "JSON number" in str(err):  # NaN, Infinity (parse_json has located the syntax errors)
            raise MissionError(Problem(_constant_at(text, source), f"invalid JSON: {err}")) from None
        # an integer too long to convert: decoded again, each integer through a hook (slower,
        # so only for such a file)
        data = parse_json(text, source, parse_constant=_constant, parse_int=_integer, object_pairs_hook=pairs)
    document = LocatedJson(source, data, text)
    if repeated:  # json.loads keeps the last silently: the first value would be lost unseen
        raise MissionError([Problem(located(source, *at), f"{path_text(path)}: the key {path[-1]!r} is given twice",
                                    "Keep one: the later value would replace the earlier.")
                            for path, at in document.positions.repeated])
    return document


def path_text(path: Path) -> str:
    """``robots[0].name``: a path as messages write it (a key that is no text, holding half of
    a UTF-16 pair, with that half escaped: a message must stay printable)."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text.encode("utf-8", "backslashreplace").decode("utf-8")


_STRING_OR_CONSTANT = re.compile(r'"(?:[^"\\]|\\.)*"|(?P<constant>-?Infinity|NaN)')


def _constant_at(text: str, source: str) -> str:
    """``file:line:col`` of the first ``NaN`` or ``Infinity`` outside a string."""
    for found in _STRING_OR_CONSTANT.finditer(text):
        if found["constant"]:
            start = found.start()
            line = text.count("\n", 0, start) + 1
            return located(source, line, start - (text.rfind("\n", 0, start) + 1) + 1)
    return source


@dataclass
class _Container:
    """An object or array being scanned: its path, the next index or the current key."""

    path: Path
    is_object: bool
    index: int = 0
    key: str = ""
    expects_key: bool = True
    seen: set[str] = field(default_factory=set)


def scan_positions(text: str) -> Positions:
    """The positions of every value and key of ``text``, valid JSON (one pass, no recursion:
    a document nested as deep as the decoder allows is scanned alike)."""
    starts = [0] + [m.end() for m in re.finditer("\n", text)]
    values: dict[Path, tuple[int, int]] = {}
    keys: dict[Path, tuple[int, int]] = {}
    repeated: list[tuple[Path, tuple[int, int]]] = []
    stack: list[_Container] = []

    def where(offset: int) -> tuple[int, int]:
        line = bisect.bisect_right(starts, offset)
        return line, offset - starts[line - 1] + 1

    for token in _TOKEN.finditer(text):
        string, mark, _ = token.groups()
        top = stack[-1] if stack else None
        offset = token.start(token.lastindex or 1)
        if mark in ("}", "]"):
            stack.pop()
            continue
        if mark == ",":
            top.expects_key = top.is_object  # type: ignore[union-attr]  # valid JSON: inside a container
            continue
        if mark == ":":
            continue
        if string is not None and top is not None and top.is_object and top.expects_key:
            name = json.loads(string)
            key = (*top.path, name)
            if name in top.seen:
                repeated.append((key, where(offset)))
            top.seen.add(name)
            keys[key] = where(offset)
            top.key, top.expects_key = name, False
            continue
        path = _value_path(top)
        values[path] = where(offset)
        if mark in ("{", "["):
            stack.append(_Container(path, mark == "{"))
    return Positions(values, keys, repeated)


def _value_path(container: _Container | None) -> Path:
    """The path of the next value inside ``container`` (the document itself without one)."""
    if container is None:
        return ()
    if container.is_object:
        return (*container.path, container.key)
    container.index += 1
    return (*container.path, container.index - 1)
