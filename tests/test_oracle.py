"""The validator as an oracle: every mission decomposition that either algorithm lists for a
generated mission must validate (docs/validate.md).

The differential tests show that the two decomposers agree; they cannot show that both are
right, because they share one reading of the semantics.  The validator rebuilds method trees,
task order and conditions from the inputs and the output file alone, so a mistake the two
decomposers share shows up here.
"""
from __future__ import annotations

import contextlib
import io
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

import missiongen
from mutrose_cp.cli.program import main
from mutrose_cp.io.decomposition_output import load_decomposition_output
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.validate import validate

ORACLE = settings(max_examples=25, deadline=None, database=None,
                  suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


def _listed_decompositions_validate(spec: missiongen.MissionSpec) -> None:
    with tempfile.TemporaryDirectory(prefix="mutrose-oracle-") as d:
        spec.write(d)
        mission = Mission.load(*find_mission_files(d))
        for algorithm, extra in (("exploratory", []), ("cpsat", ["--limit", "0"])):
            out = Path(d) / f"{algorithm}.json"
            with contextlib.redirect_stderr(io.StringIO()):
                status = main(["decompose", d, "-q", "--algorithm", algorithm, *extra, "-o", str(out)])
            assert status in (0, 3), f"{algorithm} exited with {status}\n{spec.dump()}"
            if status == 3:
                continue
            report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state,
                              load_decomposition_output(str(out)))
            assert report.valid, (f"{algorithm} listed invalid decompositions:\n"
                                  + "\n".join(map(str, report.violations[:10])) + "\n" + spec.dump())


@pytest.mark.parametrize("shape", missiongen.SHAPES)
def test_every_listed_decomposition_validates(shape):
    @ORACLE
    @given(missiongen.missions(shape=shape))
    def check(spec):
        _listed_decompositions_validate(spec)

    check()


def test_numeric_preconditions_no_value_meets_together():
    """Found by the oracle: a method requiring (= (level ?rm) 0) and (> (level ?rm) 0) of a room
    whose level the world does not know (its action tells it from the other method).  Each comparison alone holds there, but no value meets
    both: neither decomposer may list the method, and the validator rejects it in either order."""
    for pre in ((missiongen.Cmp("=", 0), missiongen.Cmp(">", 0)), (missiongen.Cmp(">", 0), missiongen.Cmp("=", 0))):
        task = missiongen.Task("TaskB", (missiongen.Method("mB0", (missiongen.Cmp(">", 0),), ("act0",)),
                                         missiongen.Method("mB1", pre, ("act1",))))
        rooms = (missiongen.Room("Room1", True, (("lit", None),), None),)
        actions = (missiongen.Action("act0"), missiongen.Action("act1"))
        spec = missiongen.MissionSpec(("lit",), (), actions, (task,), rooms, True, "",
                                      missiongen.GoalNode((missiongen.TaskNode("TaskB"),)))
        _listed_decompositions_validate(spec)
        assert missiongen.load_mission(spec).decomposition_space().count == 1


def test_an_achieve_goal_inside_a_forall_is_checked_per_copy():
    """Found by the oracle: G6 (level > 0) sits in each copy of the item forAll and its task
    lowers the room's level by one.  With two items and level 2, each copy holds after its own
    task (the copies run in parallel and do not see each other); the validator grouped both
    copies by the condition's variables (only current_room) and checked them after both."""
    m = missiongen
    lower = m.Action("iact0", (), (m.Lit("tagged", "?it", False), m.Change("decrease", 1)), item=True)
    task_i = m.Task("TaskI", (m.Method("mI1", (), ("iact0",)),), item=True)
    task_a = m.Task("TaskA", (m.Method("mA0", (), ("act0",)),))
    items_goal = m.GoalNode((m.TaskNode("TaskA"), m.GoalNode((m.TaskNode("TaskI"),), achieve="current_room.level > 0")),
                            annotation=("flat", "#"), forall="")
    tree = m.GoalNode((m.QueryNode(), items_goal), annotation=("flat", "#"))
    rooms = (m.Room("Room1", True, (("clean", None),), 2, items=("Item2", "Item1")),)
    spec = m.MissionSpec(("clean",), (), (m.Action("act0"), lower), (task_a, task_i), rooms, False, "", tree,
                         item_predicates=("tagged",), items=(m.Item("Item1"), m.Item("Item2")))
    assert m.load_mission(spec).decomposition_space().count == 1
    _listed_decompositions_validate(spec)


def test_tasks_after_a_subtree_without_constraints_see_its_effects():
    """Found by the oracle: the room runs [G4;G5;G8], G5 being a FALLBACK over the items whose
    second branch drops (its condition is false and nothing makes it true).  G5's subtree is then
    one task with no constraint, so, as in the original, no SEQ constraint joins it to G8's task
    (semantics.md §6.1); G8's task still runs after it and sees the room it cleaned.  The
    validator read the order from the constraints only."""
    m = missiongen
    task = m.Task("TaskA", (m.Method("mA0", (m.Lit("clean", "?rm", False),), ("act0",)),
                            m.Method("mA1", (m.Lit("clean", "?rm"),), ("act1",))))
    actions = (m.Action("act0", (), (m.Lit("clean", "?rm"),)), m.Action("act1", (), (m.Lit("clean", "?rm"),)))
    items_goal = m.GoalNode((m.GoalNode((m.TaskNode("TaskA"),)),
                             m.GoalNode((m.TaskNode("TaskA"),), condition="current_room.is_clean")),
                            annotation=("flat", "FALLBACK"), forall="")
    tree = m.GoalNode((m.QueryNode(), items_goal, m.GoalNode((m.TaskNode("TaskA"),))), annotation=("flat", ";"))
    rooms = (m.Room("Room1", True, (("clean", False),), 0, items=("Item1",)),)
    spec = m.MissionSpec(("clean",), (), actions, (task,), rooms, True, "", tree,
                         item_predicates=("ready",), items=(m.Item("Item1", (("ready", True),)),))
    mission = m.load_mission(spec)
    assert not [c for c in mission.constraints if c.kind == "SEQ"], "the quirk this test is about is gone"
    assert mission.decomposition_space().count == 1
    _listed_decompositions_validate(spec)
