"""Template stamping of forAll copies in the Task Graph (spec ``semantics.md`` §5).

A forAll goal becomes a parallel node over one copy of its subtree per iterated element, and in
a large mission most copies are identical up to renaming: the same goals, operators and tasks,
for another room and its patients.  Their Task Graph fragments then have one shape (vertices,
tree edges, execution constraints, trimming) and differ only in content: variable values, task
instances and their grounded decompositions.  So the graph is built, connected and trimmed with
a few copies of each such forAll (the first two, the last and the first of each shape), and
every other copy is stamped from the trimmed fragment of the first copy of its shape (its
*representative*), with its own content.

Stamping gives the graph the full construction gives, which the tests check on every mission
they build.  It is used only where that follows from the rules, and the full construction is
run otherwise:

* a copy's shape is its annotation subtree (kinds, operators, goals, flags, the gm task and HDDL
  task of each instance), so copies of one shape make the same vertices and tree edges, and
  trimming keeps the same ones;
* no goal inside the copies has a creation condition, and no context elsewhere is false in the
  initial world state: the only rule that searches the graph built so far, and so could see a
  copy left out, is never asked for (and no context dependency exists);
* no decomposition needs its recursive methods unrolled (that reads the world per copy);
* in the reduced graph, every execution constraint of a built copy's task stays inside the copy
  (the Group/Divisible scope restarts at each copy);
* the walk that adds the execution constraints meets every built copy in the same state.  The
  walk can carry a scope opened in one copy into the next, so that copies of one shape are
  constrained differently; when every built copy starts alike, each copy leaves the walk as the
  first of its shape did, and the next copy starts alike too (the first of a shape is followed
  by a built copy, the last copy is built);
* the reduced graph is not unique-branch (it is neither trimmed nor expanded).

Achieve goals that trimming carries to a kept vertex stay inside their copy: a chain of
single-child vertices cannot pass through the forAll's node, which has two children or more.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable, Hashable, Iterator, Mapping, NamedTuple, Sequence, TypeVar

from .annotation_tree import TASK, RatNode
from ..model.task_instances import TaskInstance, Value
from ..model.decomposition_paths import DecompositionPath
from .htn import ground_path
from ..model import GoalModel
from ..model.task_graph import (
    Decomposition,
    EdgeKind,
    ExecutionPartner,
    ScopeVertex,
    StampedCopy,
    TaskGraphBuilder,
    TaskVertex,
    Vertex,
    vertex_copier,
)

MIN_COPIES = 4  # the first two and the last are built: something is left to stamp


@dataclass
class ForallCopies:
    """The copies of one forAll node: which are built, and which built copy each one is
    stamped from."""

    copies: list[RatNode]  # the children of the forAll's parallel node
    preorder: list[list[RatNode]]  # each copy's annotation nodes, depth first
    representative: list[int]  # copy -> the built copy of its shape (itself when built)


@dataclass
class StampingPlan:
    """The forAll nodes whose copies are stamped (none inside another)."""

    foralls: list[ForallCopies]

    @property
    def skipped(self) -> frozenset[int]:
        """The copies the reduced construction leaves out (ids of their annotation nodes)."""
        return frozenset(id(f.copies[i]) for f in self.foralls
                         for i, r in enumerate(f.representative) if r != i)


def plan_stamping(rat: RatNode, instances: Mapping[str, TaskInstance], gm: GoalModel,
                  paths: Mapping[str, list[DecompositionPath]]) -> StampingPlan | None:
    """The forAll nodes whose copies are stamped, outermost first; None when there is nothing to
    stamp or a rule of the module docstring rules it out for the whole mission."""
    if any(path.needs_expansion for inst in instances.values() for path in paths.get(inst.name, ())):
        return None
    foralls: list[ForallCopies] = []
    stack = [rat]
    while stack:
        node = stack.pop()
        if node.is_forall_dummy and len(node.children) >= MIN_COPIES:
            copies = _forall_copies(node, instances, gm)
            if copies is not None:
                foralls.append(copies)
                continue
        stack.extend(reversed(node.children))
    return StampingPlan(foralls) if foralls else None


def _forall_copies(node: RatNode, instances: Mapping[str, TaskInstance], gm: GoalModel) -> ForallCopies | None:
    """The copies of ``node`` and their representatives (only the distinct shapes are kept: a
    shape is as long as its copy), or None when a copy cannot be stamped or none would be."""
    preorder: list[list[RatNode]] = []
    representative: list[int] = []
    first: dict[tuple[object, ...], int] = {}
    last = len(node.children) - 1
    for i, copy in enumerate(node.children):
        nodes, shape = _shape(copy, instances)
        if shape is None:
            return None
        preorder.append(nodes)
        r = first.setdefault(shape, i)
        representative.append(i if i < 2 or i == last else r)
    goals = {n.related_goal for i in first.values() for n in preorder[i] if n.related_goal}
    if any(_has_condition(gm, goal) for goal in goals):
        return None
    if all(r == i for i, r in enumerate(representative)):
        return None  # every copy has a shape of its own
    return ForallCopies(list(node.children), preorder, representative)


def _has_condition(gm: GoalModel, goal: str) -> bool:
    context = gm.node(goal).context
    return context is not None and context.kind == "condition"


def _shape(copy: RatNode, instances: Mapping[str, TaskInstance]) -> tuple[list[RatNode], tuple[object, ...] | None]:
    """A copy's annotation nodes depth first, and its shape: what the construction reads of
    each node other than its variable values and instance ids (None for an unknown instance,
    which the construction reports)."""
    nodes: list[RatNode] = []
    shape: list[object] = []
    stack = [copy]
    while stack:
        n = stack.pop()
        nodes.append(n)
        if n.kind == TASK:
            inst = instances.get(n.content)
            if inst is None:
                return nodes, None
            shape.append((inst.gm_task, inst.name, n.related_goal))
        else:
            shape.append((n.kind, n.content, n.related_goal, n.group, n.divisible, n.or_decomposition,
                          n.is_forall_dummy, n.inner, len(n.children)))
        stack.extend(reversed(n.children))
    return nodes, tuple(shape)


@dataclass
class _Fragment:
    """A built copy of a stamped forAll: its vertices in the untrimmed graph and in the trimmed
    one."""

    copy: int
    nodes: list[RatNode]  # the copy's annotation nodes, depth first
    untrimmed: tuple[int, int]
    trimmed: tuple[int, int]
    originals: list[int]  # the untrimmed vertex of each trimmed one (trimming may reorder them)
    number: int = 0  # its place among all fragments, in vertex order
    region: int = 0  # its forAll's place among the stamped ones, in vertex order
    positions: dict[int, int] | None = None  # annotation node id -> place in ``nodes`` (made on first use)
    recipe: "_Recipe | None" = None  # how its stamped copies make their vertices (made on first use)
    partners: tuple[list[ExecutionPartner], dict[int, list[int]]] | None = None  # see Stamper._partner_records


@dataclass
class _Region:
    """A stamped forAll's built copies, one run of vertices in each reduced graph."""

    forall: ForallCopies
    fragments: dict[int, _Fragment]  # built copy -> its fragment, in copy order

    @property
    def trimmed(self) -> tuple[int, int]:
        ranges = [f.trimmed for f in self.fragments.values()]
        return ranges[0][0], ranges[-1][1]

    @property
    def untrimmed(self) -> tuple[int, int]:
        ranges = [f.untrimmed for f in self.fragments.values()]
        return ranges[0][0], ranges[-1][1]


