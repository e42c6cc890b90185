"""The rules of valid mission decompositions (spec ``semantics.md`` §7), decided once.

Both decomposers ask the same questions and answer them here:

* the mission queue (§7.2): :func:`mission_queue`;
* which effects a vertex sees and in which order they apply (§7.3): :class:`EffectScopes`,
  :func:`application_order`, :class:`State`;
* preconditions (§7.4): :func:`ground_preconditions_hold`, :func:`contradicts_itself`;
* context dependencies (§5.2, checked where the task starts): :func:`context_enablers`;
* robot-related preconditions against execution-constrained partners (§7.4):
  :func:`robot_partners`, :func:`robot_precondition_writers`;
* parallel conflicts (§7.3): :func:`checks_parallel_conflicts`, :func:`parallel_conflicts` (and
  :class:`ParallelConflicts`, the same for every operator of a graph at once);
* achieve conditions (§7.5): :func:`achieve_tests`;
* unique-branch missions (§7.7): :func:`unique_branch_valid`.

The exploratory algorithm applies these rules to explicit lists of partial decompositions; the
CP-SAT encoder posts the same rules as clauses over choice literals.
"""
from __future__ import annotations

import itertools
import math
from bisect import bisect_left
from dataclasses import dataclass
from functools import cached_property
from typing import Iterable, Iterator, Mapping, Sequence, TypeVar, overload

from ..model.state_tests import AllOf, Test, ValueTest
from ..pipeline.conditions import compare, holds, translate
from ..pipeline.constraints import EC, SEQ, Constraint
from ..errors import MissionError
from ..model import Binding, Configuration, Domain, GoalModel, InitialState, Literal, show_precondition
from ..model.task_graph import (
    Decomposition,
    DecompositionVertex,
    EdgeKind,
    OperatorVertex,
    ScopeVertex,
    TaskGraph,
    TaskVertex,
)
from ..model.world import scaled
from .numeric import StartCondition, StartConditions

AtomKey = tuple[str, tuple[str, ...]]


def is_ground(args: Iterable[str]) -> bool:
    return not any(a.startswith("?") for a in args)


@dataclass(frozen=True)
class Effects:
    """What a decomposition does to the world, in application order."""

    facts: tuple[tuple[AtomKey, bool], ...]  # ground boolean effects
    numeric: tuple[tuple[AtomKey, str, float], ...]  # ground (atom, "assign"|"increase", amount)
    free: tuple[Literal, ...]  # non-ground effects (over the task's parameter names)


NO_EFFECTS = Effects((), (), ())


def effects_of(dec: Decomposition) -> Effects:
    p = dec.predicates
    if not p.effects and not p.numeric_effects:
        return NO_EFFECTS  # most decompositions of a large mission: one frozen record serves them
    facts: list[tuple[AtomKey, bool]] = []
    free: list[Literal] = []
    for e in p.effects:  # one pass: the encoder asks this of every decomposition
        if is_ground(e.args):
            facts.append(((e.predicate, e.args), e.positive))
        else:
            free.append(e)
    numeric = tuple(((f, a), k, float(v) if isinstance(v, float) else v) for f, a, k, v in p.numeric_effects if is_ground(a))
    return Effects(tuple(facts), numeric, tuple(free))


