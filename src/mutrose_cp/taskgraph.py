"""The Task Graph (spec ``semantics.md`` §5), shared by both decomposition algorithms.

Vertices are operators (``;``, ``#``, ``FALLBACK``), means-end goal nodes, task instances and
their decompositions; edges are AND/OR refinements, context dependencies (CD) and execution
constraints (EC).  The graph is built from the runtime annotation tree, then reduced to the
"minimal Task Graph" whose vertex order fixes the output keys ``t0, t1, ...``.
"""
from __future__ import annotations

import copy
from dataclasses import dataclass, field
from typing import Iterator, Mapping


from .annotation_tree import GOAL, MEANSEND, TASK, RatNode
from .conditions import Test, holds, translate
from .errors import MissionError
from .expansion import Expansion, TaskInstance
from .htn import DecompositionPath, GroundPredicates, expand_path, ground_path
from .io.config import Configuration
from .io.goal_model import GoalModel
from .query import Binding
from .world import InitialState

AND, OR, CD, EC = "AND", "OR", "CD", "EC"
OP, GOALNODE, ATASK, DECOMPOSITION = "op", "goal", "task", "decomposition"


@dataclass(frozen=True)
class Decomposition:
    """One HTN decomposition path of one task instance: ``AT1_1|2``."""

    id: str
    instance: TaskInstance
    number: int  # 1-based path number
    path: DecompositionPath
    predicates: GroundPredicates


@dataclass
class Vertex:
    index: int
    kind: str  # OP | GOALNODE | ATASK | DECOMPOSITION
    content: str  # operator symbol, goal id, instance id or decomposition id
    parent: int = -1
    group: bool = True
    divisible: bool = True
    related_goal: str | None = None
    is_forall: bool = False
    is_achieve_type: bool = False
    achieve_goal: str | None = None
    instance: TaskInstance | None = None
    decomposition: Decomposition | None = None
    var_maps: Mapping[str, Binding] = field(default_factory=dict)  # variable values at this node
    # goal/operator vertices: a creation condition false in the initial state that an earlier task
    # can make true (§5.2); task vertices: every such condition above them, which must hold
    # where the task starts
    contexts: tuple[Test, ...] = ()


@dataclass
class TaskGraph:
    """Vertices in index order and typed edges (``AND``, ``OR``, ``CD``, ``EC``).

    Edges are kept in plain adjacency lists, in insertion order (which the original's
    traversals depend on); :attr:`graph` gives the same graph as a networkx ``DiGraph`` for
    analysis and drawing.  Large missions have hundreds of thousands of EC edges, and building
    them directly in networkx doubled the time of the whole pipeline."""

    vertices: list[Vertex] = field(default_factory=list)
    unique_branch: bool = False
    _succ: dict[int, list[tuple[int, str]]] = field(default_factory=dict)
    _by_kind: dict[tuple[int, str], list[int]] = field(default_factory=dict)
    _edges: dict[tuple[int, int], dict] = field(default_factory=dict)  # (a, b) -> {"type": .., flags}
    # execution constraints are symmetric and numerous: task -> [(partner, group, divisible)]
    _ec: dict[int, list[tuple[int, bool, bool]]] = field(default_factory=dict)
    _ec_pairs: set[tuple[int, int]] = field(default_factory=set)
    _decs: dict[int, list[Vertex]] = field(default_factory=dict)
    # achieve goals that trimming removed (means-end goals, single-child chains above the root),
    # by the kept vertex that now stands for their subtree: their conditions are checked there
    achieve_carried: dict[int, list[Vertex]] = field(default_factory=dict)

    def add(self, vertex: Vertex) -> Vertex:
        vertex.index = len(self.vertices)
        self.vertices.append(vertex)
        self._succ[vertex.index] = []
        if vertex.kind == DECOMPOSITION:
            self._decs.setdefault(vertex.parent, []).append(vertex)
        return vertex

    def add_ec(self, a: int, b: int, group: bool, divisible: bool) -> None:
        """An execution constraint between task vertices ``a`` and ``b`` (both directions)."""
        self._ec.setdefault(a, []).append((b, group, divisible))
        self._ec.setdefault(b, []).append((a, group, divisible))
        self._ec_pairs.add((a, b))
        self._ec_pairs.add((b, a))

    def ec_partners(self, v: int) -> list[tuple[int, bool, bool]]:
        """EC partners of task ``v`` with the constraint's flags, in the order they were added."""
        return self._ec.get(v, [])

    def add_edge(self, a: int, b: int, kind: str, **flags) -> None:
        old = self._edges.get((a, b))
        if old is None:
            self._succ[a].append((b, kind))
            self._by_kind.setdefault((a, kind), []).append(b)
        elif old["type"] != kind:
            self._succ[a] = [(u, kind if u == b else k) for u, k in self._succ[a]]
            self._by_kind[(a, old["type"])].remove(b)
            self._by_kind.setdefault((a, kind), []).append(b)
        self._edges[(a, b)] = {"type": kind, **flags}

    def has_edge(self, a: int, b: int) -> bool:
        return (a, b) in self._edges or (a, b) in self._ec_pairs

    def edges(self) -> Iterator[tuple[int, int, dict]]:
        """All edges (EC ones in both directions), by source vertex and then insertion order."""
        for a in range(len(self.vertices)):
            for b, _k in self._succ[a]:
                yield a, b, self._edges[(a, b)]
            for b, group, divisible in self._ec.get(a, ()):
                yield a, b, {"type": EC, "group": group, "divisible": divisible}

    def out(self, v: int, *kinds: str) -> list[int]:
        """Successors of ``v`` through edges of the given types, in insertion order."""
        if len(kinds) == 1:
            return self._by_kind.get((v, kinds[0]), [])
        return [u for u, k in self._succ[v] if k in kinds]

    def children(self, v: int) -> list[int]:
        """AND/OR successors in insertion order (a vertex refines into one kind only)."""
        ands = self._by_kind.get((v, AND))
        ors = self._by_kind.get((v, OR))
        if ands and ors:
            return self.out(v, AND, OR)
        return ands or ors or []

    def edge_type(self, a: int, b: int) -> str:
        return self._edges[(a, b)]["type"]

    def decompositions(self) -> list[Vertex]:
        return [v for v in self.vertices if v.kind == DECOMPOSITION]

    def tasks(self) -> list[Vertex]:
        return [v for v in self.vertices if v.kind == ATASK]

    def decompositions_of(self, task: int) -> list[Vertex]:
        return self._decs.get(task, [])

    def is_or(self, v: int) -> bool:
        return any(k == OR for _, k in self._succ[v])


