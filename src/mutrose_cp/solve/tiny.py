"""Exact enumeration of tiny components without CP-SAT.

Most components of a small mission have a handful of choices (a task with two decompositions
and a condition on a fact another task sets).  Loading OR-Tools and building a model for them
costs more than the whole rest of the run, so they are enumerated here: every assignment of the
component's free variables, with each auxiliary variable computed from its defining record (the
encoder defines every auxiliary variable by an equivalence, and always after its inputs), and
the other records checked.  Each assignment that satisfies them is one solution, exactly as
CP-SAT's ``enumerate_all_solutions`` counts them; ``tests/test_tiny.py`` compares the two.
"""
from __future__ import annotations

import itertools
from typing import Sequence

from ..pipeline.conditions import compare
from .boolean_model import (
    FALSE,
    TRUE,
    AndOf,
    BoolModel,
    Clause,
    Compare,
    Const,
    Difference,
    Exactly,
    Lit,
    NumericEffectKind,
    OrOf,
    Record,
    ValueAfter,
)

MAX_WORK = 4096  # assignments x records: beyond this CP-SAT is the faster way

def defined_variable(r: Record) -> int | None:
    """The variable ``r`` defines, if it is a definition."""
    match r:
        case AndOf(target=target) | OrOf(target=target) | ValueAfter(target=target) | Difference(target=target):
            return target
        case Compare(holds=holds):
            return holds if isinstance(holds, int) and holds > 0 else -1  # -1: not a definition
    return None


def free_variables(records: Sequence[Record]) -> list[int] | None:
    """The variables no record defines, in order; None when a definition would need an input
    defined later (never the encoder's order, but then this enumeration does not apply)."""
    defined: set[int] = set()
    seen: set[int] = set()
    free: list[int] = []
    for r in records:
        target = defined_variable(r)
        for v in r.variables():
            if v == target:
                continue
            if v not in seen:
                seen.add(v)
                if v not in defined:
                    free.append(v)
        if target is not None:
            if target < 0 or target in seen or target in defined:
                return None  # not a definition the encoder writes, used before it, or defined twice
            defined.add(target)
            seen.add(target)
    return free


def enumerate_tiny(bm: BoolModel, records: Sequence[Record],
                   choice_vars: Sequence[int]) -> tuple[int, list[frozenset[int]]] | None:
    """The number of solutions of ``records`` and, for each, the true ``choice_vars``; None when
    the component is too large for this (``MAX_WORK``) or not in definition order."""
    free = free_variables(records)
    if free is None or len(records) << len(free) > MAX_WORK:
        return None
    solutions: list[frozenset[int]] = []
    for bits in itertools.product((False, True), repeat=len(free)):
        values: dict[int, int] = dict(zip(free, map(int, bits)))
        if all(holds(r, values, bm) for r in records):
            solutions.append(frozenset(v for v in choice_vars if values.get(v)))
    return len(solutions), solutions


def _lit(l: Lit, values: dict[int, int]) -> int:
    if isinstance(l, Const):
        return 1 if l is TRUE else 0
    return values[l] if l > 0 else 1 - values[-l]


def holds(r: Record, values: dict[int, int], bm: BoolModel) -> bool:
    """Check constraint ``r``, or compute the variable it defines into ``values`` (False when
    the value falls outside the variable's domain, as CP-SAT would reject it)."""
    match r:
        case Clause(lits=lits):
            return any(_lit(l, values) for l in lits)
        case Exactly(lits=lits, target=target):
            return sum(_lit(l, values) for l in lits) == (1 if target is TRUE else 0 if target is FALSE
                                                           else _lit(target, values))
        case AndOf(lits=lits, target=target):
            values[target] = int(all(_lit(l, values) for l in lits))
        case OrOf(lits=lits, target=target):
            values[target] = int(any(_lit(l, values) for l in lits))
        case ValueAfter():
            return _value_after(r, values, bm)
        case Difference(target=target, first=first, second=second):
            values[target] = (values[first] if first is not None else 0) - (values[second] if second is not None else 0)
            bounds = bm.ints[target]
            return bounds.lo <= values[target] <= bounds.hi
        case Compare(holds=holds, value=value, op=op, bound=bound):
            assert isinstance(holds, int)  # a variable of its own (free_variables checked it)
            values[holds] = int(compare(values[value], op, bound))
    return True


def _value_after(r: ValueAfter, values: dict[int, int], bm: BoolModel) -> bool:
    """The numeric value after one writer (see :class:`ValueAfter`), within its domain."""
    before = values[r.previous] if r.previous is not None else r.previous_value
    if not _lit(r.writer, values):
        value = before
    elif r.effect == NumericEffectKind.ASSIGN:
        value = r.amount
    else:
        value = before + r.amount
    bounds = bm.ints[r.target]
    values[r.target] = value
    return bounds.lo <= value <= bounds.hi
