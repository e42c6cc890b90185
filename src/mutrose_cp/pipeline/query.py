"""Evaluation of ``QueriedProperty`` select expressions on the world knowledge (spec
``goal-model.md`` §8 and §8.1).

The original classifies each condition atom by string search and has several quirks that the
reference outputs depend on; they are reproduced here:

* the left operand's variable prefix is ignored (``r.is_clean`` -> field ``is_clean``);
* ``!`` is the only negation and ``!x.attr`` requires the field to exist;
* ``=`` is an exact string comparison whose right side (quotes stripped) must start with a
  letter, so ``= 5`` never matches;
* ``>=`` / ``<=`` behave as ``=`` with an empty right side;
* ``>`` / ``<`` compare with the first run of digits after the operator (``> 2.5`` is ``> 2``);
* ``&&`` is an intersection keeping the left operand's order.

Deliberate deviations: ``<>`` is reported as an error instead of crashing, and ``||`` returns the
union of both sides (left result, then the right side's new records) where the original
returns only the left side.

Queries run once per ``forAll`` iteration, so atoms of the form ``x.b in ...`` / ``x.b = v`` on
the world's top-level records use a per-field index instead of scanning every record.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Callable, Mapping, NamedTuple, Sequence

from lxml import etree

from ..errors import MissionError
from ..io.knowledge import parse_number, split_list
from ..model import Atom, Binding, BoolOp, Condition, Select, WorldKnowledge, base_type, is_collection_type
from ..model.records import child, element_children, field_text, text_of

Element = etree._Element


_IN = re.compile(r"\s+in\s+")
_OPERATOR = re.compile(r"<>|>=|<=|=|>|<")
_DIGITS = re.compile(r"\d+")


@dataclass(frozen=True)
class _Filter:
    """A compiled atom: a per-record test, and, when the test is "field ``lookup[0]``'s text is
    one of ``lookup[1]``", that equivalent form so full record lists can use an index."""

    test: Callable[[Element], bool]
    lookup: tuple[str, frozenset[str]] | None = None


