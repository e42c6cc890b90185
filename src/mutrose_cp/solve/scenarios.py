"""Decompositions when the goal model reads uncertain facts: one expansion per world, and what
the worlds share (docs/formats/uncertainty.md).

Each world of ``pipeline/scenarios.py`` is decided as any mission with uncertain facts
(:func:`mutrose_cp.solve.uncertain.uncertain_space`).  Across worlds a decomposition is known by
its content, not by its task ids (a world where a room needs no disinfection numbers the
others' tasks differently): a task decomposition is the goal-model task, the HDDL task, its
location and variable values, the method path chosen and the steps it expands to (a recursion
repeats as often as the world's value says), the n-th of equal ones in a world.

Most of a mission is the same in every world: its components are equal, content for content,
with the same alternatives allowed in the same scenarios of the facts they read.  Those are
*shared*, decided once.  The rest, where the worlds differ, is gathered into one component over
the facts the goal model reads and the uncertain facts of those parts: its alternatives are the
content of the differing parts in each world, each allowed in the scenarios (the world's values,
and the values of the other facts that allow it there) where it is valid.  Then every answer of
an uncertain space holds as it is: robust when every scenario allows each part, possible when
some does, the probability a sum over scenarios, products across components, and the facts to
sense first, now among the facts the goal model reads as well.

Decompositions are written in the task ids of one world, the *frame*: a robust decomposition
exists in every world; the most likely one in the world where it is most likely valid.  The
possible decompositions of different worlds cannot be listed in one output, so only counted.
"""
from __future__ import annotations

import itertools
import math
from collections import Counter
from dataclasses import dataclass, field
from functools import cached_property
from typing import Callable, Hashable, Iterable, Iterator, Mapping

from ..errors import MissionError
from ..model.task_graph import TaskGraph
from ..model.uncertainty import UncertainFact, Uncertainty, Value, rounded_probability
from ..pipeline.scenarios import ScenarioWorld, scenario_worlds
from ..pipeline.stages import MissionStages
from .cpsat import Component, DecompositionSpace
from .uncertain import MAX_PAIRS, Part, Scenario, UncertainComponent, UncertainSpace, uncertain_space

ComponentKey = tuple[Hashable, ...]


def decided_space(stages: MissionStages) -> UncertainSpace:
    """The mission's decompositions under its uncertain facts: expanded per world when the goal
    model reads some of them (:class:`ExpandedSpace`), else decided in one expansion."""
    return expanded_space(stages) if stages.expands_per_world else uncertain_space(stages)


@dataclass
class WorldSpace:
    """One world, decided: its space (None when the mission cannot be expanded there, with
    ``problem`` saying why) and each task decomposition's content id."""

    world: ScenarioWorld
    space: UncertainSpace | None
    problem: str = ""
    content: dict[int, int] = field(default_factory=dict)  # decomposition vertex -> content id
    failed: bool = False  # the mission cannot be expanded there (an error), not merely has no task

    @property
    def stages(self) -> MissionStages:
        return self.world.stages

    @cached_property
    def vertex_of(self) -> dict[int, int]:
        return {c: d for d, c in self.content.items()}

    @property
    def live(self) -> bool:
        """Whether some decomposition is valid here for some value of the other facts."""
        return self.space is not None and all(c.allowed for c in self.space.components)


