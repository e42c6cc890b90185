"""CP-SAT decomposer: the decomposition space as factored CP-SAT models.

The boolean model of :mod:`mutrose_cp.solve.encoding` is split into connected components (parts
that share no variable).  The valid mission decompositions are the Cartesian product of the
components' solutions, so the space is counted exactly as a product, streamed with a mixed-radix
counter, sampled uniformly by sampling each component, and optimised component by component.
Each component is solved by CP-SAT (``enumerate_all_solutions`` with one worker: with more
workers solutions were lost or repeated); components that are a single exactly-one choice are
read off directly, tiny ones enumerated in Python (:mod:`.tiny`), ones that cut into blocks
sharing a little state solved as a layered graph (:mod:`.layered`: counted, listed, sampled and
optimised without enumerating them), and ones coupled by a few wide definitions counted from
them (:mod:`.hubs`).  The CP-SAT layer (:mod:`.proto`, :mod:`.run`) is loaded on first use:
small missions often need none.
"""
from __future__ import annotations

import itertools
import math
import random
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Iterable, Iterator, Protocol, Sequence

from ..errors import MissionError
from .boolean_model import (
    FALSE,
    TRUE,
    Const,
    AndOf,
    BoolModel,
    Clause,
    Compare,
    Difference,
    Exactly,
    Lit,
    OrOf,
    Record,
    ValueAfter,
    VariableGroups,
)
from .encoding import Encoding
from .hubs import count_by_hubs
from .layered import LayeredSpace, layered_space
from .tiny import enumerate_tiny


ENUMERATION_CAP = 2_000_000  # solutions kept per component; beyond that a component is counted only
# a layered component with at most this many solutions is also listed in full, in the canonical
# order of enumerated components; a larger one is listed lazily from its layers
LAYERED_LIST_LIMIT = 10_000


# ---------------------------------------------------------------------------------------------
# Posting records to CP-SAT


# ---------------------------------------------------------------------------------------------
# Components


@dataclass(slots=True)
class Component:
    """An independent part of the decomposition space (slots: a large mission has tens of
    thousands, one per forAll instance and task at least)."""

    records: list[Record]
    choice_vars: list[int]  # decomposition literals of the component (positive var ids)
    solutions: list[frozenset[int]] | None = None  # chosen decomposition vertices per solution
    count: int = 0
    layers: LayeredSpace | None = None  # the component as a layered graph, when it cuts into blocks


def split_components(enc: Encoding) -> list[Component]:
    """The independent parts of an encoding: its records grouped by shared variables, each with
    its decomposition literals (records without variables are constant components)."""
    bm = enc.model
    groups_of = VariableGroups()
    firsts: list[int] = []  # each record's first variable (0: none), read once
    for r in bm.records:
        vs = r.variables()
        firsts.append(vs[0] if vs else 0)
        groups_of.join_all(vs)
    find = groups_of.find
    groups: dict[int, Component] = {}
    constant: list[Component] = []
    for r, first in zip(bm.records, firsts):
        if not first:  # a constant record: an empty clause or an exactly-one over nothing
            if not (isinstance(r, Exactly) and r.target is FALSE):
                constant.append(Component([r], [], solutions=[], count=0))
            continue
        root = find(first)
        group = groups.get(root)
        if group is None:
            group = groups[root] = Component([], [])
        group.records.append(r)
    dec_var = {lit: d for d, lit in enc.decomposition_lit.items() if isinstance(lit, int)}
    for var in sorted(dec_var):
        root = find(var)
        groups.setdefault(root, Component([], [])).choice_vars.append(var)
    return constant + [groups[k] for k in sorted(groups)]


def _simple_choice(comp: Component) -> list[frozenset[int]] | None:
    """Solutions of a component that is one exactly-one choice plus unit exclusions."""
    sums = [r for r in comp.records if isinstance(r, Exactly)]
    if len(sums) != 1 or sums[0].target is not TRUE:
        return None
    options = list(sums[0].lits)
    excluded: set[int] = set()
    for r in comp.records:
        if r is sums[0]:
            continue
        match r:
            case Clause(lits=(int(excluded_lit),)) if excluded_lit < 0:
                excluded.add(-excluded_lit)
            case Clause(lits=()):
                return []
            case _:
                return None
    choices = [l for l in options if isinstance(l, int) and l > 0]
    if len(choices) != len(options):
        return None
    return [frozenset([v]) for v in choices if v not in excluded]