class State:
    """A ground world state: the initial facts overlaid with applied effects.

    A function's value is known (``values``), or unknown plus what the increases and decreases
    applied so far add up to (``offsets``, :mod:`.numeric`): an increase of a value the world
    does not give leaves it unknown."""

    __slots__ = ("facts", "values", "offsets")

    def __init__(self, facts: dict[AtomKey, bool], values: dict[AtomKey, float],
                 offsets: dict[AtomKey, float] | None = None) -> None:
        self.facts = facts
        self.values = values
        self.offsets: dict[AtomKey, float] = offsets if offsets is not None else {}

    def copy(self) -> "State":
        return State(dict(self.facts), dict(self.values), dict(self.offsets))

    def apply(self, eff: Effects) -> None:
        for key, val in eff.facts:
            self.facts[key] = val
        for key, kind, amount in eff.numeric:
            if kind == "assign":
                self.values[key] = amount
                self.offsets.pop(key, None)
            elif key in self.values:
                self.values[key] = self.values[key] + amount
            else:
                self.offsets[key] = self.offsets.get(key, 0) + amount

    def start_condition(self, atom: AtomKey, op: str, bound: float, source: str) -> StartCondition | None:
        """What ``atom op bound`` required here asks of the atom's start value, when the world
        does not give it and no assignment did (None when the value is known)."""
        if atom in self.values:
            return None
        return StartCondition(op, scaled(bound) - scaled(self.offsets.get(atom, 0)), source)

    def required_conditions(self, test: Test, source: str) -> list[tuple[AtomKey, StartCondition]]:
        """The start conditions of the comparisons ``test`` requires outright (its conjuncts;
        a comparison in a disjunction constrains nothing, the open world)."""
        if isinstance(test, ValueTest):
            atom = (test.function, test.args)
            condition = self.start_condition(atom, test.op, test.value, source)
            return [] if condition is None else [(atom, condition)]
        if isinstance(test, AllOf):
            return [found for part in test.parts for found in self.required_conditions(part, source)]
        return []

    def fact(self, predicate: str, args: tuple[str, ...]) -> bool | None:
        return self.facts.get((predicate, args))

    def value(self, function: str, args: tuple[str, ...]) -> float | None:
        return self.values.get((function, args))

    def satisfies(self, test: Test) -> bool:
        """Whether ``test`` holds here (open world: unknown atoms are satisfied)."""
        return holds(test, self.fact, self.value)


def initial_state(initial: InitialState) -> State:
    """The initial world as a :class:`State` (the first entry of a repeated atom wins)."""
    return State(initial.fact_map(), dict(initial.value_map()))


class ConstraintIndex:
    """Execution-constraint partners and SEQ successors of each decomposition vertex.

    Only decompositions with robot-related preconditions ask for them (§7.4), so the tables are
    built on first use: a large mission often has no such precondition, while its execution
    constraints number in the millions.  The decompositions of one task have the same partners,
    so they share one sorted tuple (a set per decomposition took more memory than the
    constraints themselves)."""

    def __init__(self, constraints: Sequence[Constraint]) -> None:
        self._constraints = constraints

    @classmethod
    def of(cls, constraints: Iterable[Constraint]) -> "ConstraintIndex":
        return cls(constraints if isinstance(constraints, Sequence) else list(constraints))

    @property
    def ec(self) -> Mapping[int, tuple[int, ...]]:
        """Decomposition -> its EC partners, in vertex order."""
        return self._tables[0]

    @property
    def seq_after(self) -> Mapping[int, frozenset[int]]:
        """Decomposition -> the decompositions a SEQ constraint puts after it."""
        return self._tables[1]

    @cached_property
    def _tables(self) -> tuple[dict[int, tuple[int, ...]], dict[int, frozenset[int]]]:
        ec: dict[int, list[int]] = {}
        seq_after: dict[int, list[int]] = {}
        for c in self._constraints:
            if c.kind == EC:
                ec.setdefault(c.first, []).append(c.second)
                ec.setdefault(c.second, []).append(c.first)
            elif c.kind == SEQ:
                seq_after.setdefault(c.first, []).append(c.second)
        shared: dict[tuple[int, ...], tuple[int, ...]] = {}
        partners = {}
        for d, found in ec.items():
            key = tuple(sorted(set(found)))
            partners[d] = shared.setdefault(key, key)
        return partners, {d: frozenset(after) for d, after in seq_after.items()}


def contradicts_itself(dec: Decomposition) -> bool:
    """Whether ``dec`` can never run: two ground boolean preconditions require opposite values
    of one atom, ground numeric preconditions on one function allow no value together (``(=
    (level ?rm) 0)`` and ``(> (level ?rm) 0)``), or a step's precondition is undone by an
    earlier step of the same path.

    The ground preconditions that remain after grounding (§2.5) all speak of the state in which
    the decomposition starts, so such a decomposition can never be executed, whatever the
    world knows.  (Parameters bound to the same entity can make a method's preconditions
    contradict only once grounded; a contradiction visible in the domain already prunes the
    path, ``htn``.)"""
    if dec.predicates.unsatisfiable:
        return True  # an earlier step of its own path undoes a later step's precondition
    required: dict[AtomKey, bool] = {}
    ranges: dict[AtomKey, _Range] = {}
    for c in dec.predicates.checked_preconditions:
        if not is_ground(c.args):
            continue
        if isinstance(c, Literal):
            if required.setdefault((c.predicate, c.args), c.positive) != c.positive:
                return True
        elif not ranges.setdefault((c.function, c.args), _Range()).narrow(c.op, c.value):
            return True
    return False


