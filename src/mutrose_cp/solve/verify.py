"""Deciding properties over every valid mission decomposition, exactly, through the components.

A property is grounded first (:mod:`.property_grounding`): its formula becomes the conjunction,
over every binding of its variables, of formulas whose atoms are sets of task decompositions
(an atom is true of a mission decomposition that chooses one of them).

The decomposition space is a product of independent components, and each conjunct reads only
the components its atoms' decompositions lie in.  The conjuncts are grouped by the components
they share (connected components of a graph of conjuncts and components), and each group is
decided on its own components alone: the verdict is the product of the groups' (``before`` per
room of a 5000-room mission is 5000 small groups, never one formula over 5000 rooms).

In a group, each component's solutions are folded into a histogram over atom vectors (which of
the group's atoms the part makes true), and the histograms are combined by OR-convolution: the
state has at most one entry per atom vector, whatever the number of decompositions.  The counts
are exact (Python integers); a witness is kept per vector as one part per component.

Components that no atom touches are counted, never listed.  A component an atom touches is
folded through its layered graph when it has one (a forward pass that carries atom vectors
instead of listing paths: exact for any number of solutions), else by listing its solutions;
one that was only counted (too many solutions to list, no layered graph) is refused, named,
rather than answered wrongly, and so is a group whose histogram would hold more than
``MAX_VECTORS`` vectors.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Iterable, Iterator, Literal, Mapping, Sequence

from ..model.domain import Domain
from ..model.properties import Property
from ..model.task_graph import TaskGraph
from ..model.world import InitialState
from ..pipeline.constraints import Constraint
from .boolean_model import VariableGroups
from .cpsat import Component, DecompositionSpace
from .layered import LayeredSpace
from .property_grounding import Grounded, GroundedProperty, ground, refusal

Status = Literal["holds", "fails", "vacuous", "count"]
#: at most this many distinct atom vectors in one group's histogram
MAX_VECTORS = 1 << 16
#: at most this many solutions of one component are read to fold it (a layered one is listed)
MAX_COMPONENT_SOLUTIONS = 200_000


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
           constraints: Iterable[Constraint] = (), initial: InitialState | None = None) -> Verdict:
    """The verdict of ``prop`` over ``space`` (the mission's valid decompositions); ``before``
    atoms read the mission's ``constraints``, ``finally`` atoms its ``initial`` state."""
    return decide(prop, ground(prop, tg, domain, constraints, initial), space)


def decide(prop: Property, grounded: GroundedProperty, space: DecompositionSpace) -> Verdict:
    """The verdict of ``prop``, grounded, over ``space``."""
    if not space.encoding.tasks or any(c.count == 0 for c in space.components):
        return Verdict(prop, "vacuous", 0, 0, None)
    grouped = _groups(space, grounded)
    groups = [_decide_group(prop, space, grounded, conjuncts, components) for conjuncts, components in grouped]
    touched = {n for _, components in grouped for n in components}
    untouched = [c for n, c in enumerate(space.components) if n not in touched]
    shared = _shared_part(space, untouched)
    others = 1
    for component in untouched:
        others *= component.count
    total, count = others, others
    for group in groups:
        total *= group.total
        count *= group.satisfied
    status: Status
    if prop.quantifier == "count":
        status, chosen = "count", _all_satisfied(groups, count)
    elif prop.quantifier == "always":
        status = "holds" if count == total else "fails"
        chosen = None if count == total else _one_broken(groups)
    elif prop.quantifier == "never":
        status, chosen = ("holds" if count == 0 else "fails"), _all_satisfied(groups, count)
    else:
        status, chosen = ("holds" if count else "fails"), _all_satisfied(groups, count)
    witness = None if chosen is None or shared is None else tuple(sorted([*shared, *chosen]))
    return Verdict(prop, status, count, total, witness)


# --- grouping: the conjuncts that share components are decided together ----------------------


def _conjuncts(formula: Grounded) -> Iterator[Grounded]:
    """The operands of ``formula``'s top-level conjunctions, nested ones spliced."""
    if isinstance(formula, tuple) and formula[0] == "and":
        for operand in formula[1]:
            yield from _conjuncts(operand)
    else:
        yield formula


def _atom_indices(formula: Grounded) -> Iterator[int]:
    if isinstance(formula, int):
        yield formula
    else:
        for operand in formula[1]:
            yield from _atom_indices(operand)


def _groups(space: DecompositionSpace, grounded: GroundedProperty) -> list[tuple[list[Grounded], list[int]]]:
    """The conjuncts grouped by the components they read (connected through shared
    components, by the model's union-find), each group with its components, in order of first
    conjunct; conjuncts that read no component (their atoms are constant) form one group
    without components, first."""
    component_of = {space.var_to_dec[v]: n for n, c in enumerate(space.components) for v in c.choice_vars}
    reads: dict[int, set[int]] = {}
    joined = VariableGroups()
    conjuncts = list(_conjuncts(grounded.formula))
    constant: list[Grounded] = []
    read_by: list[list[int]] = []
    for conjunct in conjuncts:
        components: set[int] = set()
        for atom in _atom_indices(conjunct):
            if atom not in reads:
                reads[atom] = {n for d in grounded.atoms[atom] if (n := component_of.get(d)) is not None}
            components |= reads[atom]
        if not components:
            constant.append(conjunct)
        ordered = sorted(components)
        joined.join_all(ordered)
        read_by.append(ordered)
    groups: dict[int, tuple[list[Grounded], set[int]]] = {}
    for conjunct, read in zip(conjuncts, read_by):
        if read:
            members, together = groups.setdefault(joined.find(read[0]), ([], set()))
            members.append(conjunct)
            together.update(read)
    found = [(members, sorted(together)) for members, together in groups.values()]
    return ([(constant, [])] if constant else []) + found


# --- one group: a histogram over its atom vectors, component by component ------------------

Witness = tuple["Witness", tuple[int, ...]] | None  # (the parts before, this part), linked
Histogram = dict[int, tuple[int, Witness]]  # atom vector -> (decompositions, one witness)


@dataclass(frozen=True)
class _Group:
    """A group of conjuncts decided on its components: how many of their joint solutions
    satisfy the group's formula, of how many, and a witness part of each kind."""

    satisfied: int
    total: int
    satisfying: tuple[int, ...] | None  # the group's decompositions in one that satisfies it
    breaking: tuple[int, ...] | None  # ... and in one that does not
    any_part: tuple[int, ...]


def _decide_group(prop: Property, space: DecompositionSpace, grounded: GroundedProperty,
                  conjuncts: list[Grounded], components: list[int]) -> _Group:
    used = sorted({a for c in conjuncts for a in _atom_indices(c)})
    local = {atom: bit for bit, atom in enumerate(used)}
    formula = _renumbered(("and", tuple(conjuncts)), local)
    sets = [grounded.atoms[a] for a in used]
    histogram: Histogram = {_vector(space.fixed, sets): (1, None)}
    for number in components:
        histogram = _combine(histogram, _component_histogram(space, space.components[number], number, sets, prop))
        if len(histogram) > MAX_VECTORS:
            raise refusal(prop, f"the parts of the mission it reads together take more than {MAX_VECTORS} "
                                "combinations of its atoms")
    satisfied = {v: e for v, e in histogram.items() if _evaluate(formula, v)}
    broken = {v: e for v, e in histogram.items() if v not in satisfied}
    return _Group(sum(c for c, _ in satisfied.values()), sum(c for c, _ in histogram.values()),
                  _first_witness(satisfied), _first_witness(broken), _first_witness(histogram) or ())


def _renumbered(formula: Grounded, local: Mapping[int, int]) -> Grounded:
    if isinstance(formula, int):
        return local[formula]
    return (formula[0], tuple(_renumbered(f, local) for f in formula[1]))


def _vector(decompositions: Iterable[int], sets: Sequence[frozenset[int]]) -> int:
    chosen = tuple(decompositions)
    return sum(1 << bit for bit, atom in enumerate(sets) if not atom.isdisjoint(chosen))


def _component_histogram(space: DecompositionSpace, component: Component, number: int,
                         sets: Sequence[frozenset[int]], prop: Property) -> dict[int, tuple[int, tuple[int, ...]]]:
    """One component's solutions folded by atom vector: through its layered graph when it has
    one (:func:`_layered_histogram`, whatever its number of solutions), else by listing them."""
    if component.layers is not None:
        return _layered_histogram(component.layers, space.var_to_dec, sets, prop, number)
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


Path = tuple["Path", tuple[int, ...]] | None  # (the edges before, this edge's choices), linked


def _layered_histogram(layers: LayeredSpace, var_to_dec: Mapping[int, int], sets: Sequence[frozenset[int]],
                       prop: Property, number: int) -> dict[int, tuple[int, tuple[int, ...]]]:
    """A layered component's solutions folded by atom vector without listing them: a forward
    pass over its blocks keeps, per state, how many paths reach it with each atom vector and one
    such path, so the cost is the number of edges times the vectors per state."""
    reached: list[dict[int, tuple[int, Path]]] = [{0: (1, None)} for _ in layers.states[0]]
    for k, block in enumerate(layers.blocks):
        after: list[dict[int, tuple[int, Path]]] = [{} for _ in layers.states[k + 1]]
        for edge in block:
            made = _vector((var_to_dec[v] for v in edge.choices), sets)
            target = after[edge.target]
            for vector, (count, path) in reached[edge.source].items():
                total, example = target.get(vector | made, (0, (path, edge.choices)))
                target[vector | made] = (total + count * edge.multiplicity, example)
            if len(target) > MAX_VECTORS:
                raise refusal(prop, f"part {number + 1} of the mission, which it reads, takes more than {MAX_VECTORS} "
                                    "combinations of its atoms")
        reached = after
    folded: dict[int, tuple[int, tuple[int, ...]]] = {}
    for vector, (count, path) in (reached[0].items() if reached else ()):
        choices: list[int] = []
        while path is not None:
            path, step = path
            choices.extend(step)
        folded[vector] = (count, tuple(sorted(var_to_dec[v] for v in choices)))
    return folded


def _combine(histogram: Histogram, component: Mapping[int, tuple[int, tuple[int, ...]]]) -> Histogram:
    combined: Histogram = {}
    for (v, (c, w)), (u, (k, part)) in itertools.product(histogram.items(), component.items()):
        count, witness = combined.get(v | u, (0, (w, part)))
        combined[v | u] = (count + c * k, witness)
    return combined


def _evaluate(formula: Grounded, vector: int) -> bool:
    if isinstance(formula, int):
        return bool(vector >> formula & 1)
    op, operands = formula
    if op == "not":
        return not _evaluate(operands[0], vector)
    if op == "and":
        return all(_evaluate(f, vector) for f in operands)
    return any(_evaluate(f, vector) for f in operands)


def _first_witness(entries: Histogram) -> tuple[int, ...] | None:
    """The parts of the smallest vector's witness among ``entries``, joined (None without
    entries)."""
    if not entries:
        return None
    node = entries[min(entries)][1]
    chosen: list[int] = []
    while node is not None:
        node, part = node
        chosen.extend(part)
    return tuple(chosen)


# --- the verdict's witness, from the groups' parts --------------------------------------------


def _shared_part(space: DecompositionSpace, untouched: Sequence[Component]) -> list[int] | None:
    """The decompositions every fixed task and untouched component contributes to a witness:
    the fixed ones and one solution of each (None when one was only counted)."""
    shared = list(space.fixed)
    for component in untouched:
        alternatives = space.alternatives(component)
        if alternatives is None:
            return None
        shared.extend(next(iter(alternatives)))
    return shared


def _all_satisfied(groups: Sequence[_Group], count: int) -> list[int] | None:
    """A decomposition that satisfies every group (None when none does)."""
    if count == 0:
        return None
    return [d for g in groups for d in g.satisfying or ()]


def _one_broken(groups: Sequence[_Group]) -> list[int] | None:
    """A decomposition that breaks the first group that can be broken, any part elsewhere."""
    for i, group in enumerate(groups):
        if group.breaking is not None:
            return [*(d for g in groups[:i] for d in g.any_part), *group.breaking,
                    *(d for g in groups[i + 1:] for d in g.any_part)]
    return None
