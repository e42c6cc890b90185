"""Numbers and recursion (docs/numbers.md): known, pinned and unknown values, and recursions
unrolled against the world, in both decomposers and in ``validate``.

Each case below failed before the numeric semantics was written down: the single-task recursion
was never unrolled, a decimal world value was unrolled once too often, an increase of an unknown
value made it known, and a value pinned by an ``=`` was forgotten from one task to the next.
Where the original decomposer is at hand, its numbering of the decompositions is compared too.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

import original
from numericgen import decomposition_actions as _actions, valid_decompositions as _valid
from missiongen import Action, Change, Cmp, GoalNode, Method, MissionSpec, Room, Task, TaskNode
from mutrose_cp.cli.program import main
from mutrose_cp.io.decomposition_output import load_decomposition_output
from mutrose_cp.mission import Mission
from mutrose_cp.validate import validate

PICK = Action("pick-object", eff=(Change("decrease"),))
PICK_TWO = Action("pick-two", eff=(Change("decrease", 2),))
REPORT = Action("report")


def _recursion(step_action: Action = PICK, guard: float = 1, base: Cmp = Cmp("=", 1),
               base_action: Action = PICK) -> Task:
    """The storage pattern: pick while more than ``guard`` objects are left, then the base case."""
    return Task("PickObject", (
        Method("object-pick-multiple", (Cmp(">", guard),), (step_action.name, "PickObject")),
        Method("object-pick-single", (base,), (base_action.name,)),
    ))


def _spec(tasks: tuple[Task, ...], actions: tuple[Action, ...], levels: tuple[float | None, ...],
          tree: GoalNode, condition: str = "") -> MissionSpec:
    rooms = tuple(Room(f"Room{i + 1}", True, (), level) for i, level in enumerate(levels))
    return MissionSpec((), (), actions, tasks, rooms, True, condition, tree)


ONE_TASK = GoalNode((TaskNode("PickObject"),))


def _decompose(spec: MissionSpec, folder: Path) -> dict[str, tuple[int, dict | None]]:
    """Both algorithms' exit status and output (None without), by algorithm; every output is
    checked by the validator too."""
    files = spec.write(folder)
    mission = Mission.load(*files)
    out: dict[str, tuple[int, dict | None]] = {}
    for algorithm in ("exploratory", "cpsat"):
        target = folder / f"{algorithm}.json"
        status = main(["decompose", str(folder), "-q", "--algorithm", algorithm, "-o", str(target)])
        document = json.loads(target.read_text()) if status == 0 else None
        if document is not None:
            report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state,
                              load_decomposition_output(str(target)))
            assert report.valid, [str(v) for v in report.violations]
        out[algorithm] = (status, document)
    return out


def _both(spec: MissionSpec, folder: Path) -> tuple[int, dict | None]:
    """The two algorithms agree (status, valid decompositions, actions); the exploratory's."""
    results = _decompose(spec, folder)
    (s1, d1), (s2, d2) = results["exploratory"], results["cpsat"]
    assert s1 == s2
    if d1 is not None:
        assert d2 is not None and _valid(d1) == _valid(d2) and _actions(d1) == _actions(d2)
    return s1, d1


# ---------------------------------------------------------------------------------------------
# 1. a recursion in a mission of one task is unrolled


def test_recursion_in_a_single_task_mission_is_unrolled(tmp_path):
    """One room with 6 objects: |1 is six picks (multiple x5, then single) and valid; the single
    pick |2 stays listed (the original's numbering) in no valid mission decomposition.  The
    original lists |1 with two picks only (it does not unroll a unique-branch mission)."""
    spec = _spec((_recursion(),), (PICK,), (6,), ONE_TASK, "current_room.level = 0")
    status, document = _both(spec, tmp_path / "mission")
    assert status == 0 and document is not None
    assert _actions(document) == {"AT1_1|1": ["pick-object"] * 6, "AT1_1|2": ["pick-object"]}
    assert _valid(document) == {frozenset({"AT1_1|1"})}
    if original.available():
        ran = original.run(tmp_path / "mission", *spec.write(tmp_path / "mission"))
        assert ran.status == 0 and ran.actions() == {"AT1_1|1": ["pick-object"] * 2, "AT1_1|2": ["pick-object"]}


