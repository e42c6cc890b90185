"""The task instances and the runtime annotation tree a mission implies (semantics.md §3, §4).

The validator walks the goal model against the world itself, so that it knows, without the
decomposers' expansion, which task instances exist (``AT2_1_3``: goal-model task AT2 in the first
room and the third patient of a forAll), what each one's HDDL task, parameter values, location,
robot number, trigger events and Group/Divisible flags are, and under which operators its goals
put it.  The walk follows the spec: children left to right, a Query goal binds its first
controlled variable, a ``forAll`` binds its iteration variable to each element in turn (one copy
of its subtree each, under a parallel node when there are several), and annotation entries take
the goal's children in order (nested operators belong to the goal, docs/deviations.md fix 4).
"""
from __future__ import annotations

from dataclasses import dataclass, field, replace
from typing import Iterator, Mapping

from ..model import AnnotationLeaf, AnnotationOp, Binding, Configuration, Domain, GMNode, GoalModel, RobotNumber
from ..model import WorldKnowledge
from ..model.records import record_id
from .select import Unresolved, run_select

Value = str | tuple[str, ...]


@dataclass(frozen=True)
class Instance:
    """A task instance as the mission implies it."""

    id: str  # "AT1_2"
    gm: GMNode  # the goal-model task
    name: str  # the HDDL abstract task
    robots: RobotNumber
    location: Value | None
    parameters: tuple[tuple[str, Value], ...]  # (HDDL parameter, value), Location first, then Params
    events: tuple[str, ...]
    group: bool  # the flags of its parent goal
    divisible: bool

    @property
    def ground(self) -> dict[str, tuple[str, ...]]:
        """HDDL parameter -> its values (the first non-empty entry wins), for grounding."""
        out: dict[str, tuple[str, ...]] = {}
        for param, value in self.parameters:
            if value != "" and param not in out:
                out[param] = value if isinstance(value, tuple) else (value,)
        return out


@dataclass
class RatNode:
    """A node of the runtime annotation tree: a goal leaf, a task, a means-end goal or an
    operator (``goal`` None: the parallel node over the copies of a forAll)."""

    kind: str  # "goal" | "task" | "meansend" | "op"
    content: str  # operator, goal id or instance id
    goal: GMNode | None
    bindings: Mapping[str, Binding]
    children: list["RatNode"] = field(default_factory=list)
    group: bool = True
    divisible: bool = True
    or_decomposed: bool = False
    inner: bool = False  # an operator nested in its goal's annotation
    instance: Instance | None = None

    @property
    def forall_node(self) -> bool:
        return self.kind == "op" and self.goal is None


def robot_count(domain: Domain, task: str) -> RobotNumber:
    """Without ``RobotNumber``: the parameters typed ``robot`` or a type declared directly below it."""
    robotic = {t for t, p in domain.types if p == "robot"} | {"robot"}
    n = sum(1 for p in domain.task_by_name[task].parameters if p.type in robotic)
    return RobotNumber(n, n, True)


@dataclass(frozen=True)
class _Above:
    """What the goals above a node pass down to it: the element of each forAll among them
    (1-based, outermost first: the numbers of an instance id) and their trigger events."""

    elements: tuple[int, ...] = ()
    events: tuple[str, ...] = ()


