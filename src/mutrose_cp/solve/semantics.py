"""World-state semantics shared by both decomposition algorithms (spec ``semantics.md`` §7).

Both the exploratory combination and the CP-SAT model ask the same questions: which world facts
a decomposition changes, whether its preconditions hold in a state, which robot-related
preconditions must be checked against execution-constrained partners, and what an operator's
achieve condition requires.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Iterable

from ..conditions import AllOf, Test, compare, holds, translate
from ..constraints import EC, SEQ, Constraint
from ..errors import MissionError
from ..io.config import Configuration
from ..io.goal_model import GoalModel
from ..io.hddl import Domain, Literal
from ..query import Binding
from ..taskgraph import CD, Decomposition, TaskGraph, Vertex
from ..world import InitialState

AtomKey = tuple[str, tuple[str, ...]]


def is_ground(args: Iterable[str]) -> bool:
    return not any(a.startswith("?") for a in args)


@dataclass(frozen=True)
class Effects:
    """What a decomposition does to the world, in application order."""

    facts: tuple[tuple[AtomKey, bool], ...]  # ground boolean effects
    numeric: tuple[tuple[AtomKey, str, float], ...]  # ground (atom, "assign"|"increase", amount)
    free: tuple[Literal, ...]  # non-ground effects (over the task's parameter names)


def effects_of(dec: Decomposition) -> Effects:
    p = dec.predicates
    facts = tuple(((e.predicate, e.args), e.positive) for e in p.effects if is_ground(e.args))
    numeric = tuple(((f, a), k, float(v) if isinstance(v, float) else v) for f, a, k, v in p.numeric_effects if is_ground(a))
    free = tuple(e for e in p.effects if not is_ground(e.args))
    return Effects(facts, numeric, free)


class State:
    """A ground world state: the initial facts overlaid with applied effects."""

    __slots__ = ("facts", "values")

    def __init__(self, facts: dict[AtomKey, bool], values: dict[AtomKey, float]) -> None:
        self.facts = facts
        self.values = values

    def copy(self) -> "State":
        return State(dict(self.facts), dict(self.values))

    def apply(self, eff: Effects) -> None:
        for key, val in eff.facts:
            self.facts[key] = val
        for key, kind, amount in eff.numeric:
            if kind == "assign" or key not in self.values:
                self.values[key] = amount
            else:
                self.values[key] = self.values[key] + amount

    def fact(self, predicate: str, args: tuple[str, ...]) -> bool | None:
        return self.facts.get((predicate, args))

    def value(self, function: str, args: tuple[str, ...]) -> float | None:
        return self.values.get((function, args))


def initial_state(initial: InitialState) -> State:
    """The initial world as a :class:`State` (the first entry of a repeated atom wins)."""
    return State(initial.fact_map(), dict(initial.value_map()))


@dataclass(frozen=True)
class ConstraintIndex:
    """Execution-constraint partners and SEQ successors of each decomposition vertex."""

    ec: dict[int, set[int]]
    seq_after: dict[int, set[int]]

    @classmethod
    def of(cls, constraints: Iterable[Constraint]) -> "ConstraintIndex":
        ec: dict[int, set[int]] = {}
        seq_after: dict[int, set[int]] = {}
        for c in constraints:
            if c.kind == EC:
                ec.setdefault(c.first, set()).add(c.second)
                ec.setdefault(c.second, set()).add(c.first)
            elif c.kind == SEQ:
                seq_after.setdefault(c.first, set()).add(c.second)
        return cls(ec, seq_after)


def contradicts_itself(dec: Decomposition) -> bool:
    """Whether ``dec`` can never run: two ground boolean preconditions require opposite values
    of one atom, or a step's precondition is undone by an earlier step of the same path.

    The ground preconditions that remain after grounding (§2.5) all speak of the state in which
    the decomposition starts, so such a decomposition can never be executed, whatever the
    world knows.  (Parameters bound to the same entity can make a method's preconditions
    contradict only once grounded; a contradiction visible in the domain already prunes the
    path, ``htn``.)"""
    if dec.predicates.unsatisfiable:
        return True  # an earlier step of its own path undoes a later step's precondition
    required: dict[AtomKey, bool] = {}
    for c in dec.predicates.preconditions:
        if isinstance(c, Literal) and is_ground(c.args):
            if required.setdefault((c.predicate, c.args), c.positive) != c.positive:
                return True
    return False


def context_enablers(tg: TaskGraph) -> dict[int, set[int]]:
    """Task vertex -> the decompositions with a context-dependency edge into it (§5.2).

    Such a decomposition makes the task's context true and the SEQ constraints put it first,
    so the task sees its effects (the original checks the task against the state without
    them; docs/deviations.md)."""
    out: dict[int, set[int]] = {}
    for d in tg.decompositions():
        for t in tg.out(d.index, CD):
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


def robot_parameters(domain: Domain, dec: Decomposition) -> list[tuple[str, str]]:
    """The (parameter, type) pairs of the decomposition's task that are robots."""
    task = domain.task_by_name[dec.instance.name]
    return [(p.name, p.type) for p in task.parameters if p.type in domain.robot_sorts]


def robot_preconditions(domain: Domain, dec: Decomposition) -> list[Literal]:
    """Non-ground boolean preconditions over robot parameters only (checked through ECs)."""
    task = domain.task_by_name[dec.instance.name]
    types = {p.name: p.type for p in task.parameters}
    out = []
    for c in dec.predicates.preconditions:
        if not isinstance(c, Literal) or is_ground(c.args):
            continue
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


def achieve_test(vertex: Vertex, gm: GoalModel, config: Configuration) -> Test | None:
    """The achieve condition an operator vertex must satisfy (§7.5), or None.

    A ``forAll`` condition must hold for *every* element of the iterated collection of this
    node (the original checks only the last element; see ``docs/deviations.md``)."""
    if not (vertex.is_forall or vertex.is_achieve_type) or not vertex.achieve_goal:
        return None
    goal = gm.node(vertex.achieve_goal)
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
    own = achieve_test(tg.vertices[v], gm, config)
    if own is not None:
        out.append((tg.vertices[v].achieve_goal or "", own))
    for vertex in tg.achieve_carried.get(v, ()):
        try:
            test = achieve_test(vertex, gm, config)
        except MissionError:
            # a condition no semantic mapping translates speaks of unknown facts, which hold
            # (the reference object-picking mission has one: current_room.objects_picked)
            continue
        if test is not None:
            out.append((vertex.achieve_goal or "", test))
    return out


def unique_branch_valid(tg: TaskGraph, dec: Vertex, initial: State, gm: GoalModel, config: Configuration) -> bool:
    """§7.7: whether a decomposition of a unique-branch mission is a mission decomposition on its
    own: its preconditions hold in the initial state, and so does every achieve condition above
    its task once its effects are applied.  (The original skips the achieve conditions here,
    so a mission whose only task undoes its own goal was "valid"; docs/deviations.md.)"""
    assert dec.decomposition is not None
    if not ground_preconditions_hold(dec.decomposition, initial):
        return False
    tests = []
    v = tg.vertices[dec.parent].parent
    while v >= 0:
        test = achieve_test(tg.vertices[v], gm, config)
        if test is not None:
            tests.append(test)
        v = tg.vertices[v].parent
    if not tests:
        return True
    state = initial.copy()
    state.apply(effects_of(dec.decomposition))
    return all(holds(t, state.fact, state.value) for t in tests)