def test_recursion_over_an_unknown_value_runs_once_with_a_warning(tmp_path, capsys):
    spec = _spec((_recursion(),), (PICK,), (None,), ONE_TASK)
    folder = tmp_path / "mission"
    spec.write(folder)
    assert main(["decompose", str(folder), "-o", str(tmp_path / "out.json")]) == 0
    err = capsys.readouterr().err
    assert ("warning: decomposition AT1_1|1: the world gives no value for level(Room1), which bounds a recursive "
            "method, so its recursion is unrolled once, as the original does") in err
    document = json.loads((tmp_path / "out.json").read_text())
    assert _actions(document)["AT1_1|1"] == ["pick-object"] * 2
    # one unrolling needs level 2 where it starts; the single pick needs 1: both are possible
    assert _valid(document) == {frozenset({"AT1_1|1"}), frozenset({"AT1_1|2"})}


# ---------------------------------------------------------------------------------------------
# 2. the repeat count, for decimal values and any step


@pytest.mark.parametrize(("level", "picks"), [(4, 4), (4.0, 4), (6, 6), (1, None), (3.5, None)])
def test_repeat_count_follows_the_world_value(tmp_path, level, picks):
    """4.0 is four picks like 4 (the original's float formula gives five, and the mission fails);
    3.5 never reaches the base case (= 1): no valid decomposition; 1 takes the single pick."""
    spec = _spec((_recursion(),), (PICK,), (level,), ONE_TASK, "current_room.level = 0")
    status, document = _both(spec, tmp_path / "mission")
    if level == 1:
        assert status == 0 and _valid(document) == {frozenset({"AT1_1|2"})}
    elif picks is None:
        assert status == 3
    else:
        assert status == 0 and _valid(document) == {frozenset({"AT1_1|1"})}
        assert _actions(document)["AT1_1|1"] == ["pick-object"] * picks


@pytest.mark.parametrize(("level", "runs"), [(7, 3), (8, 3), (9, 4), (8.5, 4), (3, 1)])
def test_repeat_count_with_a_step_that_does_not_divide_the_distance(tmp_path, level, runs):
    """Pick two while more than two are left, then one: 7 runs at 7, 5 and 3 (the original's
    (7 - 2) // 2 - 1 = 1 more gives two runs, and leaves 3 > 2 unpicked)."""
    spec = _spec((_recursion(PICK_TWO, 2, Cmp(">", 0)),), (PICK, PICK_TWO), (level,), ONE_TASK)
    status, document = _both(spec, tmp_path / "mission")
    assert status == 0
    # the single pick (> 0) is a valid decomposition too: no goal asks for an empty room
    assert _valid(document) == {frozenset({"AT1_1|1"}), frozenset({"AT1_1|2"})}
    assert _actions(document)["AT1_1|1"] == ["pick-two"] * runs + ["pick-object"]


# ---------------------------------------------------------------------------------------------
# 3. an increase of an unknown value leaves it unknown


def test_decreases_of_an_unknown_value_do_not_refute_the_condition(tmp_path):
    """Drain decreases level twice; the goal's condition is level > 0 and the world has no
    level: the value is unknown - 2, not -2, and the decomposition is kept (as by the original
    and the validator).  With level 5 in the world it is kept too; with 2 it is not."""
    drain = Task("Drain", (Method("drain", (), ("pick-object", "pick-object")),))
    tree = GoalNode((TaskNode("Drain"),))
    for level, status in ((None, 0), (5, 0), (2, 3)):
        spec = _spec((drain,), (PICK,), (level,), tree, "current_room.level > 0")
        got, document = _both(spec, tmp_path / f"level-{level}")
        assert got == status, level
        if status == 0:
            assert _valid(document) == {frozenset({"AT1_1|1"})}
    if original.available():
        spec = _spec((drain,), (PICK,), (None,), tree, "current_room.level > 0")
        ran = original.run(tmp_path / "level-None", *spec.write(tmp_path / "level-None"))
        assert ran.valid_decompositions() == {frozenset({"AT1_1|1"})}


def test_unknown_value_in_a_sequence_keeps_its_offset(tmp_path):
    """[Raise;Check] with level unknown: Raise adds 1, Check needs level = 1 and its own
    method level > 0: the start value must be 0, which is possible."""
    raise_ = Task("Raise", (Method("raise", (), ("bump",)),))
    check = Task("Check", (Method("check", (Cmp("=", 1), Cmp(">", 0)), ("report",)),))
    tree = GoalNode((TaskNode("Raise"), TaskNode("Check")), annotation=("flat", ";"))
    spec = _spec((raise_, check), (Action("bump", eff=(Change("increase"),)), REPORT), (None,), tree)
    status, document = _both(spec, tmp_path / "mission")
    assert status == 0 and _valid(document) == {frozenset({"AT1_1|1", "AT2_1|1"})}


