"""World knowledge reader (spec ``config-and-knowledge.md`` §5) with a hardened lxml parser:
no entity expansion, no DTD loading, no network, lenient end tags as the original accepts."""
from __future__ import annotations

from dataclasses import dataclass

from lxml import etree


@dataclass(frozen=True)
class WorldKnowledge:
    source: str
    root: etree._Element  # the xml_root element; its element children are the records
    unique_id: str = "name"
