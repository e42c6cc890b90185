"""The rules of valid mission decompositions (``solve/semantics.py``), each tested once, directly,
on small hand-built Task Graphs.

Both decomposers call these functions, so a rule broken here shows up in both; the end-to-end
tests (differential, oracle, ordering) check the decomposers' use of them."""
from __future__ import annotations

import pytest
from hypothesis import HealthCheck, given, settings

from missiongen import load_mission, missions
from mutrose_cp.pipeline.constraints import Constraint, EC, SEQ
from mutrose_cp.model.task_instances import TaskInstance
from mutrose_cp.model.decomposition_paths import DecompositionPath, GroundPredicates, TreeNode
from mutrose_cp.io.hddl import load_domain
from mutrose_cp.model import Comparison, Literal, RobotNumber
from mutrose_cp.model.task_graph import (
    Decomposition,
    DecompositionVertex,
    EdgeKind,
    GoalVertex,
    OperatorVertex,
    TaskGraph,
    TaskGraphBuilder,
    TaskVertex,
)
from mutrose_cp.solve.numeric import StartCondition
from mutrose_cp.solve.semantics import (
    ConstraintIndex,
    EffectScopes,
    Effects,
    ParallelConflicts,
    State,
    application_order,
    checks_parallel_conflicts,
    context_enablers,
    contradicts_itself,
    effects_of,
    ground_preconditions_hold,
    mission_queue,
    parallel_conflicts,
    robot_partners,
    robot_precondition_writers,
)


class Graph:
    """A tiny Task Graph under construction: operators, tasks and their decompositions."""

    def __init__(self) -> None:
        self.b = TaskGraphBuilder()

    def op(self, symbol: str, parent: int = -1, edge: EdgeKind = EdgeKind.AND, goal: str = "G") -> int:
        v = self.b.add(OperatorVertex(index=self.b.next_index, parent=parent, content=symbol, goal=goal))
        if parent >= 0:
            self.b.add_edge(parent, v.index, edge)
        return v.index

    def goal(self, goal_id: str, parent: int) -> int:
        v = self.b.add(GoalVertex(index=self.b.next_index, parent=parent, content=goal_id, goal=goal_id))
        self.b.add_edge(parent, v.index, EdgeKind.AND)
        return v.index

    def task(self, name: str, parent: int, *decompositions: GroundPredicates, task_name: str = "T",
             params: tuple[tuple[str, str], ...] = (), edge: EdgeKind = EdgeKind.AND) -> list[int]:
        """A task with one decomposition per ``GroundPredicates``; returns their vertices."""
        inst = TaskInstance(name, name.split("_")[0], task_name, RobotNumber(1, 1, True), None, (), ())
        t = self.b.add(TaskVertex(index=self.b.next_index, parent=parent, content=name, instance=inst))
        self.b.add_edge(parent, t.index, edge)
        out = []
        for n, predicates in enumerate(decompositions, start=1):
            path = DecompositionPath((), TreeNode("task", task_name, ()))
            dec = Decomposition(f"{name}|{n}", inst, n, path, predicates)
            d = self.b.add(DecompositionVertex(index=self.b.next_index, parent=t.index, content=dec.id,
                                               decomposition=dec))
            self.b.add_edge(t.index, d.index, EdgeKind.AND)
            out.append(d.index)
        return out

    def freeze(self) -> TaskGraph:
        return self.b.freeze()


def sets(*facts: tuple[str, bool], numeric: tuple[tuple[str, str, int], ...] = ()) -> GroundPredicates:
    """A decomposition that sets ``p(x)`` facts and numeric ``f(x)`` values."""
    return GroundPredicates(preconditions=(), effects=tuple(Literal(p, ("x",), v) for p, v in facts),
                            numeric_effects=tuple((f, ("x",), kind, amount) for f, kind, amount in numeric))


