"""World knowledge reader (spec ``config-and-knowledge.md`` §5) with a hardened lxml parser:
no entity expansion, no DTD loading, no network, lenient end tags as the original accepts.

The original reads the knowledge with Boost.PropertyTree (rapidxml), which does not validate
closing-tag names and whose record values are strings taken verbatim.  This module reproduces
that reading on top of lxml and offers the small value parsers (boolean, number, list) the
original applies to field texts, plus indexes by tag / id / field so that queries evaluated
thousands of times (one per ``forAll`` iteration) do not rescan the whole document.
"""
from __future__ import annotations

import json
import os
import re
from dataclasses import dataclass
from functools import cached_property
from typing import Iterator

from lxml import etree

from ..errors import MissionError, Problem, located
from .text import read_bytes

# ---------------------------------------------------------------------------------------------
# Problems shared by the readers (configuration, goal model, knowledge)


def hinted(where: str, message: str, hint: str = "") -> Problem:
    """A :class:`Problem`, with ``hint`` when there is one."""
    return Problem(where, message, hint)


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


def json_depth_problem(text: str, source: str) -> Problem:
    """The JSON nests too deeply to be read (Python's decoder recursed out): located at the
    first bracket of the deepest nesting."""
    depth = deepest = 0
    line, column, at = 1, 1, (1, 1)
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
        elif char in "[{":
            depth += 1
            if depth > deepest:
                deepest, at = depth, (line, column)
        elif char in "]}":
            depth -= 1
        if char == "\n":
            line, column = line + 1, 1
        else:
            column += 1
    return Problem(
        located(source, *at),
        f"invalid JSON: arrays and objects are nested {deepest} levels deep, too deep to be read",
        "No mission file nests like this: the file is probably damaged.",
    )


# ---------------------------------------------------------------------------------------------
# Hardened, tolerant XML parsing (shared with the XML configuration reader)

# libxml2 errors that the original's reader (rapidxml) does not report either: a closing tag
# whose name differs from the open element (libxml2's recovery pops the innermost element, the
# same as rapidxml) and extra content after the first top-level element (only the first one is
# read).  Every other well-formedness error is a real error of the input.
TOLERATED_XML_ERRORS = frozenset({"ERR_TAG_NAME_MISMATCH", "ERR_DOCUMENT_END"})

_XML_WHITESPACE = " \t\r\n"
_CPP_SPACE = " \t\n\v\f\r"  # what ``istream >>`` skips
_LIST_SEPARATORS = re.compile(r"[,\s]+")
_INT_PREFIX = re.compile(r"[+-]?\d+")
_FLOAT_PREFIX = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


def _hardened_parser() -> etree.XMLParser:
    """A fresh parser per document: error logs are per parser, and the settings make entity
    expansion, DTD loading and network access impossible (billion laughs, XXE)."""
    return etree.XMLParser(
        recover=True,
        resolve_entities=False,
        no_network=True,
        load_dtd=False,
        huge_tree=False,
        remove_blank_text=False,
    )


def _line_of(data: bytes, needle: bytes) -> int:
    pos = data.find(needle)
    return data.count(b"\n", 0, pos) + 1 if pos >= 0 else 1


_DTD_HINT = (
    "Remove the <!DOCTYPE ...> declaration and write every value out literally: the decomposer "
    "never reads DTDs nor expands entities (this protects against billion-laughs and "
    "external-entity attacks)."
)


_XML_DECL_ENCODING = re.compile(r"""^(\ufeff?\s*<\?xml[^>]*?encoding\s*=\s*)(["'])[^"']*\2""")


_MISMATCH = re.compile(r"Opening and ending tag mismatch: (\S+) line (\d+) and (\S+)")
LENIENT_HINT = ("Fix the XML, or pass --lenient-xml to read it as the original does (which keeps the recovered "
                "structure).")


def _more_after(data: bytes, line: int, column: int) -> bool:
    """Whether anything but blanks follows position ``line:column`` (1-based) of ``data``."""
    lines = data.split(b"\n")
    rest = b"\n".join([lines[line - 1][column - 1:], *lines[line:]]) if line <= len(lines) else b""
    return bool(rest.strip())