@dataclass
class ExpandedSpace(UncertainSpace):
    """An uncertain space whose parts are content ids, over every world (module docstring).
    ``frame``: the world whose task ids the decompositions handed out and judged are in."""

    worlds: list[WorldSpace] = field(default_factory=list)
    frame: int = 0

    @property
    def frame_world(self) -> WorldSpace:
        return self.worlds[self.frame]

    @property
    def output_stages(self) -> MissionStages:
        """The mission in the frame world: what an output of its decompositions is written from."""
        return self.frame_world.stages

    @cached_property
    def fixed(self) -> list[int]:
        return []  # every world's fixed choices are parts of the components here

    @cached_property
    def component_of(self) -> dict[int, int]:
        """Content id -> the index of its component in :attr:`components`."""
        return {d: i for i, c in enumerate(self.components) for part in c.allowed for d in part}

    def parts(self, decomposition: Iterable[int]) -> list[Part]:
        """``decomposition`` (task ids of the frame world)'s part in each component."""
        content = self.frame_world.content
        return super().parts(content[d] for d in decomposition)

    def space(self, robust: bool) -> DecompositionSpace:
        """The robust decompositions in the frame world, for listing as any space; the possible
        ones of several worlds have no common task ids, and are refused."""
        if not robust:
            raise MissionError("the goal model reads uncertain facts, so the decompositions valid for some value of "
                               "them belong to different expansions of the mission, which one output cannot hold: "
                               "list the robust ones (--robust) or the most likely (--most-likely), or count them")
        self.require_listed()
        frame = self.frame_world
        if frame.space is None:  # no world has a task: no decomposition
            return DecompositionSpace(self.encoding, [Component([], [], solutions=[], count=0)], self.var_to_dec)
        enc = frame.space.encoding
        dec_to_var = {d: v for v, d in frame.space.var_to_dec.items()}
        fixed = set(frame.space.fixed)
        components = []
        for c in self.components:
            parts = [p for p in c.allowed if c.robust(p)]
            if not parts:
                components.append(Component([], [], solutions=[], count=0))
                continue
            solutions = sorted({frozenset(dec_to_var[frame.vertex_of[d]] for d in p
                                          if frame.vertex_of[d] not in fixed) for p in parts}, key=sorted)
            choice_vars = sorted({v for s in solutions for v in s})
            if choice_vars:
                components.append(Component([], choice_vars, solutions=solutions, count=len(solutions)))
        return DecompositionSpace(enc, components, frame.space.var_to_dec)

    def content_costs(self, costs_of: Callable[[TaskGraph], Mapping[int, int]]) -> dict[int, int]:
        """Each content id's cost, from the cost of its task decomposition in a world."""
        costs: dict[int, int] = {}
        for w in self.worlds:
            if w.space is not None:
                for d, cost in costs_of(w.stages.task_graph).items():
                    if d in w.content:
                        costs.setdefault(w.content[d], cost)
        return costs

    def most_likely(self, costs: Mapping[int, int]) -> tuple[list[int], float]:
        """The decomposition most likely to be valid (``costs`` by content id, see
        :meth:`content_costs`), in the task ids of the world where it is most likely valid, which
        becomes the frame."""
        parts, probability = self.likeliest_parts(costs)
        best = parts[-1]
        varying = self.components[-1]  # the last: where the worlds differ (``best`` is its part)
        expanded = len(self.uncertainty.expanded)
        weight = {i: math.fsum(varying.scenario_probability(s) for s in varying.allowed[best]
                               if s[:expanded] == w.world.values)
                  for i, w in enumerate(self.worlds) if w.live}
        self.frame = max(weight, key=lambda i: (rounded_probability(weight[i]), -i))
        vertex_of = self.frame_world.vertex_of
        return sorted(vertex_of[d] for p in parts for d in p), probability


def expanded_space(stages: MissionStages) -> ExpandedSpace:
    """Every world decided, the components they share found, the rest gathered into one."""
    uncertainty = stages.uncertainty
    assert uncertainty is not None
    contents: dict[Hashable, int] = {}
    worlds = [_decided_world(w, contents) for w in scenario_worlds(stages)]
    for w in worlds:
        if w.space is not None:
            w.space.require_listed()
    live = [w for w in worlds if w.live]
    if all(w.failed for w in worlds):
        raise MissionError(f"the mission cannot be expanded in any world of its uncertain facts: {worlds[0].problem}")
    common, apart = split_shared([_keyed_components(w) for w in live])
    differing = {id(w): comps for w, comps in zip(live, apart)}
    varying = _varying(uncertainty, live, differing, len(common), len(live) == len(worlds))
    frame = next((i for i, w in enumerate(worlds) if w.live),
                 next((i for i, w in enumerate(worlds) if w.space), next(i for i, w in enumerate(worlds) if not w.failed)))
    # no world has a task: the mission's decompositions are none, as when the world is known
    base = worlds[frame].space or uncertain_space(worlds[frame].stages)
    return ExpandedSpace(base.encoding, uncertainty, [*common, varying], base.var_to_dec, worlds=worlds, frame=frame)


