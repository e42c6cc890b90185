"""The goal model (spec ``goal-model.md``): the mission as a tree of goals and tasks, with the
variables, conditions, queries and runtime annotations attached to its nodes.

Produced by :mod:`mutrose_cp.io.goal_model` from piStar/GODA JSON; read by the static checks,
the expansion (which instantiates it against the world knowledge) and the renderers.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from .expressions import Annotation, Condition, ForAll, Select


def base_type(ocl_type: str) -> str:
    """``Sequence(Room)`` -> ``Room``; plain types unchanged."""
    lp = ocl_type.find("(")
    if lp >= 0 and ocl_type.endswith(")"):
        return ocl_type[lp + 1 : -1].strip()
    return ocl_type


def is_collection_type(ocl_type: str) -> bool:
    """Collection OCL types are written ``Kind(Base)``, e.g. ``Sequence(Room)``."""
    return "(" in ocl_type and ocl_type.endswith(")")


@dataclass(frozen=True)
class VarDecl:
    """A ``Controls``/``Monitors`` declaration ``name : Type`` (type may be empty)."""

    name: str
    type: str = ""

    @property
    def is_collection(self) -> bool:
        """Whether the variable holds a sequence (the original tests the type's text)."""
        return "SEQUENCE" in self.type.upper()

    @property
    def base_type(self) -> str:
        """The element type of a collection, else the type itself."""
        return base_type(self.type)


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
    """A goal or task of the goal model with its custom properties, as read and checked."""

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
    children: tuple[str, ...] = ()  # keys, left to right
    parent: str | None = None
    or_decomposed: bool = False  # some child link is an OR refinement
    # unique key: the id, or ``id#k`` for the k-th node reusing an id (ids are not checked for
    # uniqueness by the original; the structure must still tell such nodes apart)
    key: str = ""

    def __post_init__(self) -> None:
        if not self.key:
            object.__setattr__(self, "key", self.id)


@dataclass(frozen=True)
class GoalModel:
    """The goal tree: nodes in the original's vertex order, the root and a depth-first order."""

    source: str
    nodes: tuple[GMNode, ...]  # final vertex order of the original (goal-model.md §3)
    root: str
    dfs: tuple[str, ...]  # depth-first order from the root, children left to right
    warnings: tuple[str, ...] = ()

    @cached_property
    def by_id(self) -> dict[str, GMNode]:
        """Nodes by unique key; a plain id names the first node with that id."""
        out: dict[str, GMNode] = {n.key: n for n in self.nodes}
        for n in self.nodes:
            out.setdefault(n.id, n)
        return out

    def node(self, key: str) -> GMNode:
        """The node with unique key (or plain id) ``key``; KeyError when there is none."""
        return self.by_id[key]