def _recoveries(parser: etree.XMLParser, root: etree._Element, data: bytes, source: str,
                what: str) -> tuple[list[Problem], list[Problem]]:
    """The repairs the reader made, as (harmless, structural) located messages.

    An end tag that is a typo of the element it closes (``</location_type>`` for
    ``<location_types>``) changes nothing, nor does a text-only element left open.  An element
    with children left open (its end tag missing, so the end tag of an outer element closes it)
    swallows the records after it, and content after the root element (often after a stray end
    tag closed the root early) is dropped: both change which records exist or how they nest."""
    harmless: list[Problem] = []
    structural: list[Problem] = []
    for e in parser.error_log:
        where = located(source, e.line, e.column)
        if e.type_name == "ERR_DOCUMENT_END":
            structural.append(Problem(where, f"{what}: content after the end of the root element <{root.tag}> is "
                                             "ignored (a stray end tag may have closed the root early): the records "
                                             "there would be lost", LENIENT_HINT))
            continue
        m = _MISMATCH.search(e.message)
        if e.type_name != "ERR_TAG_NAME_MISMATCH" or m is None:
            continue
        opened, line, closing = m.group(1), int(m.group(2)), m.group(3)
        element = next((el for el in root.iter(opened) if el.sourceline == line), None)
        left_open = element is not None and any(a.tag == closing for a in element.iterancestors())
        # an element left open with only text inside swallowed nothing; one holding elements
        # (a record with its fields) has taken the records after it
        if element is not None and element.getparent() is None and _more_after(data, e.line, e.column):
            structural.append(Problem(where, f"{what}: </{closing}> closes the root element <{opened}> early (a stray "
                                             "end tag?): the records after it would be lost", LENIENT_HINT))
        elif left_open and any(isinstance(c.tag, str) for c in element):
            structural.append(Problem(where, f"{what}: <{opened}> (line {line}) is never closed, so </{closing}> "
                                             f"closes it and everything after it is nested inside it (a missing "
                                             f"</{opened}>?)", LENIENT_HINT))
        else:
            harmless.append(Problem(where, f"{what}: </{closing}> closes <{opened}> (line {line}); read as "
                                           f"</{opened}>"))
    return harmless, structural


def parse_tolerant_xml(data: bytes | str, source: str, what: str, *, lenient: bool = False,
                       warnings: list[str] | None = None) -> etree._Element:
    """Parse ``data`` like the original's lenient reader and return the first top-level element.

    The original's reader repairs mismatched end tags and ignores content after the root.  Here
    every repair is a warning at ``file:line:col`` (appended to ``warnings``); a repair that
    changes which records exist or how they nest is an error unless ``lenient``.  A DOCTYPE
    (and therefore any entity declaration) is rejected before anything could be expanded; other
    syntax errors are reported at ``file:line:col``.  ``what`` names the document in messages
    (``world knowledge``, ``configuration``).
    """
    if isinstance(data, str):
        # the text is already decoded: re-encode as UTF-8 and make the declaration say so
        data = _XML_DECL_ENCODING.sub(r"\1\2UTF-8\2", data, count=1).encode("utf-8")
    parser = _hardened_parser()
    try:
        root = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as exc:
        line, col = (exc.position if exc.position else (None, None))
        raise MissionError(Problem(located(source, line, col), f"XML syntax error in {what}: {exc.msg}")) from None
    if root is not None:
        info = root.getroottree().docinfo
        if info.internalDTD is not None or info.doctype:
            raise MissionError(Problem(
                located(source, _line_of(data, b"<!DOCTYPE")),
                f"DTD and entity declarations are not allowed in {what}",
                _DTD_HINT,
            ))
    errors = [e for e in parser.error_log if e.type_name not in TOLERATED_XML_ERRORS]
    if errors or root is None:
        if not errors:
            raise MissionError(Problem(source, f"XML syntax error in {what}: the document has no root element"))
        # libxml2 reports one mistake as several messages at one position: one problem per position
        by_position: dict[tuple[int, int], list[str]] = {}
        for e in errors:
            messages = by_position.setdefault((e.line, e.column), [])
            if e.message not in messages:
                messages.append(e.message)
        raise MissionError([
            Problem(located(source, line, column), f"XML syntax error in {what}: {'; '.join(messages)}")
            for (line, column), messages in by_position.items()
        ])
    harmless, structural = _recoveries(parser, root, data, source, what)
    if structural and not lenient:
        raise MissionError(structural)
    if warnings is not None:
        warnings.extend(f"{p.where}: {p.message}" for p in harmless + structural)
    return root