class _Builder:
    """Initial build (§5.1) with context dependencies (§5.2)."""

    def __init__(self, exp: Expansion, gm: GoalModel, config: Configuration, state: InitialState,
                 paths: dict[str, list[DecompositionPath]]) -> None:
        self.exp = exp
        self.gm = gm
        self.config = config
        self.state = state
        self.paths = paths
        self.tg = TaskGraph()
        self.instances = {i.id: i for i in exp.instances}
        self.cd_edges: list[tuple[int, int]] = []

    def build(self) -> TaskGraph:
        self._visit(self.exp.rat, None, None)
        return self.tg

    def _context_test(self, goal_id: str, node: RatNode) -> Test | None:
        g = self.gm.node(goal_id)
        if g.context is None or g.context.kind != "condition" or g.context.condition is None:
            return None
        return translate(g.context.condition, node.var_maps, self.config, f"{self.gm.source}: goal {goal_id}")

    def _visit(self, node: RatNode, parent: Vertex | None, parent_rat: RatNode | None) -> None:
        tg = self.tg
        edge = OR if parent_rat is not None and parent_rat.or_decomposition else AND
        if node.kind == GOAL:
            return
        if node.kind == TASK:
            if parent is None:
                raise MissionError("the goal model's root is a task; a mission needs a root goal", self.gm.source)
            self._add_task(node, parent, edge)
            return
        test = None
        if node.is_forall_dummy:
            first = node.children[0]
            goal = first.related_goal
            is_forall, is_achieve = True, False
        else:
            goal = node.related_goal
            is_forall = False
            gm_goal = self.gm.node(goal) if goal else None
            is_achieve = bool(gm_goal is not None and gm_goal.goal_type == "Achieve" and not node.inner)
            if not node.inner and goal:
                test = self._context_test(goal, node)
        vertex = Vertex(
            index=-1,
            kind=GOALNODE if node.kind == MEANSEND else OP,
            content=node.content,
            parent=parent.index if parent else -1,
            group=node.group,
            divisible=node.divisible,
            related_goal=goal,
            is_forall=is_forall,
            is_achieve_type=is_achieve and not (parent is not None and parent.is_forall),
            achieve_goal=goal,
            var_maps=node.var_maps,
        )
        if test is not None and not holds(test, self.state.value_of, self.state.function_value):
            pending: list[int] = []
            if not self._enabled(test, parent, pending):
                return  # a false context that nothing enables: the branch disappears
            vertex.contexts = (test,)
            tg.add(vertex)
            for d in pending:
                self.cd_edges.append((d, vertex.index))
        else:
            tg.add(vertex)
        if parent is not None:
            tg.add_edge(parent.index, vertex.index, edge)
        for child in node.children:
            self._visit(child, vertex, node)

    def _add_task(self, node: RatNode, parent: Vertex, edge: str) -> None:
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
        contexts: list[Test] = []
        up = parent.index
        while up >= 0:
            contexts.extend(tg.vertices[up].contexts)
            up = tg.vertices[up].parent
        tv = tg.add(Vertex(-1, ATASK, inst.id, parent.index, parent.group, parent.divisible, instance=inst,
                           contexts=tuple(contexts)))
        tg.add_edge(parent.index, tv.index, edge)
        binding = inst.binding
        for n, path in enumerate(self.paths[inst.name], start=1):
            dec = Decomposition(f"{inst.id}|{n}", inst, n, path, ground_path(path, binding))
            dv = tg.add(Vertex(-1, DECOMPOSITION, dec.id, tv.index, parent.group, parent.divisible,
                               instance=inst, decomposition=dec))
            tg.add_edge(tv.index, dv.index, AND)

    def _enabled(self, test: Test, parent: Vertex | None, pending: list[int]) -> bool:
        """Search the already-built graph for tasks that can make a false context true (§5.2)."""
        tg = self.tg
        visited: set[int] = set()
        state = self.state

        def search(v: int, par: bool) -> bool:
            if v == -1:
                return False
            vx = tg.vertices[v]
            if vx.kind != ATASK:
                if tg.is_or(v) or vx.content == "FALLBACK":
                    if v == 0:
                        return False
                    visited.add(v)
                    return search(vx.parent, False)
                par2 = par or (vx.kind == OP and vx.content == "#")
                for u in tg.children(v):
                    if u in visited:
                        continue
                    found = search(u, par2)
                    visited.add(u)
                    if found:
                        return True
                visited.add(v)
                return search(vx.parent, False)
            ok = False
            for dv in tg.decompositions_of(v):
                dec = dv.decomposition
                assert dec is not None
                effects = {(e.predicate, e.args): e.positive for e in dec.predicates.ground_effects}

                def fact(p, a, effects=effects):
                    return effects[(p, a)] if (p, a) in effects else state.value_of(p, a)

                if holds(test, fact, state.function_value):
                    if par:
                        pending.append(dv.index)
                    ok = True
            return ok

        return search(parent.index if parent else -1, False)