class _Range:
    """The values a function may have for the numeric preconditions seen so far: an interval
    (each end open or closed), or one value; read the way preconditions are evaluated
    (:func:`compare`, ``negated`` ignored as by the original)."""

    def __init__(self) -> None:
        self.low, self.low_open = -math.inf, True
        self.high, self.high_open = math.inf, True
        self.value: float | None = None
        self.tests: list[tuple[str, float]] = []

    def narrow(self, op: str, bound: float) -> bool:
        """Add ``value op bound``; False when no value is left."""
        self.tests.append((op, bound))
        if op == "=":
            if self.value is None:
                self.value = bound
        elif op in (">", ">="):
            if bound > self.low or (bound == self.low and op == ">"):
                self.low, self.low_open = bound, op == ">"
        elif op in ("<", "<="):
            if bound < self.high or (bound == self.high and op == "<"):
                self.high, self.high_open = bound, op == "<"
        if self.value is not None:
            return all(compare(self.value, o, b) for o, b in self.tests)
        if self.low > self.high or (self.low == self.high and (self.low_open or self.high_open)):
            return False
        return not (self.low == self.high and any(o == "<>" and compare(self.low, "=", b) for o, b in self.tests))


def context_enablers(tg: TaskGraph) -> dict[int, set[int]]:
    """Task vertex -> the decompositions with a context-dependency edge into it (§5.2).

    Such a decomposition makes the task's context true and the SEQ constraints put it first,
    so the task sees its effects (the original checks the task against the state without
    them; docs/deviations.md)."""
    out: dict[int, set[int]] = {}
    for d in tg.decompositions():
        for t in tg.out(d.index, EdgeKind.CD):
            out.setdefault(t, set()).add(d.index)
    return out


def ground_preconditions_hold(dec: Decomposition, state: State) -> bool:
    """§7.4: ground boolean and numeric preconditions; unknown atoms are satisfied, but a
    decomposition that contradicts itself never holds."""
    if contradicts_itself(dec):
        return False
    for c in dec.predicates.checked_preconditions:
        if not is_ground(c.args):
            continue
        if isinstance(c, Literal):
            known = state.facts.get((c.predicate, c.args))
            if known is not None and known != c.positive:
                return False
        else:
            known_v = state.values.get((c.function, c.args))
            if known_v is not None and not compare(known_v, c.op, c.value):
                return False
    return True


def precondition_start_conditions(dec: Decomposition, state: State) -> list[tuple[AtomKey, StartCondition]]:
    """The start conditions (:mod:`.numeric`) of ``dec``'s ground numeric preconditions on
    values that are unknown where it starts in ``state``."""
    out = []
    for c in dec.predicates.checked_preconditions:
        if isinstance(c, Literal) or not is_ground(c.args):
            continue
        atom = (c.function, c.args)
        condition = state.start_condition(atom, c.op, c.value, f"{dec.id}: precondition {show_precondition(c)}")
        if condition is not None:
            out.append((atom, condition))
    return out


def robot_parameters(domain: Domain, dec: Decomposition) -> list[tuple[str, str]]:
    """The (parameter, type) pairs of the decomposition's task that are robots."""
    task = domain.task_by_name[dec.instance.name]
    return [(p.name, p.type) for p in task.parameters if p.type in domain.robot_sorts]


def robot_preconditions(domain: Domain, dec: Decomposition) -> list[Literal]:
    """Non-ground boolean preconditions over robot parameters only (checked through ECs)."""
    free = [c for c in dec.predicates.preconditions if isinstance(c, Literal) and not is_ground(c.args)]
    if not free:
        return []
    task = domain.task_by_name[dec.instance.name]
    types = {p.name: p.type for p in task.parameters}
    out = []
    for c in free:
        params = [a for a in c.args if a in types]
        if params and all(types[a] in domain.robot_sorts for a in params):
            out.append(c)
    return out


