"""Task entries of stamped forAll copies, formatted once per source copy.

A stamped copy (``TaskGraph.stamped_copies``) has the vertices of its source copy with other
names: other keys and ids, another room, other patients.  Its task entries are then its source's
with those names put in: the source's entries are formatted once, with a slot for every key, id
and value (``EntryTemplates.slotted_entry``), and each copy fills the slots with its own names,
one string format per copy instead of one formatting per entry.

A copy is filled only where that gives the bytes that formatting its entries one by one gives:

* each decomposition of the copy has its source's task, path, robots, triggering events and
  flags, and parameters of the same names and lengths;
* the copy's values correspond one to one to its source's (equal values print alike, so an
  equality that one side has and the other lacks could print differently);
* a renamed value belongs to the sorts its source value belongs to (the attribute a predicate
  prints is chosen by sort), and neither is a constant of a path or a "?" value, which the
  printed predicates keep as themselves; an empty value stays empty.

Any other copy is formatted entry by entry.
"""
from __future__ import annotations

from bisect import bisect_left
from typing import Mapping, Sequence

from .boost_json import escape_json
from .entry_templates import EntryTemplates, slot_text, Template
from ..model.task_instances import TaskInstance, Value
from ..model.task_graph import DecompositionVertex, StampedCopy, TaskGraph

Slot = tuple[str, int, str]  # ("key" | "id", place in the copy, "") or ("value", -1, the source's value)


class _Block:
    """A source copy's entries as the text between its fields, with a free place for every
    field, and what each slot holds."""

    def __init__(self, template: Template, slots: list[Slot], constants: frozenset[str]) -> None:
        self.pieces = [piece for part in template.parts for piece in (part, "")][:-1]  # fields at odd places
        self.fields = template.slots  # the slot each field shows
        self.slots = slots
        self.values = frozenset(name for kind, _, name in slots if kind == "value")  # of the source
        self.constants = constants  # of the paths of its entries

    def fill(self, names: list[str]) -> str:
        """The text with each field showing its slot's name (one join; formatting the text as a
        format string parsed its twenty kilobytes again for every copy)."""
        self.pieces[1::2] = map(names.__getitem__, self.fields)
        return "".join(self.pieces)


