"""Deciding properties over every valid mission decomposition, exactly, through the components.

A property's formula is grounded first: each ``?variable`` takes every value that the task
instances matching its patterns give it, and the formula holds when it holds for every such
binding.  Each ``uses`` atom of the grounded formula is then a set of task decompositions (the
atom is true of a mission decomposition that chooses one of them).  ``before(A, B)`` reads the
order of the mission's sequential and fallback constraints (a graph built once, its paths the
transitive order): each pair of an A and a B decomposition that it leaves unordered becomes
``not (a and b)``.

The decomposition space is a product of independent components, so a mission decomposition
makes an atom true when one of its components' parts does.  Each component's solutions are
folded into a histogram over atom vectors (which atoms the part makes true), and the
histograms are combined by OR-convolution: with k atoms the state has at most 2^k vectors,
whatever the number of decompositions.  The counts are exact (Python integers); a witness is
kept per vector as one part per component.

Components that no atom touches are counted, never listed.  A component an atom touches must be
listed or layered; one that was only counted (too many solutions to list) is refused, named,
rather than answered wrongly, and so is a property with more than ``MAX_ATOMS`` atoms after
grounding.  ``robots(A) >= k`` is true when every chosen A decomposition's robot number
allows only numbers that compare so.  Atoms over state (``finally``, ``initially-needed``) are
refused with a message saying so.
"""
from __future__ import annotations

import itertools
import operator
from functools import cached_property
from dataclasses import dataclass
from typing import Callable, Iterable, Iterator, Literal, Mapping, Sequence

import networkx as nx

from ..errors import MissionError, Problem
from ..model.domain import Domain
from ..model.goal_model import RobotNumber
from ..model.properties import (
    Before,
    Formula,
    Implies,
    Junction,
    Not,
    Property,
    Robots,
    TaskPattern,
    Uses,
    atoms,
    task_patterns,
)
from ..model.task_graph import Decomposition, TaskGraph
from ..pipeline.constraints import FB, SEQ, Constraint
from .cpsat import Component, DecompositionSpace

Status = Literal["holds", "fails", "vacuous", "count"]
#: at most this many atoms after grounding (the histograms have up to 2^k vectors)
MAX_ATOMS = 16
#: at most this many solutions of one component are read to fold it (a layered one is listed)
MAX_COMPONENT_SOLUTIONS = 200_000
#: at most this many bindings of a property's variables
MAX_BINDINGS = 4096


@dataclass(frozen=True)
class Verdict:
    """What a property is over the valid mission decompositions.

    ``status``: ``holds`` / ``fails`` for ``always``, ``some`` and ``never``, ``count`` for
    ``count``, and ``vacuous`` when the mission has no valid decomposition at all.  ``count``:
    how many valid decompositions satisfy the formula, of ``total``.  ``witness``: the task
    decompositions (Task Graph vertices) of one mission decomposition that shows the verdict:
    one that breaks an ``always`` or ``never`` property, one that satisfies a ``some`` property
    that holds, one that satisfies a ``count`` formula; None when there is none."""

    property: Property
    status: Status
    count: int
    total: int
    witness: tuple[int, ...] | None


def verify(prop: Property, space: DecompositionSpace, tg: TaskGraph, domain: Domain,
           constraints: Iterable[Constraint] = ()) -> Verdict:
    """The verdict of ``prop`` over ``space`` (the mission's valid decompositions); ``before``
    atoms read the mission's ``constraints``."""
    grounded = ground(prop, tg, domain, constraints)
    histogram, shared = _histogram(space, grounded.atoms, prop)
    total = sum(count for count, _ in histogram.values())
    if total == 0:
        return Verdict(prop, "vacuous", 0, 0, None)
    satisfied = {vector: entry for vector, entry in histogram.items() if _evaluate(grounded.formula, vector)}
    count = sum(c for c, _ in satisfied.values())
    broken = {vector: entry for vector, entry in histogram.items() if vector not in satisfied}
    if prop.quantifier == "count":
        return Verdict(prop, "count", count, total, _first_witness(satisfied, shared))
    if prop.quantifier == "always":
        return Verdict(prop, "holds" if not broken else "fails", count, total, _first_witness(broken, shared))
    if prop.quantifier == "never":
        return Verdict(prop, "holds" if not satisfied else "fails", count, total, _first_witness(satisfied, shared))
    return Verdict(prop, "holds" if satisfied else "fails", count, total, _first_witness(satisfied, shared))