def translate_robot_effects(domain: Domain, source: Decomposition, target: Decomposition) -> list[Literal]:
    """``source``'s non-ground effects renamed into ``target``'s robot parameters, pairing
    robot parameters of equal type in order (how ECs share a robot between tasks)."""
    src = robot_parameters(domain, source)
    dst = robot_parameters(domain, target)
    rename: dict[str, str] = {}
    used: set[int] = set()
    for name, type_ in src:
        for j, (dname, dtype) in enumerate(dst):
            if j not in used and dtype == type_:
                rename[name] = dname
                used.add(j)
                break
    out = []
    for e in source.predicates.effects:
        if is_ground(e.args) or not all(a in rename for a in e.args if a.startswith("?")):
            continue
        out.append(Literal(e.predicate, tuple(rename.get(a, a) for a in e.args), e.positive))
    return out


def achieve_test(vertex: ScopeVertex, gm: GoalModel, config: Configuration) -> Test | None:
    """The achieve condition an operator vertex must satisfy (§7.5), or None.

    A ``forAll`` condition must hold for *every* element of the iterated collection of this
    node (the original checks only the last element; see ``docs/deviations.md``)."""
    if not (vertex.forall or vertex.achieve) or not vertex.goal:
        return None
    goal = gm.node(vertex.goal)
    where = f"{gm.source}: goal {goal.id}"
    if goal.forall is not None:
        fa = goal.forall
        if fa.condition is None:
            return None
        iterated = vertex.var_maps.get(fa.iterated)
        if iterated is None:
            return None
        decl = next((d for d in goal.controls if d.name == fa.iteration), None)
        it_type = decl.type if decl is not None else ""
        values = iterated.value if isinstance(iterated.value, tuple) else (iterated.value,)
        parts = []
        for i, value in enumerate(values):
            record = iterated.records[i: i + 1]
            bindings = {**vertex.var_maps, fa.iteration: Binding(value, it_type, tuple(record))}
            parts.append(translate(fa.condition, bindings, config, where))
        return AllOf(tuple(parts))
    if goal.achieve_condition is None:
        return None
    return translate(goal.achieve_condition, vertex.var_maps, config, where)


def achieve_tests(tg: TaskGraph, v: int, gm: GoalModel, config: Configuration) -> list[tuple[str, Test]]:
    """(goal, condition) pairs to check once vertex ``v``'s subtree is done (§7.5): the vertex's
    own achieve condition and those of the achieve goals trimming removed above it.

    The original loses the latter: a means-end achieve goal (one child) is not an operator, so
    trimming drops it with its condition (docs/deviations.md)."""
    out = []
    at = tg.vertices[v]
    own = achieve_test(at, gm, config) if isinstance(at, ScopeVertex) else None
    if own is not None:
        out.append((tg.scope(v).goal or "", own))
    for vertex in tg.achieve_carried.get(v, ()):
        try:
            test = achieve_test(vertex, gm, config)
        except MissionError:
            # a condition no semantic mapping translates speaks of unknown facts, which hold
            # (the reference object-picking mission has one: current_room.objects_picked)
            continue
        if test is not None:
            out.append((vertex.goal or "", test))
    return out


def unique_branch_valid(tg: TaskGraph, dec: DecompositionVertex, initial: State, gm: GoalModel, config: Configuration) -> bool:
    """§7.7: whether a decomposition of a unique-branch mission is a mission decomposition on its
    own: its preconditions hold in the initial state, and so does every achieve condition above
    its task once its effects are applied.  (The original skips the achieve conditions here,
    so a mission whose only task undoes its own goal was "valid"; docs/deviations.md.)"""
    assert dec.decomposition is not None
    if not ground_preconditions_hold(dec.decomposition, initial):
        return False
    required = precondition_start_conditions(dec.decomposition, initial)
    tests = []
    v = tg.vertices[dec.parent].parent
    while v >= 0:
        test = achieve_test(tg.scope(v), gm, config)
        if test is not None:
            tests.append(test)
        v = tg.vertices[v].parent
    state = initial.copy()
    state.apply(effects_of(dec.decomposition))
    for t in tests:
        if not state.satisfies(t):
            return False
        required += state.required_conditions(t, "achieve condition")
    return StartConditions().admit(required) is not None


# ---------------------------------------------------------------------------------------------
# The mission queue and the scope of effects (§7.2, §7.3)

