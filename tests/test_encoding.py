"""The CP-SAT model of valid mission decompositions (``solve/encoding.py``) on small hand-made
missions, one rule each: parallel conflicts (pairwise and the many-writers form), conflicts
below OR alternatives, achieve conditions of alternatives that are not chosen, and robot
preconditions checked against execution-constrained partners.  Each test pins the exact set of
valid mission decompositions and checks that the exploratory algorithm agrees."""
from __future__ import annotations

import dataclasses
import tempfile

import pytest

from mutrose_cp.errors import NoDecompositionError
from mutrose_cp.mission import Mission

from missiongen import Action, Change, Cmp, GoalNode, Lit, Method, MissionSpec, Room, Task, TaskNode

SET_CLEAN = Action("act0", (), (Lit("clean", "?rm"),))
UNSET_CLEAN = Action("act1", (), (Lit("clean", "?rm", False),))
SET_LIT = Action("act2", (), (Lit("lit", "?rm"),))
NOOP = Action("act3", (), ())
DISCHARGE = Action("act4", (), (Lit("charged", "?r", False),))
CHARGE = Action("act5", (), (Lit("charged", "?r"),))
NEEDS_CHARGE = Action("act6", (Lit("charged", "?r"),), ())
ACTIONS = (SET_CLEAN, UNSET_CLEAN, SET_LIT, NOOP, DISCHARGE, CHARGE, NEEDS_CHARGE)


def _task(name: str, *bodies: str) -> Task:
    """A task whose k-th method calls the action ``bodies[k]``."""
    return Task(name, tuple(Method(f"m{name[-1]}{k}", (), (b,)) for k, b in enumerate(bodies)))


def _spec(tree: GoalNode, *tasks: Task) -> MissionSpec:
    """One room (not clean, not lit); the robot's charge is unknown."""
    room = Room("Room1", True, (("clean", False), ("lit", False)), 0)
    return MissionSpec(("clean", "lit"), ("charged",), ACTIONS, tasks, (room,), True, "", tree)


def _decompose(mission: Mission) -> set[frozenset[str]]:
    """Valid mission decompositions (decomposition ids) of the CP-SAT decomposer, checked
    against the exploratory algorithm."""
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    space = mission.decomposition_space()
    cpsat = {frozenset(ids[d] for d in md) for md in space}
    assert space.count == len(cpsat)
    try:
        exploratory = {frozenset(ids[d] for d in md) for md in mission.exploratory()}
    except NoDecompositionError:
        exploratory = set()
    assert cpsat == exploratory
    return cpsat


def _solve(spec: MissionSpec, edit=None) -> set[frozenset[str]]:
    with tempfile.TemporaryDirectory(prefix="mutrose-enc-") as d:
        hddl, gm, config = spec.write(d)
        if edit is not None:
            hddl.write_text(edit(hddl.read_text()))
        return _decompose(Mission.load(hddl, gm, config))


def _md(*ids: str) -> frozenset[str]:
    return frozenset(ids)


# ---------------------------------------------------------------------------------------------
# Parallel conflicts


@pytest.mark.parametrize("setters", [1, 2, 5])
def test_parallel_tasks_may_not_set_a_fact_both_ways(setters):
    """AT1 # AT2: every method of TaskA makes the room clean; four methods of TaskB make it not
    clean and the fifth only lights it.  Only the fifth can run in parallel with TaskA.  With five
    setters there are 5 x 4 = 20 conflicting pairs, more than the pairwise form posts."""
    a = _task("TaskA", *["act0"] * setters)
    b = _task("TaskB", "act1", "act1", "act1", "act1", "act2")
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", "#"))
    assert _solve(_spec(tree, a, b)) == {_md(f"AT1_1|{k}", "AT2_1|5") for k in range(1, setters + 1)}


def test_a_task_sees_the_writers_of_its_branch_not_those_of_a_parallel_one():
    """AT1 # (AT2 ; AT3): TaskB may make the room clean, TaskA may make it not clean (or do
    nothing), TaskD needs it clean.  AT3 sees AT2's effects but not AT1's, although AT1 writes
    the fact first in Task Graph order: only AT2's cleaning can enable AT3, and AT1 must then
    keep out of the way (a parallel conflict otherwise)."""
    needs_clean = Action("act7", (Lit("clean", "?rm"),), ())
    tree = GoalNode((TaskNode("TaskA"), GoalNode((TaskNode("TaskB"), TaskNode("TaskD")), annotation=("flat", ";"))),
                    annotation=("flat", "#"))
    spec = dataclasses.replace(_spec(tree, _task("TaskA", "act1", "act3"), _task("TaskB", "act0", "act3"),
                                     _task("TaskD", "act7")), actions=(*ACTIONS, needs_clean))
    assert _solve(spec) == {_md("AT1_1|2", "AT2_1|1", "AT3_1|1")}


def test_a_task_sees_the_numeric_writers_of_its_branch_not_those_of_a_parallel_one():
    """The same with a number: AT1 # (AT2 ; AT3), TaskA may raise the level by 2, TaskB by 1,
    TaskD needs it at 1 (from 0).  AT3 sees only AT2's change, although AT1 writes first in Task
    Graph order: TaskB must raise it, whatever TaskA does."""
    up2, up1 = Action("act7", (), (Change("increase", 2),)), Action("act8", (), (Change("increase", 1),))
    needs1 = Action("act9", (Cmp("=", 1),), ())
    tree = GoalNode((TaskNode("TaskA"), GoalNode((TaskNode("TaskB"), TaskNode("TaskD")), annotation=("flat", ";"))),
                    annotation=("flat", "#"))
    spec = dataclasses.replace(_spec(tree, _task("TaskA", "act7", "act3"), _task("TaskB", "act8", "act3"),
                                     _task("TaskD", "act9")), actions=(*ACTIONS, up2, up1, needs1))
    assert _solve(spec) == {_md("AT1_1|1", "AT2_1|1", "AT3_1|1"), _md("AT1_1|2", "AT2_1|1", "AT3_1|1")}