class CopyBlocks:
    """The task entries of the stamped copies, by the position of their first decomposition."""

    def __init__(self, tg: TaskGraph, decs: Sequence[DecompositionVertex], key: Mapping[int, str],
                 templates: EntryTemplates) -> None:
        self.decs = decs
        self.key = key
        self.templates = templates
        self._blocks: dict[int, _Block | None] = {}  # position of a source's first decomposition -> its block
        indices = [d.index for d in decs]
        self.copies: dict[int, tuple[int, int, int]] = {}  # first position -> (end, source's first, vertex shift)
        for region in tg.stamped_copies:
            for c in region:
                if c.start != c.source:
                    lo, hi = _positions(indices, c)
                    slo, shi = _positions(indices, StampedCopy(c.source, c.source, c.size))
                    if hi > lo and hi - lo == shi - slo:
                        self.copies[lo] = (hi, slo, c.start - c.source)

    def entries(self, first: int) -> tuple[str, int] | None:
        """The entries (each as ``"key": {...}``, joined by ``,\\n``) of the stamped copy whose
        first decomposition is at ``first``, and the position after its last; None when no copy
        starts there or it cannot be filled from its source."""
        copy = self.copies.get(first)
        if copy is None:
            return None
        end, source_first, shift = copy
        block = self._block(source_first, source_first + end - first)
        if block is None:
            return None
        values = self._values(first, end, source_first, shift, block.constants)
        if values is None or not block.values <= values.keys():
            return None
        decs, key = self.decs, self.key
        escaped = {source: escape_json(value)[1:-1] for source, value in values.items()}  # once per value
        names = [key[decs[first + place].index] if kind == "key"  # "t<k>": nothing to escape
                 else escape_json(decs[first + place].decomposition.id)[1:-1] if kind == "id"
                 else escaped[source_value]
                 for kind, place, source_value in block.slots]
        return block.fill(names), end

    def _block(self, lo: int, hi: int) -> _Block | None:
        if lo in self._blocks:
            return self._blocks[lo]
        slots: list[Slot] = []
        numbers: dict[Slot, int] = {}
        texts = []
        for place, d in enumerate(self.decs[lo:hi]):
            def slot(kind: str, name: str) -> int:
                held: Slot = ("value", -1, name) if kind == "value" else (kind, place, "")  # noqa: B023 (used at once)
                k = numbers.get(held)
                if k is None:
                    k = numbers[held] = len(slots)
                    slots.append(held)
                return k

            entry = self.templates.slotted_entry(d.decomposition, d.group, d.divisible, slot)
            if entry is None:
                self._blocks[lo] = None
                return None
            texts.append(f'        "{slot_text(slot("key", self.key[d.index]))}": {entry}')
        constants = frozenset().union(*(d.decomposition.path.constants for d in self.decs[lo:hi]))
        block = self._blocks[lo] = _Block(Template(",\n".join(texts)), slots, constants)
        return block

    def _values(self, lo: int, hi: int, source_lo: int, shift: int, constants: frozenset[str]) -> dict[str, str] | None:
        """Each value of the source copy -> the copy's, or None when the copy cannot be filled
        (module docstring)."""
        decs = self.decs
        values: dict[str, str] = {}
        same_instance = None
        for k in range(hi - lo):
            d, s = decs[lo + k], decs[source_lo + k]
            dd, sd = d.decomposition, s.decomposition
            if (d.index - s.index != shift or dd.path is not sd.path or d.group != s.group
                    or d.divisible != s.divisible):
                return None
            if dd.instance is not same_instance:
                same_instance = dd.instance
                pairs = _instance_values(sd.instance, dd.instance)
                if pairs is None or not _pair_values(pairs, values):
                    return None
        return values if self._renamed_alike(values, constants) else None

    def _renamed_alike(self, values: dict[str, str], constants: frozenset[str]) -> bool:
        """Whether the source's values print as the copy's would: one to one, within the same
        sorts, no constant or "?" value renamed, no empty value filled."""
        if len(set(values.values())) != len(values):
            return False  # two values of the source became one
        sorts = self.templates.sorts_of
        return all(a == b or (a and b and a not in constants and b not in constants and a[0] != "?" and b[0] != "?"
                              and sorts(a) == sorts(b)) for a, b in values.items())


def _instance_values(source: TaskInstance, inst: TaskInstance) -> list[tuple[Value | None, Value | None]] | None:
    """The location and parameter values of a source instance and its copy's, side by side;
    None when they differ otherwise (task, robots, triggering events or parameter names)."""
    if (inst.name != source.name or inst.robot_number != source.robot_number
            or inst.triggering_events != source.triggering_events or len(inst.parameters) != len(source.parameters)
            or any(p.hddl_param != q.hddl_param for p, q in zip(source.parameters, inst.parameters))):
        return None
    return [(source.location, inst.location), *((p.value, q.value) for p, q in zip(source.parameters, inst.parameters))]


def _pair_values(pairs: list[tuple[Value | None, Value | None]], values: dict[str, str]) -> bool:
    """Add the value pairs (single or collections) to ``values``; False when a source value
    would have two names, or the shapes differ."""
    for a, b in pairs:
        if isinstance(a, tuple) or isinstance(b, tuple):
            if not (isinstance(a, tuple) and isinstance(b, tuple) and len(a) == len(b)):
                return False
            items: Sequence[tuple[str | None, str | None]] = list(zip(a, b))
        else:
            items = [(a, b)]
        for x, y in items:
            x, y = x or "", y or ""
            if values.setdefault(x, y) != y:
                return False
    return True


def _positions(indices: list[int], copy: StampedCopy) -> tuple[int, int]:
    """The positions (among the decompositions, in vertex order) of ``copy``'s decompositions."""
    return bisect_left(indices, copy.start), bisect_left(indices, copy.start + copy.size)