# --- grounding: every atom becomes a set of task decompositions ------------------------------


@dataclass(frozen=True)
class GroundedProperty:
    """A property's formula over atoms that are sets of task decompositions (Task Graph
    vertices): ``formula`` is an atom's index, or ``(operator, operands)`` with ``and``, ``or``
    and ``not``.  What the embedding model posts (``DecompositionModel.add_property``)."""

    formula: "Grounded"
    atoms: tuple[frozenset[int], ...]


def ground(prop: Property, tg: TaskGraph, domain: Domain, constraints: Iterable[Constraint] = ()) -> GroundedProperty:
    """``prop``'s formula grounded on the mission (its quantifier is not part of it)."""
    atoms = _Atoms(tg, domain, prop, constraints)
    formula = atoms.ground(prop.formula)
    return GroundedProperty(formula, tuple(atoms.sets))


Grounded = int | tuple[str, tuple["Grounded", ...]]  # an atom's bit, or (operator, operands)


class _Atoms:
    """The grounded atoms of one property: each a set of Task Graph decomposition vertices, kept
    once however often it recurs."""

    def __init__(self, tg: TaskGraph, domain: Domain, prop: Property, constraints: Iterable[Constraint]) -> None:
        self.prop = prop
        self.constraints = constraints
        self.decompositions: list[tuple[int, Decomposition]] = []
        for vertex in tg.decompositions():
            assert vertex.decomposition is not None
            self.decompositions.append((vertex.index, vertex.decomposition))
        self.parameters = {t.name: tuple(p.name for p in t.parameters) for t in domain.tasks}
        self.sets: list[frozenset[int]] = []
        self.bit_of: dict[frozenset[int], int] = {}

    def ground(self, formula: Formula) -> Grounded:
        # a variable that only meets robot parameters (no value before allocation) or no
        # instance at all takes no value: it stays a wildcard
        candidates = {v: sorted(found) for v in sorted(set(_variables(formula)))
                      if (found := self._values_of(formula, v))}
        variables = list(candidates)
        if not variables:
            return self._ground(formula, {})
        bindings = 1
        for values in candidates.values():
            bindings *= max(1, len(values))
        if bindings > MAX_BINDINGS:
            raise self.refused(f"its variables have {bindings} bindings, more than {MAX_BINDINGS}")
        return ("and", tuple(self._ground(formula, dict(zip(variables, values)))
                             for values in itertools.product(*candidates.values())))

    def _ground(self, formula: Formula, binding: Mapping[str, str]) -> Grounded:
        if isinstance(formula, Not):
            return ("not", (self._ground(formula.operand, binding),))
        if isinstance(formula, Junction):
            return (formula.op, tuple(self._ground(f, binding) for f in formula.operands))
        if isinstance(formula, Implies):
            return ("or", (("not", (self._ground(formula.premise, binding),)), self._ground(formula.conclusion, binding)))
        if isinstance(formula, Uses):
            chosen = frozenset(v for v, d in self.decompositions if self._used(formula.target, d, binding))
            if not chosen and isinstance(formula.target, tuple) and formula.target[0] == "decomposition":
                raise self.refused(f"the mission has no task decomposition {formula.target[1]} "
                                   "(the output names them, e.g. AT1_1|1)")
            return self._bit(chosen)
        if isinstance(formula, Before):
            return self._before(formula, binding)
        if isinstance(formula, Robots):
            # every number the instance's robot number allows must compare so: [1,3] >= 2 does not
            short = frozenset(v for v, d in self.decompositions if self._matches(formula.task, d, binding) is not None
                              and not _robots_compare(d.instance.robot_number, formula.comparison, formula.bound))
            return ("not", (self._bit(short),))
        raise self.refused(f"{type(formula).__name__.lower()} atoms are not decided yet "
                           "(uses, before and robots atoms are)")

    def _before(self, formula: Before, binding: Mapping[str, str]) -> Grounded:
        """No pair of chosen task decompositions, one of an A instance and one of a B instance,
        that the constraints leave unordered: each such pair becomes ``not (a and b)``."""
        firsts = [v for v, d in self.decompositions if self._matches(formula.first, d, binding) is not None]
        seconds = [v for v, d in self.decompositions if self._matches(formula.second, d, binding) is not None]
        pairs = [(a, b) for a in firsts for b in seconds
                 if a != b and not (a in self.order and b in self.order and nx.has_path(self.order, a, b))]
        return ("and", tuple(("not", (("and", (self._bit(frozenset([a])), self._bit(frozenset([b])))),))
                             for a, b in pairs))

    @cached_property
    def order(self) -> "nx.DiGraph[int]":
        """The sequential and fallback constraints between task decompositions, as a graph (its
        paths are the transitive order), built once."""
        graph: "nx.DiGraph[int]" = nx.DiGraph()
        graph.add_edges_from((c.first, c.second) for c in self.constraints if c.kind in (SEQ, FB))
        return graph

    def _bit(self, decompositions: frozenset[int]) -> int:
        if decompositions not in self.bit_of:
            if len(self.sets) >= MAX_ATOMS:
                raise self.refused(f"it grounds into more than {MAX_ATOMS} distinct atoms")
            self.bit_of[decompositions] = len(self.sets)
            self.sets.append(decompositions)
        return self.bit_of[decompositions]

    def _used(self, target: TaskPattern | tuple[str, str], d: Decomposition, binding: Mapping[str, str]) -> bool:
        if isinstance(target, TaskPattern):
            return self._matches(target, d, binding) is not None
        kind, name = target
        if kind == "decomposition":
            return d.id == name
        steps = d.path.actions
        if kind == "action":
            return any(s.name == name for s in steps)
        if kind == "capability":
            return any(name in s.capabilities for s in steps)
        return name in _methods(d)

    def _matches(self, pattern: TaskPattern, d: Decomposition, binding: Mapping[str, str]) -> dict[str, str] | None:
        """The binding extended so that ``pattern`` matches ``d``'s task instance, or None."""
        if d.instance.name != pattern.name:
            return None
        if pattern.arguments is None:
            return dict(binding)
        values = {p.hddl_param: str(p.value) for p in d.instance.parameters}
        declared = self.parameters.get(pattern.name, ())
        if len(pattern.arguments) > len(declared):
            return None
        extended = dict(binding)
        for argument, parameter in zip(pattern.arguments, declared):
            value = values.get(parameter, "")
            if value == "":  # a robot parameter: no value before allocation, matches anything
                continue
            if argument.startswith("?"):
                if extended.setdefault(argument, value) != value:
                    return None
            elif argument != value:
                return None
        return extended

    def _values_of(self, formula: Formula, variable: str) -> set[str]:
        return {bound[variable] for pattern in _patterns(formula) if variable in pattern.variables
                for _, d in self.decompositions
                if (bound := self._matches(pattern, d, {})) is not None and variable in bound}

    def refused(self, why: str) -> MissionError:
        return refusal(self.prop, why)