def solve_component(bm: BoolModel, comp: Component, keep: bool = True, list_limit: int = ENUMERATION_CAP) -> None:
    """Enumerate a component's solutions (as sets of decomposition literals).  A component
    counted without enumeration (:mod:`.hubs`) is listed only up to ``list_limit`` solutions; one
    solved as layers (:mod:`.layered`) is listed in full only up to ``LAYERED_LIST_LIMIT`` of them
    (in the canonical order), and lazily from its layers beyond."""
    if not comp.records or comp.solutions == [] and not comp.choice_vars:
        return
    simple = _simple_choice(comp)
    if simple is not None:
        chosen = sorted((s & frozenset(comp.choice_vars) for s in simple), key=sorted)
        comp.solutions, comp.count = chosen, len(chosen)
        return
    found: tuple[int, list[frozenset[int]] | None] | None
    found = enumerate_tiny(bm, comp.records, comp.choice_vars)  # at most 4096 solutions: listed
    if found is None:
        comp.layers = layered_space(bm, comp.records, comp.choice_vars)
        if comp.layers is not None:
            comp.count = comp.layers.count
            listed = keep and comp.count <= min(list_limit, LAYERED_LIST_LIMIT)
            comp.solutions = sorted(map(frozenset, comp.layers.solutions()), key=sorted) if listed else None
            return
        counted = count_by_hubs(bm, comp.records, lambda records, watched: _block_solutions(bm, records, watched))
        if counted is not None and (not keep or counted > list_limit):
            comp.count, comp.solutions = counted, None  # counted without listing (too many to list)
            return
        found = enumerate_with_cp_sat(bm, comp, keep)
    comp.count, solutions = found
    # a canonical order (by decomposition literal), independent of the solver's search
    comp.solutions = sorted(solutions, key=sorted) if keep and solutions is not None else None


def _block_solutions(bm: BoolModel, records: Sequence[Record], watched: list[int]) -> list[frozenset[int]] | None:
    """Each solution of one block of a coupled component, as its true ``watched`` variables."""
    tiny = enumerate_tiny(bm, records, watched)
    if tiny is not None:
        return tiny[1]
    return enumerate_with_cp_sat(bm, Component(list(records), watched))[1]


def enumerate_with_cp_sat(bm: BoolModel, comp: Component,
                          keep: bool = True) -> tuple[int, list[frozenset[int]] | None]:
    """The number of solutions of ``comp`` and, while ``keep`` and under ``ENUMERATION_CAP``,
    the true decomposition literals of each, as CP-SAT enumerates them."""
    from .proto import ProtoBuilder  # the CP-SAT layer, loaded when a component needs it
    from .run import INFEASIBLE, OPTIMAL, SolutionCollector, run_solver

    builder = ProtoBuilder(bm)
    for r in comp.records:
        builder.post(r)
    variables = [builder.var(v) for v in comp.choice_vars]
    collector = SolutionCollector(variables, comp.choice_vars, keep, ENUMERATION_CAP)
    # an enumeration is complete only with OPTIMAL (every solution seen) or INFEASIBLE (none)
    run_solver(builder.proto, accept=(OPTIMAL, INFEASIBLE), callback=collector,
               enumerate_all=True, what="enumerating a component")
    return collector.count, collector.solutions if collector.keep else None


# ---------------------------------------------------------------------------------------------
# The space


