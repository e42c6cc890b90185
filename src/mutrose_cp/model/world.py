"""The world: the knowledge records, the objects and ground facts derived from them, and the
values goal-model variables take while the mission is expanded.

* :class:`WorldKnowledge` is produced by :mod:`mutrose_cp.io.knowledge` (the world knowledge
  file, indexed for the queries);
* :class:`InitialState` (objects per sort, :class:`GroundLiteral` facts, function values) is
  built from it by :mod:`mutrose_cp.pipeline.initial_state` through the configuration's semantic mappings;
* :class:`Binding` is what the expansion binds a goal-model variable to; the query evaluator
  :mod:`mutrose_cp.pipeline.query` and the condition tests read it.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
from functools import cached_property
from typing import Collection, Mapping

from lxml import etree

from .records import child, element_children, field_text, record_id, text_of

Element = etree._Element

# ---------------------------------------------------------------------------------------------
# The knowledge


@dataclass(frozen=True)
class WorldKnowledge:
    """The world knowledge document: its records (the element children of ``root``) and the
    indexes that let a query run once per ``forAll`` iteration without rescanning them."""

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

    # -- entities at any depth, and a world with one field changed ------------------------------

    @cached_property
    def entity_names(self) -> frozenset[str]:
        """The unique ids of every record of the document, nested ones included."""
        return frozenset(self.entity_tags)

    @cached_property
    def entity_tags(self) -> dict[str, frozenset[str]]:
        """Each unique id's record tags (``Room``), nested records included: the types the
        configuration's mappings read it as."""
        tags: dict[str, set[str]] = {}
        for el in self.root.iter():
            if isinstance(el.tag, str) and el is not self.root and (rid := record_id(el, self.unique_id)) is not None:
                tags.setdefault(rid, set()).add(el.tag)
        return {rid: frozenset(found) for rid, found in tags.items()}

    def with_fields(self, values: Mapping[tuple[str, str], str]) -> "WorldKnowledge":
        """A copy of this world where each (entity, field) has the text given, in every record
        of the entity (the field added to a record that has none): the world of one scenario.
        Every record, not the first, because a query reads the top-level record, a path the
        nested one, and the domain each record of its type: a nested reference written before
        the entity's own record must not take the value alone.  One pass over the copy."""
        root = copy.deepcopy(self.root)
        fields: dict[str, list[tuple[str, str]]] = {}
        for (entity, name), text in values.items():
            fields.setdefault(entity, []).append((name, text))
        found: set[str] = set()
        for record in root.iter():
            if not isinstance(record.tag, str) or record is root:
                continue
            rid = record_id(record, self.unique_id)
            if rid not in fields:
                continue
            found.add(rid)
            for name, text in fields[rid]:
                field = child(record, name)
                if field is None:
                    field = etree.SubElement(record, name)
                field.text = text
        assert found == set(fields), set(fields) - found  # checked when the uncertainty file was resolved
        return WorldKnowledge(self.source, root, self.unique_id, self.warnings)

    # -- per-record helpers --------------------------------------------------------------------

    def record_id(self, el: etree._Element) -> str | None:
        """The record's unique id (its ``unique_id`` field), None if it has none."""
        return record_id(el, self.unique_id)

    @staticmethod
    def field(el: etree._Element, name: str) -> etree._Element | None:
        """The first field ``name`` of a record."""
        return child(el, name)

    @staticmethod
    def field_text(el: etree._Element, name: str) -> str | None:
        """The text of the first field ``name`` of a record; None when it is missing."""
        return field_text(el, name)

    @staticmethod
    def text(el: etree._Element) -> str:
        """The element's text as PropertyTree sees it."""
        return text_of(el)


# ---------------------------------------------------------------------------------------------
# The initial state

Number = int | float

#: numbers are compared as integers in thousandths (docs/numbers.md)
SCALE = 1000


def scaled(value: float) -> int:
    """``value`` in thousandths: two values alike in thousandths are one value."""
    return round(value * SCALE)

#: the largest magnitude of a number the decomposers compute with: the CP-SAT model holds values
#: in thousandths as 64-bit integers, with room left for the sums of increases (docs/numbers.md)
MAX_NUMBER = 10**15


