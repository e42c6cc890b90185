"""One world per scenario of the uncertain facts the goal model reads (docs/formats/uncertainty.md).

A query's condition, a forAll or achieve condition or a context decides which task instances
exist before any decomposition is chosen, so a fact such a condition reads cannot be a free
variable of the boolean model as the others are.  Instead the mission is expanded once per
scenario of those facts: the world file with each fact given its value, the goal model expanded
and the Task Graph built in that world as in any other.  The facts only the domain reads stay
uncertain in every world, decided there by the boolean model (``solve/uncertain.py``); what the
worlds share is found after solving (``solve/scenarios.py``).

A scenario of probability 0 is no world.  More than ``MAX_WORLDS`` worlds are refused, naming
the goals and the facts, rather than expanded for minutes.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, replace
from typing import Mapping

from ..errors import MissionError
from ..model.uncertainty import UncertainFact, Value, scenario_can_happen, value_text
from .stages import MissionStages

#: at most this many expansions of the mission, one per scenario of the facts the goal model reads
MAX_WORLDS = 16


@dataclass(frozen=True)
class ScenarioWorld:
    """The mission in one scenario of the facts the goal model reads: their values (in the
    uncertainty file's order) and the stages of the mission in that world, where the other
    uncertain facts are still uncertain."""

    values: tuple[Value, ...]
    stages: MissionStages

    def shown(self, facts: tuple[UncertainFact, ...]) -> str:
        """``needs-disinfection(Room101), not needs-disinfection(Room102)``."""
        return ", ".join(f.shown(v) for f, v in zip(facts, self.values))


def world_scenarios(stages: MissionStages) -> list[tuple[Value, ...]]:
    """The scenarios of the facts the goal model reads, one per world to expand the mission in
    (each fact's values in its order: false first), those of probability 0 left out; more than
    ``MAX_WORLDS`` are refused, naming the goals and the facts."""
    uncertainty = stages.uncertainty
    assert uncertainty is not None
    facts = uncertainty.expanded
    joints = [j for j in uncertainty.joints if j.facts[0].read_by_goal]
    scenarios = [s for s in itertools.product(*(f.values for f in facts)) if scenario_can_happen(facts, joints, s)]
    if len(scenarios) > MAX_WORLDS:
        named = "; ".join(f"{f.text}: {f.read_by_goal}" for f in facts[:4]) + ("; ..." if len(facts) > 4 else "")
        raise MissionError(f"{len(facts)} uncertain facts that the goal model reads give {len(scenarios)} worlds to "
                           f"expand the mission in, more than the {MAX_WORLDS} that are ({named}): give some of "
                           "their values in the world file", facts[0].entry.where)
    return scenarios


def scenario_worlds(stages: MissionStages) -> list[ScenarioWorld]:
    """The worlds of ``stages``' uncertain facts that the goal model reads (:func:`world_scenarios`)."""
    uncertainty = stages.uncertainty
    assert uncertainty is not None and uncertainty.expanded
    facts = uncertainty.expanded
    scenarios = world_scenarios(stages)
    expanded = {f.entry for f in facts}
    decided = tuple(e for e in stages.uncertainty_entries or () if e not in expanded)
    decided_joints = tuple(j for j in stages.uncertainty_joints
                           if not any(f.entry.entity == e and f.entry.attribute == a for f in facts for e, a in j.facts))
    worlds = []
    for values in scenarios:
        world = world_with(stages, {(f.entry.entity, f.entry.attribute): value_text(v) for f, v in zip(facts, values)})
        worlds.append(ScenarioWorld(values, replace(world, uncertainty_entries=decided, uncertainty_joints=decided_joints)))
    return worlds


def world_with(stages: MissionStages, fields: Mapping[tuple[str, str], str], where: str = "") -> MissionStages:
    """The mission in the world file with each (entity, attribute) given the text of its value:
    one scenario's world, or the one an output says its tasks were expanded in (``where``: the
    place that says so, for an entity the world does not have)."""
    for entity, attribute in fields:
        if entity not in stages.knowledge.entity_names:
            raise MissionError(f"{entity}.{attribute}: the world has no record {entity}", where)
    return replace(stages, knowledge=stages.knowledge.with_fields(fields), warnings=[], progress=None,
                   report_warning=None)


