"""The validator's own evaluation of ``QueriedProperty`` selects (spec ``goal-model.md`` §8.1).

The validator rebuilds the task instances a mission implies (which rooms a ``forAll`` visits, in
which order, and so which instance is ``AT1_2``) without the decomposers' query code, so that a
mistake there, or an output that renames instances, shows up.  The rules are the spec's, with
the documented choices of mutrose-cp (docs/deviations.md): ``||`` is the union of both sides,
and a list in a world field is split at commas and whitespace.  What the original cannot
evaluate (``<>``, a variable that holds no record) raises :class:`Unresolved`; the validator
then notes that the instances below that goal are not checked.
"""
from __future__ import annotations

import re
from typing import Callable, Mapping, Sequence

from lxml import etree

from ..io.knowledge import parse_number, split_list
from ..model import Atom, Binding, BoolOp, Condition, Select, WorldKnowledge, base_type, is_collection_type
from ..model.records import child, element_children, field_text, text_of

Element = etree._Element
Test = Callable[[Element], bool]

_IN = re.compile(r"\s+in\s+")
_OPERATOR = re.compile(r"<>|>=|<=|=|>|<")
_DIGITS = re.compile(r"\d+")


class Unresolved(Exception):
    """A select the validator cannot evaluate (the message says why)."""


def _attribute(operand: str) -> str:
    """The field a left operand names: the text after its first ``.`` (the variable before it
    is not read, as in the original)."""
    _, dot, rest = operand.partition(".")
    return rest.strip() if dot else operand.strip()


