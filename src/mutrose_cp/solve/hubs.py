"""Counting a component that a few wide definitions couple, without enumerating it.

Parallel tasks that set and clear one shared fact (a door, a charging station) make one
component: the parallel-conflict rule becomes ``anypos <=> OR(setters)``, ``anyneg <=>
OR(clearers)`` and ``not (anypos and anyneg)``, and every task's choice hangs off those two
definitions.  Enumerating the component costs its number of solutions, which doubles with every
task.  Removing the wide definitions (the *hubs*) leaves independent blocks, one per task; each
is enumerated on its own, and the count is rebuilt by conditioning on the hubs' values:

* a hub at its *forcing* value (an OR false, an AND true) fixes every literal it defines over;
* a hub at the other value is "not all fixed", counted by inclusion and exclusion:
  everything minus all fixed.

So the count is a sum over the hubs' values and their inclusion-exclusion subsets (4^hubs terms
at most) of products over the blocks, each block summed over its solutions' values on the hub
literals: linear in the number of tasks.  ``tests/test_hubs.py`` compares it with enumeration.

The layered solver (:mod:`.layered`) is tried first: it writes such definitions as chains and
solves the component block by block, listing and sampling it too; the hubs count the
components it cannot cut into blocks with small frontiers.
"""
from __future__ import annotations

import itertools
from collections import Counter
from dataclasses import dataclass
from typing import Callable, Sequence

from .boolean_model import AndOf, BoolModel, Lit, OrOf, Record, VariableGroups
from .tiny import holds

HUB_MIN_LITERALS = 8  # a definition over this many literals or more is a hub
MAX_HUBS = 4

#: enumerates a block: (records, watched variables) -> solutions as the true watched variables
#: (one entry per solution), or None when the block is too large to enumerate
BlockEnumerator = Callable[[Sequence[Record], list[int]], list[frozenset[int]] | None]


@dataclass(frozen=True)
class _Hub:
    target: int
    lits: tuple[Lit, ...]
    # the hub value that fixes its literals, which is also the value they then have:
    # 0 for an OR (all false), 1 for an AND (all true)
    fixed: int


def count_by_hubs(bm: BoolModel, records: Sequence[Record], enumerate_block: BlockEnumerator,
                  hub_min: int = HUB_MIN_LITERALS, max_hubs: int = MAX_HUBS) -> int | None:
    """The number of solutions of ``records``, or None when they are not hubs over independent
    blocks (then the component is enumerated as a whole)."""
    hubs = [_Hub(r.target, r.lits, 0 if isinstance(r, OrOf) else 1)
            for r in records if isinstance(r, (AndOf, OrOf)) and len(r.lits) >= hub_min]
    if not hubs or len(hubs) > max_hubs:
        return None
    targets = {h.target for h in hubs}
    if any(abs(l) in targets for h in hubs for l in h.lits if isinstance(l, int)):
        return None  # hubs over hubs
    on_hubs: list[Record] = []  # constraints between hubs only
    in_blocks: list[Record] = []
    for r in records:
        if isinstance(r, (AndOf, OrOf)) and r.target in targets:
            continue
        variables = set(r.variables())
        if variables and variables <= targets:
            on_hubs.append(r)
        elif variables & targets:
            return None  # a record mixes hubs and block variables
        else:
            in_blocks.append(r)
    hub_literal_vars = {abs(l) for h in hubs for l in h.lits if isinstance(l, int)}
    blocks = _blocks(in_blocks, hub_literal_vars)
    tallies: list[Tally] = []
    for block_records, variables in blocks:
        watched = sorted(variables & hub_literal_vars)
        solutions = enumerate_block(block_records, watched) if block_records else _free(watched)
        if solutions is None:
            return None
        tallies.append((frozenset(watched), Counter(solutions)))
    return sum(_count_given(hubs, values, tallies) for values in itertools.product((0, 1), repeat=len(hubs))
               if all(holds(r, dict(zip((h.target for h in hubs), values)), bm) for r in on_hubs))


def _free(variables: list[int]) -> list[frozenset[int]]:
    """The solutions of variables no record constrains: every assignment."""
    return [frozenset(v for v, on in zip(variables, bits) if on)
            for bits in itertools.product((False, True), repeat=len(variables))]


def _blocks(records: Sequence[Record], hub_literal_vars: set[int]) -> list[tuple[list[Record], set[int]]]:
    """The records split into independent blocks (records sharing no variable), each with its
    variables; hub literals no record mentions are blocks of their own."""
    find = VariableGroups(records).find
    groups: dict[int, tuple[list[Record], set[int]]] = {}
    for r in records:
        vs = r.variables()
        group = groups.setdefault(find(vs[0]) if vs else -1, ([], set()))
        group[0].append(r)
        group[1].update(vs)
    mentioned = {v for _, variables in groups.values() for v in variables}
    for v in sorted(hub_literal_vars - mentioned):
        groups[find(v)] = ([], {v})
    return [groups[k] for k in sorted(groups)]


Tally = tuple[frozenset[int], Counter[frozenset[int]]]  # a block's watched variables, its solutions


def _count_given(hubs: list[_Hub], values: tuple[int, ...], tallies: list[Tally]) -> int:
    """Solutions with the hubs at ``values``: forced hubs fix their literals; each other hub
    is "not all fixed", by inclusion and exclusion."""
    forced = [h for h, v in zip(hubs, values) if v == h.fixed]
    unforced = [h for h, v in zip(hubs, values) if v != h.fixed]
    total = 0
    for k in range(len(unforced) + 1):
        for subset in itertools.combinations(unforced, k):
            total += (-1) ** k * _product(forced + list(subset), tallies)
    return total


def _product(fixing: list[_Hub], tallies: list[Tally]) -> int:
    """Solutions where every literal of the ``fixing`` hubs has the hub's fixed value."""
    required: dict[int, int] = {}  # variable -> value
    for h in fixing:
        for l in h.lits:
            assert isinstance(l, int)
            value = h.fixed if l > 0 else 1 - h.fixed
            if required.setdefault(abs(l), value) != value:
                return 0
    product = 1
    for watched, tally in tallies:
        here = [(v, required[v]) for v in watched if v in required]
        product *= sum(n for solution, n in tally.items() if all((v in solution) == bool(value) for v, value in here))
        if product == 0:
            return 0
    return product