@dataclass
class DecompositionSpace:
    """The valid mission decompositions of a mission as a product of components."""

    encoding: Encoding
    components: list[Component]
    var_to_dec: dict[int, int] = field(default_factory=dict)

    @property
    def count(self) -> int:
        if not self.encoding.tasks:
            return 0  # a mission without task instances decomposes into nothing
        return math.prod(c.count for c in self.components)

    def _decompositions(self, parts: Sequence[frozenset[int]]) -> list[int]:
        decs = [self.var_to_dec[v] for p in parts for v in p]
        decs += self.fixed
        return sorted(decs)  # vertex order is the mission-queue order

    @cached_property
    def fixed(self) -> list[int]:
        """Decompositions chosen in every solution through constant literals."""
        return fixed_decompositions(self.encoding)

    def __iter__(self) -> Iterator[list[int]]:
        """All decompositions, in mixed-radix order over the components (last varies fastest)."""
        if not self.encoding.tasks or any(c.count == 0 for c in self.components):
            return
        for suffix in self._odometer(self._choices(), 0):
            yield sorted(itertools.chain(self.fixed, suffix))

    def contains(self, decompositions: Iterable[int]) -> bool:
        """Whether ``decompositions`` (Task Graph vertices) are exactly one valid mission
        decomposition: every fixed one, and one solution of each component.  A component that
        was only counted cannot be asked (MissionError, exit 2)."""
        if not self.encoding.tasks or any(c.count == 0 for c in self.components):
            return False
        rest = set(decompositions)
        if not rest.issuperset(self.fixed):
            return False
        rest.difference_update(self.fixed)
        for number, component in enumerate(self.components):
            own = {self.var_to_dec[v] for v in component.choice_vars}
            part = tuple(sorted(rest & own))
            rest -= own
            alternatives = self.alternatives(component)
            if alternatives is None:
                raise MissionError(f"part {number + 1} of the mission has more than {ENUMERATION_CAP} alternative "
                                   "decompositions on its own: a decomposition cannot be looked up among them")
            if all(tuple(a) != part for a in alternatives):
                return False
        return not rest

    def alternatives(self, component: Component) -> Alternatives | None:
        """One component's solutions as sorted decomposition vertices: listed, or lazily from
        its layers; None for a component that was only counted."""
        if component.solutions is not None:
            return Listed(component.solutions, self.var_to_dec)
        if component.layers is not None:
            return FromLayers(component.layers, self.var_to_dec)
        return None

    def _choices(self) -> list[Alternatives]:
        """Each component's solutions as sorted decomposition vertices: listed, or lazily from
        its layers."""
        choices: list[Alternatives] = []
        for c in self.components:
            alternatives = self.alternatives(c)
            if alternatives is not None:
                choices.append(alternatives)
            else:
                raise MissionError(f"a part of the mission has more than {ENUMERATION_CAP} alternative "
                                   "decompositions on its own: they can be counted (count) but not listed")
        return choices

    def split_listing(self, limit: int | None) -> tuple[list[int], Iterator[list[int]]] | None:
        """The first ``limit`` decompositions (all if None) as one part common to all of them and
        an iterator over the parts that vary, in the order of :meth:`__iter__`.

        Listing is mixed-radix with the last component varying fastest, so the first ``limit``
        decompositions differ only in the last few components; when the components occupy
        consecutive vertex ranges, the common part can be written once.  None when they do not."""
        if not self.encoding.tasks or any(c.count == 0 for c in self.components) or self.fixed:
            return None
        choices = self._choices()
        last = -1
        for ch in choices:
            b = ch.bounds()
            if b is None:
                continue
            if b[0] <= last:
                return None
            last = b[1]
        varying, product = 0, 1
        for c in reversed(self.components):
            if limit is not None and product >= limit:
                break
            varying += 1
            product *= c.count
        fixed_part = len(choices) - varying
        prefix = [d for ch in choices[:fixed_part] for d in ch.first()]
        return prefix, self._odometer(choices[fixed_part:], 0)  # the fixed part is not held while listing

    @staticmethod
    def _odometer(choices: Sequence[Alternatives], start: int) -> Iterator[list[int]]:
        """Concatenations of one choice per component from ``start`` on, last varying fastest
        (each component's choices iterated again when the one before it moves on)."""
        comps = choices[start:]
        iterators = [iter(ch) for ch in comps]
        current = [next(it) for it in iterators]
        while True:
            yield [d for part in current for d in part]
            k = len(comps) - 1
            while k >= 0:
                following = next(iterators[k], None)
                if following is not None:
                    current[k] = following
                    break
                iterators[k] = iter(comps[k])
                current[k] = next(iterators[k])
                k -= 1
            if k < 0:
                return

    def sample(self, k: int, seed: int) -> list[list[int]]:
        """``k`` decompositions drawn uniformly and independently (with replacement)."""
        if any(c.solutions is None and c.layers is None for c in self.components):
            raise MissionError(f"a part of the mission has more than {ENUMERATION_CAP} alternative "
                               "decompositions on its own: uniform sampling needs them listed")
        if self.count == 0:
            return []
        rng = random.Random(seed)
        out = []
        for _ in range(k):
            out.append(self._decompositions([rng.choice(c.solutions) if c.solutions is not None
                                             else frozenset(c.layers.sample(rng))  # type: ignore[union-attr]
                                             for c in self.components]))
        return out

    def component_table(self, key: Callable[[int], str]) -> list[dict[str, object]]:
        """Per component: its alternative sets of task decompositions (by output key), or its
        layered graph when it was solved block by block."""
        table: list[dict[str, object]] = []
        for c in self.components:
            if c.layers is not None:
                table.append({"count": str(c.count), **self._layer_table(c.layers, key)})
                continue
            alts = [sorted(self.var_to_dec[v] for v in s) for s in c.solutions or []]
            table.append({"count": str(c.count), "alternatives": [[key(d) for d in a] for a in alts]})
        return table

    def _layer_table(self, layers: LayeredSpace, key: Callable[[int], str]) -> dict[str, object]:
        """``states``: per layer, each state as the values of the variables the blocks around it
        share; ``blocks``: per block, its edges with the task decompositions they choose."""
        model = self.encoding.model
        states = [[[f"{layers.names.get(v) or model.name(v)}={value}" for v, value in zip(frontier, state)] for state in layer]
                  for frontier, layer in zip(layers.frontiers, layers.states)]
        blocks = [[{"from": str(e.source), "to": str(e.target),
                    "decompositions": [key(d) for d in sorted(self.var_to_dec[v] for v in e.choices)],
                    "count": str(e.multiplicity)} for e in block] for block in layers.blocks]
        return {"states": states, "blocks": blocks}