class _Select:
    """One evaluation of a select against the world and the variables bound so far."""

    def __init__(self, select: Select, world: WorldKnowledge, bindings: Mapping[str, Binding]) -> None:
        self.select = select
        self.world = world
        self.bindings = bindings

    def first_record(self, name: str) -> Element | None:
        binding = self.bindings.get(name)
        if binding is None:
            raise Unresolved(f"variable {name} is not bound")
        if binding.records:
            return binding.records[0]
        ids = binding.ids
        return self.world.find_record(base_type(binding.type), ids[0]) if ids else None

    def candidates(self) -> Sequence[Element]:
        queried, qtype = self.select.queried.strip(), self.select.type
        if queried == "world_db":
            return self.world.records_of(qtype)
        if "." not in queried:
            binding = self.bindings.get(queried)
            if binding is None or is_collection_type(binding.type) or len(binding.records) > 1:
                raise Unresolved(f"{queried} does not hold exactly one record")
            record = self.first_record(queried)
            return [] if record is None else [c for c in element_children(record) if c.tag == qtype]
        return self.path_candidates(queried, qtype)

    def path_candidates(self, queried: str, qtype: str) -> list[Element]:
        var, *path = queried.split(".")
        record = self.first_record(var)
        rid = None if record is None else self.world.record_id(record)
        el = None if rid is None else self.world.find_record(base_type(self.bindings[var].type), rid)
        for attr in path:
            el = None if el is None else child(el, attr)
        if el is None:
            raise Unresolved(f"{queried} is not in the world knowledge")
        records = list(element_children(el))
        if any(r.tag != qtype for r in records):
            raise Unresolved(f"{queried} holds records other than {qtype}")
        return records

    def field_values(self, var: str, attr: str) -> frozenset[str]:
        """A field of a variable's record as a set of values: its child elements' texts, or its
        text split at commas and whitespace."""
        record = self.first_record(var)
        el = None if record is None else child(record, attr)
        if el is None:
            raise Unresolved(f"{var}.{attr} is not in the world knowledge")
        kids = list(element_children(el))
        return frozenset(text_of(k) for k in kids) if kids else frozenset(split_list(text_of(el)))

    # -- atoms --------------------------------------------------------------------------------
    def test(self, atom: Atom) -> tuple[Test, tuple[str, frozenset[str]] | None]:
        """The atom as a record test, and (field, values) when it is a look-up by field value."""
        text = atom.text.strip()
        m_in, m_op = _IN.search(text), _OPERATOR.search(text)
        if m_in is not None and (m_op is None or m_in.start() < m_op.start()):
            return self.membership(text[:m_in.start()].strip(), text[m_in.end():].strip())
        if m_op is None:
            negated = text.startswith("!")
            attr = _attribute(text[1:] if negated else text)
            return (lambda x: (c := child(x, attr)) is not None and (text_of(c).lower() == "true") != negated), None
        return self.comparison(text, m_op)

    def comparison(self, text: str, m_op: re.Match[str]) -> tuple[Test, tuple[str, frozenset[str]] | None]:
        op, attr, rhs = m_op.group(), _attribute(text[:m_op.start()].strip().lstrip("!")), text[m_op.end():].strip()
        if op == "<>":
            raise Unresolved("<> is not supported in select conditions")
        if op in (">=", "<="):
            rhs = '""'  # the original reads them as "=" with an empty right side
        if op in ("=", ">=", "<="):
            if len(rhs) >= 2 and rhs[0] == rhs[-1] and rhs[0] in "\"'":
                rhs = rhs[1:-1]
            if op == "=" and not (rhs[:1].isascii() and rhs[:1].isalpha()):
                return (lambda x: False), None
            return (lambda x: field_text(x, attr) == rhs), (attr, frozenset((rhs,)))
        digits = _DIGITS.search(rhs)
        if digits is None:
            raise Unresolved(f"no number after {op} in {text}")
        bound, greater = int(digits.group()), op == ">"

        def compare(x: Element) -> bool:
            c = child(x, attr)
            return c is not None and (parse_number(text_of(c)) > bound if greater
                                      else parse_number(text_of(c)) < bound)
        return compare, None

    def membership(self, left: str, right: str) -> tuple[Test, tuple[str, frozenset[str]] | None]:
        lvar, _, lattr = left.partition(".")
        lattr = lattr or lvar
        if right.split(".", 1)[0] == self.select.variable:  # ownership: "v.b in q.attr"
            if right.count(".") != 1:
                raise Unresolved("the ownership in accepts only [var].[attr]")
            container, values = right.split(".", 1)[1], self.field_values(lvar.lstrip("!"), lattr)

            def owns(x: Element) -> bool:
                c = child(x, container)
                return c is not None and any(field_text(y, lattr) in values for y in element_children(c))
            return owns, None
        if "." in right:
            var, _, attr = right.partition(".")
            values = self.field_values(var, attr)
        else:
            binding = self.bindings.get(right)
            if binding is None:
                raise Unresolved(f"variable {right} is not bound")
            values = frozenset(binding.ids)
        return (lambda x: field_text(x, lattr) in values), (lattr, values)

    # -- conditions ---------------------------------------------------------------------------
    def evaluate(self, cond: Condition, cands: Sequence[Element], full: bool) -> list[Element]:
        """Records of ``cands`` that meet ``cond``; ``full``: ``cands`` is every top-level record
        of the queried type (a look-up by field value may then use the world's index)."""
        if isinstance(cond, BoolOp):
            result = self.evaluate(cond.children[0], cands, full)
            for c in cond.children[1:]:
                if cond.op == "&&":
                    keep = set(self.evaluate(c, result, False))
                    result = [x for x in result if x in keep]
                else:
                    seen = set(result)
                    result = result + [x for x in self.evaluate(c, cands, full) if x not in seen]
            return result
        test, lookup = self.test(cond)
        if full and lookup is not None:
            index = self.world.field_index(self.select.type, lookup[0])
            return [cands[p] for p in sorted(p for v in lookup[1] for p in index.get(v, ()))]
        return [x for x in cands if test(x)]


def run_select(select: Select, world: WorldKnowledge, bindings: Mapping[str, Binding]) -> list[Element]:
    """The records ``select`` chooses, in document order (after ``||``: the left side's, then the
    right side's new ones)."""
    query = _Select(select, world, bindings)
    cands = query.candidates()
    if select.condition is None:
        return list(cands)
    full = select.queried.strip() == "world_db"
    return query.evaluate(select.condition, cands, full)