def refusal(prop: Property, why: str) -> MissionError:
    """The error of a property that is not decided (never answered approximately)."""
    return MissionError(Problem(prop.where, f"property {prop.name}: cannot be verified: {why}"))


_COMPARE: dict[str, Callable[[int, int], bool]] = {
    ">=": operator.ge, "<=": operator.le, "==": operator.eq, "!=": operator.ne, ">": operator.gt, "<": operator.lt}


def _robots_compare(number: RobotNumber, comparison: str, bound: int) -> bool:
    """Whether every robot number the instance allows compares so with ``bound``."""
    allowed = (number.min, number.max)
    return all(_COMPARE[comparison](n, bound) for n in allowed) if comparison != "!=" else \
        not number.min <= bound <= number.max


def _methods(d: Decomposition) -> set[str]:
    names: set[str] = set()
    stack = [d.path.tree]
    while stack:
        node = stack.pop()
        if node.kind == "method":
            names.add(node.name)
        stack.extend(node.children)
    return names


def _patterns(formula: Formula) -> Iterator[TaskPattern]:
    for atom in atoms(formula):
        yield from task_patterns(atom)


def _variables(formula: Formula) -> Iterator[str]:
    for pattern in _patterns(formula):
        yield from pattern.variables


def _evaluate(formula: Grounded, vector: int) -> bool:
    if isinstance(formula, int):
        return bool(vector >> formula & 1)
    op, operands = formula
    if op == "not":
        return not _evaluate(operands[0], vector)
    if op == "and":
        return all(_evaluate(f, vector) for f in operands)
    return any(_evaluate(f, vector) for f in operands)