@dataclass(frozen=True)
class GroundLiteral:
    """A ground atom with polarity, e.g. ``clean(RoomA)`` or ``not at(CleanLinens, Storage1)``."""

    predicate: str
    args: tuple[str, ...]
    positive: bool = True

    def __str__(self) -> str:
        atom = f"{self.predicate}({', '.join(self.args)})"
        return atom if self.positive else f"not {atom}"


@dataclass(frozen=True)
class InitialState:
    """The ground initial state: objects per sort, literals and function values.

    ``literals`` and ``functions`` keep mapping order and duplicates, as the original's vectors
    do; look-ups use the first matching entry.  Absent atoms are *unknown* (None), which every
    consumer treats as satisfied (spec §6).
    """

    sorts: dict[str, frozenset[str]]
    literals: tuple[GroundLiteral, ...]
    functions: tuple[tuple[tuple[str, tuple[str, ...]], Number], ...]
    warnings: tuple[str, ...] = ()  # world values read differently from how they are written
    # atoms whose values were dropped (:meth:`forgetting`), and those of them read since
    forgotten: frozenset[tuple[str, tuple[str, ...]]] = frozenset()
    _forgotten_reads: set[tuple[str, tuple[str, ...]]] = field(default_factory=set, compare=False, repr=False)

    @cached_property
    def _literal_index(self) -> dict[tuple[str, tuple[str, ...]], bool]:
        index: dict[tuple[str, tuple[str, ...]], bool] = {}
        for lit in self.literals:
            index.setdefault((lit.predicate, lit.args), lit.positive)
        return index

    @cached_property
    def _function_index(self) -> dict[tuple[str, tuple[str, ...]], Number]:
        index: dict[tuple[str, tuple[str, ...]], Number] = {}
        for key, value in self.functions:
            index.setdefault(key, value)
        return index

    def forgetting(self, atoms: Collection[tuple[str, tuple[str, ...]]]) -> "InitialState":
        """This state with ``atoms`` unknown: their literals and values dropped (the uncertain
        facts of docs/formats/uncertainty.md, whose values the decomposer then chooses)."""
        return InitialState(self.sorts, tuple(lit for lit in self.literals if (lit.predicate, lit.args) not in atoms),
                            tuple(f for f in self.functions if f[0] not in atoms), self.warnings,
                            frozenset(atoms))

    def forgotten_reads(self) -> set[tuple[str, tuple[str, ...]]]:
        """The forgotten atoms whose function values were asked for (a recursion's count)."""
        return set(self._forgotten_reads)

    def fact_map(self) -> dict[tuple[str, tuple[str, ...]], bool]:
        """Every known atom and its polarity (the first literal of an atom decides), a copy to
        change as effects are applied."""
        return dict(self._literal_index)

    def value_map(self) -> dict[tuple[str, tuple[str, ...]], Number]:
        """Every known function value (the first entry decides), a copy to change."""
        return dict(self._function_index)

    def value_of(self, pred: str, args: tuple[str, ...] | list[str]) -> bool | None:
        """Polarity of the first literal ``pred(args)``; None when the atom is unknown."""
        return self._literal_index.get((pred, tuple(args)))

    def function_value(self, fn: str, args: tuple[str, ...] | list[str]) -> Number | None:
        """Value of the first ``fn(args)`` entry; None when unknown."""
        key = (fn, tuple(args))
        if self.forgotten and key in self.forgotten:
            self._forgotten_reads.add(key)
        return self._function_index.get(key)

    def objects_of(self, sort: str) -> frozenset[str]:
        """Objects of ``sort`` (empty for an unknown sort)."""
        return self.sorts.get(sort, frozenset())


# ---------------------------------------------------------------------------------------------
# Variable values


@dataclass(frozen=True)
class Binding:
    """The current value of a GM variable during decomposition.

    ``value`` is a record id (single-valued variable; ``""`` when a query found nothing) or a
    tuple of ids (collection); ``type`` the OCL type as declared (``Room``,
    ``Sequence(Room)``); ``records`` the knowledge records behind the value, in order (needed
    for ``v.attr`` look-ups and path queries)."""

    value: str | tuple[str, ...]
    type: str
    records: tuple[Element, ...] = ()

    @property
    def ids(self) -> tuple[str, ...]:
        """The record ids held (empty for a query that found nothing)."""
        if isinstance(self.value, tuple):
            return self.value
        return (self.value,) if self.value else ()
