"""World records as the original's reader (Boost.PropertyTree) sees them.

The world knowledge (and the XML configuration) are lxml element trees; these accessors give
the data PropertyTree would give: element children only, the first child of a tag, text pieces
with blank ones dropped.  They are the vocabulary of :class:`~mutrose_cp.model.WorldKnowledge`,
of the world builder and of the query evaluator.
"""
from __future__ import annotations

from typing import Iterator

from lxml import etree

_XML_WHITESPACE = " \t\r\n"


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
