"""What a decomposition output says, as read from either form (JSON or XML).

``None`` for a field means the file does not give it; a field that cannot be read is recorded
in :attr:`OutputTask.problems`, so that the validator reports it as a violation of that task
and still checks the other fields.
"""
from __future__ import annotations

from dataclasses import dataclass, field

SECTIONS = ("tasks", "constraints", "mission_decompositions")
"""The sections every output has and the validator needs (``actions`` is derived data)."""

Capabilities = str | tuple[str, ...] | None
"""An ``actions`` entry's capabilities as written: the last one as a string (the original's
JSON), all of them (the standard style, XML), or None where the entry gives none."""


@dataclass(frozen=True)
class OutputAction:
    """One action of a task's decomposition; ``args`` is None when the file does not list them
    (the XML form names the actions only)."""

    name: str
    args: tuple[str, ...] | None


@dataclass(frozen=True)
class RobotsNum:
    fixed: bool
    min: int
    max: int


@dataclass(frozen=True)
class OutputPredicate:
    """A printed precondition or effect: ``not RoomA.is_clean`` with its ``vars`` and
    ``var_types`` as written (JSON: the last argument; XML: all, comma separated)."""

    text: str
    vars: str
    var_types: str


@dataclass(frozen=True)
class OutputTask:
    """A decomposition of a task instance as the file lists it.

    The XML form leaves empty lists out, so there an absent list is read as empty.
    ``problems`` are (field, message) pairs for fields the reader could not make sense of."""

    key: str  # "t3" (JSON) or "task3" (XML)
    id: str  # "AT1_2|3"
    name: str  # the HDDL abstract task
    arguments: tuple[tuple[str, str, str], ...]  # (parameter, type, value); value "" if unbound
    robots: RobotsNum | None
    actions: tuple[OutputAction, ...]
    locations: tuple[str, ...] = ()  # the value of the task's Location variable
    where: str = ""  # key path (JSON ``tasks.t3``) or line (XML ``line 12``), for messages
    values: tuple[tuple[str, str], ...] | None = None  # arguments_values as written, in order
    preconditions: tuple[OutputPredicate, ...] | None = None
    effects: tuple[OutputPredicate, ...] | None = None
    events: tuple[str, ...] | None = None
    group: bool | None = None
    divisible: bool | None = None
    problems: tuple[tuple[str, str], ...] = ()
    # read from the id once (the validator asks for them for every task of every decomposition)
    instance: str = field(init=False)  # the task instance (``AT1_2``) of which this is one decomposition
    gm_task: str = field(init=False)  # the goal-model task (``AT1``) the instance was generated from

    def __post_init__(self) -> None:
        instance = self.id.split("|", 1)[0]
        object.__setattr__(self, "instance", instance)
        object.__setattr__(self, "gm_task", instance.split("_", 1)[0])

    @property
    def number(self) -> str:
        """The decomposition number as written (``3`` of ``AT1_2|3``; ``""`` when absent)."""
        return self.id.partition("|")[2]


@dataclass(frozen=True)
class OutputConstraint:
    kind: str  # "SEQ" | "FB" | "EC"
    first: str
    second: str
    where: str  # "constraints[4]" (JSON) or "line 120" (XML)
    # an EC's flags as written; None where the file leaves one out or it cannot be read
    group: bool | None = None
    divisible: bool | None = None


@dataclass(frozen=True)
class DecompositionOutput:
    source: str
    tasks: dict[str, OutputTask]  # by key, file order
    constraints: tuple[OutputConstraint, ...]
    # each one a tuple of task keys; the keys are interned strings, so that hundreds of
    # thousands of decompositions over the same tasks cost a pointer per key
    mission_decompositions: tuple[tuple[str, ...], ...]
    format: str = "json"  # "json" | "xml": which layout rules the fields follow
    # the ``actions`` section: (name, capabilities as written); None when there is no list of actions
    actions: tuple[tuple[str, Capabilities], ...] | None = None
    # (entity, attribute, value text) of the world the tasks were expanded in, when the goal model
    # reads uncertain facts (``mission_decomposition_uncertainty.world``); empty: the world as written
    assumed_world: tuple[tuple[str, str, str], ...] = ()