def _decided_world(world: ScenarioWorld, contents: dict[Hashable, int]) -> WorldSpace:
    """One world's uncertain space, and its task decompositions' content ids."""
    try:
        tg = world.stages.task_graph
    except MissionError as err:
        return WorldSpace(world, None, "; ".join(p.message for p in err.problems), failed=True)
    if not tg.tasks():
        return WorldSpace(world, None, "no entity of the world matched the queries: the mission has no task")
    space = uncertain_space(world.stages)
    return WorldSpace(world, space, "", _content_ids(tg, contents))


def _content_ids(tg: TaskGraph, contents: dict[Hashable, int]) -> dict[int, int]:
    """Each task decomposition's id by content, shared by every world: its goal-model task, HDDL
    task, location, variable values, method path and the steps it expands to (a recursion
    repeats as often as a world's value says: two picks in one world are not three in another),
    and which of equal ones it is."""
    seen: Counter[Hashable] = Counter()
    ids = {}
    for vertex in tg.decompositions():
        d = vertex.decomposition
        inst = d.instance
        steps = tuple((s.name, s.args) for s in d.path.steps)
        key: Hashable = (inst.gm_task, inst.name, inst.location, inst.parameters, d.number, steps)
        seen[key] += 1
        ids[vertex.index] = contents.setdefault((key, seen[key]), len(contents))
    return ids


def split_shared(keyed: list[list[tuple[ComponentKey, UncertainComponent]]]
                 ) -> tuple[list[UncertainComponent], list[list[UncertainComponent]]]:
    """The components every world has (by :func:`component_key`; the first world's copies),
    and each world's others, where the worlds differ."""
    shared = Counter(key for key, _ in keyed[0]) if keyed else Counter()
    for components in keyed[1:]:
        shared &= Counter(key for key, _ in components)
    common: list[UncertainComponent] = []
    differing: list[list[UncertainComponent]] = []
    for n, components in enumerate(keyed):
        left = Counter(shared)
        differing.append([])
        for key, comp in components:
            if left[key] > 0:
                left[key] -= 1
                if n == 0:
                    common.append(comp)
            else:
                differing[-1].append(comp)
    return common, differing


def component_key(facts: tuple[UncertainFact, ...], allowed: Mapping[Part, frozenset[Scenario]]) -> ComponentKey:
    """A key equal for components that are the same in two worlds: the facts they read, and each
    alternative with the scenarios that allow it.  The same alternatives allowed in other
    scenarios are another component: shared, one world's scenarios would stand for every world's."""
    return tuple(f.atom for f in facts), frozenset(allowed.items())


def _keyed_components(w: WorldSpace) -> list[tuple[ComponentKey, UncertainComponent]]:
    """The world's components with content ids for parts, each with a key equal for components
    that are the same in two worlds: the facts they read and each alternative's scenarios.  The
    decompositions chosen in every solution are one more component, of one alternative."""
    assert w.space is not None
    fixed = tuple(sorted(w.content[d] for d in w.space.fixed))
    found: list[tuple[ComponentKey, UncertainComponent]] = [
        (("fixed", fixed), UncertainComponent(-1, (), {fixed: frozenset({()})}))]
    for c in w.space.components:
        allowed = {tuple(sorted(w.content[d] for d in part)): scenarios for part, scenarios in c.allowed.items()}
        found.append((component_key(c.facts, allowed), UncertainComponent(c.number, c.facts, allowed, joints=c.joints)))
    return found


