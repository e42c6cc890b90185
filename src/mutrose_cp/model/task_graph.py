"""The Task Graph's types (spec ``semantics.md`` §5): one frozen vertex type per kind, typed
edges, and the graph itself, which :class:`TaskGraphBuilder` assembles and then freezes.

Vertices are operators (``;``, ``#``, ``FALLBACK``), means-end goal nodes, task instances and
their decompositions; edges are AND/OR refinements, context dependencies (CD) and execution
constraints (EC).  A vertex's ``index`` is its position, which fixes the output keys
``t0, t1, ...``; ``parent`` is -1 at the root.
"""
from __future__ import annotations

import dataclasses
import itertools
from dataclasses import dataclass, field
from functools import cached_property
from enum import StrEnum
from typing import TYPE_CHECKING, Any, Callable, ClassVar, Iterable, Iterator, Mapping, NamedTuple, Self, Sequence, overload

if TYPE_CHECKING:  # the types of the stages that produce a vertex's content
    from .state_tests import Test
    from .task_instances import TaskInstance
    from .decomposition_paths import DecompositionPath, GroundPredicates
    from .world import Binding


class VertexKind(StrEnum):
    OPERATOR = "op"
    GOAL = "goal"  # a means-end goal node (a goal refined by a single child)
    TASK = "task"
    DECOMPOSITION = "decomposition"


class EdgeKind(StrEnum):
    AND = "AND"
    OR = "OR"
    CD = "CD"  # context dependency: a decomposition that can make a task's context true
    EC = "EC"  # execution constraint: tasks that share robots (Group/Divisible)


@dataclass(frozen=True, slots=True)
class Decomposition:
    """One HTN decomposition path of one task instance: ``AT1_1|2``."""

    id: str
    instance: TaskInstance
    number: int  # 1-based path number
    path: DecompositionPath
    predicates: GroundPredicates


# per vertex class and fields given anew: a function copying a vertex (see vertex_copier)
_VERTEX_COPIERS: dict[tuple[type, tuple[str, ...]], Callable[..., Any]] = {}


def vertex_copier(cls: type, given: tuple[str, ...]) -> Callable[..., Any]:
    """A function ``(vertex, index, parent, *given values)`` that copies a ``cls`` vertex with
    those fields set, slot by slot.  Trimming and stamping copy hundreds of thousands of
    vertices: ``dataclasses.replace`` re-runs the frozen ``__init__``, and a loop over the
    fields took three times as long as this straight-line function, generated once per class
    and set of fields (as ``dataclasses`` generates ``__init__``).  Each field is set through
    its slot's descriptor, as ``object.__setattr__`` would after looking the descriptor up."""
    copier = _VERTEX_COPIERS.get((cls, given))
    if copier is None:
        names = [f.name for f in dataclasses.fields(cls)]
        params = ("index", "parent", *given)
        assert set(params) <= set(names), (cls, given)
        body = "".join(f"    set_{n}(new, {n if n in params else 'vertex.' + n})\n" for n in names)
        namespace: dict[str, Any] = {"new_": object.__new__, "cls": cls}
        namespace.update((f"set_{n}", getattr(cls, n).__set__) for n in names)  # the slots' descriptors
        exec(f"def copy(vertex, {', '.join(params)}):\n    new = new_(cls)\n{body}    return new\n", namespace)
        copier = _VERTEX_COPIERS[(cls, given)] = namespace["copy"]
    return copier


@dataclass(frozen=True, kw_only=True, slots=True)
class _Vertex:
    index: int
    parent: int  # -1 at the root
    content: str  # operator symbol, goal id, instance id or decomposition id
    group: bool = True
    divisible: bool = True

    def moved(self, index: int, parent: int) -> Self:
        """The same vertex at another position: trimming renumbers the graph."""
        copied: Self = vertex_copier(type(self), ())(self, index, parent)
        return copied

    def stamped(self, index: int, parent: int, **content: Any) -> Self:
        """The same vertex at another position with other content: a vertex of a forAll copy
        made from the same vertex of an identical copy (:mod:`mutrose_cp.pipeline.stamping`)."""
        copied: Self = vertex_copier(type(self), tuple(content))(self, index, parent, *content.values())
        return copied


