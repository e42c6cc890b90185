"""Regression tests for the world state a task sees (effect order, enclosing sequences, context
dependencies, achieve conditions) and for self-contradictory or inapplicable methods, in both
decomposers, on minimal missions built with the mission generator's model.

Effects of the decompositions a task sees are applied in Task Graph vertex order (§7.3, the
order of the SEQ constraints), not in the string order of their ids, where ``AT10_1|1`` comes
before ``AT2_1|1``.
"""
from __future__ import annotations

import json

from mutrose_cp.cli.program import main
from mutrose_cp.errors import NoDecompositionError
from mutrose_cp.mission import Mission

from missiongen import Action, Change, Cmp, GoalNode, Lit, Method, MissionSpec, Room, Task, TaskNode

NOOP = Action("wait-here")
SET_LIT = Action("switch-on", eff=(Lit("lit", "?rm"),))
UNSET_LIT = Action("switch-off", eff=(Lit("lit", "?rm", False),))
NEED_DARK = Action("inspect-dark", pre=(Lit("lit", "?rm", False),))
NEED_LIGHT = Action("inspect-lit", pre=(Lit("lit", "?rm"),))
ACTIONS = (NOOP, SET_LIT, UNSET_LIT, NEED_DARK, NEED_LIGHT)


def _task(name: str, action: Action, pre: tuple = ()) -> Task:
    return Task(name, (Method(f"{name.lower()}-method", pre, (action.name,)),))


TASKS = (_task("Wait", NOOP), _task("LightOn", SET_LIT), _task("LightOff", UNSET_LIT),
         _task("InspectDark", NEED_DARK), _task("InspectLit", NEED_LIGHT))


def _spec(tree: GoalNode, tasks=TASKS, actions=ACTIONS, lit: bool | None = None) -> MissionSpec:
    room = Room("Room1", True, (("lit", lit), ("sealed", None)), 0)
    return MissionSpec(("lit", "sealed"), ("charged",), actions, tasks, (room,), True, "", tree)


def _solve(spec: MissionSpec, tmp_path) -> tuple[Mission, list[set[str]], list[set[str]]]:
    """Both algorithms' valid mission decompositions, as sets of decomposition ids."""
    mission = Mission.load(*spec.write(tmp_path / "mission"))
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    try:
        exploratory = sorted(({ids[d] for d in md} for md in mission.exploratory()), key=sorted)
    except NoDecompositionError:
        exploratory = []
    cpsat = sorted(({ids[d] for d in md} for md in mission.decomposition_space()), key=sorted)
    return mission, exploratory, cpsat


def test_effects_apply_in_task_graph_order_not_id_order(tmp_path):
    """[AT1;...;AT11]: AT2 switches the light on, AT10 off, AT11 needs it off.  In id order
    AT10's effect would come before AT2's and leave the light on."""
    children = [TaskNode("Wait")] * 11
    children[1] = TaskNode("LightOn")
    children[9] = TaskNode("LightOff")
    children[10] = TaskNode("InspectDark")
    tree = GoalNode(tuple(children), annotation=("flat", ";"))
    mission, exploratory, cpsat = _solve(_spec(tree), tmp_path)
    expected = [{f"AT{k}_1|1" for k in range(1, 12)}]
    assert exploratory == cpsat == expected
    assert main(["count", str(tmp_path / "mission")]) == 0


def test_effects_follow_the_sequence_constraints_after_trimming(tmp_path, capsys):
    """[G4;AT2;G5] with G4 -> AT1 (light off), AT2 (light on), G5 -> AT3 (needs light).
    Trimming puts the direct task AT2 first: the SEQ constraints say AT2, AT1, AT3, so the light
    is off when AT3 runs and no mission decomposition is valid (as in the original)."""
    tree = GoalNode((GoalNode((TaskNode("LightOff"),)), TaskNode("LightOn"), GoalNode((TaskNode("InspectLit"),))),
                    annotation=("flat", ";"))
    spec = _spec(tree)
    mission, exploratory, cpsat = _solve(spec, tmp_path)
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    seq = [(ids[c.first], ids[c.second]) for c in mission.constraints if c.kind == "SEQ"]
    assert seq == [("AT2_1|1", "AT1_1|1"), ("AT1_1|1", "AT3_1|1")]
    assert exploratory == cpsat == []
    for algorithm in ("exploratory", "cpsat"):
        assert main(["decompose", str(tmp_path / "mission"), "--algorithm", algorithm, "-q",
                     "-o", str(tmp_path / "out.json")]) == 3
    assert "AT3_1" in capsys.readouterr().err


