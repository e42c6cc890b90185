"""Goal-model expansion against the world (spec ``semantics.md`` §3 and §4).

One depth-first walk of the goal model, children left to right, does what the original does in
two passes that visit nodes in the same order: it resolves query goals, iterates universal
achieve goals (``forAll``), creates the abstract-task instances (ids ``AT1_2_1``, locations,
parameter values, triggering events) and builds the runtime annotation tree over them.

Annotation children are paired with the goal's children *positionally* (left to right), as the
original does; nested operators of one annotation belong to the same goal and share its flags
(the original mis-pairs them; see ``docs/deviations.md``).
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Iterator, Mapping, NamedTuple

from .annotation_tree import GOAL, MEANSEND, OPERATOR, TASK, RatNode
from ..errors import MissionError, Problem
from ..model import (
    Annotation,
    AnnotationLeaf,
    AnnotationOp,
    Binding,
    Configuration,
    Domain,
    GMNode,
    GoalModel,
    RobotNumber,
    WorldKnowledge,
)
from ..model.records import record_id
from .query import Element, run_select
from ..model.task_instances import Value, ParameterValue, TaskInstance



MAX_GOAL_DEPTH = 10_000  # goal levels; deeper models are refused with the goal named






@dataclass
class Expansion:
    instances: list[TaskInstance]
    rat: RatNode
    bindings: dict[str, Binding]  # global variable values after the walk (last forAll element)


def infer_robot_number(domain: Domain, task_name: str) -> RobotNumber:
    """Without ``RobotNumber``: the number of parameters typed ``robot`` or a direct subtype."""
    task = domain.task_by_name[task_name]
    robot_like = {t for t, p in domain.types if p == "robot"} | {"robot"}
    n = sum(1 for p in task.parameters if p.type in robot_like)
    return RobotNumber(n, n, True)


class _TaskShape(NamedTuple):
    """What every instance of a goal-model task shares (:meth:`_Walker._task_shape`)."""

    name: str  # the HDDL abstract task
    robots: RobotNumber
    mapped: dict[str, list[str]]  # goal-model variable -> the HDDL parameters it maps to
    sequential: bool  # a step of a sequence: it takes no trigger events


class _ReadBindings(Mapping[str, Binding]):
    """The variable values, telling whether a query read any of them."""

    def __init__(self, bindings: Mapping[str, Binding]) -> None:
        self._bindings = bindings
        self.read = False

    def __getitem__(self, name: str) -> Binding:
        self.read = True
        return self._bindings[name]

    def __iter__(self) -> Iterator[str]:
        self.read = True
        return iter(self._bindings)

    def __len__(self) -> int:
        self.read = True
        return len(self._bindings)


class _Walker:
    def __init__(self, gm: GoalModel, domain: Domain, config: Configuration, world: WorldKnowledge,
                 progress: Callable[[int, int], None] | None = None) -> None:
        self.progress = progress
        self.gm = gm
        self.domain = domain
        self.config = config
        self.world = world
        self.bindings: dict[str, Binding] = {}  # changed only through _bind
        self._shared: Mapping[str, Binding] | None = None
        self.counters: dict[int, int] = {}  # depth -> current forAll index (1-based)
        self.events: dict[int, str] = {}  # depth -> trigger event text
        self.instances: list[TaskInstance] = []
        self._robot_numbers: dict[str, RobotNumber] = {}  # by goal-model task, one record per value
        self._task_shapes: dict[str, _TaskShape] = {}  # by goal-model task
        self._static_queries: dict[str, list[Element]] = {}  # by query goal: the queries that read no variable
        self.var_mapping: dict[str, list[tuple[str, str]]] = {}
        for vm in config.var_mapping:
            self.var_mapping.setdefault(vm.task_id, []).extend(vm.pairs)
        self.declared_types: dict[str, str] = {}
        for n in gm.nodes:
            for d in n.controls:
                self.declared_types.setdefault(d.name, d.type)

    # -- helpers -----------------------------------------------------------------------------
    def _robot_number(self, node: GMNode, task_name: str) -> RobotNumber:
        """The robot number of ``node``'s instances (given, or inferred from the HDDL task once
        per goal-model task), one record per value in the whole mission: thousands of instances
        share it, and execution-constrained tasks that share it agree without a check (a million
        linked pairs on large missions, see ``constraints``)."""
        robots = self._robot_numbers.get(node.id)
        if robots is None:
            value = node.robot_number or infer_robot_number(self.domain, task_name)
            same = next((r for r in self._robot_numbers.values() if r == value), value)
            robots = self._robot_numbers[node.id] = same
        return robots

    def _enter(self, depth: int) -> None:
        """Forget the forAll indexes and trigger events of the levels at ``depth`` and below.
        A level is only ever added below the deepest one kept (entering it forgets the rest),
        so the tables are ordered by depth and the deepest are dropped from their end."""
        for table in (self.counters, self.events):
            while table and next(reversed(table)) >= depth:
                table.popitem()

    def _bind(self, name: str, binding: Binding) -> None:
        self.bindings[name] = binding
        self._shared = None  # the next snapshot is a new one

    def _snapshot(self) -> Mapping[str, Binding]:
        """The variable values at this node.  Nodes between two changes of the bindings share
        one copy (never modified: readers build new mappings), so memory grows with the changes,
        not with goals times variables."""
        if self._shared is None:
            self._shared = dict(self.bindings)
        return self._shared

    def _leaf_snapshot(self, node: GMNode) -> Mapping[str, Binding]:
        """A goal leaf (a query, an empty forAll) keeps only the variables it declares: what is
        shown for it.  Thousands of query goals would otherwise each copy every variable."""
        names = [d.name for d in (*node.controls, *node.monitors)]
        if node.forall is not None:
            names += [node.forall.iterated, node.forall.iteration]
        return {n: self.bindings[n] for n in names if n in self.bindings}

    def _where(self, node: GMNode) -> str:
        return f"{self.gm.source}: {'goal' if node.kind == 'goal' else 'task'} {node.id}"

    def _resolve_query(self, node: GMNode) -> None:
        assert node.query is not None
        if not node.controls:
            raise MissionError(f"No controlled variable was declared for Query goal [{node.id}]", self._where(node))
        records = self._static_queries.get(node.id)
        if records is None:
            read = _ReadBindings(self.bindings)
            try:
                records = run_select(node.query, self.world, read, node.id)
            except MissionError as err:  # locate world-dependent query problems in the goal model
                raise MissionError([Problem(self._where(node), p.message) if p.where in ("", node.id) else p
                                    for p in err.problems]) from None
            if not read.read:  # the same records every time: a forAll asks it once per element
                self._static_queries[node.id] = records
        var = node.controls[0]
        ids = tuple(record_id(r, self.world.unique_id) or "" for r in records)
        if var.is_collection:
            self._bind(var.name, Binding(ids, var.type, tuple(records)))
        else:
            self._bind(var.name, Binding(ids[0] if ids else "", var.type, tuple(records[:1])))

    # -- the walk ----------------------------------------------------------------------------
    def walk(self, node: GMNode, depth: int) -> RatNode:
        if depth > MAX_GOAL_DEPTH:
            raise MissionError(f"the goal model is nested more than {MAX_GOAL_DEPTH} levels deep here; "
                               "flatten the chain of single-child goals", self._where(node))
        self._enter(depth)
        if node.kind == "task":
            return self._task(node)
        if node.goal_type == "Query" and node.query is not None:
            self._resolve_query(node)
            return RatNode(GOAL, node.id, node.key, var_maps=self._leaf_snapshot(node))
        if node.context is not None and node.context.kind == "trigger":
            self.events[depth] = node.context.text
        if not node.children:
            return RatNode(GOAL, node.id, node.key, var_maps=self._leaf_snapshot(node))
        if node.forall is not None:
            return self._forall(node, depth)
        return self._expand(node, depth)

    def _forall(self, node: GMNode, depth: int) -> RatNode:
        fa = node.forall
        assert fa is not None
        iterated = self.bindings.get(fa.iterated)
        if iterated is None or not isinstance(iterated.value, tuple):
            raise MissionError(
                f"forAll iterates over {fa.iterated}, which does not hold a collection "
                "(declare it with a Sequence type and fill it with a Query goal first)",
                self._where(node),
            )
        decl = next((d for d in node.controls if d.name == fa.iteration), None)
        it_type = decl.type if decl is not None else ""
        elements = list(zip(iterated.value, iterated.records))
        if not elements:
            return RatNode(GOAL, node.id, node.key, var_maps=self._leaf_snapshot(node))
        self.counters[depth] = 1
        copies: list[RatNode] = []
        outermost = len(self.counters) == 1
        for i, (value, record) in enumerate(elements):
            self.counters[depth] = i + 1
            self._bind(fa.iteration, Binding(value, it_type, (record,)))
            copies.append(self._expand(node, depth))
            if outermost and self.progress is not None:
                self.progress(i + 1, len(elements))
        if len(copies) == 1:
            return copies[0]
        return RatNode(OPERATOR, "#", "", copies, var_maps=self._snapshot(), is_forall_dummy=True)

    def _expand(self, node: GMNode, depth: int) -> RatNode:
        """The operator structure of a goal with children, its leaves paired left to right."""
        children = [self.gm.node(c) for c in node.children]
        snapshot = self._snapshot()
        if len(children) == 1:
            rat = RatNode(MEANSEND, node.id, node.key, [], group=node.group, divisible=node.divisible,
                          or_decomposition=node.or_decomposed, var_maps=snapshot)
            rat.children.append(self.walk(children[0], depth + 1))
            return rat
        annotation: AnnotationOp = node.annotation if isinstance(node.annotation, AnnotationOp) else AnnotationOp(
            "#", tuple(AnnotationLeaf(c.id) for c in children)
        )
        if node.or_decomposed and annotation.op in (";", "FALLBACK"):
            kind = "sequential" if annotation.op == ";" else "fallback"
            raise MissionError(f"OR decomposed goal cannot have {kind} runtime annotations", self._where(node))
        return self._annotation_node(annotation, False, node, depth, list(children), snapshot)

    def _annotation_node(self, a: Annotation, inner: bool, node: GMNode, depth: int, queue: list[GMNode],
                         snapshot: Mapping[str, Binding]) -> RatNode:
        """The node of annotation ``a`` of ``node``'s goal; its leaves take the goal's children
        from ``queue`` in order.  (A method rather than a recursive closure: such a closure is a
        reference cycle, which the paused cyclic collector never frees, one per goal.)"""
        if isinstance(a, AnnotationLeaf):
            if not queue:
                raise MissionError(
                    f"runtime annotation names more children than the goal has ({a.name})", self._where(node)
                )
            return self.walk(queue.pop(0), depth + 1)
        op = RatNode(OPERATOR, a.op, node.key, [], group=node.group, divisible=node.divisible,
                     or_decomposition=node.or_decomposed, var_maps=snapshot, inner=inner)
        for c in a.children:
            op.children.append(self._annotation_node(c, True, node, depth, queue, snapshot))
        return op

    def _task(self, node: GMNode) -> RatNode:
        shape = self._task_shapes.get(node.id)
        if shape is None:
            shape = self._task_shapes[node.id] = self._task_shape(node)
        name, robots, mapped, sequential = shape
        # counters and events are ordered by depth (see _enter)
        suffix = "".join(f"_{i}" for i in self.counters.values()) or "_1"
        inst_id = f"{node.id}{suffix}"
        bindings = self.bindings
        location: Value | None = None
        variables: list[str] = []
        if node.location:
            b = bindings.get(node.location)
            if b is not None:
                location = b.value
                variables.append(node.location)
        for p in node.params:
            if p not in bindings:
                raise MissionError(f"Could not find value for parameter [{p}] for task [{name}]", self._where(node))
            variables.append(p)
        params: list[ParameterValue] = []
        for var in variables:
            b = bindings[var]
            for hddl_var in mapped.get(var, ()):
                params.append(ParameterValue(hddl_var, b.value, b.type, var))
        events = () if sequential else tuple(self.events.values())
        inst = TaskInstance(inst_id, node.id, name, robots, location, tuple(params), events)
        self.instances.append(inst)
        return RatNode(TASK, inst_id, node.key, var_maps=self._snapshot())

    def _task_shape(self, node: GMNode) -> _TaskShape:
        """What every instance of a goal-model task shares, worked out at its first instance: the
        HDDL task, the robot number, the HDDL parameters each goal-model variable maps to (in the
        configuration's order), and whether it is a step of a sequence (which drops trigger
        events).  A forAll makes thousands of instances of each."""
        name = node.task_name or ""
        if name not in self.domain.task_by_name:
            raise MissionError(f"Could not find AT [{name}] in HDDL Domain definition.", self._where(node))
        mapped: dict[str, list[str]] = {}
        for gm_var, hddl_var in self.var_mapping.get(node.id, []):
            mapped.setdefault(gm_var, []).append(hddl_var)
        parent = self.gm.node(node.parent) if node.parent else None
        sequential = (
            parent is not None
            and isinstance(parent.annotation, AnnotationOp)
            and parent.annotation.op == ";"
            and len(parent.children) > 1
        )
        return _TaskShape(name, self._robot_number(node, name), mapped, sequential)


def expand(gm: GoalModel, domain: Domain, config: Configuration, world: WorldKnowledge,
           progress: Callable[[int, int], None] | None = None) -> Expansion:
    """Expand the goal model against the world: task instances and the runtime annotation tree
    (``progress`` is told how many instances of the outermost forAll are done)."""
    walker = _Walker(gm, domain, config, world, progress)
    rat = walker.walk(gm.node(gm.root), 0)
    return Expansion(walker.instances, rat, walker.bindings)