def needs(*facts: tuple[str, bool], compare: tuple[Comparison, ...] = ()) -> GroundPredicates:
    """A decomposition whose preconditions are ``p(x)`` facts and numeric comparisons."""
    return GroundPredicates(preconditions=tuple(Literal(p, ("x",), v) for p, v in facts) + compare,
                            effects=(), numeric_effects=())


# --- the mission queue and the order of effects (§7.2, §7.3) ---------------------------------------


def test_mission_queue_holds_operators_and_tasks_in_vertex_order():
    g = Graph()
    root = g.op(";")
    means_end = g.goal("G2", root)
    (d1,) = g.task("AT1_1", means_end, sets())
    par = g.op("#", root)
    g.task("AT2_1", par, sets())
    tg = g.freeze()
    assert mission_queue(tg) == [root, 2, par, 5]  # no goal node, no decomposition
    assert d1 not in mission_queue(tg)


def test_effects_apply_in_vertex_order_not_in_id_order():
    assert application_order({12, 3, 7}) == [3, 7, 12]
    state = State({}, {})
    for eff in (Effects(((("p", ("x",)), True),), (), ()), Effects(((("p", ("x",)), False),), (), ())):
        state.apply(eff)
    assert state.fact("p", ("x",)) is False  # the later writer wins


def test_numeric_effects_assign_or_add():
    state = State({}, {("f", ("x",)): 5.0})
    state.apply(Effects((), ((("f", ("x",)), "increase", 2.0),), ()))
    assert state.value("f", ("x",)) == 7.0
    state.apply(Effects((), ((("f", ("x",)), "assign", 1.0),), ()))
    assert state.value("f", ("x",)) == 1.0
    state.apply(Effects((), ((("g", ("x",)), "increase", 3.0),), ()))
    state.apply(Effects((), ((("g", ("x",)), "increase", -1.0),), ()))
    # an unknown value stays unknown, two more than where it started
    assert state.value("g", ("x",)) is None and state.offsets == {("g", ("x",)): 2.0}
    assert state.start_condition(("g", ("x",)), ">", 0, "") == StartCondition(">", -2000)
    assert state.start_condition(("f", ("x",)), ">", 0, "") is None  # known
    state.apply(Effects((), ((("g", ("x",)), "assign", 4.0),), ()))
    assert state.value("g", ("x",)) == 4.0 and not state.offsets


def test_effects_of_splits_ground_and_free_effects():
    predicates = GroundPredicates(preconditions=(), effects=(Literal("p", ("x",), True), Literal("q", ("?r",), False)),
                                  numeric_effects=(("f", ("x",), "increase", 2), ("g", ("?r",), "assign", 1)))
    g = Graph()
    (d,) = g.task("AT1_1", g.op(";"), predicates)
    eff = effects_of(g.freeze().decomposition(d).decomposition)
    assert eff.facts == ((("p", ("x",)), True),)
    assert eff.numeric == ((("f", ("x",)), "increase", 2),)
    assert eff.free == (Literal("q", ("?r",), False),)


def test_a_task_sees_what_every_enclosing_sequence_puts_before_it():
    """[AT1 ; (AT2 # (AT3 ; AT4))]: AT2 sees AT1; AT4 sees AT1 and AT3, not its parallel cousin AT2."""
    g = Graph()
    root = g.op(";")
    (a1,) = g.task("AT1_1", root, sets())
    par = g.op("#", root)
    (a2,) = g.task("AT2_1", par, sets())
    inner = g.op(";", par)
    (a3,) = g.task("AT3_1", inner, sets())
    a4 = g.task("AT4_1", inner, sets(), sets())
    tg = g.freeze()
    scopes = EffectScopes(tg)
    task = {d: tg.vertices[d].parent for d in (a1, a2, a3, a4[0])}
    assert scopes.preceding(task[a1]) == set()
    assert scopes.preceding(task[a2]) == {a1}
    assert scopes.preceding(task[a4[0]]) == {a1, a3}
    assert scopes.subtree(par) == [a2, a3, *a4]
    # an achieve condition at the inner sequence sees its subtree and what precedes it
    assert scopes.seen_by_achieve(inner) == {a1, a3, *a4}
    # the same as runs of vertex indices, which select the writers by bisection
    decompositions = [d.index for d in tg.decompositions()]
    for t in (task[a1], task[a2], task[a4[0]]):
        seen = scopes.seen_runs_by_task(t)
        assert set(seen.select(decompositions, decompositions)) == scopes.seen_by_task(t)
    assert set(scopes.seen_runs_by_achieve(inner).select(decompositions, decompositions)) == {a1, a3, *a4}


