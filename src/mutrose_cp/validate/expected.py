"""What a mission implies for its output, rebuilt from the four inputs: the task instances of
the Task Graph, each decomposition's fields, and the constraints.

Everything here comes from the goal model, the configuration, the world and the HDDL domain
through the validator's own modules (:mod:`.mission_tree`, :mod:`.numbering`, :mod:`.printed`,
:mod:`.task_graph`, :mod:`.constraint_rules`), never from the decomposers.
"""
from __future__ import annotations

from dataclasses import dataclass

from ..model import Configuration, Domain, GoalModel, InitialState, WorldKnowledge
from .constraint_rules import Expected, expected_constraints
from .mission_tree import Instance, expand_mission
from .numbers import AtomKey
from .numbering import Listed, PathError, task_decompositions, unrolled
from .printed import Grounded, Printed, Printer, ground_conditions
from .select import Unresolved
from .task_graph import build_graph, minimal_tree


@dataclass(frozen=True)
class Fields:
    """One decomposition's fields as the mission implies them (values as the format writes them)."""

    name: str
    arguments: tuple[tuple[str, str], ...]  # (parameter, type)
    values: dict[str, str]
    locations: tuple[str, ...]
    robots: tuple[bool, int, int]
    preconditions: tuple[Printed, ...]
    effects: tuple[Printed, ...]
    events: tuple[str, ...]
    actions: tuple[tuple[str, tuple[str, ...]], ...]
    group: bool
    divisible: bool


def _shown(value: str | tuple[str, ...], xml: bool) -> str:
    if isinstance(value, tuple):
        return " ".join(value) if xml else "[" + ",".join(value) + "]"
    return value


class ExpectedMission:
    """The instances, decompositions and constraints of a mission (raises :class:`Unresolved`
    when the goal model cannot be expanded against the world, or the domain's decompositions listed)."""

    def __init__(self, domain: Domain, gm: GoalModel, config: Configuration, initial: InitialState,
                 world: WorldKnowledge) -> None:
        self.domain = domain
        self.initial = initial
        self.printer = Printer(domain, config, initial)
        rat, generated = expand_mission(gm, domain, config, world)
        self.generated = {i.id: i for i in generated}
        self._listings: dict[str, list[Listed]] = {}
        self._unrolled: dict[tuple[str, int], Listed] = {}
        self._grounded: dict[tuple[str, int], Grounded] = {}
        self._values = {k: float(v) for k, v in initial.value_map().items()}
        self.graph = build_graph(rat, config, initial, self.effects_of)
        self.instances = {v.content: v.instance for v in self.graph.tasks if v.instance is not None}
        self.counts = {i: len(self.listing(inst.name)) for i, inst in self.instances.items()}
        self.constraints: Expected = expected_constraints(self.graph, minimal_tree(self.graph), self.counts)

    def listing(self, task: str) -> list[Listed]:
        if task not in self._listings:
            try:
                self._listings[task] = task_decompositions(self.domain, task)
            except PathError as err:
                raise Unresolved(str(err)) from None
        return self._listings[task]

    def decomposition(self, inst: Instance, n: int) -> Listed:
        """Decomposition ``|n`` of ``inst``, its recursions unrolled against the world."""
        key = (inst.id, n)
        if key not in self._unrolled:
            self._unrolled[key] = unrolled(self.listing(inst.name)[n - 1], inst.ground, self._values)
        return self._unrolled[key]

    def grounded(self, inst: Instance, n: int) -> Grounded:
        key = (inst.id, n)
        if key not in self._grounded:
            self._grounded[key] = ground_conditions(self.decomposition(inst, n), inst.ground)
        return self._grounded[key]

    def effects_of(self, inst: Instance) -> list[dict[AtomKey, bool]]:
        return [self.grounded(inst, n).ground_effects() for n in range(1, len(self.listing(inst.name)) + 1)]

    def fields(self, inst: Instance, n: int, xml: bool) -> Fields:
        task = self.domain.task_by_name[inst.name]
        values = {p.name: "" for p in task.parameters}
        for param, value in inst.parameters:
            if param in values:
                values[param] = _shown(value, xml)
        loc = inst.location
        locations = loc if isinstance(loc, tuple) else ((loc,) if loc else ())
        grounded = self.grounded(inst, n)
        return Fields(inst.name, tuple((p.name, p.type) for p in task.parameters), values, locations,
                      (inst.robots.fixed, inst.robots.min, inst.robots.max),
                      self.printer.listing(inst.name, grounded.preconditions, xml),
                      self.printer.listing(inst.name, grounded.effects, xml), inst.events,
                      tuple((s.name, s.args) for s in self.decomposition(inst, n).actions), inst.group, inst.divisible)