class _Query:
    def __init__(
        self, select: Select, knowledge: WorldKnowledge, bindings: Mapping[str, Binding], goal_id: str
    ) -> None:
        self.select = select
        self.knowledge = knowledge
        self.bindings = bindings
        self.goal_id = goal_id
        self.filters: dict[int, _Filter] = {}

    # -- errors -------------------------------------------------------------------------------

    def invalid(self, detail: str = "") -> MissionError:
        msg = f"Invalid query in Goal {self.goal_id}"
        return MissionError(f"{msg}: {detail}" if detail else msg, where=self.goal_id)

    def unsolvable(self, detail: str = "") -> MissionError:
        msg = f"Cannot solve condition in QueriedProperty of Goal {self.goal_id}"
        return MissionError(f"{msg}: {detail}" if detail else msg, where=self.goal_id)

    def first_record(self, binding: Binding) -> Element | None:
        """The binding's first record; callers that bound only ids get the top-level record
        with that id (and the base type's tag)."""
        if binding.records:
            return binding.records[0]
        ids = binding.ids
        return self.knowledge.find_record(base_type(binding.type), ids[0]) if ids else None

    # -- candidates ---------------------------------------------------------------------------

    def candidates(self) -> tuple[Sequence[Element], str | None]:
        """Records to filter and, when they are the full top-level list of a tag, that tag."""
        queried = self.select.queried.strip()
        qtype = self.select.type
        if queried == "world_db":
            return self.knowledge.records_of(qtype), qtype
        if "." not in queried:
            return self.variable_candidates(queried, qtype), None
        return self.path_candidates(queried, qtype), None

    def variable_candidates(self, queried: str, qtype: str) -> list[Element]:
        """``v->select(x:T | ...)``: the ``T`` children of the one record ``v`` holds."""
        binding = self.bindings.get(queried)
        if binding is None:
            raise self.invalid(f"variable [{queried}] is not instantiated")
        if is_collection_type(binding.type) or len(binding.records) > 1:
            raise self.invalid(f"variable [{queried}] must hold exactly one record to be queried")
        first = self.first_record(binding)
        if first is None:
            return []  # the variable holds "" (its query found nothing)
        return [c for c in element_children(first) if c.tag == qtype]

    def path_candidates(self, queried: str, qtype: str) -> list[Element]:
        """``v.a1.a2->select(x:T | ...)``: the children of field ``a1.a2`` of ``v``'s record in
        the world knowledge, which must all be ``T`` records."""
        var, *path = queried.split(".")
        binding = self.bindings.get(var)
        first = self.first_record(binding) if binding is not None else None
        if binding is None or first is None:
            raise self.invalid(f"variable [{var}] is not instantiated")
        rid = self.knowledge.record_id(first)
        el = self.knowledge.find_record(base_type(binding.type), rid) if rid is not None else None
        if el is None:
            raise self.invalid(f"no {base_type(binding.type)} record [{rid}] in the world knowledge")
        for attr in path:
            el = child(el, attr)
            if el is None:
                raise self.invalid(f"[{queried}] does not exist in the world knowledge")
        records = list(element_children(el))
        for r in records:
            if r.tag != qtype:
                raise self.invalid(f"[{queried}] holds a <{r.tag}>, not only {qtype} records")
        return records

    # -- compilation (all errors are raised here, independently of the candidates) -----------

    def compile(self, cond: Condition) -> None:
        if isinstance(cond, BoolOp):
            for c in cond.children:
                self.compile(c)
        else:
            self.filters[id(cond)] = self.compile_atom(cond)

    def record_values(self, var: str, attr: str) -> frozenset[str]:
        """Values of field ``attr`` of ``var``'s (first) record: a leaf is a comma/whitespace
        separated list, a container lists one value per child element."""
        binding = self.bindings.get(var)
        first = self.first_record(binding) if binding is not None else None
        if first is None:
            raise self.unsolvable(f"variable [{var}] is not instantiated")
        el = child(first, attr)
        if el is None:
            raise self.unsolvable(f"[{var}.{attr}] does not exist in the world knowledge")
        kids = list(element_children(el))
        if kids:
            return frozenset(text_of(k) for k in kids)
        return frozenset(split_list(text_of(el)))

    def compile_atom(self, atom: Atom) -> _Filter:
        """One atom as a record test, classified by string search as the original does: an
        ``in`` before any comparison operator, a bare (possibly negated) boolean field, or a
        comparison."""
        text = atom.text.strip()
        form = _atom_form(text)
        if form.membership is not None:
            return self.compile_in(text[: form.membership.start()].strip(), text[form.membership.end() :].strip())
        if form.comparison is None:
            return _boolean(text)
        return self.compile_comparison(text, form.comparison)

    def compile_comparison(self, text: str, m_op: re.Match[str]) -> _Filter:
        """``x.attr op rhs`` with the original's quirks: ``<>`` refused, ``>=``/``<=`` read as
        ``=`` with an empty right side, ``=`` an exact string match, ``>``/``<`` against the
        first run of digits."""
        op = m_op.group()
        attr = _attribute(text[: m_op.start()].strip().lstrip("!"))
        rhs = text[m_op.end() :]
        if op == "<>":
            raise MissionError(
                f"Goal {self.goal_id}: operator <> is not supported in select conditions", where=self.goal_id
            )
        if op in (">=", "<="):
            return _equals(attr, "")  # [bug] parsed as "=" with an empty right side
        if op == "=":
            return _string_equals(attr, rhs)
        digits = _DIGITS.search(rhs)
        if digits is None:
            raise self.invalid(f"no number after {op} in [{text}]")
        threshold = int(digits.group())  # [bug] "> 2.5" is "> 2"
        greater = op == ">"

        def compare(x: Element) -> bool:
            c = child(x, attr)
            if c is None:
                return False
            v = parse_number(text_of(c))
            return v > threshold if greater else v < threshold

        return _Filter(compare)

    def compile_in(self, left: str, right: str) -> _Filter:
        lvar, _, lattr = left.partition(".")
        lattr = lattr if lattr else lvar
        rvar = right.split(".", 1)[0]
        if rvar == self.select.variable:
            # ownership in: "v.b in q.attr"
            if right.count(".") != 1:
                raise MissionError(
                    "The in operator for ownership relations currently only accepts a variable "
                    "direct attribute ([var].[attr])",
                    where=self.goal_id,
                )
            container_tag = right.split(".", 1)[1]
            values = self.record_values(lvar.lstrip("!"), lattr)

            def owns(x: Element) -> bool:
                c = child(x, container_tag)
                if c is None:
                    return False
                return any(field_text(y, lattr) in values for y in element_children(c))

            return _Filter(owns)
        if "." not in right:
            binding = self.bindings.get(right)
            if binding is None:
                raise self.unsolvable(f"variable [{right}] is not instantiated")
            return _members(lattr, frozenset(binding.ids))
        var, _, attr = right.partition(".")
        return _members(lattr, self.record_values(var, attr))

    # -- evaluation ---------------------------------------------------------------------------

    def evaluate(self, cond: Condition, cands: Sequence[Element], full_tag: str | None) -> list[Element]:
        if isinstance(cond, BoolOp):
            first, *rest = cond.children
            result = self.evaluate(first, cands, full_tag)
            if cond.op == "&&":
                for c in rest:
                    # as a set, every condition is a per-record test: the right side only needs
                    # to be evaluated on the records that survived the left side
                    keep = set(self.evaluate(c, result, None))
                    result = [x for x in result if x in keep]
            else:  # "||": union (deliberate fix; the original returns only the left side)
                for c in rest:
                    seen = set(result)
                    result = result + [x for x in self.evaluate(c, cands, full_tag) if x not in seen]
            return result
        flt = self.filters[id(cond)]
        if full_tag is not None and flt.lookup is not None:
            name, values = flt.lookup
            index = self.knowledge.field_index(full_tag, name)
            positions: list[int] = []
            for v in values:
                positions.extend(index.get(v, ()))
            positions.sort()
            return [cands[p] for p in positions]
        test = flt.test
        return [x for x in cands if test(x)]

    def run(self) -> list[Element]:
        cands, full_tag = self.candidates()
        cond = self.select.condition
        if cond is None:
            return list(cands)
        self.compile(cond)
        return self.evaluate(cond, cands, full_tag)


