"""World knowledge reader (spec ``config-and-knowledge.md`` §5).

The file is parsed by :func:`~mutrose_cp.io.tolerant_xml.parse_tolerant_xml` (no entity
expansion, no DTD loading, no network, lenient end tags as the original accepts) into the
:class:`~mutrose_cp.model.WorldKnowledge`.  The original reads its records with
Boost.PropertyTree, whose values are strings taken verbatim; this module also offers the small
value parsers (boolean, number, list) the original applies to those field texts.
"""
from __future__ import annotations

import os
import re

from lxml import etree

from ..errors import MissionError, Problem, located
from ..model.world import WorldKnowledge
from .text import read_bytes
from .tolerant_xml import parse_tolerant_xml, source_line

# ---------------------------------------------------------------------------------------------
# Value helpers (C++ stream semantics of the original)

_CPP_SPACE = " \t\n\v\f\r"  # what ``istream >>`` skips
_LIST_SEPARATORS = re.compile(r"[,\s]+")
_INT_PREFIX = re.compile(r"[+-]?\d+")
_FLOAT_PREFIX = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?")


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
            located(source, source_line(doc_root)),
            f"Root element [{xml_root}] (world_db.xml_root) was not found in world knowledge",
            f"Set world_db.xml_root in the configuration to the tag of the element that holds the "
            f"records (the document root here is <{doc_root.tag}>).",
        ))
    return WorldKnowledge(source=source, root=root, unique_id=unique_id or "name", warnings=tuple(warnings))