# ---------------------------------------------------------------------------------------------
# Value helpers (C++ stream semantics of the original)


def element_children(el: etree._Element) -> Iterator[etree._Element]:
    """Element children in document order, skipping comments and PIs (the original stores them
    as pseudo-children that never match a type name)."""
    return el.iterchildren(tag=etree.Element)


def text_of(el: etree._Element) -> str:
    """The element's data as PropertyTree sees it: all directly contained text pieces,
    concatenated, where a piece consisting only of XML whitespace is dropped (rapidxml skips
    whitespace before a tag).  Non-blank pieces are verbatim, including their blanks."""
    if len(el) == 0:
        t = el.text
        return t if t and t.strip(_XML_WHITESPACE) else ""
    pieces = [el.text] + [c.tail for c in el]
    return "".join(p for p in pieces if p and p.strip(_XML_WHITESPACE))


def child(el: etree._Element, tag: str) -> etree._Element | None:
    """First element child with ``tag`` (PropertyTree ``get_child`` returns the first)."""
    if not tag:
        return None
    return next(el.iterchildren(tag=tag), None)


def field_text(el: etree._Element, name: str) -> str | None:
    """Text of the first child ``name``; None when the field is missing."""
    c = child(el, name)
    return None if c is None else text_of(c)


def record_id(el: etree._Element, unique_id: str = "name") -> str | None:
    """The record's unique id (text of its first ``unique_id`` child), None if it has none."""
    return field_text(el, unique_id)


def split_list(text: str) -> list[str]:
    """Split a multi-valued leaf: commas (HEAD) *and* whitespace (older builds, used for the
    reference VSM data) separate values; empty pieces are dropped."""
    return [p for p in _LIST_SEPARATORS.split(text) if p]


def parse_bool(text: str) -> bool:
    """``istringstream >> boolalpha`` on the lower-cased text: blanks skipped, then the word
    ``true`` (a prefix suffices: the stream stops after it) is true; anything else false."""
    return text.lstrip(_CPP_SPACE).lower().startswith("true")


def number_is_partial(text: str) -> bool:
    """Whether :func:`parse_number` reads only a part of ``text`` (``1e9`` read as 1, ``NaN`` as
    0): the original's stream semantics, which a user rarely means."""
    s = text.strip(_CPP_SPACE)
    pattern = _FLOAT_PREFIX if "." in text else _INT_PREFIX
    m = pattern.match(s)
    return m is None or m.end() != len(s)


def parse_number(text: str) -> int | float:
    """Float if the text contains ``.``, else int; like ``istream >>``: leading blanks skipped,
    the longest numeric prefix read, trailing garbage ignored, a non-number gives 0."""
    s = text.lstrip(_CPP_SPACE)
    if "." in text:
        m = _FLOAT_PREFIX.match(s)
        return float(m.group()) if m else 0.0
    m = _INT_PREFIX.match(s)
    return int(m.group()) if m else 0


def base_type(ocl_type: str) -> str:
    """``Sequence(Room)`` -> ``Room``; plain types unchanged."""
    lp = ocl_type.find("(")
    if lp >= 0 and ocl_type.endswith(")"):
        return ocl_type[lp + 1 : -1].strip()
    return ocl_type


def is_collection_type(ocl_type: str) -> bool:
    """Collection OCL types are written ``Kind(Base)``, e.g. ``Sequence(Room)``."""
    return "(" in ocl_type and ocl_type.endswith(")")


# ---------------------------------------------------------------------------------------------
# The knowledge