# --- the histogram over atom vectors, component by component ---------------------------------

Witness = tuple["Witness", tuple[int, ...]] | None  # (the parts before, this part), linked
Histogram = dict[int, tuple[int, Witness]]  # atom vector -> (decompositions, one witness)


def _vector(decompositions: Sequence[int], sets: Sequence[frozenset[int]]) -> int:
    return sum(1 << bit for bit, chosen in enumerate(sets) if not chosen.isdisjoint(decompositions))


def _histogram(space: DecompositionSpace, sets: Sequence[frozenset[int]],
               prop: Property) -> tuple[Histogram, tuple[int, ...] | None]:
    """The histogram over atom vectors of the whole space, and the part every witness shares
    (one solution of each component no atom touches; None when one of them was only counted,
    so that no witness can be written out)."""
    if not space.encoding.tasks:
        return {}, None
    touched: frozenset[int] = frozenset().union(*sets)
    fixed = tuple(space.fixed)
    histogram: Histogram = {_vector(fixed, sets): (1, (None, fixed))}
    shared: list[int] | None = []
    for number, component in enumerate(space.components):
        if component.count == 0:
            return {}, None
        own = {space.var_to_dec[v] for v in component.choice_vars}
        if touched.isdisjoint(own):
            histogram = {v: (c * component.count, w) for v, (c, w) in histogram.items()}
            alternatives = space.alternatives(component)
            if alternatives is None:
                shared = None
            elif shared is not None:
                shared.extend(next(iter(alternatives)))
            continue
        histogram = _combine(histogram, _component_histogram(space, component, number, sets, prop))
    return histogram, None if shared is None else tuple(shared)


def _component_histogram(space: DecompositionSpace, component: Component, number: int,
                         sets: Sequence[frozenset[int]], prop: Property) -> dict[int, tuple[int, tuple[int, ...]]]:
    alternatives = space.alternatives(component)
    if alternatives is None or component.count > MAX_COMPONENT_SOLUTIONS:
        raise refusal(prop, f"part {number + 1} of the mission, which it reads, has {component.count} "
                             f"alternative decompositions on its own (at most {MAX_COMPONENT_SOLUTIONS} are read)")
    folded: dict[int, tuple[int, tuple[int, ...]]] = {}
    for part in alternatives:
        vector = _vector(part, sets)
        count, example = folded.get(vector, (0, part))
        folded[vector] = (count + 1, example)
    return folded


def _combine(histogram: Histogram, component: Mapping[int, tuple[int, tuple[int, ...]]]) -> Histogram:
    combined: Histogram = {}
    for (v, (c, w)), (u, (k, part)) in itertools.product(histogram.items(), component.items()):
        count, witness = combined.get(v | u, (0, (w, part)))
        combined[v | u] = (count + c * k, witness)
    return combined


def _first_witness(entries: Histogram, shared: tuple[int, ...] | None) -> tuple[int, ...] | None:
    """The witness of the smallest vector among ``entries`` with the ``shared`` part, as sorted
    decomposition vertices (None without entries or without a shared part)."""
    if not entries or shared is None:
        return None
    node = entries[min(entries)][1]
    chosen: list[int] = list(shared)
    while node is not None:
        node, part = node
        chosen.extend(part)
    return tuple(sorted(chosen))