def test_sequence_below_or_alternative_is_not_a_parallel_conflict():
    """An OR goal (``#`` over its alternatives) whose first alternative is AT1;AT2 (clean, then
    not clean): the sequence is fine, only one alternative runs, so both are valid."""
    seq = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", ";"))
    tree = GoalNode((GoalNode((seq, GoalNode((TaskNode("TaskC"),))), "or", ("flat", "#")),))
    found = _solve(_spec(tree, _task("TaskA", "act0"), _task("TaskB", "act1"), _task("TaskC", "act2")))
    assert found == {_md("AT1_1|1", "AT2_1|1"), _md("AT3_1|1")}


def test_parallel_conflict_inside_or_alternative():
    """The same alternative with AT1#AT2 is a conflict: only the other alternative is left."""
    par = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", "#"))
    tree = GoalNode((GoalNode((par, GoalNode((TaskNode("TaskC"),))), "or", ("flat", "#")),))
    found = _solve(_spec(tree, _task("TaskA", "act0"), _task("TaskB", "act1"), _task("TaskC", "act2")))
    assert found == {_md("AT3_1|1")}


# ---------------------------------------------------------------------------------------------
# Achieve conditions


@pytest.mark.parametrize("lights", [False, True])
def test_achieve_condition_binds_only_the_chosen_alternative(lights):
    """OR over (AT1;AT2 with achieve condition ``is_lit``) and AT3.  When TaskA does not light
    the room, the first alternative fails its achieve condition, but the second one is still a
    valid mission decomposition (an inactive operator's condition does not apply)."""
    a = _task("TaskA", "act2" if lights else "act3")
    alt = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", ";"), achieve="current_room.is_lit")
    tree = GoalNode((GoalNode((alt, GoalNode((TaskNode("TaskB"),))), "or", ("flat", "#")),))
    found = _solve(_spec(tree, a, _task("TaskB", "act3")))
    assert found == ({_md("AT1_1|1", "AT2_1|1")} if lights else set()) | {_md("AT3_1|1")}


# ---------------------------------------------------------------------------------------------
# Robot preconditions through execution constraints (Divisible=False shares the robot)


def test_robot_precondition_sees_an_earlier_partner():
    """[AT1;AT2] under Divisible=False: TaskA discharges the shared robot, so TaskB's method
    that needs a charged robot is invalid; its other method remains."""
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", ";"), divisible=False)
    found = _solve(_spec(tree, _task("TaskA", "act4"), _task("TaskB", "act6", "act3")))
    assert found == {_md("AT1_1|1", "AT2_1|2")}


def test_robot_precondition_ignores_a_later_partner():
    """[AT1;AT2] with TaskA needing the charge and TaskB discharging afterwards: both methods of
    TaskA are valid."""
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", ";"), divisible=False)
    found = _solve(_spec(tree, _task("TaskA", "act6", "act3"), _task("TaskB", "act4")))
    assert found == {_md("AT1_1|1", "AT2_1|1"), _md("AT1_1|2", "AT2_1|1")}


def test_robot_precondition_without_execution_constraint():
    """Without Divisible=False the tasks need not share a robot: no robot rule applies."""
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", ";"))
    found = _solve(_spec(tree, _task("TaskA", "act4"), _task("TaskB", "act6", "act3")))
    assert found == {_md("AT1_1|1", "AT2_1|1"), _md("AT1_1|1", "AT2_1|2")}


def test_robot_precondition_sees_the_last_partner_writer():
    """[AT1;AT2;AT3]: TaskA discharges, TaskB either recharges (method 1) or does nothing
    (method 2), TaskC needs the charge.  The last writer decides: only the recharge works."""
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskB"), TaskNode("TaskC")), annotation=("flat", ";"),
                    divisible=False)
    found = _solve(_spec(tree, _task("TaskA", "act4"), _task("TaskB", "act5", "act3"), _task("TaskC", "act6")))
    assert found == {_md("AT1_1|1", "AT2_1|1", "AT3_1|1")}


@pytest.mark.parametrize("discharged, valid", [("?r", {2}), ("?r2", {1, 2})])
def test_robot_precondition_matches_the_robot_argument(discharged, valid):
    """Tasks with two robots ``?r ?r2`` (paired in order between EC partners): TaskA discharges
    ``discharged``, TaskB's first method needs ``?r`` charged.  Discharging the other robot
    does not invalidate it."""
    def two_robots(text: str) -> str:
        text = text.replace("(?r - Bot ?rm - room)", "(?r - Bot ?r2 - Bot ?rm - room)").replace(" ?r ?rm)", " ?r ?r2 ?rm)")
        return text.replace("(not (charged ?r))", f"(not (charged {discharged}))")

    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", ";"), divisible=False)
    found = _solve(_spec(tree, _task("TaskA", "act4"), _task("TaskB", "act6", "act3")), two_robots)
    assert found == {_md("AT1_1|1", f"AT2_1|{k}") for k in valid}
