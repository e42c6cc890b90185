"""Goal model reader: piStar/GODA JSON (spec ``goal-model.md``).

Builds the tree with the original's child order (children left to right by ``x``), reads every
custom property, and parses the embedded expressions.  Problems are collected per node so that
``check`` can report all of them; each is located by file and goal/task id.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from .expressions import Annotation, Condition, ForAll, Select


@dataclass(frozen=True)
class VarDecl:
    """A ``Controls``/``Monitors`` declaration ``name : Type`` (type may be empty)."""

    name: str
    type: str = ""

    @property
    def is_collection(self) -> bool:
        return "SEQUENCE" in self.type.upper()

    @property
    def base_type(self) -> str:
        if "(" in self.type and ")" in self.type:
            return self.type[self.type.index("(") + 1 : self.type.index(")")]
        return self.type


@dataclass(frozen=True)
class Context:
    """A ``CreationCondition``: ``kind`` is ``trigger`` or ``condition``."""

    kind: str
    text: str  # the quoted text (event string, or condition source)
    condition: Condition | None = None  # parsed for condition contexts


@dataclass(frozen=True)
class RobotNumber:
    """``RobotNumber``: fixed ``n`` (``min == max``, ``fixed``) or a range ``[a,b]``."""

    min: int
    max: int
    fixed: bool


@dataclass(frozen=True)
class GMNode:
    uid: str  # piStar node id
    id: str  # "G3", "AT1"
    kind: str  # "goal" | "task"
    text: str
    x: float
    y: float
    goal_type: str = "Perform"  # "Perform" | "Achieve" | "Query" | (odd value kept, warned)
    controls: tuple[VarDecl, ...] = ()
    monitors: tuple[VarDecl, ...] = ()
    context: Context | None = None
    forall: ForAll | None = None  # universal achieve condition
    achieve_condition: Condition | None = None  # plain (non-forAll) achieve condition
    achieve_text: str = ""  # raw AchieveCondition ("" when absent)
    query: Select | None = None
    group: bool = True
    divisible: bool = True
    location: str | None = None
    params: tuple[str, ...] = ()
    robot_number: RobotNumber | None = None
    annotation: Annotation | None = None  # None: no annotation / empty brackets
    task_name: str | None = None  # HDDL abstract task name (tasks only)
    children: tuple[str, ...] = ()  # ids, left to right
    parent: str | None = None
    or_decomposed: bool = False  # some child link is an OR refinement


@dataclass(frozen=True)
class GoalModel:
    source: str
    nodes: tuple[GMNode, ...]  # final vertex order of the original (goal-model.md §3)
    root: str
    dfs: tuple[str, ...]  # depth-first order from the root, children left to right
    warnings: tuple[str, ...] = ()

    @cached_property
    def by_id(self) -> dict[str, GMNode]:
        out: dict[str, GMNode] = {}
        for n in self.nodes:
            out.setdefault(n.id, n)
        return out

    def node(self, node_id: str) -> GMNode:
        return self.by_id[node_id]