class Alternatives(Protocol):
    """A component's solutions as sorted decomposition vertices, iterable again and again."""

    def __iter__(self) -> Iterator[tuple[int, ...]]: ...

    def first(self) -> tuple[int, ...]: ...

    def bounds(self) -> tuple[int, int] | None:
        """The least and greatest vertex of any solution (None when every solution is empty)."""


@dataclass
class Listed:
    """Solutions listed in full, each read as its sorted decomposition vertices when it is
    asked for (made for every solution of every component at once, they were a large mission's
    largest part of the listing)."""

    solutions: list[frozenset[int]]  # decomposition literals
    var_to_dec: dict[int, int]

    def _vertices(self, solution: frozenset[int]) -> tuple[int, ...]:
        return tuple(sorted(self.var_to_dec[v] for v in solution))

    def __iter__(self) -> Iterator[tuple[int, ...]]:
        return map(self._vertices, self.solutions)

    def first(self) -> tuple[int, ...]:
        return self._vertices(self.solutions[0])

    def bounds(self) -> tuple[int, int] | None:
        vertices = [self.var_to_dec[v] for s in self.solutions for v in s]  # one pass (50,000 components)
        return (min(vertices), max(vertices)) if vertices else None


@dataclass
class FromLayers:
    """Solutions listed lazily from a layered graph, in its order."""

    layers: LayeredSpace
    var_to_dec: dict[int, int]

    def __iter__(self) -> Iterator[tuple[int, ...]]:
        return (tuple(sorted(self.var_to_dec[v] for v in sol)) for sol in self.layers.solutions())

    def first(self) -> tuple[int, ...]:
        return next(iter(self))

    def bounds(self) -> tuple[int, int] | None:
        vertices = [self.var_to_dec[v] for v in self.layers.choice_variables()]
        return (min(vertices), max(vertices)) if vertices else None


def _signature(bm: BoolModel, comp: Component) -> tuple[tuple[object, ...], list[int]]:
    """A key equal for components that are the same up to renaming their variables (one per
    delivery or room of a forAll), and the variables in canonical order."""
    canon: dict[int, int] = {}

    def cid(v: int) -> int:
        if v not in canon:
            canon[v] = len(canon)
        return canon[v]

    def lit(l: Lit) -> int | Const:
        if isinstance(l, int):
            return cid(abs(l)) if l > 0 else -cid(abs(l)) - 1_000_000
        return l

    parts = []
    for r in comp.records:
        # only a numeric record has integer variables (their ranges belong to the key)
        ints = (tuple((bm.ints[v].lo, bm.ints[v].hi) for v in r.variables() if v in bm.ints)
                if isinstance(r, (ValueAfter, Compare, Difference)) else ())
        parts.append((r.kind, _canonical(r, lit, cid), ints))
    order = sorted(canon, key=canon.__getitem__)
    key = (tuple(parts), tuple(canon[v] for v in comp.choice_vars if v in canon))
    return key, order


