"""A component solved block by block: a layered graph over the state its blocks share.

Tasks in a sequence that set, clear and test a few shared facts (a door, a charging station, a
lift) make one component, and enumerating it costs its number of solutions, which grows
exponentially with the number of tasks.  The encoder writes the value of a fact as a chain, one
step per writer (:meth:`.encoding.Encoder._bool_value`), so between two tasks of the sequence
the whole shared state is a few variables.  Parallel tasks that may set and clear one fact are
coupled by one wide definition (``anypos <=> OR(setters)``); it is written here as a chain too
(:func:`as_chains`), so what passes from task to task is "some setter so far".  The component
is cut into *blocks* along its variables, and each block is compiled into a transition relation
over the variables it shares with the blocks around it:

* every variable gets a *position*: a free variable (no record defines it) the largest id among
  the literals of its exactly-one choices (the encoder creates a task's decomposition literals
  together, in mission order), a defined variable the largest position of its inputs;
* a record belongs to the block of its largest position, and blocks follow their positions;
* the *frontier* between block k-1 and block k is the set of variables of blocks before k that a
  later block uses; layer k holds its values in some solution (*states*);
* block k's *edges* lead from a state of layer k to a state of layer k+1, each with the choice
  literals the block sets true and how many assignments of the block's own variables do it.

A solution of the component is a path from the one state of layer 0 to the one of the last
layer.  So the number of solutions is a sum over paths (computed backwards, linear in the number
of blocks), a uniform sample draws edges weighted by the solutions behind them, the least-cost
solution is a shortest path, and the solutions are listed lazily, depth first, edges in order
of their choices.  A component that does not cut into small frontiers (``MAX_FRONTIER``,
``MAX_STATES``) or has a block too large to enumerate (``MAX_BLOCK_FREE``, ``MAX_BLOCK_WORK``)
is left to the other solvers.  ``tests/test_layered.py`` compares all four with brute-force enumeration.
"""
from __future__ import annotations

import itertools
import random
from collections import Counter
from dataclasses import dataclass, field
from typing import Iterator, Mapping, Sequence

from .boolean_model import AndOf, BoolModel, Exactly, Lit, OrOf, Record, VariableGroups
from .tiny import defined_variable, free_variables, holds

MAX_FRONTIER = 16  # variables passed from one block to the next
MAX_STATES = 256  # values of one frontier that solutions take
MAX_BLOCK_FREE = 12  # free variables of one block, enumerated for each state before it
MAX_BLOCK_WORK = 1 << 16  # states before a block x assignments of its free variables

State = tuple[int, ...]  # values of a frontier's variables, in the frontier's order


@dataclass(frozen=True)
class Edge:
    """One way through a block: from state ``source`` of the layer before it to state ``target``
    of the layer after it, setting ``choices`` true (the other choice literals the block owns
    false); ``multiplicity`` assignments of the block's own variables do so."""

    source: int
    target: int
    choices: tuple[int, ...]
    multiplicity: int = 1