def test_a_task_sees_the_decompositions_that_enable_its_context():
    g = Graph()
    root = g.op("#")
    (enabler,) = g.task("AT1_1", root, sets(("ready", True)))
    (d2,) = g.task("AT2_1", root, sets())
    g.b.add_edge(enabler, tg_task := g.b.vertices[d2].parent, EdgeKind.CD)
    tg = g.freeze()
    assert context_enablers(tg) == {tg_task: {enabler}}
    assert EffectScopes(tg).seen_by_task(tg_task) == {enabler}  # parallel, yet seen through the CD edge
    seen = EffectScopes(tg).seen_runs_by_task(tg_task)
    assert list(seen.select([enabler, d2], [enabler, d2])) == [enabler]


def test_seen_runs_agree_with_seen_sets_on_every_reference_task_graph(reference):
    """The runs rely on the depth-first numbering of the Task Graph: on every reference mission,
    what they select is what the sets hold, for every task and every scope vertex."""
    from mutrose_cp.mission import Mission
    from mutrose_cp.io.mission_files import find_mission_files

    graphs = 0
    for folder in sorted(p for p in reference.glob("*/*") if (p / "configuration").is_dir()):
        for config in sorted((folder / "configuration").glob("*.json")):
            try:
                tg = Mission.load(*find_mission_files(folder, config.name)).task_graph
            except Exception:  # noqa: BLE001 - missions the pipeline refuses have no Task Graph
                continue
            graphs += 1
            scopes = EffectScopes(tg)
            decompositions = [d.index for d in tg.decompositions()]
            for v in range(len(tg.vertices)):
                if isinstance(tg.vertices[v], TaskVertex):
                    got = scopes.seen_runs_by_task(v).select(decompositions, decompositions)
                    assert list(got) == sorted(scopes.seen_by_task(v)), (folder, v)
                elif not isinstance(tg.vertices[v], DecompositionVertex):
                    got = scopes.seen_runs_by_achieve(v).select(decompositions, decompositions)
                    assert list(got) == sorted(scopes.seen_by_achieve(v)), (folder, v)
    assert graphs > 20


# --- preconditions (§7.4) -----------------------------------------------------------------------------


def test_preconditions_hold_unless_the_state_contradicts_them():
    g = Graph()
    (d,) = g.task("AT1_1", g.op(";"), needs(("clean", True), compare=(Comparison("level", ("x",), ">", 2),)))
    dec = g.freeze().decomposition(d).decomposition
    assert ground_preconditions_hold(dec, State({}, {}))  # unknown atoms are satisfied
    assert ground_preconditions_hold(dec, State({("clean", ("x",)): True}, {("level", ("x",)): 3.0}))
    assert not ground_preconditions_hold(dec, State({("clean", ("x",)): False}, {}))
    assert not ground_preconditions_hold(dec, State({}, {("level", ("x",)): 2.0}))