@dataclass(frozen=True, kw_only=True, slots=True)
class ScopeVertex(_Vertex):
    """An operator or a means-end goal: a vertex that scopes the subtree of a goal."""

    goal: str | None = None  # the goal the vertex stands for
    forall: bool = False  # the parallel node over the copies of a forAll goal
    achieve: bool = False  # the top node of an Achieve goal: its condition is checked here
    var_maps: Mapping[str, Binding] = field(default_factory=dict)  # variable values at this node
    # a creation condition false in the initial state that an earlier task can make true (§5.2)
    contexts: tuple[Test, ...] = ()


@dataclass(frozen=True, kw_only=True, slots=True)
class OperatorVertex(ScopeVertex):
    kind: ClassVar[VertexKind] = VertexKind.OPERATOR


@dataclass(frozen=True, kw_only=True, slots=True)
class GoalVertex(ScopeVertex):
    kind: ClassVar[VertexKind] = VertexKind.GOAL


@dataclass(frozen=True, kw_only=True, slots=True)
class TaskVertex(_Vertex):
    kind: ClassVar[VertexKind] = VertexKind.TASK
    instance: TaskInstance
    # every enabled creation condition above the task: each must hold where the task starts
    contexts: tuple[Test, ...] = ()


@dataclass(frozen=True, kw_only=True, slots=True)
class DecompositionVertex(_Vertex):
    kind: ClassVar[VertexKind] = VertexKind.DECOMPOSITION
    decomposition: Decomposition

    @property
    def instance(self) -> TaskInstance:
        return self.decomposition.instance


Vertex = OperatorVertex | GoalVertex | TaskVertex | DecompositionVertex


class ExecutionPartner(NamedTuple):
    """The other end of an execution constraint, with the constraint's flags."""

    task: int
    group: bool
    divisible: bool


class StampedCopy(NamedTuple):
    """A forAll copy's vertices ``start .. start + size - 1``, made from those of the copy at
    ``source`` (itself for a copy that was built): vertex ``source + k`` and ``start + k``
    stand for the same goal, task or decomposition of their copies."""

    start: int
    source: int
    size: int


class Edge(NamedTuple):
    source: int
    target: int
    kind: EdgeKind
    group: bool = True  # EC edges only
    divisible: bool = True


class _SameKind(Sequence[tuple[int, EdgeKind]]):
    """The successors of a finished graph's vertex whose edges all have one kind: its list of
    successors by that kind, read as (successor, kind) pairs.  Most vertices with successors
    are such; a list of pairs each took four times the memory."""

    __slots__ = ("targets", "kind")

    def __init__(self, targets: list[int], kind: EdgeKind) -> None:
        self.targets = targets
        self.kind = kind

    def __len__(self) -> int:
        return len(self.targets)

    @overload
    def __getitem__(self, i: int) -> tuple[int, EdgeKind]: ...

    @overload
    def __getitem__(self, i: slice) -> list[tuple[int, EdgeKind]]: ...

    def __getitem__(self, i: int | slice) -> tuple[int, EdgeKind] | list[tuple[int, EdgeKind]]:
        if isinstance(i, slice):
            return [(t, self.kind) for t in self.targets[i]]
        return self.targets[i], self.kind

    def __iter__(self) -> Iterator[tuple[int, EdgeKind]]:
        return zip(self.targets, itertools.repeat(self.kind))

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Sequence) and not isinstance(other, (str, bytes)):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]

    def __repr__(self) -> str:
        return repr(list(self))


# shared by every vertex without AND, OR or CD edges (never changed: a first edge replaces it)
_NO_SUCCESSORS = _SameKind([], EdgeKind.AND)