class _Reading:
    """The goal model read against the world.  Variables are bound as the walk meets the goals
    that bind them and keep their last value for every goal after (the spec's global variables)."""

    def __init__(self, gm: GoalModel, domain: Domain, config: Configuration, world: WorldKnowledge) -> None:
        self.gm, self.domain, self.world = gm, domain, world
        self.bindings: dict[str, Binding] = {}
        self.instances: list[Instance] = []
        self.mapped: dict[str, list[tuple[str, str]]] = {}
        for vm in config.var_mapping:
            self.mapped.setdefault(vm.task_id, []).extend(vm.pairs)

    def node(self, node: GMNode, above: _Above) -> RatNode:
        if node.kind == "task":
            return self._task(node, above)
        if node.goal_type == "Query" and node.query is not None:
            self._query(node)
            return self._leaf(node)
        if node.context is not None and node.context.kind == "trigger":
            above = replace(above, events=above.events + (node.context.text,))
        if not node.children:
            return self._leaf(node)
        if node.forall is None:
            return self._refined(node, above)
        return self._copies(node, above)

    def _leaf(self, node: GMNode) -> RatNode:
        return RatNode("goal", node.id, node, dict(self.bindings))

    def _scope(self, kind: str, content: str, node: GMNode, inner: bool = False) -> RatNode:
        return RatNode(kind, content, node, dict(self.bindings), group=node.group, divisible=node.divisible,
                       or_decomposed=node.or_decomposed, inner=inner)

    def _query(self, node: GMNode) -> None:
        """A Query goal binds its first controlled variable to what its select finds: the
        records' ids for a collection, else the first one ("" when none)."""
        assert node.query is not None
        if not node.controls:
            raise Unresolved(f"query goal {node.id} controls no variable")
        records = run_select(node.query, self.world, self.bindings)
        ids = tuple(record_id(r, self.world.unique_id) or "" for r in records)
        var = node.controls[0]
        self.bindings[var.name] = (Binding(ids, var.type, tuple(records)) if var.is_collection
                                   else Binding(ids[0] if ids else "", var.type, tuple(records[:1])))

    def _copies(self, node: GMNode, above: _Above) -> RatNode:
        """A forAll: its subtree once per element of the iterated collection, the iteration
        variable bound to the element, under a parallel node when there are several."""
        assert node.forall is not None
        iterated = self.bindings.get(node.forall.iterated)
        if iterated is None or not isinstance(iterated.value, tuple):
            raise Unresolved(f"goal {node.id}: forAll over {node.forall.iterated}, which holds no collection")
        sort = next((d.type for d in node.controls if d.name == node.forall.iteration), "")
        copies = []
        for number, (value, record) in enumerate(zip(iterated.value, iterated.records), start=1):
            self.bindings[node.forall.iteration] = Binding(value, sort, (record,))
            copies.append(self._refined(node, replace(above, elements=above.elements + (number,))))
        if len(copies) < 2:
            return copies[0] if copies else self._leaf(node)
        return RatNode("op", "#", None, dict(self.bindings), copies)

    def _refined(self, node: GMNode, above: _Above) -> RatNode:
        """A goal's refinement: a means-end node over its only child, else the operators of its
        annotation (``#`` over the children when it has none), whose entries take the children
        in order."""
        children = [self.gm.node(c) for c in node.children]
        if len(children) == 1:
            means = self._scope("meansend", node.id, node)
            means.children.append(self.node(children[0], above))
            return means
        annotation = node.annotation if isinstance(node.annotation, AnnotationOp) else \
            AnnotationOp("#", tuple(AnnotationLeaf(c.id) for c in children))
        if node.or_decomposed and annotation.op != "#":
            raise Unresolved(f"OR decomposed goal {node.id} has a {annotation.op} runtime annotation")
        return self._operator(annotation, node, above, iter(children), False)

    def _operator(self, a: AnnotationOp | AnnotationLeaf, node: GMNode, above: _Above, children: Iterator[GMNode],
                  inner: bool) -> RatNode:
        if isinstance(a, AnnotationLeaf):
            child = next(children, None)
            if child is None:
                raise Unresolved(f"the runtime annotation of goal {node.id} names more children than it has")
            return self.node(child, above)
        op = self._scope("op", a.op, node, inner)
        op.children.extend(self._operator(c, node, above, children, True) for c in a.children)
        return op

    def _task(self, node: GMNode, above: _Above) -> RatNode:
        name = node.task_name or ""
        if name not in self.domain.task_by_name:
            raise Unresolved(f"task {node.id} names {name!r}, which is no abstract task of the domain")
        location = self.bindings.get(node.location) if node.location else None
        missing = next((p for p in node.params if p not in self.bindings), None)
        if missing is not None:
            raise Unresolved(f"task {node.id}: parameter {missing} has no value")
        variables = ([node.location] if node.location and location is not None else []) + list(node.params)
        params = tuple((hddl, self.bindings[var].value) for var in variables
                       for gm_var, hddl in self.mapped.get(node.id, []) if gm_var == var)
        parent = self.gm.node(node.parent) if node.parent else None
        sequential = (parent is not None and isinstance(parent.annotation, AnnotationOp)
                      and parent.annotation.op == ";" and len(parent.children) > 1)
        inst = Instance(node.id + "".join(f"_{i}" for i in above.elements or (1,)), node, name,
                        node.robot_number or robot_count(self.domain, name),
                        None if location is None else location.value,
                        params, () if sequential else above.events,
                        parent.group if parent else True, parent.divisible if parent else True)
        self.instances.append(inst)
        return RatNode("task", inst.id, node, dict(self.bindings), instance=inst)


def expand_mission(gm: GoalModel, domain: Domain, config: Configuration,
                   world: WorldKnowledge) -> tuple[RatNode, list[Instance]]:
    """The runtime annotation tree and the task instances in creation order; :class:`Unresolved`
    when the goal model cannot be expanded against this world."""
    reading = _Reading(gm, domain, config, world)
    return reading.node(gm.node(gm.root), _Above()), reading.instances
