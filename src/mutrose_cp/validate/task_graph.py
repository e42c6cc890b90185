"""The validator's own Task Graph of a mission (semantics.md §5): which task instances the output
must hold, which execution constraints and context dependencies join them, and the operators the
ordering constraints come from.

Built from the runtime annotation tree of :mod:`.mission_tree` in depth-first order:

* a goal whose creation condition is false in the initial world is kept only when a task built
  before it (to its left) has a decomposition that makes it true; reached through a parallel
  operator, each such decomposition gets a context dependency to the tasks below the goal
  (OR goals and fallbacks are jumped over, §5.2); otherwise its branch, and every instance in it,
  is not part of the mission;
* execution constraints come from Group=False (one robot) and Divisible=False (one team) goals,
  walked in vertex order with the priorities of §5.4;
* the minimal graph keeps the operators with two or more children, or with an achieve condition
  of their own, and hangs each task under its closest kept operator, its direct tasks first
  (§5.5); a graph in which no operator has two children is a *unique branch*.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Iterator, Mapping

from ..model import Atom, Binding, BoolOp, Condition, Configuration, InitialState, base_type
from .mission_tree import Instance, RatNode
from .numbers import AtomKey
from .select import Unresolved

# per task instance, the ground boolean effects of each of its decompositions (|1 first)
EffectsOf = Callable[[Instance], list[dict[AtomKey, bool]]]


@dataclass
class Vertex:
    index: int
    kind: str  # "op" | "goal" (a means-end goal) | "task"
    content: str
    parent: int
    rat: RatNode
    children: list[int] = field(default_factory=list)
    forall: bool = False
    achieve: bool = False

    @property
    def instance(self) -> Instance | None:
        return self.rat.instance


@dataclass
class Graph:
    vertices: list[Vertex]
    # context dependencies: (enabling task vertex, its decomposition number) -> dependent task vertices
    dependencies: dict[tuple[int, int], list[int]]
    # execution constraints between task vertices (earlier, later) -> (group, divisible)
    execution: dict[tuple[int, int], tuple[bool, bool]]

    @property
    def tasks(self) -> list[Vertex]:
        return [v for v in self.vertices if v.kind == "task"]

    @property
    def unique_branch(self) -> bool:
        return not any(v.kind != "task" and len(v.children) >= 2 for v in self.vertices)


def literals(cond: Condition, bindings: Mapping[str, Binding], config: Configuration) -> Condition:
    """``cond`` with each atom checked to be a boolean attribute the configuration maps (the only
    kind a creation condition may test, goal-model.md §6)."""
    if isinstance(cond, BoolOp):
        return BoolOp(cond.op, tuple(literals(c, bindings, config) for c in cond.children))
    if cond.op is not None or _mapping(cond, bindings, config) is None:
        raise Unresolved(f"creation condition {cond.text}: no attribute mapping translates it")
    return cond


def _mapping(atom: Atom, bindings: Mapping[str, Binding], config: Configuration) -> str | None:
    binding = bindings.get(atom.variable)
    relates = base_type(binding.type) if binding is not None else ""
    return next((m.pred for m in config.semantic_mapping if m.type == "attribute" and m.mapped_type == "predicate"
                 and m.name == atom.attribute and m.relates_to == relates), None)


def holds(cond: Condition, bindings: Mapping[str, Binding], config: Configuration,
          fact: Callable[[AtomKey], bool | None]) -> bool:
    """Open-world truth of a creation condition: an atom nobody knows holds."""
    if isinstance(cond, BoolOp):
        parts = (holds(c, bindings, config, fact) for c in cond.children)
        return all(parts) if cond.op == "&&" else any(parts)
    pred = _mapping(cond, bindings, config)
    binding = bindings.get(cond.variable)
    ids = binding.ids if binding is not None else ()
    return all(fact((pred or "", (v,))) in (None, not cond.negated) for v in ids)


class _Builder:
    def __init__(self, config: Configuration, initial: InitialState, effects_of: EffectsOf) -> None:
        self.config = config
        self.initial = initial
        self.effects_of = effects_of
        self.vertices: list[Vertex] = []
        self.pending: list[tuple[tuple[int, int], int]] = []  # (decomposition, goal vertex) CD edges

    def visit(self, node: RatNode, parent: Vertex | None) -> None:
        if node.kind == "goal":
            return
        index = len(self.vertices)
        if node.kind == "task":
            if parent is None:
                raise Unresolved("the goal model's root is a task")
            self._add(Vertex(index, "task", node.content, parent.index, node), parent)
            return
        vertex = self._scope(node, parent, index)
        if vertex is not None:
            for child in node.children:
                self.visit(child, vertex)

    def _add(self, vertex: Vertex, parent: Vertex | None) -> None:
        self.vertices.append(vertex)
        if parent is not None:
            parent.children.append(vertex.index)

    def _scope(self, node: RatNode, parent: Vertex | None, index: int) -> Vertex | None:
        goal = node.goal if not node.forall_node else node.children[0].goal
        achieve = bool(not node.forall_node and not node.inner and goal is not None and goal.goal_type == "Achieve"
                       and not (parent is not None and parent.forall))
        vertex = Vertex(index, "goal" if node.kind == "meansend" else "op", node.content,
                        parent.index if parent else -1, node, forall=node.forall_node, achieve=achieve)
        context = goal.context if goal is not None and not node.inner and not node.forall_node else None
        if context is not None and context.kind == "condition" and context.condition is not None:
            cond = literals(context.condition, node.bindings, self.config)
            initially = self.initial.value_of
            if not holds(cond, node.bindings, self.config, lambda k: initially(*k)) \
                    and not self._enabled(cond, node.bindings, parent.index if parent else -1, index):
                return None
        self._add(vertex, parent)
        return vertex

    def _enabled(self, cond: Condition, bindings: Mapping[str, Binding], start: int, goal: int) -> bool:
        """Whether a task to the left can make a false creation condition true (§5.2): the first
        one the search meets that can; met through a ``#``, each of its decompositions that does
        becomes a context dependency of the goal."""
        for task, parallel in _met_leftwards(self.vertices, start):
            assert task.instance is not None
            numbers = _enabling(self.effects_of(task.instance), cond, bindings, self.config, self.initial)
            if numbers:
                if parallel:
                    self.pending.extend(((task.index, n), goal) for n in numbers)
                return True
        return False


def _met_leftwards(vertices: list[Vertex], start: int) -> Iterator[tuple[Vertex, bool]]:
    """The task vertices the search of §5.2 meets from ``start`` (the parent of the goal whose
    creation condition is false), in the order it meets them, each with whether a ``#`` operator
    lies between: the built subtrees below each vertex, then its parent's, up to the root.  An
    OR goal or a FALLBACK met on the way is not entered: the walk goes on from its parent (and
    there no ``#`` above counts)."""
    visited: set[int] = set()

    def from_vertex(v: int, parallel: bool) -> Iterator[tuple[Vertex, bool]]:
        if v == -1:
            return
        vx = vertices[v]
        if vx.kind == "task":
            yield vx, parallel
            return
        if vx.rat.or_decomposed or vx.content == "FALLBACK":
            if v != 0:
                visited.add(v)
                yield from from_vertex(vx.parent, False)
            return
        below = parallel or (vx.kind == "op" and vx.content == "#")
        for u in vx.children:
            if u not in visited:
                yield from from_vertex(u, below)
                visited.add(u)
        visited.add(v)
        yield from from_vertex(vx.parent, False)

    return from_vertex(start, False)


def _enabling(effects: list[dict[AtomKey, bool]], cond: Condition, bindings: Mapping[str, Binding],
              config: Configuration, initial: InitialState) -> list[int]:
    """The decompositions (numbers) whose effects make ``cond`` true in the initial world."""
    numbers = []
    for n, made in enumerate(effects, start=1):
        def fact(k: AtomKey, made: dict[AtomKey, bool] = made) -> bool | None:
            return made[k] if k in made else initial.value_of(*k)
        if holds(cond, bindings, config, fact):
            numbers.append(n)
    return numbers


def _below(vertices: list[Vertex], goal: int) -> set[int]:
    """The task vertices a dependency on ``goal`` reaches: those below it (§5.3)."""
    found, stack = set(), [goal]
    while stack:
        vx = vertices[stack.pop()]
        if vx.kind == "task":
            found.add(vx.index)
        stack.extend(vx.children)
    return found


def _dependencies(vertices: list[Vertex], pending: list[tuple[tuple[int, int], int]]) -> dict[tuple[int, int], list[int]]:
    """Each dependency on a goal becomes one on every task below it (§5.3).  The spec follows
    every edge out of the goal, but no edge of another dependency can lead on from a task below
    it: that dependency's goal would have been entered after the task was built, so after this
    goal, and its edges are only added after this goal's (the edges are redirected in the order
    the goals were entered)."""
    out: dict[tuple[int, int], list[int]] = {}
    for decomposition, goal in pending:
        linked = out.setdefault(decomposition, [])
        linked.extend(t for t in sorted(_below(vertices, goal)) if t not in linked)
    return out


@dataclass
class _Scopes:
    """Where the walk of §5.4 stands: the active Group/Divisible scope and those it suspended,
    each scope's flags, the tasks met under the active one, and the tasks met at the start of
    each forAll copy and OR goal (a copy or an alternative starts from them again)."""

    active: int | None = None
    suspended: list[int] = field(default_factory=list)
    flags: dict[int, tuple[bool, bool]] = field(default_factory=dict)
    met: list[int] = field(default_factory=list)
    saved: dict[int, list[int]] = field(default_factory=dict)
    or_goals: set[int] = field(default_factory=set)


def _execution(vertices: list[Vertex]) -> dict[tuple[int, int], tuple[bool, bool]]:
    """Execution constraints from Group=False (one robot) and Divisible=False (one team) scopes,
    walked in vertex order with the priorities of §5.4: a task is constrained with every task
    met before it under the active scope, with that scope's flags."""
    at = _Scopes()
    edges: dict[tuple[int, int], tuple[bool, bool]] = {}
    for vx in vertices:
        parent = vertices[vx.parent] if vx.parent >= 0 else None
        if at.active is not None:
            if vx.parent <= vertices[at.active].parent:  # the walk has left the active scope
                at.active = at.suspended.pop() if at.suspended else None
                at.met = at.met if at.active is not None else []
            if (parent is not None and parent.forall and at.active is not None and at.active >= vx.parent) \
                    or vx.parent in at.or_goals:
                at.met = list(at.saved.get(vx.parent, []))
        if vx.kind == "task":
            if at.active is not None:
                for earlier in sorted(at.met):
                    edges.setdefault((earlier, vx.index), at.flags[at.active])
                at.met.append(vx.index)
            continue
        _enter(at, vx)
    return edges


def _enter(at: _Scopes, vx: Vertex) -> None:
    """A scope vertex: noted where copies and alternatives restart, and opened as the active
    scope when it constrains and no Group=False scope is active (a Group=False scope inside a
    Divisible=False one takes over, the other is suspended)."""
    if vx.rat.or_decomposed:
        at.or_goals.add(vx.index)
    if vx.forall or vx.index in at.or_goals:
        at.saved[vx.index] = list(at.met)
    if vx.rat.group and vx.rat.divisible:
        return
    if at.active is None or at.flags[at.active][0]:
        if at.active is not None:
            at.suspended.append(at.active)
        at.flags[vx.index] = (vx.rat.group, vx.rat.divisible)
        at.active = vx.index


def build_graph(rat: RatNode, config: Configuration, initial: InitialState, effects_of: EffectsOf) -> Graph:
    """The Task Graph before trimming (vertex order is depth-first), with its context
    dependencies and execution constraints."""
    builder = _Builder(config, initial, effects_of)
    builder.visit(rat, None)
    vertices = builder.vertices
    return Graph(vertices, _dependencies(vertices, builder.pending), _execution(vertices))


@dataclass
class TreeNode:
    """An operator of the minimal Task Graph: ``kind`` SEQ, FB or PAR, children in the order the
    minimal graph holds them (an int is a task vertex)."""

    kind: str
    children: list["TreeNode | int"]


_KINDS = {";": "SEQ", "FALLBACK": "FB", "#": "PAR"}


def minimal_tree(graph: Graph) -> TreeNode | None:
    """The constraint tree of the minimal Task Graph (§5.5, §6.1): from the first vertex with two
    children, the kept operators, each with its direct tasks first and then, in vertex order, the
    kept operators and the tasks of removed vertices below it.  None for a unique branch."""
    vertices = graph.vertices
    root = next((v for v in vertices if v.kind != "task" and len(v.children) >= 2), None)
    if root is None:
        return None
    kept: dict[int, TreeNode] = {}
    for vx in vertices[root.index:]:
        if vx.kind == "task":
            continue
        direct = [c for c in vx.children if vertices[c].kind == "task"]
        if vx is root or (vx.kind == "op" and (len(vx.children) >= 2 or vx.achieve)):
            node = TreeNode(_KINDS.get(vx.content, "PAR") if vx.kind == "op" else "PAR", list(direct))
            if vx is not root:
                kept[_kept_above(vertices, vx, kept)].children.append(node)
            kept[vx.index] = node
        elif direct:
            kept[_kept_above(vertices, vx, kept)].children.extend(direct)
    return kept[root.index]


def _kept_above(vertices: list[Vertex], vx: Vertex, kept: Mapping[int, TreeNode]) -> int:
    p = vx.parent
    while p not in kept:
        p = vertices[p].parent
    return p