def _varying(uncertainty: Uncertainty, live: list[WorldSpace], differing: dict[int, list[UncertainComponent]],
             number: int, every_world_live: bool) -> UncertainComponent:
    """The parts where the worlds differ, as one component over the facts the goal model reads
    and the other facts those parts read: an alternative per world and combination of the
    differing components' alternatives, allowed in that world's scenarios.  More pairs of an
    alternative and a scenario than ``MAX_PAIRS`` are not listed: the component is bounded."""
    order = {f.atom: i for i, f in enumerate(uncertainty.facts)}
    read = {f for comps in differing.values() for c in comps for f in c.facts}
    facts: tuple[UncertainFact, ...] = (*uncertainty.expanded, *sorted(read, key=lambda f: order[f.atom]))
    atoms = {f.atom for f in facts}
    joints = tuple(j for j in uncertainty.joints if any(f.atom in atoms for f in j.facts))
    component = UncertainComponent(number, facts, {}, joints=joints)
    expanded = len(uncertainty.expanded)
    free = {id(w): [i for i, f in enumerate(facts[expanded:], expanded)
                    if not any(f in c.facts for c in differing[id(w)])] for w in live}
    pairs = sum(math.prod(sum(len(s) for s in c.allowed.values()) for c in differing[id(w)])
                * math.prod(len(facts[i].values) for i in free[id(w)]) for w in live)
    if pairs > MAX_PAIRS:
        return _bounded(component, live, differing, pairs, every_world_live)
    allowed: dict[Part, set[Scenario]] = {}
    for w in live:
        for part, scenario in _world_pairs(w, differing[id(w)], facts, free[id(w)]):
            if component.can_happen(scenario):
                allowed.setdefault(part, set()).add(scenario)
    component.allowed = dict(sorted(((p, frozenset(s)) for p, s in allowed.items()), key=lambda item: item[0]))
    return component


def _world_pairs(w: WorldSpace, comps: list[UncertainComponent], facts: tuple[UncertainFact, ...],
                 free: list[int]) -> Iterator[tuple[Part, Scenario]]:
    """World ``w``'s pairs of an alternative where the worlds differ (one part of each of its
    differing components) and a scenario of ``facts`` (the world's values, the values its parts
    are allowed in, and any value of the ``free`` facts, which its parts do not read)."""
    index = {f.atom: i for i, f in enumerate(facts)}
    expanded = len(w.world.values)
    for choice in itertools.product(*(list(c.allowed.items()) for c in comps)):
        part = tuple(sorted(d for p, _ in choice for d in p))
        given = itertools.product(*(s for _, s in choice))
        for scenarios, others in itertools.product(given, itertools.product(*(facts[i].values for i in free))):
            values: list[Value] = [*w.world.values, *([False] * (len(facts) - expanded))]
            for c, scenario in zip(comps, scenarios):
                for f, v in zip(c.facts, scenario):
                    values[index[f.atom]] = v
            for i, v in zip(free, others):
                values[i] = v
            yield part, tuple(values)


def _bounded(component: UncertainComponent, live: list[WorldSpace], differing: dict[int, list[UncertainComponent]],
             pairs: int, every_world_live: bool) -> UncertainComponent:
    """Where the worlds differ, too many pairs to list: between bounds, said so.  Each world's
    combinations of its differing parts' alternatives are possible (at least the most of one
    world, at most all worlds' together); a robust one is robust in every world, so none is when
    a world has no decomposition, and at most the fewest robust combinations of a world."""
    possible = [math.prod(len(c.allowed) for c in differing[id(w)]) for w in live]
    robust = [math.prod(sum(1 for p in c.allowed if c.robust(p)) for c in differing[id(w)]) for w in live]
    facts = component.facts
    component.bounds = (max(possible, default=0), sum(possible), min(robust) if every_world_live and robust else 0)
    component.unlisted = (f"the worlds of the uncertain facts the goal model reads differ in parts of the mission with "
                          f"{pairs} pairs of an alternative and a scenario ({', '.join(f.text for f in facts[:4])}"
                          f"{', ...' if len(facts) > 4 else ''}), more than the {MAX_PAIRS} that are listed")
    return component


__all__ = ["ExpandedSpace", "WorldSpace", "component_key", "decided_space", "expanded_space", "split_shared"]