def test_a_decomposition_that_contradicts_itself_never_holds():
    g = Graph()
    root = g.op(";")
    (both,) = g.task("AT1_1", root, needs(("clean", True), ("clean", False)))
    undone = GroundPredicates(preconditions=(), effects=(), numeric_effects=(), unsatisfiable=("clean(x)",))
    (later,) = g.task("AT2_1", root, undone)
    (fine,) = g.task("AT3_1", root, needs(("clean", True), ("dry", False)))
    tg = g.freeze()
    assert contradicts_itself(tg.decomposition(both).decomposition)
    assert contradicts_itself(tg.decomposition(later).decomposition)
    assert not contradicts_itself(tg.decomposition(fine).decomposition)
    assert not ground_preconditions_hold(tg.decomposition(both).decomposition, State({}, {}))


@pytest.mark.parametrize("tests,contradicts", [
    ((("=", 0), (">", 0)), True),
    (((">", 0), ("=", 0)), True),
    (((">", 2), ("<", 1)), True),
    (((">", 1), ("<", 1)), True),
    (((">=", 1), ("<=", 1)), False),
    (((">=", 1), ("<=", 1), ("<>", 1)), True),
    ((("=", 1), ("=", 1.0)), False),
    ((("=", 1), ("=", 2)), True),
    (((">", 0), (">", 3), ("<", 5)), False),
    ((("=", 4), (">", 3), ("<", 5)), False),
])
def test_numeric_preconditions_that_allow_no_value_together_contradict(tests, contradicts):
    """The world need not know the value: no value meets (= 0) and (> 0), in either order."""
    g = Graph()
    compare = tuple(Comparison("level", ("x",), op, value) for op, value in tests)
    (d,) = g.task("AT1_1", g.op(";"), needs(compare=compare))
    dec = g.freeze().decomposition(d).decomposition
    assert contradicts_itself(dec) == contradicts
    assert ground_preconditions_hold(dec, State({}, {})) != contradicts


# --- parallel conflicts (§7.3) ------------------------------------------------------------------------


def test_parallel_conflicts_are_checked_below_an_and_parallel_operator_only():
    g = Graph()
    root = g.op(";")
    par = g.op("#", root)
    choice = g.op("#", root)
    g.task("AT1_1", par, sets())
    g.task("AT2_1", choice, sets(), edge=EdgeKind.OR)
    tg = g.freeze()
    assert checks_parallel_conflicts(tg, par)
    assert not checks_parallel_conflicts(tg, choice)  # an OR: its children never run together
    assert not checks_parallel_conflicts(tg, root)


def test_parallel_conflicts_name_the_setters_of_each_side():
    g = Graph()
    par = g.op("#")
    on1, off1 = g.task("AT1_1", par, sets(("door", True)), sets(("door", False)))
    (off2,) = g.task("AT2_1", par, sets(("door", False), ("light", True)))
    tg = g.freeze()
    effects = {d.index: effects_of(d.decomposition) for d in tg.decompositions()}
    (conflict,) = parallel_conflicts(par, EffectScopes(tg), effects)
    assert conflict.atom == ("door", ("x",))
    assert conflict.setting_true == (on1,)
    assert conflict.setting_false == (off1, off2)
    assert _indexed_conflicts(tg, effects, par) == [conflict]


def _indexed_conflicts(tg: TaskGraph, effects: dict[int, Effects], v: int) -> list:
    """What :class:`ParallelConflicts` finds below ``v``, built from the writers of each atom in
    application order (as the encoder keeps them)."""
    writers: dict = {}
    for d in application_order(effects):
        for atom, value in effects[d].facts:
            writers.setdefault(atom, []).append((d, value))
    return ParallelConflicts(EffectScopes(tg), writers).below(v)