@dataclass(frozen=True)
class WorldKnowledge:
    source: str
    root: etree._Element  # the xml_root element; its element children are the records
    unique_id: str = "name"
    warnings: tuple[str, ...] = ()  # repairs of the XML, located

    # -- records ------------------------------------------------------------------------------

    @cached_property
    def records(self) -> tuple[etree._Element, ...]:
        """Top-level records (element children of the root) in document order."""
        return tuple(element_children(self.root))

    @cached_property
    def _by_tag(self) -> dict[str, tuple[etree._Element, ...]]:
        groups: dict[str, list[etree._Element]] = {}
        for r in self.records:
            groups.setdefault(r.tag, []).append(r)
        return {t: tuple(rs) for t, rs in groups.items()}

    def records_of(self, tag: str) -> tuple[etree._Element, ...]:
        """Top-level records with ``tag`` in document order (same tuple object on every call,
        so callers may recognise the full candidate list)."""
        return self._by_tag.get(tag, ())

    @cached_property
    def _by_tag_id(self) -> dict[tuple[str, str], etree._Element]:
        index: dict[tuple[str, str], etree._Element] = {}
        for r in self.records:
            rid = self.record_id(r)
            if rid is not None:
                index.setdefault((r.tag, rid), r)
        return index

    def find_record(self, tag: str, rid: str) -> etree._Element | None:
        """First top-level record with ``tag`` and unique id ``rid``."""
        return self._by_tag_id.get((tag, rid))

    @cached_property
    def _field_indexes(self) -> dict[tuple[str, str], dict[str, list[int]]]:
        return {}

    def field_index(self, tag: str, name: str) -> dict[str, list[int]]:
        """For top-level records of ``tag``: text of field ``name`` -> positions in
        :meth:`records_of` (ascending).  Built once per (tag, field); lets ``x.b in ...``
        select among thousands of records without a scan."""
        key = (tag, name)
        index = self._field_indexes.get(key)
        if index is None:
            index = {}
            for pos, r in enumerate(self.records_of(tag)):
                t = field_text(r, name)
                if t is not None:
                    index.setdefault(t, []).append(pos)
            self._field_indexes[key] = index
        return index

    # -- per-record helpers --------------------------------------------------------------------

    def record_id(self, el: etree._Element) -> str | None:
        return record_id(el, self.unique_id)

    @staticmethod
    def field(el: etree._Element, name: str) -> etree._Element | None:
        return child(el, name)

    @staticmethod
    def field_text(el: etree._Element, name: str) -> str | None:
        return field_text(el, name)

    @staticmethod
    def text(el: etree._Element) -> str:
        return text_of(el)


def load_knowledge(
    path: str | os.PathLike[str], xml_root: str | None, unique_id: str = "name", *, lenient: bool = False
) -> WorldKnowledge:
    """Read the world knowledge file and locate the record container.

    ``xml_root`` is the tag of the container (the root itself or its first descendant with that
    tag, pre-order); None uses the document root, as the original does after its warning.
    """
    source = os.fspath(path)
    data = read_bytes(
        path,
        "world knowledge",
        "The world knowledge file is named by world_db.path in the configuration; a relative path "
        "is looked up from the current directory, then from the mission folder.",
    )
    warnings: list[str] = []
    doc_root = parse_tolerant_xml(data, source, "world knowledge", lenient=lenient, warnings=warnings)
    root: etree._Element | None
    if xml_root is None:
        root = doc_root
    elif doc_root.tag == xml_root:
        root = doc_root
    else:
        root = next(doc_root.iterdescendants(tag=xml_root), None) if xml_root else None
    if root is None:
        raise MissionError(Problem(
            located(source, doc_root.sourceline),
            f"Root element [{xml_root}] (world_db.xml_root) was not found in world knowledge",
            f"Set world_db.xml_root in the configuration to the tag of the element that holds the "
            f"records (the document root here is <{doc_root.tag}>).",
        ))
    return WorldKnowledge(source=source, root=root, unique_id=unique_id or "name", warnings=tuple(warnings))