def _final_context_edges(tg: TaskGraph, cd_edges: list[tuple[int, int]]) -> None:
    """Redirect each CD edge ``d -> goal`` to every task vertex below the goal (§5.3)."""
    for d, c in cd_edges:
        stack, seen, targets = [c], {c}, []
        while stack:
            v = stack.pop()
            if tg.vertices[v].kind == ATASK:
                targets.append(v)
            for u, _k in reversed(tg._succ[v]):
                if u not in seen:
                    seen.add(u)
                    stack.append(u)
        for t in sorted(targets):
            if not tg.has_edge(d, t):
                tg.add_edge(d, t, CD)


def _execution_constraint_edges(tg: TaskGraph) -> None:
    """EC edges from Group/Divisible with the original's priority rules (§5.4)."""
    active: int | None = None
    stack: list[int] = []
    flags: dict[int, tuple[bool, bool]] = {}
    cur: list[int] = []
    snap: dict[int, list[int]] = {}
    or_nodes: set[int] = set()
    for v, vx in enumerate(tg.vertices):
        q = vx.parent
        if active is not None:
            if q <= tg.vertices[active].parent:
                if not stack:
                    cur = []
                    active = None
                else:
                    active = stack.pop()
            if (q >= 0 and tg.vertices[q].is_forall and active is not None and active >= q) or q in or_nodes:
                cur = list(snap.get(q, []))
        if vx.kind in (OP, GOALNODE) and tg.is_or(v):
            or_nodes.add(v)
        if vx.is_forall or v in or_nodes:
            snap[v] = list(cur)
        if vx.kind in (OP, GOALNODE) and (not vx.group or not vx.divisible):
            if active is None:
                flags[v] = (vx.group, vx.divisible)
                active = v
            elif flags[active][0]:
                flags[v] = (vx.group, vx.divisible)
                stack.append(active)
                active = v
        elif vx.kind == ATASK and active is not None:
            group, divisible = flags[active]
            for t in sorted(cur):
                if (t, v) not in tg._ec_pairs:
                    tg.add_ec(t, v, group, divisible)
            cur.append(v)