def test_indexed_parallel_conflicts_are_those_inside_each_operator_only():
    """Nested parallel operators: the outer one sees the conflicts of both inner ones and the
    one between them; an inner one only its own, though the atom's other writers lie outside."""
    g = Graph()
    outer = g.op("#")
    left = g.op("#", outer)
    on1, off1 = g.task("AT1_1", left, sets(("door", True)), sets(("door", False)))
    (keep1,) = g.task("AT2_1", left, sets(("light", True)))
    right = g.op("#", outer)
    (off2,) = g.task("AT1_2", right, sets(("light", False)))
    (on2,) = g.task("AT2_2", right, sets(("door", True)))
    tg = g.freeze()
    effects = {d.index: effects_of(d.decomposition) for d in tg.decompositions()}
    scopes = EffectScopes(tg)
    for v in (outer, left, right):
        assert _indexed_conflicts(tg, effects, v) == parallel_conflicts(v, scopes, effects)
    assert [(c.atom[0], c.setting_true, c.setting_false) for c in _indexed_conflicts(tg, effects, outer)] == [
        ("door", (on1, on2), (off1,)), ("light", (keep1,), (off2,))]
    assert [c.atom[0] for c in _indexed_conflicts(tg, effects, left)] == ["door"]
    assert _indexed_conflicts(tg, effects, right) == []


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions())
def test_indexed_parallel_conflicts_agree_with_the_subtree_walk_on_random_missions(spec):
    """The encoder's index of parallel conflicts finds what the exploratory algorithm's walk of
    each operator's subtree finds, on every parallel operator of random missions."""
    try:
        tg = load_mission(spec).task_graph
    except Exception:  # noqa: BLE001 - missions the pipeline refuses have no Task Graph
        return
    effects = {d.index: effects_of(d.decomposition) for d in tg.decompositions()}
    scopes = EffectScopes(tg)
    for v in range(len(tg.vertices)):
        if checks_parallel_conflicts(tg, v):
            assert _indexed_conflicts(tg, effects, v) == parallel_conflicts(v, scopes, effects)


# --- robot-related preconditions (§7.4) -----------------------------------------------------------------

ROBOT_DOMAIN = """(define (domain robots)
  (:types Arm - robot)
  (:predicates (holding ?r - Arm))
  (:capabilities grasp)
  (:task Pick :parameters (?r - Arm))
  (:method pick-m :parameters (?r - Arm) :task (Pick ?r) :ordered-subtasks (and (pick ?r)))
  (:task Drop :parameters (?s - Arm))
  (:method drop-m :parameters (?s - Arm) :task (Drop ?s) :ordered-subtasks (and (drop ?s)))
  (:action pick :parameters (?r - Arm) :required-capabilities (grasp)
     :precondition (and (not (holding ?r))) :effect (and (holding ?r)))
  (:action drop :parameters (?s - Arm) :required-capabilities (grasp)
     :precondition (and (holding ?s)) :effect (and (not (holding ?s))))
)
"""


def test_robot_partners_are_earlier_execution_partners_not_sequenced_after(tmp_path):
    """The EC partners of a decomposition that can have changed a shared robot before it: of a
    task earlier in the mission queue, and not put after it by a SEQ constraint."""
    g = Graph()
    par = g.op("#")
    (pick,) = g.task("AT1_1", par, sets())
    (drop,) = g.task("AT2_1", par, sets())
    (late,) = g.task("AT3_1", par, sets())
    tg = g.freeze()
    ecs = [Constraint(EC, pick, drop), Constraint(EC, drop, late), Constraint(EC, pick, late)]
    index = ConstraintIndex.of(ecs)
    position = {v: i for i, v in enumerate(mission_queue(tg))}
    assert robot_partners(tg, index, pick, position) == []  # nothing earlier
    assert robot_partners(tg, index, drop, position) == [pick]  # AT3 comes later in the queue
    assert robot_partners(tg, index, late, position) == [pick, drop]
    sequenced = ConstraintIndex.of(ecs + [Constraint(SEQ, late, pick)])
    assert robot_partners(tg, sequenced, late, position) == [drop]  # late must run before pick


