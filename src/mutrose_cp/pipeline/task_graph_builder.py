"""Building the Task Graph (spec ``semantics.md`` §5), shared by both decomposition algorithms.

The graph is built from the runtime annotation tree (§5.1) with its context dependencies
(§5.2, §5.3) and execution constraints (§5.4), then reduced to the "minimal Task Graph" (§5.5)
whose vertex order fixes the output keys ``t0, t1, ...``.  The types are in
:mod:`mutrose_cp.model.task_graph`; a :class:`TaskGraphBuilder` is frozen once the rules are done.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Callable, Collection, Sequence

from .annotation_tree import GOAL, MEANSEND, TASK, RatNode
from ..model.state_tests import Test
from .conditions import holds, translate
from ..errors import MissionError
from .expansion import Expansion
from ..model.decomposition_paths import DecompositionPath
from .htn import expand_path, ground_path
from ..model import Configuration, GoalModel, InitialState
from ..model.task_graph import (
    Decomposition,
    DecompositionVertex,
    EdgeKind,
    GoalVertex,
    OperatorVertex,
    ScopeVertex,
    TaskGraph,
    TaskGraphBuilder,
    TaskVertex,
)
from .stamping import Stamper, StampingPlan, plan_stamping

AND, OR, CD, EC = EdgeKind.AND, EdgeKind.OR, EdgeKind.CD, EdgeKind.EC


class _Builder:
    """Initial build (§5.1) with context dependencies (§5.2)."""

    def __init__(self, exp: Expansion, gm: GoalModel, config: Configuration, state: InitialState,
                 paths: dict[str, list[DecompositionPath]]) -> None:
        self.exp = exp
        self.gm = gm
        self.config = config
        self.state = state
        self.paths = paths
        self.tg = TaskGraphBuilder()
        self.instances = {i.id: i for i in exp.instances}
        self.cd_edges: list[tuple[int, int]] = []
        # every enabled creation condition from a scope vertex up to the root, innermost first:
        # a task below must meet them all where it starts
        self.contexts_in_scope: dict[int, tuple[Test, ...]] = {}
        # for stamping (mutrose_cp.pipeline.stamping): the forAll copies left out (by id of their RAT
        # node), the vertex range of each copy built, the RAT node of each vertex (a
        # decomposition's: its task's), and whether a false context made the build search it
        self.skip: frozenset[int] = frozenset()
        self.copy_ranges: dict[int, tuple[int, int]] = {}
        self.origins: list[RatNode] = []
        self.searched = False
        self.copy_states: dict[int, WalkState] = {}  # first vertex of a copy -> the EC walk's state there

    def build(self) -> tuple[TaskGraphBuilder, list[tuple[int, int]]]:
        """The initial graph and its CD edges to redirect (§5.3); the builder's per-vertex maps
        are dropped with it."""
        self._visit(self.exp.rat, None, None)
        return self.tg, self.cd_edges

    def _context_test(self, goal_id: str, node: RatNode) -> Test | None:
        g = self.gm.node(goal_id)
        if g.context is None or g.context.kind != "condition" or g.context.condition is None:
            return None
        return translate(g.context.condition, node.var_maps, self.config, f"{self.gm.source}: goal {goal_id}")

    def _visit(self, node: RatNode, parent: ScopeVertex | None, parent_rat: RatNode | None) -> None:
        edge = OR if parent_rat is not None and parent_rat.or_decomposition else AND
        if node.kind == GOAL:
            return
        if node.kind == TASK:
            if parent is None:
                raise MissionError("the goal model's root is a task; a mission needs a root goal", self.gm.source)
            self._add_task(node, parent, edge)
            return
        vertex = self._scope_vertex(node, parent, edge)
        if vertex is None:
            return  # a false context that nothing enables: the branch disappears
        if not (node.is_forall_dummy and self.skip):
            for child in node.children:
                self._visit(child, vertex, node)
            return
        for child in node.children:  # forAll copies, some left out to be stamped
            if id(child) not in self.skip:
                start = self.tg.next_index
                self._visit(child, vertex, node)
                self.copy_ranges[id(child)] = (start, self.tg.next_index)

    def _scope_vertex(self, node: RatNode, parent: ScopeVertex | None, edge: EdgeKind) -> ScopeVertex | None:
        """The operator or means-end goal vertex of ``node``, added to the graph below ``parent``
        through an ``edge``, or None when its goal's creation condition is false and no earlier
        task can make it true."""
        test = None
        if node.is_forall_dummy:
            goal = node.children[0].related_goal
            is_forall, is_achieve = True, False
        else:
            goal = node.related_goal
            is_forall = False
            gm_goal = self.gm.node(goal) if goal else None
            is_achieve = bool(gm_goal is not None and gm_goal.goal_type == "Achieve" and not node.inner)
            if not node.inner and goal:
                test = self._context_test(goal, node)
        contexts: tuple[Test, ...] = ()
        pending: list[int] = []
        if test is not None and not holds(test, self.state.value_of, self.state.function_value):
            if not self._enabled(test, parent, pending):
                return None
            contexts = (test,)
        kind = GoalVertex if node.kind == MEANSEND else OperatorVertex
        vertex = kind(
            index=self.tg.next_index, parent=parent.index if parent else -1, content=node.content,
            group=node.group, divisible=node.divisible, goal=goal, forall=is_forall,
            achieve=is_achieve and not (parent is not None and parent.forall),
            var_maps=node.var_maps, contexts=contexts,
        )
        if parent is None:
            self.tg.add(vertex)
        else:
            self.tg.add_child(vertex, edge)
        self.origins.append(node)
        self.cd_edges.extend((d, vertex.index) for d in pending)
        self.contexts_in_scope[vertex.index] = contexts + (self.contexts_in_scope[parent.index] if parent else ())
        return vertex

    def _add_task(self, node: RatNode, parent: ScopeVertex, edge: EdgeKind) -> None:
        tg = self.tg
        inst = self.instances.get(node.content)
        if inst is None:
            raise MissionError(f"Could not find AT {node.content} definition", self.gm.source)
        if not parent.group and not (inst.robot_number.fixed and inst.robot_number.min == 1):
            raise MissionError(
                f"Non group task [{inst.id}] does not have 1 robot in its declaration "
                "(tasks under a goal with Group=False are executed by one robot: set RobotNumber to 1)",
                f"{self.gm.source}: task {inst.gm_task}",
            )
        flags = {"group": parent.group, "divisible": parent.divisible}
        tv = tg.add_child(TaskVertex(index=tg.next_index, parent=parent.index, content=inst.id, instance=inst,
                                     contexts=self.contexts_in_scope[parent.index], **flags), edge)
        origins = self.origins
        origins.append(node)
        binding = inst.binding
        for n, path in enumerate(self.paths[inst.name], start=1):
            dec = Decomposition(f"{inst.id}|{n}", inst, n, path, ground_path(path, binding))
            tg.add_child(DecompositionVertex(index=tg.next_index, parent=tv.index, content=dec.id,
                                             decomposition=dec, **flags), AND)
            origins.append(node)

    def _enabled(self, test: Test, parent: ScopeVertex | None, pending: list[int]) -> bool:
        """Search the already-built graph for tasks that can make a false context true (§5.2);
        the enabling decompositions below a parallel operator go to ``pending`` (CD edges)."""
        tg = self.tg
        self.searched = True
        visited: set[int] = set()

        def search(v: int, par: bool) -> bool:
            if v == -1:
                return False
            vx = tg.vertices[v]
            if isinstance(vx, TaskVertex):
                return self._task_enables(test, v, par, pending)
            if tg.is_or(v) or vx.content == "FALLBACK":
                if v == 0:
                    return False
                visited.add(v)
                return search(vx.parent, False)
            par2 = par or (isinstance(vx, OperatorVertex) and vx.content == "#")
            for u in tg.children(v):
                if u in visited:
                    continue
                found = search(u, par2)
                visited.add(u)
                if found:
                    return True
            visited.add(v)
            return search(vx.parent, False)

        return search(parent.index if parent else -1, False)

    def _task_enables(self, test: Test, task: int, parallel: bool, pending: list[int]) -> bool:
        """Whether some decomposition of ``task`` makes ``test`` true; below a parallel operator
        each such decomposition is recorded in ``pending``."""
        state = self.state
        ok = False
        for dv in self.tg.decompositions_of(task):
            effects = {(e.predicate, e.args): e.positive for e in dv.decomposition.predicates.ground_effects}

            def fact(p: str, a: tuple[str, ...], effects: dict[tuple[str, tuple[str, ...]], bool] = effects) -> bool | None:
                return effects[(p, a)] if (p, a) in effects else state.value_of(p, a)

            if holds(test, fact, state.function_value):
                if parallel:
                    pending.append(dv.index)
                ok = True
        return ok


def _final_context_edges(tg: TaskGraphBuilder, cd_edges: list[tuple[int, int]]) -> None:
    """Redirect each CD edge ``d -> goal`` to every task vertex below the goal (§5.3)."""
    for d, c in cd_edges:
        stack, seen, targets = [c], {c}, []
        while stack:
            v = stack.pop()
            if isinstance(tg.vertices[v], TaskVertex):
                targets.append(v)
            for u, _k in reversed(tg.successors(v)):
                if u not in seen:
                    seen.add(u)
                    stack.append(u)
        linked = {u for u, _kind in tg.successors(d)}  # (execution constraints come later, between tasks)
        for t in sorted(targets):
            if t not in linked:  # one decomposition can enable the tasks of every forAll copy
                tg.add_new_edge(d, t, CD)
                linked.add(t)


# where the walk of §5.4 stands: the active scope, the scopes it suspends, the tasks met in it
WalkState = tuple[int | None, tuple[int, ...], tuple[int, ...]]


class _ExecutionScopes:
    """The walk of §5.4 in vertex order: the active Group/Divisible scope (a stack of nested
    ones whose enclosing scope allows it), the tasks already met in it, and the snapshots that
    forAll copies and OR alternatives restart from."""

    def __init__(self, tg: TaskGraphBuilder, link: Callable[[Sequence[int], int, bool, bool], None]) -> None:
        self.tg = tg
        self.link = link  # adds the execution constraints of one met task (see meet_task)
        self.active: int | None = None
        self.stack: list[int] = []
        self.flags: dict[int, tuple[bool, bool]] = {}
        self.tasks: list[int] = []
        self.snapshots: dict[int, list[int]] = {}
        self.or_nodes: set[int] = set()

    def leave_finished(self, parent: int) -> None:
        """Close the active scope when the walk has left it, and restart the met tasks at the
        start of a new forAll copy or OR alternative."""
        tg = self.tg
        if self.active is None:
            return
        if parent <= tg.vertices[self.active].parent:
            if not self.stack:
                self.tasks = []
                self.active = None
            else:
                self.active = self.stack.pop()
        above = tg.vertices[parent] if parent >= 0 else None
        restart_forall = isinstance(above, ScopeVertex) and above.forall and self.active is not None \
            and self.active >= parent
        if restart_forall or parent in self.or_nodes:
            self.tasks = list(self.snapshots.get(parent, []))

    def enter_scope(self, v: int, vertex: ScopeVertex) -> None:
        """Note OR nodes and snapshots, and open a scope at a Group=False or Divisible=False
        vertex (nested inside an active scope only if that one is a group)."""
        if self.tg.is_or(v):
            self.or_nodes.add(v)
        if vertex.forall or v in self.or_nodes:
            self.snapshots[v] = list(self.tasks)
        if vertex.group and vertex.divisible:
            return
        if self.active is None:
            self.flags[v] = (vertex.group, vertex.divisible)
            self.active = v
        elif self.flags[self.active][0]:
            self.flags[v] = (vertex.group, vertex.divisible)
            self.stack.append(self.active)
            self.active = v

    def meet_task(self, v: int) -> None:
        """Constrain task ``v`` with every task met before it in the active scope."""
        if self.active is None:
            return
        group, divisible = self.flags[self.active]
        self.link(sorted(self.tasks), v, group, divisible)
        self.tasks.append(v)


def _execution_constraint_edges(tg: TaskGraphBuilder,
                                link: Callable[[Sequence[int], int, bool, bool], None] | None = None,
                                watched: Collection[int] = ()) -> dict[int, WalkState]:
    """EC edges from Group/Divisible with the original's priority rules (§5.4), walked on the
    untrimmed graph (whose scopes decide them) and added by ``link`` (default: into ``tg``).
    Returns the state the walk meets each ``watched`` vertex in (the first vertices of forAll
    copies, for stamping: the walk carries scopes from one copy into the next)."""
    scopes = _ExecutionScopes(tg, link or tg.add_ec_to_all)
    states: dict[int, WalkState] = {}
    for v, vx in enumerate(tg.vertices):
        scopes.leave_finished(vx.parent)
        if v in watched:
            states[v] = (scopes.active, tuple(scopes.stack), tuple(scopes.tasks))
        if isinstance(vx, ScopeVertex):
            scopes.enter_scope(v, vx)
        elif isinstance(vx, TaskVertex):
            scopes.meet_task(v)
    return states


def _is_unique_branch(tg: TaskGraphBuilder) -> bool:
    return not any(isinstance(vx, ScopeVertex) and len(tg.children(vx.index)) >= 2 for vx in tg.vertices)


class _Trimmer:
    """The minimal Task Graph (§5.5): from the first vertex with two or more children, keep the
    operators with two or more children (or an achieve condition) and every task with its
    decompositions, each hung under its closest kept ancestor."""

    def __init__(self, tg: TaskGraphBuilder) -> None:
        self.tg = tg
        self.new = TaskGraphBuilder()
        self.index: dict[int, int] = {}  # old vertex -> new vertex

    def trim(self) -> TaskGraphBuilder:
        tg = self.tg
        root = next(v.index for v in tg.vertices if isinstance(v, ScopeVertex) and len(tg.children(v.index)) >= 2)
        # the vertices are in depth-first order and those before the root have one child at
        # most: they are the chain leading down to it, and every vertex after it is below it
        for vx in tg.vertices[root:]:
            if not isinstance(vx, ScopeVertex):
                continue
            v = vx.index
            if v == root:
                self._insert(v, None)
                self._insert_tasks(v, v)
            elif isinstance(vx, OperatorVertex) and (len(tg.children(v)) >= 2 or vx.achieve):
                self._insert(v, self._kept_ancestor(v))
                self._insert_tasks(v, v)
            else:
                self._insert_tasks(v, self._kept_ancestor(v))
        self._carry_removed_achieve_goals()
        self._copy_cd_edges()
        return self.new

    def _first_edge_kind(self, old: int) -> EdgeKind:
        kids = self.tg.children(old)
        return self.tg.edge_kind(old, kids[0]) if kids else AND

    def _insert(self, old: int, parent_old: int | None) -> None:
        if parent_old is None:
            vertex = self.new.add(self.tg.vertices[old].moved(self.new.next_index, -1))
        else:
            vertex = self.new.add_child(self.tg.vertices[old].moved(self.new.next_index, self.index[parent_old]),
                                        self._first_edge_kind(parent_old))
        self.index[old] = vertex.index

    def _insert_tasks(self, op_old: int, under_old: int) -> None:
        """The task children of ``op_old``, each followed by its decompositions, hung under the
        kept copy of ``under_old`` (the bulk of the graph: the loop is kept tight)."""
        tg, new, index = self.tg, self.new, self.index
        vertices = tg.vertices
        parent, kind = -1, AND
        for u in tg.children(op_old):
            task = vertices[u]
            if not isinstance(task, TaskVertex):
                continue
            if parent == -1:
                parent, kind = index[under_old], self._first_edge_kind(under_old)
            moved = new.add_child(task.moved(new.next_index, parent), kind).index
            index[u] = moved
            for d in tg.out(u, AND):
                index[d] = new.add_child(vertices[d].moved(new.next_index, moved), AND).index

    def _kept_ancestor(self, old: int) -> int:
        p = self.tg.vertices[old].parent
        while p not in self.index:
            p = self.tg.vertices[p].parent
        return p

    def _carry_removed_achieve_goals(self) -> None:
        """A removed achieve goal's condition is checked at the kept vertex its single-child
        chain leads down to."""
        tg, index = self.tg, self.index
        for vx in tg.vertices:
            if vx.index in index or not isinstance(vx, ScopeVertex) or not vx.achieve:
                continue
            u = vx.index
            while u not in index and len(tg.children(u)) == 1:
                u = tg.children(u)[0]
            if u in index:
                self.new.achieve_carried.setdefault(index[u], []).append(vx)

    def _copy_cd_edges(self) -> None:
        tg, index = self.tg, self.index
        for a in range(len(tg.vertices)):
            if a not in index:
                continue
            for b, kind in tg.successors(a):
                if kind == CD and b in index:  # (a, b) has one kind: the copy is a new edge
                    self.new.add_new_edge(index[a], index[b], CD)

    def link_kept(self, tasks: Sequence[int], v: int, group: bool, divisible: bool) -> None:
        """Execution constraints met on the untrimmed graph, added between the kept copies of
        its tasks: the same partners in the same order as constraining there and copying
        afterwards, without holding every edge twice."""
        index, new = self.index, self.new
        if v not in index:
            return
        new.add_ec_to_all([index[t] for t in tasks if t in index], index[v], group, divisible)


def build_task_graph(exp: Expansion, gm: GoalModel, config: Configuration, state: InitialState,
                     paths: dict[str, list[DecompositionPath]], *, stamp: bool = True) -> TaskGraph:
    """Build, connect and trim the Task Graph of an expanded mission.  With ``stamp``, forAll
    copies identical up to renaming are built once and stamped where that gives the same graph
    (:func:`stamped_task_graph`)."""
    builder = _Builder(exp, gm, config, state, paths)
    plan = plan_stamping(exp.rat, builder.instances, gm, paths) if stamp else None
    if plan is not None:
        stamped = _stamped(builder, plan)
        if stamped is not None:
            return stamped
        builder = _Builder(exp, gm, config, state, paths)  # the reduced build used the first
    graph, trimmer = _connected(builder)
    return graph.freeze(unique_branch=trimmer is None)


def stamped_task_graph(exp: Expansion, gm: GoalModel, config: Configuration, state: InitialState,
                       paths: dict[str, list[DecompositionPath]]) -> TaskGraph | None:
    """The Task Graph built with the first copies of each shape of the forAll goals that allow
    it and stamped for the others (:mod:`mutrose_cp.pipeline.stamping`), or None when no forAll allows
    it or a rule of stamping fails on the reduced graph."""
    builder = _Builder(exp, gm, config, state, paths)
    plan = plan_stamping(exp.rat, builder.instances, gm, paths)
    return None if plan is None else _stamped(builder, plan)


def _stamped(builder: _Builder, plan: StampingPlan) -> TaskGraph | None:
    """The graph ``builder`` builds without the copies ``plan`` leaves out, those stamped in."""
    builder.skip = plan.skipped
    reduced, trimmer = _connected(builder)
    if trimmer is None or builder.searched:
        return None
    stamped = Stamper(plan, reduced, trimmer.index, builder.origins, builder.copy_ranges, builder.copy_states,
                      builder.instances).stamp()
    return None if stamped is None else stamped.freeze()


def _connected(builder: _Builder) -> tuple[TaskGraphBuilder, _Trimmer | None]:
    """The graph of ``builder`` with its context dependencies and execution constraints, trimmed
    (§5.5) with the trimmer that did it; a unique-branch graph is not trimmed
    (§7.7), and comes with None.  The walk's state at the first vertex of each forAll copy
    built goes to ``builder.copy_states``."""
    tg, cd_edges = builder.build()
    if not tg.vertices:
        raise MissionError("the mission has no task: every branch was removed or no task instance exists",
                           builder.gm.source)
    _final_context_edges(tg, cd_edges)
    _expand_recursions(tg, builder.state)
    if _is_unique_branch(tg):
        _execution_constraint_edges(tg)
        return tg, None
    trimmer = _Trimmer(tg)
    trimmed = trimmer.trim()
    trimmed.warnings = tg.warnings
    tg.release_lookups()  # the walk reads the untrimmed vertices and successors while the trimmed graph fills
    builder.copy_states = _execution_constraint_edges(tg, trimmer.link_kept,
                                                      {start for start, _ in builder.copy_ranges.values()})
    return trimmed, trimmer


def _expand_recursions(tg: TaskGraphBuilder, state: InitialState) -> None:
    """Unroll recursive methods as often as the initial world state asks (§7.6), in every
    kind of mission: the original skips unique-branch missions, where a recursion then runs
    once whatever the world holds (docs/deviations.md, fix 23).

    The original computes the repetitions from the world state at the point where the
    decomposition is accepted; here the initial state is used, so that the decomposition does
    not depend on the combination (docs/deviations.md)."""
    for v in tg.decompositions():
        dec = v.decomposition
        if not dec.path.needs_expansion:
            continue
        binding = dec.instance.binding
        path = expand_path(dec.path, binding, state.function_value, dec.id, tg.warnings.append)
        tg.replace(replace(v, decomposition=Decomposition(dec.id, dec.instance, dec.number, path,
                                                          ground_path(path, binding))))
