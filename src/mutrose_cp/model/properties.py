"""Properties over the valid mission decompositions, as values (docs/formats/properties.md).

A property is a quantifier over a formula: ``always`` (every valid decomposition satisfies it),
``some`` (at least one does), ``never`` (none does) and ``count`` (how many do).  Formulas are
built from atoms over one decomposition (which tasks, methods, actions, capabilities and
decompositions it uses; the order the mission's constraints impose; the state it ends in; the
robots a task gets) with ``and``, ``or``, ``not`` and ``implies``.

Produced by :mod:`mutrose_cp.io.properties`; the values are immutable and hashable, so a
formula can key a cache of the literals it is encoded into.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterator, Literal

Quantifier = Literal["always", "some", "never", "count"]
UsedKind = Literal["method", "action", "capability", "decomposition"]
Comparison = Literal[">=", "<=", "==", "!=", ">", "<"]


@dataclass(frozen=True)
class TaskPattern:
    """``task NAME`` or ``task NAME(a, ?x)``: the task instances of abstract task ``name`` whose
    arguments match (a ``?variable`` matches any value, the same one wherever it recurs)."""

    name: str
    arguments: tuple[str, ...] | None  # None: any arguments

    @property
    def variables(self) -> tuple[str, ...]:
        """The pattern's ``?variables``, in order of first appearance."""
        return tuple(dict.fromkeys(a for a in self.arguments or () if a.startswith("?")))


@dataclass(frozen=True)
class Uses:
    """``uses(task P)`` or ``uses(method|action|capability|decomposition NAME)``."""

    target: TaskPattern | tuple[UsedKind, str]


@dataclass(frozen=True)
class Before:
    """``before(A, B)``: every instance matching A is ordered before every instance matching B
    by the mission's sequential and fallback constraints, transitively."""

    first: TaskPattern
    second: TaskPattern


@dataclass(frozen=True)
class Fact:
    """A ground predicate (``busy(kitchen)``, ``not busy(kitchen)``) or a numeric comparison
    (``stock(kitchen) >= 2``), arguments possibly ``?variables``."""

    name: str
    arguments: tuple[str, ...]
    negated: bool = False
    comparison: tuple[Comparison, float] | None = None


@dataclass(frozen=True)
class Finally:
    """``finally(FACT)``: the fact holds in the state after the whole decomposition."""

    fact: Fact


@dataclass(frozen=True)
class InitiallyNeeded:
    """``initially-needed(FACT)``: the decomposition is valid only if the fact holds at the start
    (some precondition it chooses reads it before anything writes it)."""

    fact: Fact


@dataclass(frozen=True)
class Robots:
    """``robots(task P) >= k``: the robot number of every matching task instance compares so."""

    task: TaskPattern
    comparison: Comparison
    bound: int


@dataclass(frozen=True)
class Not:
    operand: "Formula"


@dataclass(frozen=True)
class Junction:
    """``and`` / ``or`` of two or more operands (nested ones of the same kind are spliced)."""

    op: Literal["and", "or"]
    operands: tuple["Formula", ...]


@dataclass(frozen=True)
class Implies:
    premise: "Formula"
    conclusion: "Formula"


Atom = Uses | Before | Finally | InitiallyNeeded | Robots
Formula = Atom | Not | Junction | Implies


@dataclass(frozen=True)
class Property:
    """A named property: its quantifier, its formula, and where it was written (for messages)."""

    name: str
    quantifier: Quantifier
    formula: Formula
    text: str
    where: str  # "file:line" or "--property 2"


def atoms(formula: Formula) -> Iterator[Atom]:
    """The atoms of ``formula``, left to right (each occurrence)."""
    if isinstance(formula, Not):
        yield from atoms(formula.operand)
    elif isinstance(formula, Junction):
        for operand in formula.operands:
            yield from atoms(operand)
    elif isinstance(formula, Implies):
        yield from atoms(formula.premise)
        yield from atoms(formula.conclusion)
    else:
        yield formula


def task_patterns(atom: Atom) -> tuple[TaskPattern, ...]:
    """The task patterns an atom names (its ``?variables`` live there)."""
    if isinstance(atom, Uses):
        return (atom.target,) if isinstance(atom.target, TaskPattern) else ()
    if isinstance(atom, Before):
        return (atom.first, atom.second)
    if isinstance(atom, Robots):
        return (atom.task,)
    return ()
