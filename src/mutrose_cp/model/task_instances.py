"""Task instances: the abstract-task instances the goal-model expansion makes, one per
goal-model task and forAll context, with their variable mappings (spec ``semantics.md`` §3).

Made by ``pipeline.expansion``; read by the HTN stage, the Task Graph and the writers."""
from __future__ import annotations

from dataclasses import dataclass

from .goal_model import RobotNumber


Value = str | tuple[str, ...]


@dataclass(frozen=True, slots=True)
class ParameterValue:
    """One entry of an instance's variable mapping: an HDDL parameter and its value."""

    hddl_param: str
    value: Value
    ocl_type: str
    gm_var: str


@dataclass(frozen=True, slots=True)
class TaskInstance:
    """An abstract-task instance created from a goal-model task in one forAll context."""

    id: str  # "AT1_2_1"
    gm_task: str  # "AT1"
    name: str  # HDDL abstract task
    robot_number: RobotNumber
    location: Value | None
    parameters: tuple[ParameterValue, ...]
    triggering_events: tuple[str, ...]

    @property
    def binding(self) -> dict[str, Value]:
        """HDDL parameter -> value (the first entry wins).  A single-valued query that matched
        nothing leaves its variable empty (""); such a parameter stays unbound."""
        out: dict[str, Value] = {}
        for p in self.parameters:
            if p.value != "":
                out.setdefault(p.hddl_param, p.value)
        return out