# ---------------------------------------------------------------------------------------------
# 4. a value pinned by "=" holds from task to task


def _pinned(tmp_path: Path, level: float | None) -> Path:
    task_b = Task("TaskB", (Method("at-one", (Cmp("=", 1),), ("bump",)),))
    tree = GoalNode((TaskNode("TaskB"), TaskNode("TaskB")), annotation=("flat", ";"))
    spec = _spec((task_b,), (Action("bump", eff=(Change("increase"),)),), (level,), tree)
    folder = tmp_path / f"level-{level}"
    spec.write(folder)
    return folder


def test_a_value_pinned_by_an_equality_is_kept_from_task_to_task(tmp_path, capsys):
    """[AT1;AT2], both needing level = 1 and raising it by 1, level unknown: AT1 pins it to 1
    and leaves 2, so AT2's (= level 1) never holds.  The original accepts it."""
    folder = _pinned(tmp_path, None)
    for algorithm in ("exploratory", "cpsat"):
        assert main(["decompose", str(folder), "-q", "--algorithm", algorithm, "-o", str(tmp_path / "o.json")]) == 3
    capsys.readouterr()
    assert main(["decompose", str(folder), "--explain", "-o", str(tmp_path / "o.json")]) == 3
    err = capsys.readouterr().err
    assert "AT2_1|1: precondition level(Room1) = 1 cannot hold together with AT1_1|1: precondition level(Room1) = 1" in err
    # the same with the world's value 1: AT2 sees 2
    assert main(["decompose", str(_pinned(tmp_path, 1)), "-q", "-o", str(tmp_path / "o.json")]) == 3


def test_validate_rejects_a_decomposition_that_forgets_a_pinned_value(tmp_path, capsys):
    """The original's output for the pinned mission lists [AT1;AT2]: the validator names AT2,
    and nothing else (every field of the file is the mission's).  The output below is the
    original's, as it writes it; where the original is at hand, the test says so."""
    folder = _pinned(tmp_path, None)
    mission = Mission.load(*(folder / p for p in ("hddl/domain.hddl", "gm/gm.json", "configuration/configuration.json")))
    forged = {"actions": [{"name": "bump", "capabilities": "work"}],
              "tasks": {f"t{k}": {"id": f"AT{k + 1}_1|1", "name": "TaskB", "arguments": {"?r": "Bot", "?rm": "room"},
                                  "arguments_values": {"?r": "", "?rm": "Room1"}, "locations": "Room1",
                                  "robots_num": {"fixed": "True", "num": "1"}, "preconditions": "", "effects": "",
                                  "triggering_events": "",
                                  "decomposition": {"a0": {"name": "bump", "arguments": "?r ?rm"}},
                                  "group": "True", "divisible": "True"} for k in range(2)},
              "constraints": [{"type": "SEQ", "task_instances": {"t0": "t0", "t1": "t1"}}],
              "mission_decompositions": [["t0", "t1"]]}
    if original.available():
        files = [folder / p for p in ("hddl/domain.hddl", "gm/gm.json", "configuration/configuration.json")]
        assert original.run(folder, *files).output == forged
    path = tmp_path / "forged.json"
    path.write_text(json.dumps(forged))
    report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state,
                      load_decomposition_output(str(path)))
    assert not report.valid
    assert [(v.task, v.message) for v in report.violations] == [(
        "AT2_1|1", "one start value of a function the world does not give must meet every comparison on it: "
                   "AT1_1|1: precondition level(Room1) = 1; AT2_1|1: precondition level(Room1) = 1: no value of "
                   "level(Room1) meets them all")]


def test_validate_tries_every_method_that_explains_the_actions(tmp_path):
    """Found by the oracle: two methods run the same action, one needing level > 0 and one
    level = 0, and the forAll condition asks for level = 0 with level unknown.  The decomposers
    list the task (its second method); the validator must not settle on the first method, whose
    > 0 the condition then contradicts."""
    task = Task("TaskA", (Method("more", (Cmp(">", 0),), ("report",)), Method("none", (Cmp("=", 0),), ("report",))))
    spec = _spec((task,), (REPORT,), (None,), GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), refinement="or"),
                 "current_room.level = 0")
    status, document = _both(spec, tmp_path / "mission")  # validates every listed decomposition
    assert status == 0 and _valid(document) == {frozenset({"AT1_1|2"}), frozenset({"AT2_1|2"})}