def _same_kind(successors: Sequence[tuple[int, EdgeKind]],
               by_kind: Mapping[EdgeKind, Mapping[int, list[int]]], v: int) -> _SameKind | None:
    """``successors`` of ``v`` as its list by kind, when they all have one kind and that list
    holds them in the same order (an edge whose kind was changed can stand elsewhere there)."""
    if not successors:
        return None
    kind = successors[0][1]
    targets = by_kind[kind].get(v)
    if targets is None or len(targets) != len(successors):
        return None
    if any(k is not kind or t != b for t, (b, k) in zip(targets, successors)):
        return None
    return _SameKind(targets, kind)


@dataclass
class _EdgeIndex:
    """The edges, indexed the ways the construction rules and the decomposers read them, in
    insertion order (which the original's traversals depend on).  Plain adjacency lists: large
    missions have hundreds of thousands of vertices and EC edges, so nothing is kept per vertex
    or edge that a query can do without: no tuple keys, no empty lists."""

    # AND, OR and CD successors by vertex index (most vertices, the decompositions, have none)
    # (once frozen, those of one kind are read from ``by_kind``: _SameKind)
    successors: list[Sequence[tuple[int, EdgeKind]]] = field(default_factory=list)
    # kind -> vertex -> its successors through edges of that kind
    by_kind: dict[EdgeKind, dict[int, list[int]]] = field(default_factory=lambda: {kind: {} for kind in EdgeKind})
    # edges are added while building, until the graph is frozen (or its lookups released)
    open: bool = True
    # execution constraints are symmetric and numerous: task -> partners, in the order added
    ec: dict[int, list[ExecutionPartner]] = field(default_factory=dict)
    # by task, in order: the stages ask for a task's decompositions hundreds of thousands of times
    decompositions: dict[int, list[DecompositionVertex]] = field(default_factory=dict)


class _Adjacency:
    """The queries that both the builder and the frozen graph answer."""

    vertices: Sequence[Vertex]
    _edges: _EdgeIndex

    def out(self, v: int, *kinds: EdgeKind) -> list[int]:
        """Successors of ``v`` through edges of the given kinds, in insertion order."""
        if len(kinds) == 1:
            return self._edges.by_kind[kinds[0]].get(v, [])
        return [u for u, k in self._edges.successors[v] if k in kinds]

    def children(self, v: int) -> list[int]:
        """AND/OR successors in insertion order (a vertex refines into one kind only)."""
        by_kind = self._edges.by_kind
        ands = by_kind[EdgeKind.AND].get(v)
        ors = by_kind[EdgeKind.OR].get(v)
        if ands and ors:
            return self.out(v, EdgeKind.AND, EdgeKind.OR)
        return ands or ors or []

    def successors(self, v: int) -> Sequence[tuple[int, EdgeKind]]:
        """AND, OR and CD successors of ``v`` with the edge kind, in insertion order."""
        return self._edges.successors[v]

    def is_or(self, v: int) -> bool:
        successors = self._edges.successors[v]
        if isinstance(successors, _SameKind):
            return successors.kind == EdgeKind.OR
        return any(k == EdgeKind.OR for _, k in successors)

    def _kind_of(self, a: int, b: int) -> EdgeKind | None:
        """The kind of the AND, OR or CD edge ``(a, b)``, None without one: looked up in the
        successors of ``a`` (an index by vertex pair took an int and a dict entry per edge, twice
        while trimming, and the rules ask only about vertices with few successors)."""
        return next((k for u, k in self._edges.successors[a] if u == b), None)

    def edge_kind(self, a: int, b: int) -> EdgeKind:
        kind = self._kind_of(a, b)
        if kind is None:
            raise KeyError((a, b))
        return kind

    def has_edges_of_kind(self, kind: EdgeKind) -> bool:
        """Whether any edge has ``kind`` (AND, OR or CD; EC edges are kept apart)."""
        return any(self._edges.by_kind[kind].values())

    def has_edge(self, a: int, b: int) -> bool:
        if self._kind_of(a, b) is not None:
            return True
        return any(p.task == b for p in self._edges.ec.get(a, ()))

    def execution_partners(self) -> Iterable[tuple[int, list[ExecutionPartner]]]:
        """Each task's EC partners, tasks in the order their first constraint was added."""
        return self._edges.ec.items()

    def ec_partners(self, v: int) -> list[ExecutionPartner]:
        """EC partners of task ``v`` with the constraint's flags, in the order they were added."""
        return self._edges.ec.get(v, [])

    def decompositions_of(self, task: int) -> list[DecompositionVertex]:
        return self._edges.decompositions.get(task, [])

    def decompositions(self) -> list[DecompositionVertex]:
        return [v for v in self.vertices if isinstance(v, DecompositionVertex)]

    def tasks(self) -> list[TaskVertex]:
        return [v for v in self.vertices if isinstance(v, TaskVertex)]

    def scope(self, v: int) -> ScopeVertex:
        """Vertex ``v``, which must be an operator or a means-end goal."""
        vertex = self.vertices[v]
        assert isinstance(vertex, ScopeVertex), vertex
        return vertex

    def task(self, v: int) -> TaskVertex:
        """Vertex ``v``, which must be a task."""
        vertex = self.vertices[v]
        assert isinstance(vertex, TaskVertex), vertex
        return vertex

    def decomposition(self, d: int) -> DecompositionVertex:
        """Vertex ``d``, which must be a decomposition."""
        vertex = self.vertices[d]
        assert isinstance(vertex, DecompositionVertex), vertex
        return vertex