@dataclass
class _Placed:
    """Where one copy of a stamped forAll lands in the full graph, and what it is made from."""

    fragment: _Fragment  # its representative's
    start: int  # its first vertex in the full trimmed graph
    untrimmed_start: int  # and in the full untrimmed graph
    content: "_Content | None"  # None: a built copy, which keeps its content
    partners: list[ExecutionPartner] | None = None  # see Stamper._partner_records

    def trimmed(self, v: int) -> int:
        return self.start + v - self.fragment.trimmed[0]

    def untrimmed(self, u: int) -> int:
        return self.untrimmed_start + u - self.fragment.untrimmed[0]


OUTSIDE = -1
V = TypeVar("V")
S = TypeVar("S", bound=ScopeVertex)


class Stamper:
    """Makes the full trimmed graph from the reduced one: the vertices outside the stamped
    copies move to their full positions, and each copy is its representative's fragment, with
    its own content.  The execution partners and carried achieve goals follow, in the order the
    full construction adds them.  (No context is false in the initial state, so the graph has no
    context dependencies, and its edges are tree edges, which come with the vertices.)"""

    def __init__(self, plan: StampingPlan, reduced: TaskGraphBuilder, kept: Mapping[int, int],
                 origins: Sequence[RatNode], copy_ranges: Mapping[int, tuple[int, int]],
                 copy_states: Mapping[int, Hashable], instances: Mapping[str, TaskInstance]) -> None:
        self.plan = plan
        self.reduced = reduced
        self.kept = kept  # untrimmed vertex -> reduced (trimmed) vertex
        self.origins = origins  # untrimmed vertex -> its annotation node
        self.copy_ranges = copy_ranges
        self.copy_states = copy_states  # first vertex of a built copy -> the EC walk's state there
        self.instances = instances
        self.new = TaskGraphBuilder()
        self.fragments: list[_Fragment] = []
        self.owner: list[int] = []  # reduced vertex -> its fragment, or OUTSIDE
        self.position: list[int] = []  # reduced vertex outside the copies -> full vertex
        self.placed: list[list[_Placed]] = []  # region -> its copies
        self.untrimmed_shifts: list[tuple[int, int]] = []  # (end of a region, shift from there on)

    def stamp(self) -> TaskGraphBuilder | None:
        """The full trimmed graph, or None when a rule of the module docstring does not hold."""
        regions = self._regions()
        if regions is None:
            return None
        self.owner = [OUTSIDE] * len(self.reduced.vertices)
        for k, f in enumerate(self.fragments):
            lo, hi = f.trimmed
            self.owner[lo:hi] = [k] * (hi - lo)
        if not self._contained():
            return None
        self._vertices(regions)
        new = self.new
        for key, partners, placed in self._in_full_order(list(self.reduced.execution_partners())):
            if placed is None:
                new.set_partners(key, [new.partner(self.position[p.task], p.group, p.divisible) for p in partners])
            else:
                records, places = self._partner_records(placed)
                new.set_partners(key, list(map(records.__getitem__, places[id(partners)])))
        for key, carried, placed in self._in_full_order(list(self.reduced.achieve_carried.items())):
            new.achieve_carried[key] = [self._carried(c, placed) for c in carried]
        return new

    # --- where the copies are ---------------------------------------------------------------
    def _regions(self) -> list[_Region] | None:
        """Each stamped forAll's built copies, in vertex order; None unless each forAll's built
        copies kept vertices in one run of the trimmed graph, one copy after the other."""
        regions = []
        for forall in self.plan.foralls:
            fragments: dict[int, _Fragment] = {}
            for i, copy in enumerate(forall.copies):
                if forall.representative[i] != i:
                    continue
                span = self.copy_ranges.get(id(copy))
                if span is None:
                    return None
                kept = {self.kept[u]: u for u in range(*span) if u in self.kept}
                if not kept or max(kept) - min(kept) + 1 != len(kept):
                    return None
                lo, hi = min(kept), max(kept) + 1
                fragments[i] = _Fragment(i, forall.preorder[i], span, (lo, hi), [kept[v] for v in range(lo, hi)])
            ordered = list(fragments.values())
            if len({self.copy_states[f.untrimmed[0]] for f in ordered}) != 1:
                return None  # the walk of the execution constraints carries a scope into a copy
            if any(a.trimmed[1] != b.trimmed[0] or a.untrimmed[1] != b.untrimmed[0] for a, b in zip(ordered, ordered[1:])):
                return None
            regions.append(_Region(forall, fragments))
        regions.sort(key=lambda region: region.untrimmed[0])
        for r, region in enumerate(regions):
            for f in region.fragments.values():
                f.region, f.number = r, len(self.fragments)
                self.fragments.append(f)
        return regions

    def _contained(self) -> bool:
        """Every execution constraint of a built copy's task stays inside the copy (the
        Group/Divisible scope restarts at each copy)."""
        owner = self.owner
        return all(owner[p.task] == owner[t] for t, partners in self.reduced.execution_partners() for p in partners)

    # --- the full graph -----------------------------------------------------------------------
    def _vertices(self, regions: list[_Region]) -> None:
        reduced, new = self.reduced, self.new
        tree_kind: list[EdgeKind] = [EdgeKind.AND] * len(reduced.vertices)
        for a in range(len(reduced.vertices)):  # no context dependencies: every edge is a tree edge
            for b, kind in reduced.successors(a):
                tree_kind[b] = kind
        self.position = list(range(len(reduced.vertices)))
        v, shift, untrimmed_shift = 0, 0, 0
        for region in regions:
            start, stop = region.trimmed
            for u in range(v, start):
                self._move(u, u + shift, tree_kind)
            forall = region.forall
            ustart = region.untrimmed[0] + untrimmed_shift
            placed = []
            for i in range(len(forall.copies)):
                rep = forall.representative[i]
                fragment = region.fragments[rep]
                content = None if rep == i else _Content(self._position_of(fragment), forall.preorder[i], self.instances)
                placed.append(_Placed(fragment, new.next_index, ustart, content))
                self._copy(placed[-1], tree_kind)
                ustart += fragment.untrimmed[1] - fragment.untrimmed[0]
            self.placed.append(placed)
            new.stamped_copies.append(tuple(
                StampedCopy(p.start, placed[forall.representative[i]].start, p.fragment.trimmed[1] - p.fragment.trimmed[0])
                for i, p in enumerate(placed)))
            shift = new.next_index - stop
            untrimmed_shift = ustart - region.untrimmed[1]
            self.untrimmed_shifts.append((region.untrimmed[1], untrimmed_shift))
            v = stop
        for u in range(v, len(reduced.vertices)):
            self._move(u, u + shift, tree_kind)

    @staticmethod
    def _position_of(fragment: _Fragment) -> dict[int, int]:
        if fragment.positions is None:
            fragment.positions = {id(n): p for p, n in enumerate(fragment.nodes)}
        return fragment.positions

    def _move(self, u: int, to: int, tree_kind: list[EdgeKind]) -> None:
        vertex = self.reduced.vertices[u]
        self.position[u] = to
        if vertex.parent < 0:
            self.new.add(vertex.moved(to, -1))
        else:
            self.new.add_child(vertex.moved(to, self.position[vertex.parent]), tree_kind[u])

    def _copy(self, placed: _Placed, tree_kind: list[EdgeKind]) -> None:
        """One copy: its representative's kept vertices, with its own content."""
        new, reduced, content = self.new, self.reduced, placed.content
        lo, hi = placed.fragment.trimmed
        base = placed.start
        if content is not None:
            content.make(self._recipe(placed.fragment, tree_kind), base, new)
            return
        for u in range(lo, hi):
            vertex = reduced.vertices[u]
            p = vertex.parent
            new.add_child(vertex.moved(base + u - lo, base + p - lo if p >= lo else self.position[p]), tree_kind[u])

    def _recipe(self, fragment: _Fragment, tree_kind: list[EdgeKind]) -> _Recipe:
        """How a copy makes its vertices from ``fragment``'s (made on first use)."""
        if fragment.recipe is None:
            lo, hi = fragment.trimmed
            positions = self._position_of(fragment)
            steps = []
            for u in range(lo, hi):
                vertex = self.reduced.vertices[u]
                p = vertex.parent
                node = positions[id(self.origins[fragment.originals[u - lo]])]
                given: tuple[str, ...]
                if isinstance(vertex, ScopeVertex):
                    tag, given = _SCOPE, ("var_maps",)
                elif isinstance(vertex, TaskVertex):
                    tag, given = _TASK, ("content", "instance")
                else:
                    tag, given = _DECOMPOSITION, ("content", "decomposition")
                steps.append(_Step(vertex, p - lo if p >= lo else ~self.position[p], node, tag,
                                   vertex_copier(type(vertex), given)))
            fragment.recipe = _Recipe(steps, [tree_kind[u] for u in range(lo, hi)])
        return fragment.recipe

    def _in_full_order(self, items: list[tuple[int, V]]) -> Iterator[tuple[int, V, _Placed | None]]:
        """``items`` keyed by reduced vertex, in the order the reduced construction added them,
        in the order the full construction adds them, keyed by full vertex: a forAll's copies
        take the place of its built ones (whose items come one copy after the other), each with
        its representative's items.  Yields (full key, value, the copy or None outside)."""
        by_fragment: dict[int, list[tuple[int, V]]] = {}
        for key, value in items:
            if self.owner[key] != OUTSIDE:
                by_fragment.setdefault(self.owner[key], []).append((key, value))
        done: set[int] = set()
        for key, value in items:
            k = self.owner[key]
            if k == OUTSIDE:
                yield self.position[key], value, None
                continue
            r = self.fragments[k].region
            if r in done:
                continue
            done.add(r)
            for placed in self.placed[r]:
                for inner, listed in by_fragment.get(placed.fragment.number, ()):
                    yield placed.trimmed(inner), listed, placed

    def _partner_records(self, placed: _Placed) -> tuple[list[ExecutionPartner], dict[int, list[int]]]:
        """The partner records of a copy (one per task and flags, as the full construction
        shares them) in the order of its representative's, and where each partner list of the
        representative's tasks finds its records there (by the list's id)."""
        fragment = placed.fragment
        if fragment.partners is None:
            lo, hi = fragment.trimmed
            place: dict[int, int] = {}
            records: list[ExecutionPartner] = []
            lists: dict[int, list[int]] = {}
            for t in range(lo, hi):
                partners = self.reduced.ec_partners(t)
                for p in partners:
                    if id(p) not in place:
                        place[id(p)] = len(records)
                        records.append(p)
                lists[id(partners)] = [place[id(p)] for p in partners]
            fragment.partners = (records, lists)
        if placed.partners is None:
            shift = placed.start - fragment.trimmed[0]
            placed.partners = [ExecutionPartner(p.task + shift, p.group, p.divisible) for p in fragment.partners[0]]
        return placed.partners, fragment.partners[1]

    def _untrimmed_outside(self, u: int) -> int:
        """Full untrimmed position of an untrimmed vertex outside the stamped copies."""
        shift = 0
        for end, after in self.untrimmed_shifts:
            if u >= end:
                shift = after
        return u + shift

    def _carried(self, vertex: ScopeVertex, placed: _Placed | None) -> ScopeVertex:
        """A carried achieve goal at its full untrimmed position, with its copy's content."""
        if placed is None:
            return vertex.moved(self._untrimmed_outside(vertex.index),
                                vertex.parent if vertex.parent < 0 else self._untrimmed_outside(vertex.parent))
        lo, hi = placed.fragment.untrimmed
        parent = placed.untrimmed(vertex.parent) if lo <= vertex.parent < hi else self._untrimmed_outside(vertex.parent)
        if placed.content is None:
            return vertex.moved(placed.untrimmed(vertex.index), parent)
        return placed.content.scope(vertex, self.origins[vertex.index], placed.untrimmed(vertex.index), parent)


