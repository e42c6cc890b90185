"""Goal-model conditions as world-state tests (spec ``goal-model.md`` §9).

Context conditions and achieve conditions are written over goal-model variables
(``current_room.is_clean``); the semantic mappings of the configuration translate each atom into
ground HDDL literals or numeric comparisons.  Evaluation follows the open-world rule of the
original: an atom that the state does not mention is satisfied.
"""
from __future__ import annotations

from typing import Callable, Mapping

from ..errors import MissionError
from ..model import Atom, Binding, BoolOp, Condition, Configuration, base_type
from ..model.state_tests import FactTest, ValueTest, AllOf, AnyOf, Test











_NUMERIC_OPS = ("=", "<>", ">", "<", ">=", "<=")


def translate(
    condition: Condition | None, bindings: Mapping[str, Binding], config: Configuration, where: str
) -> Test:
    """Translate a parsed condition into ground tests with the semantic mappings."""
    if condition is None:
        return AllOf(())
    if isinstance(condition, BoolOp):
        parts = tuple(translate(c, bindings, config, where) for c in condition.children)
        return AllOf(parts) if condition.op == "&&" else AnyOf(parts)
    return _atom(condition, bindings, config, where)


def _atom(atom: Atom, bindings: Mapping[str, Binding], config: Configuration, where: str) -> Test:
    """One atom as ground tests, one per value of its variable: ``v.attr`` (or ``!v.attr``)
    through an attribute *predicate* mapping, ``v.attr op N`` through an attribute *function*
    mapping of the variable's type."""
    binding = bindings.get(atom.variable)
    relates = base_type(binding.type) if binding is not None else ""
    values = () if binding is None else (binding.value if isinstance(binding.value, tuple) else (binding.value,))
    op = atom.op
    numeric = op in _NUMERIC_OPS
    wanted = "function" if numeric else "predicate"
    if op is not None and not numeric:
        raise MissionError(f"Invalid condition: {atom.text} (operator {op} is not allowed here)", where)
    mapping = next(
        (m for m in config.semantic_mapping
         if m.type == "attribute" and m.mapped_type == wanted and m.name == atom.attribute and m.relates_to == relates),
        None,
    )
    if mapping is None:
        raise MissionError(
            f"Invalid condition: {atom.text} (no attribute {wanted} mapping named '{atom.attribute}' "
            f"for the type of '{atom.variable}'{' (' + relates + ')' if relates else ', which is not instantiated'})",
            where,
        )
    if op is None:
        return AllOf(tuple(FactTest(mapping.pred, (v,), not atom.negated) for v in values))
    try:
        bound = float(atom.value)
    except ValueError:
        raise MissionError(f"Invalid condition: {atom.text} (expected a number after {op})", where) from None
    return AllOf(tuple(ValueTest(mapping.pred, (v,), op, bound) for v in values))


def compare(value: float, op: str, bound: float) -> bool:
    if op == "=":
        return abs(value - bound) < 1e-9
    if op == "<>":
        return abs(value - bound) >= 1e-9
    if op == ">":
        return value > bound
    if op == "<":
        return value < bound
    if op == ">=":
        return value >= bound
    if op == "<=":
        return value <= bound
    raise ValueError(op)


def holds(
    test: Test,
    fact: Callable[[str, tuple[str, ...]], bool | None],
    value: Callable[[str, tuple[str, ...]], float | None],
) -> bool:
    """Evaluate with open-world semantics: unknown facts and values satisfy the test."""
    if isinstance(test, FactTest):
        known = fact(test.predicate, test.args)
        return known is None or known == test.positive
    if isinstance(test, ValueTest):
        known_v = value(test.function, test.args)
        return known_v is None or compare(known_v, test.op, test.value)
    if isinstance(test, AllOf):
        return all(holds(p, fact, value) for p in test.parts)
    return any(holds(p, fact, value) for p in test.parts)