def mission_queue(tg: TaskGraph) -> list[int]:
    """§7.2: every task and operator vertex of the trimmed Task Graph, in vertex order.

    Trimming keeps only operators with two or more children (or an achieve condition), but an
    operator whose children were goal leaves (queries) can be left with fewer: it still scopes
    its subtree."""
    return [v.index for v in tg.vertices if isinstance(v, (TaskVertex, OperatorVertex))]


def application_order(decompositions: Iterable[int]) -> list[int]:
    """Decomposition vertices in the order their effects apply: Task Graph vertex order.

    The original's maps are keyed by vertex index (§7.3), which is also the order of the SEQ
    constraints; the order of the id strings would put ``AT10_1|1`` before ``AT2_1|1``."""
    return sorted(decompositions)


T = TypeVar("T")


class _Span(Sequence[T]):
    """``items[start:stop]`` without copying them: the tasks of a long sequence each see a
    longer prefix of a fact's writers, and copying every prefix would be quadratic."""

    __slots__ = ("items", "start", "stop")

    def __init__(self, items: Sequence[T], start: int, stop: int) -> None:
        self.items, self.start, self.stop = items, start, stop

    def __len__(self) -> int:
        return self.stop - self.start

    @overload
    def __getitem__(self, i: int) -> T: ...

    @overload
    def __getitem__(self, i: slice) -> Sequence[T]: ...

    def __getitem__(self, i: int | slice) -> T | Sequence[T]:
        if isinstance(i, slice):
            return self.items[self.start:self.stop][i]
        n = self.stop - self.start
        if not -n <= i < n:
            raise IndexError(i)
        return self.items[self.start + (i if i >= 0 else i + n)]

    def __iter__(self) -> Iterator[T]:
        return itertools.islice(self.items, self.start, self.stop)


@dataclass(frozen=True)
class Seen:
    """Decomposition vertices whose effects a vertex sees, as runs of vertex indices plus single
    vertices.  The Task Graph is numbered depth first, so what the enclosing sequences put before
    a vertex is one run per sequence: the tasks of a sequence of thousands see ever longer runs,
    which are looked up by bisection instead of being copied into a set per task."""

    runs: tuple[tuple[int, int], ...]  # [first, end) vertex indices, in order, disjoint
    single: frozenset[int] = frozenset()  # context-dependency enablers

    def select(self, items: Sequence[T], positions: Sequence[int]) -> Sequence[T]:
        """The ``items`` whose vertex (``positions``, increasing) is seen, in order: a slice per
        run and per single vertex, found by bisection."""
        spans = [(bisect_left(positions, lo), bisect_left(positions, hi)) for lo, hi in self.runs]
        for d in self.single:
            i = bisect_left(positions, d)
            if i < len(positions) and positions[i] == d and not any(lo <= d < hi for lo, hi in self.runs):
                spans.append((i, i + 1))
        spans = sorted((a, b) for a, b in spans if a < b)
        joined: list[tuple[int, int]] = []
        for a, b in spans:  # runs apart in the graph may hold adjacent writers: one span then
            if joined and joined[-1][1] == a:
                joined[-1] = (joined[-1][0], b)
            else:
                joined.append((a, b))
        if len(joined) == 1:
            return _Span(items, *joined[0])
        return list(itertools.chain.from_iterable(items[a:b] for a, b in joined))