@dataclass
class LayeredSpace:
    """The solutions of a component as paths through layers of states.  ``frontiers[k]`` are the
    variables of layer k, ``states[k]`` their values; ``blocks[k]`` are the edges from layer k
    to layer k+1, ordered by source state, then by choices, then by target.  Frontier variables
    may be steps of a chain that the model does not have (:func:`as_chains`): ``names`` names them."""

    frontiers: list[tuple[int, ...]]
    states: list[list[State]]
    blocks: list[list[Edge]]
    names: dict[int, str] = field(default_factory=dict)  # frontier variables the model does not name

    def __post_init__(self) -> None:
        self._outgoing = [[[e for e in block if e.source == s] for s in range(len(self.states[k]))]
                          for k, block in enumerate(self.blocks)]
        # completions[k][s]: the solutions' paths from state s of layer k to the end
        completions = [[0] * len(layer) for layer in self.states]
        completions[-1] = [1] * len(self.states[-1])
        for k in range(len(self.blocks) - 1, -1, -1):
            after = completions[k + 1]
            for s, edges in enumerate(self._outgoing[k]):
                completions[k][s] = sum(e.multiplicity * after[e.target] for e in edges)
        self.completions = completions

    @property
    def count(self) -> int:
        return self.completions[0][0] if self.states[0] else 0

    def choice_variables(self) -> set[int]:
        """The choice literals some edge sets true."""
        return {v for block in self.blocks for e in block for v in e.choices}

    def solutions(self) -> Iterator[tuple[int, ...]]:
        """Every solution's true choice literals (sorted), depth first: block by block, each
        block's edges in order of their choices.  An edge that ``multiplicity`` assignments of
        its block's own variables give is taken that many times, as enumeration lists them."""
        if not self.count:
            return
        path: list[Edge] = []
        pending = [self._taken(0, 0)]
        last = len(self.blocks) - 1
        while pending:
            edge = next(pending[-1], None)
            if edge is None:
                pending.pop()
                if path:
                    path.pop()
            elif len(pending) - 1 < last:
                path.append(edge)
                pending.append(self._taken(len(pending), edge.target))
            else:
                yield tuple(sorted(itertools.chain.from_iterable(e.choices for e in path + [edge])))

    def _taken(self, k: int, state: int) -> Iterator[Edge]:
        return itertools.chain.from_iterable(itertools.repeat(e, e.multiplicity) for e in self._outgoing[k][state])

    def solution_at(self, index: int) -> tuple[int, ...]:
        """Solution ``index`` (0-based) of :meth:`solutions`, without listing those before it."""
        if not 0 <= index < self.count:
            raise IndexError(index)
        chosen: list[int] = []
        state = 0
        for k, outgoing in enumerate(self._outgoing):
            after = self.completions[k + 1]
            for edge in outgoing[state]:
                weight = edge.multiplicity * after[edge.target]
                if index < weight:
                    index %= after[edge.target]
                    break
                index -= weight
            chosen += edge.choices
            state = edge.target
        return tuple(sorted(chosen))

    def sample(self, rng: random.Random) -> tuple[int, ...]:
        """One solution drawn uniformly: each edge is taken with the share of the solutions that
        go through it (exact integers, however many solutions there are)."""
        chosen: list[int] = []
        state = 0
        for k, outgoing in enumerate(self._outgoing):
            after = self.completions[k + 1]
            draw = rng.randrange(self.completions[k][state])
            for edge in outgoing[state]:
                weight = edge.multiplicity * after[edge.target]
                if draw < weight:
                    break
                draw -= weight
            chosen += edge.choices
            state = edge.target
        return tuple(sorted(chosen))

    def least_cost(self, cost: Mapping[int, int]) -> tuple[tuple[int, ...], int]:
        """A solution of least total ``cost`` (per choice literal, 0 when absent) and that cost:
        a shortest path, ties broken by the listing order (the first such solution listed)."""
        def edge_cost(e: Edge) -> int:
            return sum(cost.get(v, 0) for v in e.choices)

        best: list[list[int | None]] = [[None] * len(layer) for layer in self.states]
        best[-1] = [0] * len(self.states[-1])
        for k in range(len(self.blocks) - 1, -1, -1):
            for s, edges in enumerate(self._outgoing[k]):
                options = [edge_cost(e) + b for e in edges if (b := best[k + 1][e.target]) is not None]
                best[k][s] = min(options) if options else None
        chosen: list[int] = []
        state = 0
        for k, outgoing in enumerate(self._outgoing):
            edge = next(e for e in outgoing[state] if best[k + 1][e.target] is not None
                        and edge_cost(e) + best[k + 1][e.target] == best[k][state])  # type: ignore[operator]
            chosen += edge.choices
            state = edge.target
        total = best[0][0]
        assert total is not None
        return tuple(sorted(chosen)), total

    def renamed(self, rename: Mapping[int, int]) -> LayeredSpace:
        """The same graph over renamed variables (a component identical up to renaming); edges
        are put back in order of their renamed choices."""
        blocks = [sorted((Edge(e.source, e.target, tuple(sorted(rename[v] for v in e.choices)), e.multiplicity)
                          for e in block), key=_edge_order) for block in self.blocks]
        # the steps of chains keep their numbers (and names): they are not the model's variables
        return LayeredSpace([tuple(rename.get(v, v) for v in f) for f in self.frontiers], self.states, blocks,
                            self.names)