class _Content:
    """The content of one stamped copy: its annotation nodes matched to its representative's by
    their place in a depth-first walk."""

    def __init__(self, position: Mapping[int, int], copy: list[RatNode], instances: Mapping[str, TaskInstance]) -> None:
        self.position = position  # the representative's annotation node id -> its place
        self.copy = copy
        self.instances = instances
        self._task: TaskInstance | None = None  # the task whose decompositions come next
        self._binding: dict[str, Value] = {}

    def _node(self, origin: RatNode) -> RatNode:
        return self.copy[self.position[id(origin)]]

    def scope(self, vertex: S, origin: RatNode, index: int, parent: int) -> S:
        return vertex.stamped(index, parent, var_maps=self._node(origin).var_maps)

    def make(self, recipe: _Recipe, base: int, new: TaskGraphBuilder) -> None:
        """Add this copy's vertices, from ``base`` on, as ``recipe`` says."""
        nodes, instances = self.copy, self.instances
        made: list[Vertex] = []
        inst: TaskInstance | None = None
        binding: dict[str, Value] = {}
        for index, step in enumerate(recipe.steps, start=base):
            parent = base + step.parent if step.parent >= 0 else ~step.parent
            node = nodes[step.node]
            if step.tag == _SCOPE:
                made.append(step.copy(step.vertex, index, parent, node.var_maps))
                continue
            task = instances[node.content]
            if step.tag == _TASK:
                made.append(step.copy(step.vertex, index, parent, task.id, task))
                continue
            if task is not inst:
                inst, binding = task, task.binding
            old = step.vertex.decomposition  # type: ignore[union-attr]
            dec = Decomposition(f"{task.id}|{old.number}", task, old.number, old.path, ground_path(old.path, binding))
            made.append(step.copy(step.vertex, index, parent, dec.id, dec))
        new.add_children(made, recipe.kinds)


_SCOPE, _TASK, _DECOMPOSITION = range(3)


class _Step(NamedTuple):
    """One vertex of a stamped copy: made from ``vertex`` of its representative, under the
    copy's vertex at ``parent`` (relative to the copy's first; ``~`` an absolute one outside
    it), with the content of the copy's annotation node at ``node`` (in its depth-first walk)."""

    vertex: Vertex
    parent: int
    node: int
    tag: int  # _SCOPE, _TASK or _DECOMPOSITION: which content the vertex takes
    copy: Callable[..., Vertex]  # the vertex copier for that content (model.task_graph.vertex_copier)


@dataclass
class _Recipe:
    """How a copy of a fragment makes its vertices: one step per vertex, and the kind of the
    edge from its parent."""

    steps: list[_Step]
    kinds: list[EdgeKind]