def test_constraint_index_shares_the_partners_of_one_task_in_vertex_order():
    """The decompositions of one task have the same EC partners: one sorted tuple, read from
    any iterable of constraints (duplicates counted once)."""
    g = Graph()
    par = g.op("#")
    first, second = g.task("AT1_1", par, sets(), sets())
    (late,) = g.task("AT2_1", par, sets())
    (early,) = g.task("AT3_1", par, sets())
    constraints = [Constraint(EC, late, first), Constraint(EC, early, first), Constraint(EC, second, late),
                   Constraint(EC, second, early), Constraint(EC, early, second), Constraint(SEQ, first, late)]
    index = ConstraintIndex.of(c for c in constraints)
    assert index.ec[first] == (late, early) == tuple(sorted((late, early)))
    assert index.ec[second] is index.ec[first]
    assert index.ec[late] == (first, second)
    assert index.seq_after == {first: frozenset({late})}


def test_robot_preconditions_are_written_by_partners_effects_renamed(tmp_path):
    hddl = tmp_path / "robots.hddl"
    hddl.write_text(ROBOT_DOMAIN)
    domain = load_domain(hddl)
    g = Graph()
    par = g.op("#")
    pick_effects = GroundPredicates(preconditions=(Literal("holding", ("?r",), False),),
                                    effects=(Literal("holding", ("?r",), True),), numeric_effects=())
    drop_needs = GroundPredicates(preconditions=(Literal("holding", ("?s",), True),),
                                  effects=(Literal("holding", ("?s",), False),), numeric_effects=())
    (pick,) = g.task("AT1_1", par, pick_effects, task_name="Pick")
    (drop,) = g.task("AT2_1", par, drop_needs, task_name="Drop")
    tg = g.freeze()
    index = ConstraintIndex.of([Constraint(EC, pick, drop)])
    position = {v: i for i, v in enumerate(mission_queue(tg))}
    (written,) = robot_precondition_writers(domain, tg, drop, index, position)
    precondition, writers = written
    assert precondition == Literal("holding", ("?s",), True)
    assert writers == [(pick, True)]  # pick's (holding ?r) renamed onto drop's ?s
    assert robot_precondition_writers(domain, tg, pick, index, position) == []  # no partner before it


def test_seen_selects_writers_by_runs_and_single_vertices():
    """Runs apart in the graph whose writers are adjacent give one view of the writers (no copy);
    a single vertex inside a run is not selected twice; the view reads like a list."""
    from mutrose_cp.solve.semantics import Seen, _Span

    positions = [1, 2, 4, 7, 9, 12]
    items = [f"w{p}" for p in positions]
    view = Seen(((0, 3), (4, 8))).select(items, positions)
    assert isinstance(view, _Span) and view.items is items
    assert list(view) == ["w1", "w2", "w4", "w7"] and len(view) == 4
    assert view[-1] is items[3] and view[0] == "w1" and view[1:3] == ["w2", "w4"]
    with pytest.raises(IndexError):
        view[4]
    assert list(Seen(((0, 3),), frozenset({2, 9, 10})).select(items, positions)) == ["w1", "w2", "w9"]
    assert list(Seen(((8, 10),), frozenset({1})).select(items, positions)) == ["w1", "w9"]
    assert list(Seen(()).select(items, positions)) == []


@settings(max_examples=60, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions())
def test_seen_runs_agree_with_seen_sets_on_random_missions(spec):
    """The depth-first numbering the runs rely on holds on random mission shapes too (nested
    forAll, tasks beside goals, OR goals, unique branches)."""
    try:
        tg = load_mission(spec).task_graph
    except Exception:  # noqa: BLE001 - missions the pipeline refuses have no Task Graph
        return
    scopes = EffectScopes(tg)
    decompositions = [d.index for d in tg.decompositions()]
    for v in range(len(tg.vertices)):
        if isinstance(tg.vertices[v], TaskVertex):
            assert list(scopes.seen_runs_by_task(v).select(decompositions, decompositions)) == sorted(
                scopes.seen_by_task(v))
        elif not isinstance(tg.vertices[v], DecompositionVertex):
            assert list(scopes.seen_runs_by_achieve(v).select(decompositions, decompositions)) == sorted(
                scopes.seen_by_achieve(v))