def test_a_method_that_contradicts_itself_is_never_valid(tmp_path):
    """A method requiring (lit ?rm) and (not (lit ?rm)) can never be applied: only the other
    method of the task gives a valid decomposition, in both algorithms and whatever the world
    says.  The original lists the contradictory path (|1), and so it stays, with its number."""
    contradictory = Method("impossible", (Lit("lit", "?rm"), Lit("lit", "?rm", False)), ("wait-here",))
    duplicate = Method("doubled", (Lit("sealed", "?rm"), Lit("sealed", "?rm")), ("switch-on",))
    tasks = (Task("Prepare", (contradictory, duplicate)),)
    tree = GoalNode((TaskNode("Prepare"), TaskNode("Prepare")), annotation=("flat", ";"))
    for lit in (None, True, False):
        mission, exploratory, cpsat = _solve(_spec(tree, tasks=tasks, lit=lit), tmp_path / str(lit))
        paths = mission.paths["Prepare"]
        assert [[s.name for s in p.actions] for p in paths] == [["wait-here"], ["switch-on"]]
        assert [bool(p.never_valid) for p in paths] == [True, False]
        assert exploratory == cpsat == [{"AT1_1|2", "AT2_1|2"}]


def test_effects_printed_in_declaration_order(tmp_path):
    """A robot-related effect declared before a ground one stays first in the output (consumers
    diff these files against the original's)."""
    act = Action("charge-and-light", eff=(Lit("charged", "?r", False), Lit("lit", "?rm")))
    tasks = (_task("Prepare", act),)
    tree = GoalNode((TaskNode("Prepare"), TaskNode("Prepare")), annotation=("flat", ";"))
    folder = tmp_path / "mission"
    _spec(tree, tasks=tasks, actions=(act,)).write(folder)
    out = tmp_path / "out.json"
    assert main(["decompose", str(folder), "-q", "-o", str(out)]) == 0
    task = json.loads(out.read_text())["tasks"]["t0"]
    assert [e["predicate"] for e in task["effects"]] == ["not ?r.is_charged", "Room1.is_lit"]


# ---------------------------------------------------------------------------------------------
# What a task sees: every task its SEQ constraints put before it (docs/deviations.md)


def test_nested_operator_sees_what_precedes_it(tmp_path):
    """[LightOff;(InspectLit#Wait)] with the light on: the SEQ constraints put LightOff before
    the parallel block, so InspectLit finds the light off.  (The original starts a nested
    operator's children from the initial state and lists the decomposition.)"""
    tree = GoalNode((TaskNode("LightOff"), GoalNode((TaskNode("InspectLit"), TaskNode("Wait")), annotation=("flat", "#"))),
                    annotation=("flat", ";"))
    _mission, exploratory, cpsat = _solve(_spec(tree, lit=True), tmp_path)
    assert exploratory == cpsat == []


def test_context_enabler_effects_are_seen(tmp_path):
    """[LightOn#G(context: lit) -> InspectLit], light off: LightOn enables the context through
    the parallel operator, the SEQ constraint puts it first, so InspectLit finds the light on."""
    dependent = GoalNode((TaskNode("InspectLit"),), condition="current_room.is_lit")
    tree = GoalNode((TaskNode("LightOn"), dependent), annotation=("flat", "#"))
    mission, exploratory, cpsat = _solve(_spec(tree, lit=False), tmp_path)
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    assert [(ids[c.first], ids[c.second]) for c in mission.constraints if c.kind == "SEQ"] == [("AT1_1|1", "AT2_1|1")]
    assert exploratory == cpsat == [{"AT1_1|1", "AT2_1|1"}]


def test_enabled_context_must_hold_where_the_task_starts(tmp_path):
    """[LightOn;LightOff;G(context: lit) -> Wait], light off: LightOn enables the context, but
    LightOff undoes it before Wait starts, so no mission decomposition is valid."""
    dependent = GoalNode((TaskNode("Wait"),), condition="current_room.is_lit")
    tree = GoalNode((TaskNode("LightOn"), TaskNode("LightOff"), dependent), annotation=("flat", ";"))
    _mission, exploratory, cpsat = _solve(_spec(tree, lit=False), tmp_path)
    assert exploratory == cpsat == []
    # without LightOff the enabled context holds
    tree = GoalNode((TaskNode("LightOn"), TaskNode("Wait"), dependent), annotation=("flat", ";"))
    _mission, exploratory, cpsat = _solve(_spec(tree, lit=False), tmp_path / "enabled")
    assert exploratory == cpsat == [{"AT1_1|1", "AT2_1|1", "AT3_1|1"}]