class EffectScopes:
    """Which decompositions' effects a vertex of the Task Graph sees (§7.3).

    A vertex sees, for every sequence above it, the decompositions of the subtrees before the
    branch that holds it (the original only looks at the vertex's own parent sequence;
    docs/deviations.md #16).  A task also sees the decompositions with a context-dependency edge
    into it, which the SEQ constraints put first (§5.2).  Subtrees are cached: each is asked for
    by every operator above it."""

    def __init__(self, tg: TaskGraph) -> None:
        self.tg = tg
        self.enablers = context_enablers(tg)
        self._subtree: dict[int, list[int]] = {}
        self._last: dict[int, int] = {}
        self._runs: dict[int, tuple[tuple[int, int], ...]] = {}

    def subtree(self, v: int) -> list[int]:
        """The decomposition vertices below ``v`` (its own, for a task), in vertex order."""
        if v not in self._subtree:
            tg = self.tg
            if isinstance(tg.vertices[v], TaskVertex):
                self._subtree[v] = [d.index for d in tg.decompositions_of(v)]
            else:
                self._subtree[v] = [d for c in tg.children(v) for d in self.subtree(c)]
        return self._subtree[v]

    def last_below(self, v: int) -> int:
        """The last decomposition vertex below ``v`` (-1 if none).  Vertices are numbered depth
        first, so the decompositions below ``v`` are exactly those from ``v`` to this one: a
        range, found without listing the subtree."""
        last = self._last.get(v)
        if last is None:
            tg = self.tg
            if isinstance(tg.vertices[v], TaskVertex):
                own = tg.decompositions_of(v)
                last = own[-1].index if own else -1
            else:
                last = -1
                for c in tg.children(v):  # a loop, not max() over a generator: deep graphs recurse
                    last = max(last, self.last_below(c))  # here without the C stack
            self._last[v] = last
        return last

    def preceding(self, v: int) -> set[int]:
        """The decompositions an enclosing sequence puts before ``v``."""
        tg = self.tg
        out: set[int] = set()
        child, p = v, tg.vertices[v].parent
        while p >= 0:
            if tg.vertices[p].content == ";":
                for c in tg.children(p):
                    if c == child:
                        break
                    out.update(self.subtree(c))
            child, p = p, tg.vertices[p].parent
        return out

    def preceding_runs(self, v: int) -> list[tuple[int, int]]:
        """:meth:`preceding` as runs of vertex indices: the earlier children of each enclosing
        sequence, from its first child up to the branch that holds ``v`` (depth-first numbering)."""
        return list(self._preceding_runs(v))

    def _preceding_runs(self, v: int) -> tuple[tuple[int, int], ...]:
        """:meth:`preceding_runs`, kept per vertex: a vertex's runs are its parent's, plus one
        when the parent is a sequence (the runs of a sequence's earlier children start before
        those of the sequences above it, so the new run goes last)."""
        tg, runs = self.tg, self._runs
        path = []  # from v up to the first vertex whose runs are known (or the root)
        u = v
        while u >= 0 and u not in runs:
            path.append(u)
            u = tg.vertices[u].parent
        known = runs[u] if u >= 0 else ()
        for u in reversed(path):
            p = tg.vertices[u].parent
            if p >= 0 and tg.vertices[p].content == ";":
                first = tg.children(p)[0]
                if first != u:
                    known = (*known, (first, u))
            runs[u] = known
        return known

    def seen_runs_by_task(self, t: int) -> Seen:
        """:meth:`seen_by_task` as a :class:`Seen`."""
        return Seen(self._preceding_runs(t), frozenset(self.enablers.get(t, ())))

    def seen_runs_by_achieve(self, v: int) -> Seen:
        """:meth:`seen_by_achieve` as a :class:`Seen`: the runs before ``v`` and its own subtree."""
        last = self.last_below(v)
        own = [(v, last + 1)] if last >= 0 else []
        return Seen((*self._preceding_runs(v), *own))

    def seen_by_task(self, t: int) -> set[int]:
        """The decompositions whose effects make the state where task ``t`` starts."""
        return self.preceding(t) | self.enablers.get(t, set())

    def seen_by_achieve(self, v: int) -> set[int]:
        """The decompositions whose effects make the state where ``v``'s achieve conditions are
        checked: those of its subtree and those before it."""
        return set(self.subtree(v)) | self.preceding(v)


# ---------------------------------------------------------------------------------------------
# Parallel conflicts (§7.3)

@dataclass(frozen=True)
class ParallelConflict:
    """Decompositions below one parallel operator that set ``atom`` to opposite values."""

    atom: AtomKey
    setting_true: tuple[int, ...]
    setting_false: tuple[int, ...]


def checks_parallel_conflicts(tg: TaskGraph, v: int) -> bool:
    """Whether operator ``v`` forbids conflicting effects: an AND-parallel ``#`` (an OR ``#``
    chooses one child, so its children never run together)."""
    vx = tg.vertices[v]
    return isinstance(vx, OperatorVertex) and vx.content == "#" and not tg.is_or(v)