def _is_unique_branch(tg: TaskGraph) -> bool:
    return not any(
        vx.kind in (OP, GOALNODE) and len(tg.children(vx.index)) >= 2 for vx in tg.vertices
    )


def _trim(tg: TaskGraph) -> TaskGraph:
    """The minimal Task Graph (§5.5)."""
    root = next(v.index for v in tg.vertices if v.kind in (OP, GOALNODE) and len(tg.children(v.index)) >= 2)
    new = TaskGraph()
    index: dict[int, int] = {}

    def first_edge_type(old: int) -> str:
        kids = tg.children(old)
        return tg.edge_type(old, kids[0]) if kids else AND

    def insert(old: int, parent_old: int | None) -> None:
        nv = copy.copy(tg.vertices[old])
        nv.parent = index[parent_old] if parent_old is not None else -1
        new.add(nv)
        index[old] = nv.index
        if parent_old is not None:
            new.add_edge(index[parent_old], nv.index, first_edge_type(parent_old))

    def insert_tasks(op_old: int, under_old: int) -> None:
        for u in tg.children(op_old):
            if tg.vertices[u].kind == ATASK:
                insert(u, under_old)
                for d in tg.out(u, AND):
                    nd = copy.copy(tg.vertices[d])
                    nd.parent = index[u]
                    new.add(nd)
                    index[d] = nd.index
                    new.add_edge(index[u], nd.index, AND)

    def kept_ancestor(old: int) -> int:
        p = tg.vertices[old].parent
        while p not in index:
            p = tg.vertices[p].parent
        return p

    below_root: set[int] = set()
    stack = [root]
    while stack:
        u = stack.pop()
        below_root.add(u)
        stack.extend(tg.children(u))
    for vx in tg.vertices[root:]:
        v = vx.index
        if vx.kind in (ATASK, DECOMPOSITION) or v not in below_root:
            continue
        keep = vx.kind == OP and (len(tg.children(v)) >= 2 or vx.is_achieve_type)
        if v == root:
            insert(v, None)
            insert_tasks(v, v)
        elif keep:
            insert(v, kept_ancestor(v))
            insert_tasks(v, v)
        else:
            insert_tasks(v, kept_ancestor(v))
    for vx in tg.vertices:
        if vx.index in index or not vx.is_achieve_type or vx.kind not in (OP, GOALNODE):
            continue
        u = vx.index  # a removed achieve goal: follow its single child down to a kept vertex
        while u not in index and len(tg.children(u)) == 1:
            u = tg.children(u)[0]
        if u in index:
            new.achieve_carried.setdefault(index[u], []).append(vx)
    for a in range(len(tg.vertices)):
        if a not in index:
            continue
        for b, kind in tg._succ[a]:
            if kind == CD and b in index:
                new.add_edge(index[a], index[b], CD)
        for b, group, divisible in tg._ec.get(a, ()):  # each direction keeps its own order
            if b in index:
                new._ec.setdefault(index[a], []).append((index[b], group, divisible))
                new._ec_pairs.add((index[a], index[b]))
    return new


def build_task_graph(exp: Expansion, gm: GoalModel, config: Configuration, state: InitialState,
                     paths: dict[str, list[DecompositionPath]]) -> TaskGraph:
    """Build, connect and trim the Task Graph of an expanded mission."""
    builder = _Builder(exp, gm, config, state, paths)
    tg = builder.build()
    if not tg.vertices:
        raise MissionError("the mission has no task: every branch was removed or no task instance exists",
                           gm.source)
    _final_context_edges(tg, builder.cd_edges)
    _execution_constraint_edges(tg)
    if _is_unique_branch(tg):
        tg.unique_branch = True  # the original neither trims nor expands these (§7.7)
        return tg
    _expand_recursions(tg, state)
    return _trim(tg)


def _expand_recursions(tg: TaskGraph, state: InitialState) -> None:
    """Unroll recursive methods as often as the initial world state asks (§7.6).

    The original computes the repetitions from the world state at the point where the
    decomposition is accepted; here the initial state is used, so that the decomposition does
    not depend on the combination (docs/deviations.md)."""
    for v in tg.vertices:
        dec = v.decomposition
        if v.kind != DECOMPOSITION or dec is None or not dec.path.needs_expansion:
            continue
        binding = dec.instance.binding
        path = expand_path(dec.path, binding, state.function_value, dec.id)
        v.decomposition = Decomposition(dec.id, dec.instance, dec.number, path, ground_path(path, binding))