def _attribute(operand: str) -> str:
    """The field named by a left operand: the text after its first ``.`` (the variable prefix
    is ignored, as in the original)."""
    _, dot, rest = operand.partition(".")
    return rest.strip() if dot else operand.strip()


def _boolean(text: str) -> _Filter:
    """``x.attr`` / ``!x.attr``: the field exists and is (not) ``true``; a missing field
    matches neither form."""
    negated = text.startswith("!")
    attr = _attribute(text[1:] if negated else text)

    def boolean(x: Element) -> bool:
        c = child(x, attr)
        return c is not None and (text_of(c).lower() == "true") != negated

    return _Filter(boolean)


def _string_equals(attr: str, rhs: str) -> _Filter:
    """``x.attr = "v"``: quotes stripped; a right side not starting with a letter never matches."""
    value = rhs.strip()
    if len(value) >= 2 and value[0] == value[-1] and value[0] in "\"'":
        value = value[1:-1]
    if not value or not ("a" <= value[0].lower() <= "z"):
        return _Filter(lambda x: False)  # the right side must start with a letter
    return _equals(attr, value)


class _AtomForm(NamedTuple):
    """How the original reads a select atom, by string search: an ``in`` before any comparison
    operator (``membership``), a comparison (``comparison``), or neither: a bare, possibly
    negated, boolean field."""

    membership: re.Match[str] | None
    comparison: re.Match[str] | None


def _atom_form(text: str) -> _AtomForm:
    m_in = _IN.search(text)
    m_op = _OPERATOR.search(text)
    if m_in is not None and (m_op is None or m_in.start() < m_op.start()):
        return _AtomForm(m_in, None)
    return _AtomForm(None, m_op)


def _equals(attr: str, value: str) -> _Filter:
    return _Filter(lambda x: field_text(x, attr) == value, (attr, frozenset((value,))))


def _members(attr: str, values: frozenset[str]) -> _Filter:
    return _Filter(lambda x: field_text(x, attr) in values, (attr, values))


def select_problems(select: Select) -> list[str]:
    """Problems of ``select`` that do not depend on the world, so that ``check`` reports them
    up front, located in the goal model (``run_select`` raises the same ones at expansion).
    Each message says what is wrong and how to fix it."""
    problems: list[str] = []

    def visit(cond: Condition) -> None:
        if isinstance(cond, BoolOp):
            for c in cond.children:
                visit(c)
            return
        text = cond.text.strip()
        form = _atom_form(text)
        if form.membership is not None:
            right = text[form.membership.end():].strip()
            if right.split(".", 1)[0] == select.variable and right.count(".") != 1:
                problems.append(
                    "The in operator for ownership relations currently only accepts a variable "
                    f"direct attribute ([var].[attr]): write [{text[: form.membership.start()].strip()} in "
                    f"{select.variable}.<attribute>]"
                )
            return
        m_op = form.comparison
        if m_op is None:
            return
        op = m_op.group()
        if op == "<>":
            problems.append(
                f"operator <> is not supported in select conditions ([{text}]): test equality with = "
                "or a boolean field with !x.attr"
            )
        elif op in (">", "<") and _DIGITS.search(text[m_op.end():]) is None:
            problems.append(f"no number after {op} in [{text}]: compare with a number, e.g. x.attr {op} 2")

    if select.condition is not None:
        visit(select.condition)
    return problems


def run_select(
    select: Select, knowledge: WorldKnowledge, bindings: Mapping[str, Binding], goal_id: str
) -> list[Element]:
    """Records selected by ``select`` (document order, except after ``||``), spec §8/§8.1.

    Raises :class:`MissionError` located at ``goal_id`` for queries the original rejects
    (``Invalid query in Goal G``, ``Cannot solve condition in QueriedProperty of Goal G``, the
    ownership-``in`` restriction) and for ``<>``."""
    return _Query(select, knowledge, bindings, goal_id).run()