def test_means_end_achieve_goal_keeps_its_condition(tmp_path):
    """An achieve goal with a single child is not an operator; trimming removes it, and the
    original loses its condition.  Here G(achieve: lit) -> LightOff can never be achieved."""
    achieve = GoalNode((TaskNode("LightOff"),), achieve="current_room.is_lit")
    tree = GoalNode((TaskNode("Wait"), achieve), annotation=("flat", ";"))
    _mission, exploratory, cpsat = _solve(_spec(tree, lit=True), tmp_path)
    assert exploratory == cpsat == []
    achieve = GoalNode((TaskNode("LightOn"),), achieve="current_room.is_lit")
    tree = GoalNode((TaskNode("Wait"), achieve), annotation=("flat", ";"))
    _mission, exploratory, cpsat = _solve(_spec(tree, lit=False), tmp_path / "kept")
    assert exploratory == cpsat == [{"AT1_1|1", "AT2_1|1"}]


def test_unique_branch_decomposition_meets_the_achieve_condition(tmp_path):
    """A mission of one task (a unique-branch Task Graph): its decomposition must still leave
    the forAll condition true; the original skips achieve conditions there."""
    tree = GoalNode((TaskNode("LightOff"),))
    spec = _spec(tree, lit=True)
    spec = MissionSpec(spec.room_predicates, spec.robot_predicates, spec.actions, spec.tasks, spec.rooms,
                       spec.query_active, "current_room.is_lit", tree)
    mission, exploratory, cpsat = _solve(spec, tmp_path)
    assert mission.task_graph.unique_branch
    assert exploratory == cpsat == []


def test_a_subtask_without_executable_method_makes_its_method_inapplicable(tmp_path):
    """Prepare's first method calls Inspect, whose only method can never run: the original drops
    the subtask and keeps [wait-here] as a decomposition that skips the inspection.  It stays
    listed with the original's number (|1), and is never valid."""
    inspect = Task("Inspect", (Method("inspect-lit", (Lit("lit", "?rm", False),), ("inspect-lit",)),))
    prepare = Task("Prepare", (Method("with-inspection", (), ("Inspect", "wait-here")),
                               Method("light-only", (), ("switch-on",))))
    tree = GoalNode((TaskNode("Prepare"), TaskNode("Wait")), annotation=("flat", ";"))
    mission, exploratory, cpsat = _solve(_spec(tree, tasks=(inspect, prepare) + TASKS), tmp_path)
    paths = mission.paths["Prepare"]
    assert [[s.name for s in p.actions] for p in paths] == [["wait-here"], ["switch-on"]]
    assert paths[0].never_valid == ("its subtask Inspect has no executable method",) and not paths[1].never_valid
    assert exploratory == cpsat == [{"AT1_1|2", "AT2_1|1"}]


def _with_level(tree: GoalNode, tasks, actions, level: int) -> MissionSpec:
    room = Room("Room1", True, (("lit", True), ("sealed", None)), level)
    return MissionSpec(("lit", "sealed"), ("charged",), actions, tasks, (room,), True, "", tree)


def test_numeric_precondition_after_an_increase_is_checked_on_the_start_value(tmp_path):
    """bump (level + 1), then Check, whose method needs level = 1.  Path generation takes the
    unknown level as 0 + 1 and the original then drops the precondition: the decomposition was
    valid whatever the world said.  It holds when the mission starts at level 0, not at 1."""
    bump = Action("bump", eff=(Change("increase"),))
    check = Task("Check", (Method("check-at-one", (Cmp("=", 1),), ("wait-here",)),))
    bump_then_check = Task("BumpThenCheck", (Method("bump-check", (), ("bump", "Check")),))
    tree = GoalNode((TaskNode("BumpThenCheck"), TaskNode("Wait")), annotation=("flat", ";"))
    tasks, actions = (check, bump_then_check, *TASKS), (bump, *ACTIONS)
    _m, exploratory, cpsat = _solve(_with_level(tree, tasks, actions, 0), tmp_path / "zero")
    assert exploratory == cpsat == [{"AT1_1|1", "AT2_1|1"}]
    _m, exploratory, cpsat = _solve(_with_level(tree, tasks, actions, 1), tmp_path / "one")
    assert exploratory == cpsat == []


def test_a_precondition_undone_inside_the_path_is_never_valid(tmp_path):
    """Twice runs Inner two times; Inner needs the light on and switches it off.  Path
    generation does not pass an abstract subtask's effects on to the next one, and the second
    Inner's precondition was dropped: the decomposition looked valid with the light on."""
    inner = Task("Inner", (Method("inner", (Lit("lit", "?rm"),), ("switch-off",)),))
    twice = Task("Twice", (Method("twice", (), ("Inner", "Inner")),))
    tree = GoalNode((TaskNode("Twice"), TaskNode("Wait")), annotation=("flat", ";"))
    mission, exploratory, cpsat = _solve(_spec(tree, tasks=(inner, twice) + TASKS, lit=True), tmp_path)
    assert [[s.name for s in p.actions] for p in mission.paths["Twice"]] == [["switch-off", "switch-off"]]
    assert exploratory == cpsat == []