def _edge_order(e: Edge) -> tuple[int, tuple[int, ...], int]:
    return e.source, e.choices, e.target


# ---------------------------------------------------------------------------------------------
# Building the graph


def layered_space(bm: BoolModel, records: Sequence[Record], choice_vars: Sequence[int]) -> LayeredSpace | None:
    """The component ``records`` as a layered graph, or None when it does not cut into blocks
    with small frontiers (then it is solved as a whole)."""
    if free_variables(records) is None:
        return None  # not in definition order
    records, names = as_chains(bm, records)
    blocks = cut_into_blocks(records)
    if len(blocks) < 2:
        return None
    frontiers = _frontiers(blocks)
    if frontiers is None:
        return None
    choice = set(choice_vars)
    states: list[list[State]] = [[()]]
    edges: list[list[Edge]] = []
    for k, block in enumerate(blocks):
        enumerator = _BlockEnumerator(bm, block, frontiers[k], frontiers[k + 1], choice)
        if not enumerator.applies() or len(states[k]) << len(enumerator.free) > MAX_BLOCK_WORK:
            return None
        following: dict[State, int] = {}
        block_edges = []
        for s, state in enumerate(states[k]):
            for (target, chosen), n in enumerator.solutions(state).items():
                block_edges.append(Edge(s, following.setdefault(target, len(following)), chosen, n))
        if len(following) > MAX_STATES:
            return None
        states.append(list(following))
        edges.append(block_edges)
    return _pruned(frontiers, states, edges, names)


def as_chains(bm: BoolModel, records: Sequence[Record]) -> tuple[list[Record], dict[int, str]]:
    """The records with every AND or OR definition over more than two literals written as a
    chain of two-literal steps (literals in order of their variables), and the names of the
    steps' new variables (numbered after the model's).

    Parallel tasks that set and clear one fact are coupled by ``anypos <=> OR(setters)``: as one
    record it keeps every setter in the frontier up to the last block; as a chain, each block
    passes on one value, "some setter so far".  Each step is an equivalence, so the solutions
    (and their number) stay the same."""
    out: list[Record] = []
    names: dict[int, str] = {}
    for r in records:
        if not isinstance(r, (AndOf, OrOf)) or len(r.lits) <= 2:
            out.append(r)
            continue
        lits = sorted(r.lits, key=lambda l: abs(l) if isinstance(l, int) else 0)
        so_far = lits[0]
        for lit in lits[1:-1]:
            step = len(bm.names) + len(names)
            names[step] = f"{bm.name(r.target)} up to {_name(bm, lit)}"
            out.append(type(r)((so_far, lit), step))
            so_far = step
        out.append(type(r)((so_far, lits[-1]), r.target))
    return out, names


def _name(bm: BoolModel, lit: Lit) -> str:
    if not isinstance(lit, int):
        return lit.value
    return bm.name(lit) if lit > 0 else f"not {bm.name(-lit)}"


def cut_into_blocks(records: Sequence[Record]) -> list[list[Record]]:
    """The records grouped by the position of their last variable, in order of positions
    (records keep their order within a block, so definitions come before their uses)."""
    position = _positions(records)
    blocks: dict[int, list[Record]] = {}
    for r in records:
        blocks.setdefault(max((position[v] for v in r.variables()), default=0), []).append(r)
    return [blocks[k] for k in sorted(blocks)]


def _positions(records: Sequence[Record]) -> dict[int, int]:
    """The position of every variable: a free one the largest literal of its exactly-one
    choices (its own id without any), a defined one the largest position of its inputs."""
    defined = {t for r in records if (t := defined_variable(r)) is not None}
    choice_group = _choice_groups(records, defined)
    position: dict[int, int] = {}
    for r in records:
        target = defined_variable(r)
        inputs = [v for v in r.variables() if v != target]
        for v in inputs:
            if v not in defined:
                position[v] = choice_group[v]
        if target is not None:
            position[target] = max((position[v] for v in inputs), default=0)
    return position