def parallel_conflicts(v: int, scopes: EffectScopes, effects: Mapping[int, Effects]) -> list[ParallelConflict]:
    """The atoms that two decompositions below the parallel operator ``v`` set both ways, by
    atom.  A valid decomposition does not choose a setter of each side (effects are net per
    decomposition, so the two setters belong to different tasks)."""
    by_atom: dict[AtomKey, tuple[list[int], list[int]]] = {}
    for d in application_order(scopes.subtree(v)):
        for atom, value in effects[d].facts:
            setting_true, setting_false = by_atom.setdefault(atom, ([], []))
            (setting_true if value else setting_false).append(d)
    return [ParallelConflict(atom, tuple(t), tuple(f)) for atom, (t, f) in sorted(by_atom.items()) if t and f]


class ParallelConflicts:
    """:func:`parallel_conflicts` of every parallel operator of one Task Graph, from each atom's
    writers (the encoder's, in application order) instead of a walk of each operator's subtree:
    nested parallel operators (one per forAll instance, below the one over all of them) would
    walk every decomposition once per level.

    An operator's decompositions are a range of vertex indices (:meth:`EffectScopes.last_below`),
    and it sets an atom both ways exactly when the range holds two writers of the atom that are
    adjacent in its writer list and write opposite values.  Those pairs are indexed by their
    first writer, so an operator looks only at the pairs that start inside it."""

    def __init__(self, scopes: EffectScopes, writers: Mapping[AtomKey, Sequence[tuple[int, bool]]]) -> None:
        self.scopes = scopes
        self._setters: dict[AtomKey, tuple[list[int], list[int]]] = {}
        pairs: list[tuple[int, int, AtomKey]] = []
        for atom, written in writers.items():
            flips = [(a, b) for (a, va), (b, vb) in zip(written, written[1:]) if va != vb]
            if flips:
                pairs.extend((a, b, atom) for a, b in flips)
                self._setters[atom] = ([d for d, value in written if value], [d for d, value in written if not value])
        pairs.sort()
        self._pairs = pairs
        self._starts = [a for a, _, _ in pairs]

    def below(self, v: int) -> list[ParallelConflict]:
        """The atoms that two decompositions below operator ``v`` set both ways, by atom."""
        if not self._pairs:
            return []
        lo, hi = v, self.scopes.last_below(v) + 1
        starts, pairs = self._starts, self._pairs
        atoms = {atom for _, b, atom in pairs[bisect_left(starts, lo):bisect_left(starts, hi)] if b < hi}
        out = []
        for atom in sorted(atoms):
            true, false = self._setters[atom]
            out.append(ParallelConflict(atom, tuple(true[bisect_left(true, lo):bisect_left(true, hi)]),
                                        tuple(false[bisect_left(false, lo):bisect_left(false, hi)])))
        return out


# ---------------------------------------------------------------------------------------------
# Robot-related preconditions (§7.4)

def robot_partners(tg: TaskGraph, index: ConstraintIndex, d: int, queue_position: Mapping[int, int]) -> list[int]:
    """The execution-constrained partners of decomposition ``d`` that can have changed the robots
    ``d`` shares with them before ``d`` starts: partners of tasks earlier in the mission queue
    that no SEQ constraint puts after ``d``, in application order."""
    task = tg.vertices[d].parent
    after = index.seq_after.get(d, frozenset())
    return [e for e in application_order(index.ec.get(d, ()))
            if queue_position[tg.vertices[e].parent] < queue_position[task] and e not in after]


def robot_precondition_writers(domain: Domain, tg: TaskGraph, d: int, index: ConstraintIndex,
                               queue_position: Mapping[int, int]) -> list[tuple[Literal, list[tuple[int, bool]]]]:
    """Each robot-related precondition of ``d`` with the :func:`robot_partners` (in application
    order) whose effects, renamed onto ``d``'s robot parameters, write it: (partner, value
    written).

    An unknown robot fact holds; the value the last chosen writer gives must agree with the
    precondition.  Preconditions that no partner writes are left out."""
    dec = tg.decomposition(d).decomposition
    preconditions = robot_preconditions(domain, dec)
    if not preconditions:
        return []
    translated = [(e, translate_robot_effects(domain, tg.decomposition(e).decomposition, dec))
                  for e in robot_partners(tg, index, d, queue_position)]
    out = []
    for lit in preconditions:
        writers = [(e, eff.positive) for e, effs in translated for eff in effs
                   if eff.predicate == lit.predicate and eff.args == lit.args]
        if writers:
            out.append((lit, writers))
    return out
