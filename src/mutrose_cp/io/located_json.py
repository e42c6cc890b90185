"""JSON documents whose values know where they are: ``file:line:col`` for every key and value.

Python's ``json`` module reads the values (and reports syntax errors at ``file:line:col``), but
forgets where each value was.  A file a user writes by hand, such as a fleet, needs its
*semantic* errors located too ("speed must be positive" at the speed's line), so the same text
is also parsed with a small lark grammar (``grammars/json.lark``) that keeps positions, and the
two are walked together: :class:`LocatedJson` maps each path (``("robots", 0, "speed")``) to the
position of its value and of its key.
"""
from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass
from typing import Any

from lark import Token, Tree

from ..errors import MissionError, Problem, located
from .grammar import cached_lalr_parser
from .text import decode_utf8, parse_json, read_bytes

Path = tuple[str | int, ...]


def _constant(name: str) -> Any:
    raise ValueError(f"{name} is not a JSON number")


@dataclass(frozen=True)
class LocatedJson:
    """A decoded JSON document and the ``(line, column)`` of each value and key, by path."""

    source: str
    data: Any
    values: dict[Path, tuple[int, int]]
    keys: dict[Path, tuple[int, int]]

    def at(self, path: Path, *, key: bool = False) -> str:
        """``file:line:col`` of the value at ``path`` (of its key with ``key``); a path that is
        not in the document (a missing key) is located at its nearest enclosing value."""
        table = self.keys if key else self.values
        for cut in range(len(path), -1, -1):
            position = table.get(path[:cut]) if cut == len(path) else self.values.get(path[:cut])
            if position is not None:
                return located(self.source, *position)
        return self.source


def read_located_json(path: str | os.PathLike[str], what: str) -> LocatedJson:
    """Read a JSON file (``what`` names it in messages: "fleet") with its positions."""
    source = os.fspath(path)
    return parse_located_json(decode_utf8(read_bytes(source, what), source, what), source)


def parse_located_json(text: str, source: str) -> LocatedJson:
    """Decode ``text``; ``NaN`` and ``Infinity``, which are not JSON, are syntax errors."""
    try:
        data = parse_json(text, source, parse_constant=_constant)
    except ValueError as err:  # NaN, Infinity (parse_json has located the syntax errors)
        raise MissionError(Problem(_constant_at(text, source), f"invalid JSON: {err}")) from None
    tree = cached_lalr_parser("json.lark", propagate_positions=True, maybe_placeholders=False).parse(text)
    values: dict[Path, tuple[int, int]] = {}
    keys: dict[Path, tuple[int, int]] = {}
    repeated: list[tuple[Path, tuple[int, int]]] = []
    _walk(tree, (), values, keys, repeated)
    if repeated:  # json.loads keeps the last silently: the first value would be lost unseen
        raise MissionError([Problem(located(source, *at), f"{path_text(path)}: the key {path[-1]!r} is given twice",
                                    "Keep one: the later value would replace the earlier.") for path, at in repeated])
    return LocatedJson(source, data, values, keys)


def path_text(path: Path) -> str:
    """``robots[0].name``: a path as messages write it."""
    text = ""
    for part in path:
        text += f"[{part}]" if isinstance(part, int) else (f".{part}" if text else str(part))
    return text


_STRING_OR_CONSTANT = re.compile(r'"(?:[^"\\]|\\.)*"|(?P<constant>-?Infinity|NaN)')


def _constant_at(text: str, source: str) -> str:
    """``file:line:col`` of the first ``NaN`` or ``Infinity`` outside a string."""
    for found in _STRING_OR_CONSTANT.finditer(text):
        if found["constant"]:
            start = found.start()
            line = text.count("\n", 0, start) + 1
            return located(source, line, start - (text.rfind("\n", 0, start) + 1) + 1)
    return source


def _position(node: Tree | Token) -> tuple[int, int]:
    if isinstance(node, Token):
        return node.line or 1, node.column or 1
    return node.meta.line, node.meta.column


def _walk(node: Tree | Token, path: Path, values: dict[Path, tuple[int, int]],
          keys: dict[Path, tuple[int, int]], repeated: list[tuple[Path, tuple[int, int]]]) -> None:
    """Record the position of ``node`` (the value at ``path``) and of everything inside it, and
    each key given a second time in one object (with the position of the repetition)."""
    values[path] = _position(node)
    if not isinstance(node, Tree) or node.data not in ("object", "array"):
        return
    seen: set[str] = set()
    for index, child in enumerate(node.children):
        if node.data == "array":
            _walk(child, (*path, index), values, keys, repeated)
            continue
        key_token, value = child.children
        name = json.loads(str(key_token))
        key = (*path, name)
        if name in seen:
            repeated.append((key, _position(key_token)))
        seen.add(name)
        keys[key] = _position(key_token)
        _walk(value, key, values, keys, repeated)