def _choice_groups(records: Sequence[Record], defined: set[int]) -> dict[int, int]:
    """Every free variable's largest fellow literal in the exactly-one choices it takes part in."""
    groups = VariableGroups()
    for r in records:
        if isinstance(r, Exactly):
            groups.join_all([abs(l) for l in r.lits if isinstance(l, int) and abs(l) not in defined])
    free = {v for r in records for v in r.variables() if v not in defined}
    latest: dict[int, int] = {}
    for v in free:
        root = groups.find(v)
        latest[root] = max(latest.get(root, 0), v)
    return {v: latest[groups.find(v)] for v in free}


def _frontiers(blocks: list[list[Record]]) -> list[tuple[int, ...]] | None:
    """For k = 0..len(blocks): the variables of blocks before k that block k or a later one
    uses (none before the first block and after the last); None when one has more than
    ``MAX_FRONTIER`` (found from their sizes first, in time linear in the records)."""
    first: dict[int, int] = {}
    last: dict[int, int] = {}
    for k, block in enumerate(blocks):
        for r in block:
            for v in r.variables():
                first.setdefault(v, k)
                last[v] = k
    change = [0] * (len(blocks) + 2)
    for v, k in first.items():
        change[k + 1] += 1
        change[last[v] + 1] -= 1
    if max(itertools.accumulate(change)) > MAX_FRONTIER:
        return None
    frontiers: list[set[int]] = [set() for _ in range(len(blocks) + 1)]
    for v, k in first.items():
        for j in range(k + 1, last[v] + 1):
            frontiers[j].add(v)
    return [tuple(sorted(f)) for f in frontiers]


class _BlockEnumerator:
    """The assignments of one block's own free variables, given the state before it."""

    def __init__(self, bm: BoolModel, records: list[Record], given: tuple[int, ...], passed: tuple[int, ...],
                 choice: set[int]) -> None:
        self.bm = bm
        self.records = records
        self.given = given
        self.passed = passed
        known = set(given)
        in_order = free_variables(records)
        self.in_order = in_order is not None  # definitions before their uses
        self.free = [v for v in in_order or () if v not in known]
        self.own_choices = [v for v in self.free if v in choice]

    def applies(self) -> bool:
        return self.in_order and len(self.free) <= MAX_BLOCK_FREE and not any(v in self.bm.ints for v in self.free)

    def solutions(self, state: State) -> Counter[tuple[State, tuple[int, ...]]]:
        """(state after the block, true choice literals) of each assignment that satisfies the
        block's records, with how many assignments give it."""
        found: Counter[tuple[State, tuple[int, ...]]] = Counter()
        for bits in itertools.product((0, 1), repeat=len(self.free)):
            values = dict(zip(self.given, state))
            values.update(zip(self.free, bits))
            if all(holds(r, values, self.bm) for r in self.records):
                found[(tuple(values[v] for v in self.passed), tuple(v for v in self.own_choices if values[v]))] += 1
        return found


def _pruned(frontiers: list[tuple[int, ...]], states: list[list[State]], edges: list[list[Edge]],
            names: dict[int, str]) -> LayeredSpace:
    """The graph without the states from which no path reaches the end, states renumbered in
    order of first use and edges sorted (see :class:`LayeredSpace`)."""
    alive = [set(range(len(layer))) for layer in states]
    for k in range(len(edges) - 1, -1, -1):
        alive[k] = {e.source for e in edges[k] if e.target in alive[k + 1]}
    number: list[dict[int, int]] = [{0: 0} if 0 in alive[0] else {}]
    blocks: list[list[Edge]] = []
    for k, block in enumerate(edges):
        kept = [e for e in block if e.source in alive[k] and e.target in alive[k + 1]]
        kept.sort(key=lambda e: (number[k][e.source], e.choices, e.target))
        following: dict[int, int] = {}
        for e in kept:
            following.setdefault(e.target, len(following))
        number.append(following)
        blocks.append(sorted((Edge(number[k][e.source], following[e.target], e.choices, e.multiplicity) for e in kept),
                             key=_edge_order))
    layers = [[states[k][old] for old in sorted(number[k], key=number[k].__getitem__)] for k in range(len(states))]
    return LayeredSpace(frontiers, layers, blocks, {v: names[v] for f in frontiers for v in f if v in names})
