"""Hardened, tolerant XML parsing, shared by the world knowledge and the XML configuration.

The original reads its XML inputs with Boost.PropertyTree (rapidxml), which does not validate
closing-tag names and ignores content after the first top-level element.  This module reads the
same documents with lxml, configured so that no entity is expanded, no DTD loaded and nothing
fetched from the network, and reports every repair it makes at ``file:line:col``.
"""
from __future__ import annotations

import re
from typing import Protocol, cast

from lxml import etree

from ..errors import MissionError, Problem, located

# libxml2 errors that the original's reader (rapidxml) does not report either: a closing tag
# whose name differs from the open element (libxml2's recovery pops the innermost element, the
# same as rapidxml) and extra content after the first top-level element (only the first one is
# read).  Every other well-formedness error is a real error of the input.
TOLERATED_XML_ERRORS = frozenset({"ERR_TAG_NAME_MISMATCH", "ERR_DOCUMENT_END"})

_DTD_HINT = (
    "Remove the <!DOCTYPE ...> declaration and write every value out literally: the decomposer "
    "never reads DTDs nor expands entities (this protects against billion-laughs and "
    "external-entity attacks)."
)

_XML_DECL_ENCODING = re.compile(r"""^(\ufeff?\s*<\?xml[^>]*?encoding\s*=\s*)(["'])[^"']*\2""")

_MISMATCH = re.compile(r"Opening and ending tag mismatch: (\S+) line (\d+) and (\S+)")
LENIENT_HINT = ("Fix the XML, or pass --lenient-xml to read it as the original does (which keeps the recovered "
                "structure).")


class _LogEntry(Protocol):
    """What is read from an entry of libxml2's error log (lxml-stubs leaves the log untyped)."""

    line: int
    column: int
    message: str
    type_name: str


def source_line(el: etree._Element) -> int | None:
    """The line of ``el`` in its document (None when lxml does not know it).

    lxml-stubs declares ``sourceline`` without a type (it reads as ``...``); lxml documents it
    as ``int | None``, which this narrow cast states once for every reader."""
    return cast("int | None", el.sourceline)


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


def _more_after(data: bytes, line: int, column: int) -> bool:
    """Whether anything but blanks follows position ``line:column`` (1-based) of ``data``."""
    lines = data.split(b"\n")
    rest = b"\n".join([lines[line - 1][column - 1:], *lines[line:]]) if line <= len(lines) else b""
    return bool(rest.strip())


def _mismatch_problem(error: _LogEntry, root: etree._Element, data: bytes, source: str,
                      what: str) -> tuple[Problem, bool] | None:
    """One repaired end-tag mismatch as (problem, structural); None for other log entries.

    An end tag that is a typo of the element it closes (``</location_type>`` for
    ``<location_types>``) changes nothing, nor does a text-only element left open.  An element
    with children left open (its end tag missing, so the end tag of an outer element closes it)
    swallows the records after it, and a stray end tag closing the root drops the rest."""
    m = _MISMATCH.search(error.message)
    if error.type_name != "ERR_TAG_NAME_MISMATCH" or m is None:
        return None
    where = located(source, error.line, error.column)
    opened, line, closing = m.group(1), int(m.group(2)), m.group(3)
    element = next((el for el in root.iter(opened) if source_line(el) == line), None)
    if element is not None and element.getparent() is None and _more_after(data, error.line, error.column):
        return Problem(where, f"{what}: </{closing}> closes the root element <{opened}> early (a stray "
                              "end tag?): the records after it would be lost", LENIENT_HINT), True
    left_open = element is not None and any(a.tag == closing for a in element.iterancestors())
    # an element left open with only text inside swallowed nothing; one holding elements
    # (a record with its fields) has taken the records after it
    if element is not None and left_open and any(isinstance(c.tag, str) for c in element):
        return Problem(where, f"{what}: <{opened}> (line {line}) is never closed, so </{closing}> "
                              f"closes it and everything after it is nested inside it (a missing "
                              f"</{opened}>?)", LENIENT_HINT), True
    return Problem(where, f"{what}: </{closing}> closes <{opened}> (line {line}); read as </{opened}>"), False


def _recoveries(parser: etree.XMLParser, root: etree._Element, data: bytes, source: str,
                what: str) -> tuple[list[Problem], list[Problem]]:
    """The repairs the reader made, as (harmless, structural) located messages.

    Content after the root element (often after a stray end tag closed the root early) is
    dropped, which changes which records exist; end-tag mismatches are judged one by one."""
    harmless: list[Problem] = []
    structural: list[Problem] = []
    log: list[_LogEntry] = list(parser.error_log)
    for e in log:
        if e.type_name == "ERR_DOCUMENT_END":
            structural.append(Problem(located(source, e.line, e.column),
                                      f"{what}: content after the end of the root element <{root.tag}> is "
                                      "ignored (a stray end tag may have closed the root early): the records "
                                      "there would be lost", LENIENT_HINT))
            continue
        judged = _mismatch_problem(e, root, data, source, what)
        if judged is not None:
            problem, is_structural = judged
            (structural if is_structural else harmless).append(problem)
    return harmless, structural


def _reject_dtd(root: etree._Element, data: bytes, source: str, what: str) -> None:
    """Refuse a DOCTYPE before anything could use it: entities are never expanded."""
    info = root.getroottree().docinfo
    if info.internalDTD is not None or info.doctype:
        raise MissionError(Problem(
            located(source, _line_of(data, b"<!DOCTYPE")),
            f"DTD and entity declarations are not allowed in {what}",
            _DTD_HINT,
        ))


def _syntax_error(errors: list[_LogEntry], source: str, what: str) -> MissionError:
    """The well-formedness errors libxml2 could not tolerate, one problem per position (it
    reports one mistake as several messages at one position)."""
    if not errors:
        return MissionError(Problem(source, f"XML syntax error in {what}: the document has no root element"))
    by_position: dict[tuple[int, int], list[str]] = {}
    for e in errors:
        messages = by_position.setdefault((e.line, e.column), [])
        if e.message not in messages:
            messages.append(e.message)
    return MissionError([
        Problem(located(source, line, column), f"XML syntax error in {what}: {'; '.join(messages)}")
        for (line, column), messages in by_position.items()
    ])


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
        # recover=True makes lxml return None for a document without a root element
        root: etree._Element | None = etree.fromstring(data, parser)
    except etree.XMLSyntaxError as exc:
        line, col = (exc.position if exc.position else (None, None))
        raise MissionError(Problem(located(source, line, col), f"XML syntax error in {what}: {exc.msg}")) from None
    if root is not None:
        _reject_dtd(root, data, source, what)
    log: list[_LogEntry] = list(parser.error_log)
    errors = [e for e in log if e.type_name not in TOLERATED_XML_ERRORS]
    if errors or root is None:
        raise _syntax_error(errors, source, what)
    harmless, structural = _recoveries(parser, root, data, source, what)
    if structural and not lenient:
        raise MissionError(structural)
    if warnings is not None:
        warnings.extend(f"{p.where}: {p.message}" for p in harmless + structural)
    return root
