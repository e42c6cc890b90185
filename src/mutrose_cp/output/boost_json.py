"""JSON exactly as Boost.PropertyTree's ``write_json`` writes it: every scalar a string, empty
containers as ``""``, ``\\/`` escapes, 4-space layout.  The original's readers (a simulator, an
editor plug-in, a mission controller) parse this dialect, so every writer of it goes through here.
"""
from __future__ import annotations

import functools
import re
from typing import IO, Callable, Iterable, Mapping, Sequence, TypeAlias

# a JSON value as PropertyTree holds it: every scalar is a string
Tree: TypeAlias = "str | Sequence[Tree] | Mapping[str, Tree]"


_PLAIN = re.compile(r'[ !#-.0-\[\]-~]*')  # printable ASCII except " / \\


_ESCAPES = {'"': '\\"', "\\": "\\\\", "/": "\\/", "\b": "\\b", "\f": "\\f", "\n": "\\n", "\r": "\\r",
            "\t": "\\t"}


@functools.lru_cache(maxsize=1 << 16)
def escape_json(s: str) -> str:
    """Boost's JSON string escaping: named escapes, then every other byte outside printable
    ASCII as ``\\u00XX`` (per UTF-8 byte, as Boost does).  Memoized: names, types and flags
    repeat across thousands of task entries."""
    if _PLAIN.fullmatch(s):
        return '"' + s + '"'
    out = []
    for ch in s:
        if ch in _ESCAPES:
            out.append(_ESCAPES[ch])
        elif ord(ch) < 0x20 or ord(ch) > 0x7E:
            out.extend(f"\\u00{b:02X}" for b in ch.encode("utf-8"))
        else:
            out.append(ch)
    return '"' + "".join(out) + '"'


_FLUSH_PARTS = 1 << 14  # pieces gathered before a streamed document is written out


def _boost_parts(tree: Tree, indent: int, out: list[str], flush: Callable[[list[str]], None] | None = None) -> None:
    """Append the pieces of ``tree``; string members are written inline (most of a task entry's
    leaves), which halves the calls on large outputs.  With ``flush``, a long ``out`` is handed
    to it after a container member: all but its last piece, the separator that the end of the
    container still rewrites, can go."""
    if isinstance(tree, str):
        out.append(escape_json(tree))
        return
    if not tree:
        out.append('""')
        return
    pad = " " * (indent + 4)
    if isinstance(tree, dict):
        out.append("{\n")
        for k, v in tree.items():
            if isinstance(v, str):
                out.append(f"{pad}{escape_json(k)}: {escape_json(v)},\n")
            else:
                out.append(f"{pad}{escape_json(k)}: ")
                _boost_parts(v, indent + 4, out, flush)
                out.append(",\n")
                if flush is not None and len(out) > _FLUSH_PARTS:
                    flush(out)
    else:
        out.append("[\n")
        for v in tree:
            if isinstance(v, str):
                out.append(f"{pad}{escape_json(v)},\n")
            else:
                out.append(pad)
                _boost_parts(v, indent + 4, out, flush)
                out.append(",\n")
                if flush is not None and len(out) > _FLUSH_PARTS:
                    flush(out)
    last = out[-1]
    out[-1] = last[:-2] + "\n"  # no comma after the last member
    out.append(" " * indent + ("}" if isinstance(tree, dict) else "]"))


def boost_json(tree: Tree, indent: int = 0) -> str:
    """Serialize like ``boost::property_tree::write_json`` (pretty): every scalar a string,
    empty containers as ``""``, 4-space indentation."""
    out: list[str] = []
    _boost_parts(tree, indent, out)
    return "".join(out)


def write_boost_json(tree: Tree, fh: IO[str], indent: int = 0) -> None:
    """:func:`boost_json` written to ``fh`` while it is serialized: a large document (the
    decomposition space of thousands of components) is never held whole as text."""
    def flush(parts: list[str]) -> None:
        fh.write("".join(parts[:-1]))
        del parts[:-1]

    out: list[str] = []
    _boost_parts(tree, indent, out, flush)
    fh.write("".join(out))


def write_list(fh: IO[str], items: Iterable[str], indent: int) -> None:
    """A JSON list whose elements are already serialized at ``indent + 4``; an item holds one
    or more of them, joined by ``,\n`` and the indentation (the constraints come a run at a
    time).  Streamed an item at a time: the file object gathers the writes (joining them here
    first copied gigabytes of text once more)."""
    pad = " " * (indent + 4)
    separator = ",\n" + pad
    elements = iter(items)
    first = next(elements, None)
    if first is None:
        fh.write('""')
        return
    fh.write("[\n" + pad)
    fh.write(first)
    for text in elements:
        fh.write(separator)
        fh.write(text)
    fh.write("\n" + " " * indent + "]")