def _canonical(r: Record, lit: Callable[[Lit], int | Const], cid: Callable[[int], int]) -> tuple[object, ...]:
    """The record's content with its variables renamed (``lit`` for literals, ``cid`` for
    integer variables), in the order the variables are met; labels are left out."""
    match r:
        case Clause(lits=lits):
            return tuple(lit(l) for l in lits),
        case Exactly(lits=lits, target=target):
            return tuple(lit(l) for l in lits), lit(target)
        case AndOf(lits=lits, target=target) | OrOf(lits=lits, target=target):
            return tuple(lit(l) for l in lits), lit(target)
        case ValueAfter():
            return (lit(r.writer), cid(r.target), None if r.previous is None else cid(r.previous),
                    r.previous_value, r.amount, r.effect)
        case Difference(target=target, first=first, second=second):
            return cid(target), None if first is None else cid(first), None if second is None else cid(second)
        case Compare(holds=holds, value=value, op=op, bound=bound):
            return lit(holds), cid(value), op, bound


def build_space(enc: Encoding, keep: bool = True, progress: Callable[[int, int], None] | None = None,
                list_limit: int = ENUMERATION_CAP) -> DecompositionSpace:
    comps = split_components(enc)
    solve_components(enc.model, comps, keep, list_limit, progress)
    # components without decomposition literals only constrain (e.g. all-constant checks)
    return DecompositionSpace(enc, [c for c in comps if c.choice_vars or c.count == 0], decomposition_variables(enc))


def decomposition_variables(enc: Encoding) -> dict[int, int]:
    """Decomposition literal (a variable) -> its decomposition vertex; constant ones left out."""
    return {lit: d for d, lit in enc.decomposition_lit.items() if isinstance(lit, int)}


def fixed_decompositions(enc: Encoding) -> list[int]:
    """The decompositions whose literal is the constant true: chosen in every solution."""
    return [d for d, lit in enc.decomposition_lit.items() if lit == TRUE]


def solve_components(bm: BoolModel, comps: Sequence[Component], keep: bool = True, list_limit: int = ENUMERATION_CAP,
                     progress: Callable[[int, int], None] | None = None) -> None:
    """Solve every component (:func:`solve_component`); components that are identical up to
    renaming their variables (one per forAll instance) are solved once and renamed."""
    solved: dict[tuple[object, ...], tuple[list[int], Component]] = {}
    for i, comp in enumerate(comps):
        if comp.count == 0 and comp.solutions == []:
            pass
        elif len(comp.records) > 1:
            key, order = _signature(bm, comp)
            hit = solved.get(key)
            if hit is None:
                solve_component(bm, comp, keep, list_limit)
                solved[key] = (order, comp)
            else:
                first_order, first = hit
                rename = dict(zip(first_order, order))
                comp.count = first.count
                comp.layers = None if first.layers is None else first.layers.renamed(rename)
                comp.solutions = (None if first.solutions is None else
                                  sorted((frozenset(rename[v] for v in sol) for sol in first.solutions), key=sorted))
        else:
            solve_component(bm, comp, keep, list_limit)
        if progress is not None:
            progress(i + 1, len(comps))


def explain(enc: Encoding) -> list[str]:
    """Why no decomposition exists: a conflicting set of labelled constraints (CP-SAT assumptions)."""
    from .proto import ProtoBuilder
    from .run import FEASIBLE, INFEASIBLE, OPTIMAL, run_solver

    reasons: list[str] = []
    for comp in split_components(enc):
        builder = ProtoBuilder(enc.model)
        assumptions: dict[int, str] = {}
        for r in comp.records:
            if r.label:
                a = builder.new_bool(f"assume:{r.label}")
                builder.post(r, enforce=a)
                assumptions[a] = r.label
            else:
                builder.post(r)
        builder.proto.assumptions.extend(list(assumptions))
        response = run_solver(builder.proto, accept=(OPTIMAL, FEASIBLE, INFEASIBLE), what="explaining a component")
        if response.status == INFEASIBLE:
            core = response.sufficient_assumptions_for_infeasibility
            labels = sorted({assumptions[i] for i in core if i in assumptions})
            reasons.extend(enc.labels.get(l, l) for l in labels)
            if not labels:
                reasons.append("the goal model's structure admits no combination (no labelled constraint involved)")
    return reasons