@dataclass(frozen=True)
class TaskGraph(_Adjacency):
    """The finished Task Graph: vertices in index order and typed edges.  Nothing changes it
    once built; the decomposers, the constraints and the outputs only read it."""

    vertices: tuple[Vertex, ...]
    _edges: _EdgeIndex
    unique_branch: bool = False
    # achieve goals that trimming removed (means-end goals, single-child chains above the root),
    # by the kept vertex that now stands for their subtree: their conditions are checked there
    achieve_carried: Mapping[int, tuple[ScopeVertex, ...]] = field(default_factory=dict)
    # the forAll copies stamped from another (mutrose_cp.pipeline.stamping), by forAll, in vertex order:
    # later stages may stamp what they make of a copy from what they make of its source
    stamped_copies: tuple[tuple[StampedCopy, ...], ...] = field(default=(), compare=False)
    # doubts met while building it: a recursion whose bound the world does not give
    warnings: tuple[str, ...] = field(default=(), compare=False)

    @cached_property
    def _decomposition_vertices(self) -> tuple[DecompositionVertex, ...]:
        return tuple(v for v in self.vertices if isinstance(v, DecompositionVertex))

    def decompositions(self) -> list[DecompositionVertex]:
        """The decomposition vertices in index order: found once (the stages ask for them
        several times, and a large graph has hundreds of thousands of vertices)."""
        return list(self._decomposition_vertices)

    @cached_property
    def decomposition_keys(self) -> dict[int, str]:
        """Decomposition vertex -> its output key, ``t0, t1, ...`` in vertex order; built once,
        for the output, its space section and the views that name the decompositions alike."""
        return {d.index: f"t{i}" for i, d in enumerate(self.decompositions())}

    def edges(self) -> Iterator[Edge]:
        """All edges (EC ones in both directions), by source vertex and then insertion order."""
        for a, successors in enumerate(self._edges.successors):
            for b, kind in successors:
                yield Edge(a, b, kind)
            for p in self._edges.ec.get(a, ()):
                yield Edge(a, p.task, EdgeKind.EC, p.group, p.divisible)

class TaskGraphBuilder(_Adjacency):
    """A Task Graph under construction: vertices are added in index order, edges in the order
    the construction rules (§5.1–§5.5) meet them; :meth:`freeze` hands out the result, after
    which the builder is dropped (the graph takes over its edge index)."""

    vertices: list[Vertex]

    def __init__(self) -> None:
        self.vertices = []
        self._edges = _EdgeIndex()
        self.achieve_carried: dict[int, list[ScopeVertex]] = {}
        self.stamped_copies: list[tuple[StampedCopy, ...]] = []
        self.warnings: list[str] = []  # what building the graph found doubtful (an unknown recursion bound)
        self._partners: dict[tuple[int, bool, bool], ExecutionPartner] = {}

    @property
    def next_index(self) -> int:
        return len(self.vertices)

    def add(self, vertex: Vertex) -> Vertex:
        """Append ``vertex``, whose index must be :attr:`next_index`."""
        assert vertex.index == len(self.vertices), (vertex.index, len(self.vertices))
        self.vertices.append(vertex)
        self._edges.successors.append(_NO_SUCCESSORS)
        if isinstance(vertex, DecompositionVertex):
            assert self._edges.open, "a frozen graph takes no vertices"
            self._edges.decompositions.setdefault(vertex.parent, []).append(vertex)
        return vertex

    def add_child(self, vertex: Vertex, kind: EdgeKind) -> Vertex:
        """Append ``vertex`` and the edge of ``kind`` from its parent to it: :meth:`add` and
        :meth:`add_edge` in one, for the tree edges, which the construction and the trimming
        add by the hundred thousand and which cannot exist yet (the vertex is new)."""
        self.add(vertex)
        self.add_new_edge(vertex.parent, vertex.index, kind)
        return vertex

    def add_children(self, made: Sequence[Vertex], kinds: Sequence[EdgeKind]) -> None:
        """:meth:`add_child` for each vertex of ``made`` with the edge kind beside it, in one
        loop: a stamped forAll copy's vertices (a large mission adds hundreds of thousands)."""
        vertices, edges = self.vertices, self._edges
        assert edges.open, "a frozen graph takes no vertices"
        successors, by_kind, by_task = edges.successors, edges.by_kind, edges.decompositions
        for vertex, kind in zip(made, kinds):
            assert vertex.index == len(vertices), (vertex.index, len(vertices))
            vertices.append(vertex)
            successors.append(_NO_SUCCESSORS)
            a, b = vertex.parent, vertex.index
            if isinstance(vertex, DecompositionVertex):
                by_task.setdefault(a, []).append(vertex)
            listed = successors[a]
            if isinstance(listed, list):
                listed.append((b, kind))
            else:  # the parent's first edge
                successors[a] = [(b, kind)]
            targets = by_kind[kind].get(a)
            if targets is None:
                by_kind[kind][a] = [b]
            else:
                targets.append(b)

    def add_new_edge(self, a: int, b: int, kind: EdgeKind) -> None:
        """An AND, OR or CD edge ``(a, b)`` that the caller knows is not in the graph yet (see
        :meth:`add_edge`)."""
        edges = self._edges
        assert edges.open, "a frozen graph's edges do not change"
        successors = edges.successors[a]
        if isinstance(successors, list):
            successors.append((b, kind))
        else:  # the vertex's first edge
            edges.successors[a] = [(b, kind)]
        by_source = edges.by_kind[kind]
        targets = by_source.get(a)
        if targets is None:
            by_source[a] = [b]
        else:
            targets.append(b)

    def replace(self, vertex: DecompositionVertex) -> None:
        """Put a changed decomposition vertex in place of the one with its index."""
        old = self.decomposition(vertex.index)
        assert self._edges.open, "a frozen graph's vertices do not change"
        siblings = self._edges.decompositions[old.parent]
        siblings[siblings.index(old)] = vertex
        self.vertices[vertex.index] = vertex

    def add_edge(self, a: int, b: int, kind: EdgeKind) -> None:
        """An AND, OR or CD edge; adding an existing edge again changes its kind in place.  The
        edge is looked for among the successors of ``a``: a rule that adds many edges from one
        vertex knows which are new and calls :meth:`add_new_edge`."""
        edges = self._edges
        assert edges.open, "a frozen graph's edges do not change"
        old = self._kind_of(a, b)
        if old is None:
            self.add_new_edge(a, b, kind)
        elif old != kind:
            edges.successors[a] = [(u, kind if u == b else k) for u, k in edges.successors[a]]
            edges.by_kind[old][a].remove(b)
            edges.by_kind[kind].setdefault(a, []).append(b)

    def partner(self, task: int, group: bool, divisible: bool) -> ExecutionPartner:
        """One shared partner record per (task, flags): a task appears in the partner list of
        every task it is constrained with, so sharing saves most of the records."""
        key = (task, group, divisible)
        partner = self._partners.get(key)
        if partner is None:
            partner = self._partners[key] = ExecutionPartner(task, group, divisible)
        return partner

    def add_ec(self, a: int, b: int, group: bool, divisible: bool) -> None:
        """An execution constraint between task vertices ``a`` and ``b`` (both directions)."""
        self._edges.ec.setdefault(a, []).append(self.partner(b, group, divisible))
        self._edges.ec.setdefault(b, []).append(self.partner(a, group, divisible))

    def set_partners(self, task: int, partners: list[ExecutionPartner]) -> None:
        """The execution partners of ``task``, in order: those of a stamped forAll copy, made
        from those of the copy it was stamped from."""
        self._edges.ec[task] = partners

    def add_ec_to_all(self, tasks: Sequence[int], v: int, group: bool, divisible: bool) -> None:
        """Execution constraints between task ``v`` and each of ``tasks`` it is not yet linked to,
        in that order (one call for what is the bulk of a large mission's edges).  Which tasks
        ``v`` is linked to is read from its partner list, once per call: a set of every linked
        pair, kept while building, was the largest index of a large mission's construction."""
        edges = self._edges
        ec = edges.ec
        assert edges.open, "a frozen graph's edges do not change"
        partner_v = self.partner(v, group, divisible)
        partners_of_v = ec.setdefault(v, [])
        linked = {p.task for p in partners_of_v}
        # no AND, OR or CD edge joins two tasks (their successors are their decompositions, and
        # context dependencies start at decompositions): the partner list is all there is to see
        for t in tasks:  # add_ec(t, v, ...) for each, inlined: a million calls on large missions
            if t not in linked:
                ec.setdefault(t, []).append(partner_v)
                partners_of_v.append(self.partner(t, group, divisible))
                linked.add(t)

    def release_lookups(self) -> None:
        """Drop the indexes that look edges up (by kind, decompositions by task), keeping the
        vertices and their successor lists, for a graph that is only walked from now on: the
        untrimmed graph, walked once more for its execution constraints while the trimmed one
        takes them.  It takes no more edges."""
        self._edges.by_kind = {kind: {} for kind in EdgeKind}
        self._edges.open = False
        self._edges.decompositions = {}

    def freeze(self, *, unique_branch: bool = False) -> TaskGraph:
        """The finished graph, whose successors of one kind are read from the lists by kind."""
        edges = self._edges
        edges.open = False
        for v, successors in enumerate(edges.successors):
            same = _same_kind(successors, edges.by_kind, v)
            if same is not None:
                edges.successors[v] = same
        return TaskGraph(tuple(self.vertices), self._edges, unique_branch=unique_branch,
                         achieve_carried={v: tuple(c) for v, c in self.achieve_carried.items()},
                         stamped_copies=tuple(self.stamped_copies), warnings=tuple(self.warnings))


@dataclass
class SplitListing:
    """Mission decompositions that share a long common part (see
    ``DecompositionSpace.split_listing``): each is ``prefix + part`` (decomposition vertices).
    The solver makes it and the writer renders the common part once, which makes listing the
    first 1000 of 3^5000 decompositions cheap."""

    prefix: list[int]
    parts: Iterable[list[int]]

    def __iter__(self) -> Iterator[list[int]]:
        for part in self.parts:
            yield self.prefix + part
