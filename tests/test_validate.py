"""``mutrose-cp validate``: the independent checker of decomposition outputs.

* acceptance: every golden output of the reference corpus, and the outputs of both decomposers
  (JSON and XML) on every reference mission and example, are valid;
* rejection: one test per kind of violation, each on a hand-broken copy of a real output (or on
  the unchanged output of a mission whose inputs were edited), asserting exit 1 and the located
  message (``OUTPUT: decomposition <i>: <task or goal>: <message>``);
* bad input (truncated JSON, non-UTF-8, malformed XML, wrong arguments): exit 2, a located
  message on stderr and no traceback;
* ``--json-summary``;
* the validator's own readings of the rules: the replay of a task's steps, what a decomposition
  number stands for, the orders a method's actions may come in, and what the goal model implies
  (trigger events, execution-constraint scopes, the search for a task that enables a condition).
"""
from __future__ import annotations

import json
import re
import shutil
from pathlib import Path

import pytest
from conftest import REFERENCE, ROOT, require_reference

from mutrose_cp.cli.program import main
from mutrose_cp.io.decomposition_output import load_decomposition_output
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.validate import validate

MISSIONS = REFERENCE / "missions"
EXAMPLES = ROOT / "examples"
HOSPITAL = EXAMPLES / "hospital-disinfection"
ROOM_PREP = MISSIONS / "room-preparation"
FOOD = MISSIONS / "food-logistics"


# ---------------------------------------------------------------------------------------------
# helpers


def _configurations() -> list:
    if not MISSIONS.is_dir():
        return [pytest.param(None, None, id="corpus-missing")]
    return [pytest.param(cfg.parent.parent, cfg.name, id=f"{cfg.parent.parent.name}/{cfg.name}")
            for cfg in sorted(MISSIONS.glob("*/configuration/*")) if cfg.suffix.lower() in (".json", ".xml")]


def _golden(mission: Path, cfg: str) -> Path:
    text = (mission / "configuration" / cfg).read_text()
    if cfg.endswith(".json"):
        return mission / json.loads(text)["output"]["file_path"]
    return mission / re.search(r"<file_path>(.*?)</file_path>", text).group(1)


def _run(capsys, *argv: str) -> tuple[int, str, str]:
    capsys.readouterr()
    rc = main(list(argv))
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, out, err


def _validate(capsys, monkeypatch, mission: Path, output: Path, *extra: str, cfg: str | None = None):
    """``mutrose-cp validate MISSION OUTPUT`` run from the mission folder (the original resolves
    configuration paths against the cwd)."""
    monkeypatch.chdir(mission)
    return _run(capsys, "validate", str(mission), str(output), "-q", *extra, *(["--config", cfg] if cfg else []))


def _decompose(capsys, monkeypatch, mission: Path, cfg: str, out: Path, *extra: str) -> None:
    monkeypatch.chdir(mission)
    rc, _, err = _run(capsys, "decompose", str(mission), "--config", cfg, "-q", "-o", str(out), *extra)
    assert rc == 0, err


def broken_copy(source: Path, tmp_path: Path, edit, name: str = "broken.json") -> Path:
    """A copy of a JSON output with one thing changed by ``edit(doc)`` (also used by
    test_validate_forged)."""
    doc = json.loads(source.read_text())
    edit(doc)
    path = tmp_path / name
    path.write_text(json.dumps(doc, indent=4))
    return path


def task_key(doc: dict, task_id: str) -> str:
    """The key (``t3``) of the task entry with id ``task_id``."""
    return next(k for k, t in doc["tasks"].items() if t["id"] == task_id)


def _copy_mission(mission: Path, tmp_path: Path) -> Path:
    copy = tmp_path / mission.name
    shutil.copytree(mission, copy, ignore=shutil.ignore_patterns("output"))
    return copy


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert text.count(old) == 1, f"{old!r} in {path}"
    path.write_text(text.replace(old, new))


@pytest.fixture(scope="module")
def hospital_output(tmp_path_factory) -> Path:
    """Our output for examples/hospital-disinfection: 27 tasks, 36 mission decompositions, an OR
    goal (G8), fallbacks (AT3 FB AT4, written as EC without group/divisible), a parallel
    operator (G13) and a condition context (G15: current_room.is_restocked)."""
    out = tmp_path_factory.mktemp("hospital") / "mission.json"
    assert main(["decompose", str(HOSPITAL), "-q", "--algorithm", "exploratory", "-o", str(out)]) == 0
    return out


@pytest.fixture
def room_prep(reference) -> Path:
    """Golden Room Preparation output: t1 = AT1_1|2 (RoomA, door closed: open-door, clean-room),
    t4 = AT1_2|1 (RoomB, door open: clean-room), t2/t6 sanitization EC with t1/t4, t3/t7 furniture
    moving (2..4 robots); one decomposition [t1, t2, t3, t4, t6, t7]."""
    return ROOM_PREP / "output" / "task_output.json"


@pytest.fixture
def food(reference) -> Path:
    """Golden Food Logistics (Delivery) output: G10 is an OR goal over AT2 (G11) and AT3 (G12);
    six decompositions, none with t6 = AT3_2|1 (Patient3 cannot fetch)."""
    return FOOD / "output" / "task_outputDelivery.json"


# ---------------------------------------------------------------------------------------------
# 1. acceptance


@pytest.mark.parametrize("mission,cfg", _configurations())
def test_golden_output_is_valid(mission, cfg, capsys, monkeypatch):
    require_reference()
    golden = _golden(mission, cfg)
    rc, out, err = _validate(capsys, monkeypatch, mission, golden, "--json-summary", cfg=cfg)
    summary = json.loads(out.splitlines()[-1])
    assert rc == 0, out + err
    assert summary["valid"] and summary["checked"] >= 1 and summary["invalid_decompositions"] == []


def _decomposer_cases() -> list:
    cases = []
    for mission, cfg in [(p.values[0], p.values[1]) for p in _configurations()] + \
            [(EXAMPLES / e, "configuration.json") for e in ("hospital-disinfection", "item-delivery")]:
        name = "corpus-missing" if mission is None else f"{mission.name}/{cfg}"
        for algorithm in ("exploratory", "cpsat"):
            for fmt in ("json", "xml"):
                cases.append(pytest.param(mission, cfg, algorithm, fmt, id=f"{name}-{algorithm}-{fmt}"))
    return cases


@pytest.mark.parametrize("mission,cfg,algorithm,fmt", _decomposer_cases())
def test_decomposer_output_is_valid(mission, cfg, algorithm, fmt, tmp_path, capsys, monkeypatch):
    if mission is None:
        require_reference()
    out = tmp_path / f"out.{fmt}"
    extra = ["--algorithm", algorithm, "--format", fmt] + (["--limit", "0"] if algorithm == "cpsat" else [])
    _decompose(capsys, monkeypatch, mission, cfg, out, *extra)
    assert out.read_bytes().lstrip().startswith(b"<" if fmt == "xml" else b"{")
    rc, stdout, err = _validate(capsys, monkeypatch, mission, out, "--json-summary", cfg=cfg)
    summary = json.loads(stdout.splitlines()[-1])
    assert rc == 0, stdout + err
    assert summary["valid"] and summary["checked"] >= 1


def test_python_api(room_prep, monkeypatch):
    monkeypatch.chdir(ROOM_PREP)
    mission = Mission.load(*find_mission_files(ROOM_PREP, "configuration.json"))
    report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state,
                      load_decomposition_output(str(room_prep)))
    assert report.valid and report.checked == 1 and report.violations == []


def test_python_api_refuses_a_world_it_cannot_read(room_prep, tmp_path, monkeypatch):
    """Without the world no task field can be checked: an error, never a quiet pass."""
    from mutrose_cp.errors import MissionError

    mission_dir = _copy_mission(ROOM_PREP, tmp_path)
    monkeypatch.chdir(tmp_path)
    mission = Mission.load(*find_mission_files(mission_dir, "configuration.json"))
    initial = mission.initial_state  # read while the world is there
    for world in (mission_dir / "knowledge").iterdir():
        world.unlink()
    with pytest.raises(MissionError, match="world"):
        validate(mission.domain, mission.goal_model, mission.config, initial, load_decomposition_output(str(room_prep)))


# ---------------------------------------------------------------------------------------------
# 2. rejection: one test per kind of violation


def _rejected(capsys, monkeypatch, mission: Path, output: Path, *expected: str, cfg: str | None = None) -> list[str]:
    rc, out, err = _validate(capsys, monkeypatch, mission, output, cfg=cfg)
    assert rc == 1, out + err
    lines = out.splitlines()
    for message in expected:
        assert f"{output}: {message}" in lines, "\n".join(lines)
    return lines


def test_rejects_key_that_is_not_a_task(room_prep, tmp_path, capsys, monkeypatch):
    broken = broken_copy(room_prep, tmp_path, lambda d: d["mission_decompositions"][0].append("t99"))
    _rejected(capsys, monkeypatch, ROOM_PREP, broken, "decomposition 0: t99: not a task of the file")


def test_rejects_task_instance_decomposed_twice(room_prep, tmp_path, capsys, monkeypatch):
    broken = broken_copy(room_prep, tmp_path, lambda d: d["mission_decompositions"][0].append("t0"))
    _rejected(capsys, monkeypatch, ROOM_PREP, broken,
              "decomposition 0: AT1_1|1: task instance AT1_1 is decomposed twice (AT1_1|2 and AT1_1|1)")


def test_rejects_missing_required_task_instance(room_prep, tmp_path, capsys, monkeypatch):
    broken = broken_copy(room_prep, tmp_path, lambda d: d["mission_decompositions"][0].remove("t3"))
    _rejected(capsys, monkeypatch, ROOM_PREP, broken,
              "decomposition 0: AT3_1: task instance AT3_1 is required (no OR goal above AT3) but none of "
              "its decompositions is chosen")


def test_rejects_two_branches_of_an_or_goal(food, tmp_path, capsys, monkeypatch):
    # decomposition 0 is [t0, t1, t4, t5]: AT2_1 (G11) for Delivery1; adding t2 = AT3_1|1 (G12)
    # chooses both branches of G10 for instance _1
    broken = broken_copy(food, tmp_path, lambda d: d["mission_decompositions"][0].append("t2"))
    lines = _rejected(capsys, monkeypatch, FOOD, broken,
                      "decomposition 0: G10: OR goal G10 has more than one chosen branch (G11, G12) for instance _1",
                      cfg="configurationDelivery.json")
    assert all(": decomposition 0: " in line for line in lines)  # the others stay valid
    assert not any("required" in line for line in lines)  # AT2/AT3 instances sit below an OR goal


def test_rejects_or_goal_without_chosen_branch(food, tmp_path, capsys, monkeypatch):
    # decomposition 0 without t1 = AT2_1|1 has neither branch of G10 for Delivery1
    broken = broken_copy(food, tmp_path, lambda d: d["mission_decompositions"][0].remove("t1"))
    lines = _rejected(capsys, monkeypatch, FOOD, broken,
                      "decomposition 0: G10: OR goal G10 has no chosen branch for instance _1",
                      cfg="configurationDelivery.json")
    assert len(lines) == 1


def test_rejects_seq_cycle(room_prep, tmp_path, capsys, monkeypatch):
    def edit(d):  # t1 -> t3 exists: add t3 -> t1
        d["constraints"].append({"type": "SEQ", "task_instances": {"t0": "t3", "t1": "t1"}})
    broken = broken_copy(room_prep, tmp_path, edit)
    lines = _rejected(capsys, monkeypatch, ROOM_PREP, broken)
    assert f"{broken}: decomposition 0: the SEQ/FB constraints between its tasks form a cycle: " \
           "AT1_1|2 -> AT3_1|1" in lines or \
           f"{broken}: decomposition 0: the SEQ/FB constraints between its tasks form a cycle: " \
           "AT3_1|1 -> AT1_1|2" in lines, "\n".join(lines)


def test_rejects_cycle_through_fallback(hospital_output, tmp_path, capsys, monkeypatch):
    """A fallback constraint (written as EC without group/divisible) orders its tasks: a SEQ back
    from the fallback to the task it replaces is a cycle."""
    def edit(d):
        d["constraints"].append({"type": "SEQ", "task_instances": {"t0": task_key(d, "AT4_1|1"), "t1": task_key(d, "AT3_1|1")}})
    broken = broken_copy(hospital_output, tmp_path, edit)
    lines = _rejected(capsys, monkeypatch, HOSPITAL, broken)
    assert any(re.fullmatch(re.escape(f"{broken}: decomposition 0: the SEQ/FB constraints between its tasks form a "
                                      "cycle: ") + r"AT(3_1\|1 -> AT4_1\|1|4_1\|1 -> AT3_1\|1)", line)
               for line in lines), "\n".join(lines)


def test_fallback_is_not_an_execution_constraint(hospital_output, tmp_path, capsys, monkeypatch):
    """The fallback AT4_1|1 of AT3_1|1 may use another number of robots (a real EC pair may not):
    the only violation is the field, which is not the mission's."""
    def edit(d):
        d["tasks"][task_key(d, "AT4_1|1")]["robots_num"] = {"fixed": "True", "num": "2"}
    broken = broken_copy(hospital_output, tmp_path, edit)
    lines = _rejected(capsys, monkeypatch, HOSPITAL, broken)
    assert lines == [f"{broken}: AT4_1|1: robots_num (tasks.t4): is 2, the mission's is 1"]


def test_effects_follow_the_constraints_not_the_file_order(hospital_output, tmp_path, capsys, monkeypatch):
    """Edited domain: bagging the waste (first phase) marks the room not disinfected, the
    disinfection (second phase) makes it disinfected again, so the forAll condition holds.  A
    file that lists the tasks in another order (reversed) is as valid: effects are applied in the
    order of the SEQ constraints, not of the file."""
    mission = _copy_mission(HOSPITAL, tmp_path)
    _edit(mission / "hddl" / "hospital-disinfection.hddl", "(cleared ?rm)\n            (loaded ?r)\n",
          "(cleared ?rm)\n            (loaded ?r)\n            (not (disinfected ?rm))\n")
    def printed(d):  # the effect the edited domain prints (the decomposers, stricter on parallel
        for t in d["tasks"].values():  # conflicts, list nothing here: the output is made by hand)
            if t["name"] == "ClearRoom":
                room = t["arguments_values"]["?rm"]
                t["effects"].append({"predicate": f"not {room}.is_disinfected", "vars": room, "var_types": "room"})
    output = broken_copy(hospital_output, tmp_path, printed)
    rc, out, err = _validate(capsys, monkeypatch, mission, output)
    assert rc == 0, out + err
    output = output.rename(tmp_path / "edited.json")
    reversed_ = broken_copy(output, tmp_path, lambda d: d.update(tasks=dict(reversed(list(d["tasks"].items())))))
    rc, out, err = _validate(capsys, monkeypatch, mission, reversed_)
    assert rc == 0, out + err


def _rename_action(d):
    d["tasks"]["t4"]["decomposition"]["a0"]["name"] = "open-door"


def _drop_action(d):
    del d["tasks"]["t1"]["decomposition"]["a1"]


def _reorder_actions(d):
    acts = d["tasks"]["t1"]["decomposition"]
    acts["a0"], acts["a1"] = acts["a1"], acts["a0"]


def _swap_arguments(d):
    d["tasks"]["t4"]["decomposition"]["a0"]["arguments"] = "?rm ?r"


@pytest.mark.parametrize("edit,expected", [
    (_rename_action, "AT1_2|1: its actions (open-door) are not a decomposition of RoomCleaning"),
    (_drop_action, "AT1_1|2: its actions (open-door) are not a decomposition of RoomCleaning"),
    (_reorder_actions, "AT1_1|2: its actions (clean-room, open-door) are not a decomposition of RoomCleaning"),
    (_swap_arguments, "AT1_2|1: its actions (clean-room) are not a decomposition of RoomCleaning"),
], ids=["rename", "drop", "reorder", "arguments"])
def test_rejects_actions_that_are_not_a_decomposition(edit, expected, room_prep, tmp_path, capsys, monkeypatch):
    broken = broken_copy(room_prep, tmp_path, edit)
    _rejected(capsys, monkeypatch, ROOM_PREP, broken, f"decomposition 0: {expected} by the domain's methods")


def test_rejects_action_precondition(room_prep, tmp_path, capsys, monkeypatch):
    """RoomB is already clean in the edited world: clean-room (needs not clean) cannot run."""
    mission = _copy_mission(ROOM_PREP, tmp_path)
    world = mission / "knowledge" / "World_db.xml"
    text = world.read_text()
    world.write_text(text.replace("<name>RoomB</name>\n\t<location>c6</location>\n        <is_clean>False",
                                  "<name>RoomB</name>\n\t<location>c6</location>\n        <is_clean>True"))
    assert world.read_text() != text
    lines = _rejected(capsys, monkeypatch, mission, room_prep,
                      "decomposition 0: AT1_2|1: precondition not clean(RoomB) of action clean-room (action 1) "
                      "does not hold")
    assert not any("method" in line for line in lines)


def test_rejects_action_precondition_after_an_earlier_task(hospital_output, tmp_path, capsys, monkeypatch):
    """Edited domain: restocking closes the door, and the parallel report needs it open; the
    report starts after the restock (the context dependency), so the effect is seen."""
    mission = _copy_mission(HOSPITAL, tmp_path)
    hddl = mission / "hddl" / "hospital-disinfection.hddl"
    _edit(hddl, "(restocked ?rm)\n        )", "(restocked ?rm)\n            (not (door-open ?rm))\n        )")
    _edit(hddl, "(update-bed-board ?r ?rm)", "(close-check ?r ?rm)\n            (update-bed-board ?r ?rm)")
    _edit(hddl, "    (:action update-bed-board",
          "    (:action close-check\n        :parameters (?r - ServiceRobot ?rm - room)\n"
          "        :precondition (and (door-open ?rm))\n        :effect ()\n    )\n    (:action update-bed-board")
    broken = broken_copy(hospital_output, tmp_path, lambda d: [
        t["decomposition"].update({"a0": {"name": "close-check", "arguments": "?r ?rm"},
                                   "a1": {"name": "update-bed-board", "arguments": "?r ?rm"}})
        for t in d["tasks"].values() if t["name"] == "ReportRoomReady"])
    _rejected(capsys, monkeypatch, mission, broken,
              "decomposition 0: AT7_1|1: precondition door-open(Room101) of action close-check (action 1) "
              "does not hold")


@pytest.mark.parametrize("replace,expected", [
    # RoomB's door is open: the door-closed method (t5 = AT1_2|2) is not applicable
    (("t4", "t5"), ("AT1_2|2: precondition not door-open(RoomB) of method room-cleaning-door-closed (action 1) "
                    "does not hold")),
    # RoomA's door is closed: the door-open method (t0 = AT1_1|1) is not applicable
    (("t1", "t0"), ("AT1_1|1: precondition door-open(RoomA) of method room-cleaning-door-open (action 1) "
                    "does not hold")),
], ids=["door-open", "door-closed"])
def test_rejects_method_precondition(replace, expected, room_prep, tmp_path, capsys, monkeypatch):
    old, new = replace

    def edit(d):
        md = d["mission_decompositions"][0]
        md[md.index(old)] = new
    broken = broken_copy(room_prep, tmp_path, edit)
    _rejected(capsys, monkeypatch, ROOM_PREP, broken, f"decomposition 0: {expected}")


def test_rejects_method_precondition_of_a_nested_method(food, tmp_path, capsys, monkeypatch):
    # decomposition 3 is [t0, t1, t4, t7]; t6 = AT3_2|1 fetches with the patient, who cannot
    broken = broken_copy(food, tmp_path, lambda d: d["mission_decompositions"][3].__setitem__(3, "t6"))
    lines = _rejected(capsys, monkeypatch, FOOD, broken,
                      "decomposition 3: AT3_2|1: precondition patientcanfetch(Patient3) of method "
                      "fetch-meal-with-human (action 2) does not hold", cfg="configurationDelivery.json")
    assert all(": decomposition 3: " in line for line in lines)


def test_rejects_parallel_conflict(hospital_output, tmp_path, capsys, monkeypatch):
    """Edited domain: restocking sets a ward-wide fact that reporting clears; the restock of one
    room and the report of another run in parallel (different forAll elements)."""
    mission = _copy_mission(HOSPITAL, tmp_path)
    hddl = mission / "hddl" / "hospital-disinfection.hddl"
    _edit(hddl, "(loaded ?r - robot)\n", "(loaded ?r - robot)\n        (ward-busy)\n")
    _edit(hddl, "(restocked ?rm)\n        )", "(restocked ?rm)\n            (ward-busy)\n        )")
    _edit(hddl, "(available ?rm)\n        )", "(available ?rm)\n            (not (ward-busy))\n        )")
    lines = _rejected(capsys, monkeypatch, mission, hospital_output,
                      "decomposition 0: AT6_1|1: parallel tasks AT6_1|1 and AT7_2|1 set ward-busy() both true and false",
                      "decomposition 0: AT7_1|1: parallel tasks AT7_1|1 and AT6_2|1 set ward-busy() both true and false")
    # the restock and report of one room are ordered (the context dependency): no conflict
    assert not any("AT6_1|1 and AT7_1|1" in line for line in lines)


def test_rejects_forall_condition(hospital_output, tmp_path, capsys, monkeypatch):
    """Edited domain: restocking (the last phase) leaves the room not disinfected, so
    ``current_room.is_disinfected`` fails after each room's tasks."""
    mission = _copy_mission(HOSPITAL, tmp_path)
    _edit(mission / "hddl" / "hospital-disinfection.hddl", "(restocked ?rm)\n        )",
          "(restocked ?rm)\n            (not (disinfected ?rm))\n        )")
    _rejected(capsys, monkeypatch, mission, hospital_output,
              *(f"decomposition 0: G3: forAll condition of goal G3 (current_room.is_disinfected; current_room = "
                f"{room}) does not hold after the tasks of G3" for room in ("Room101", "Room102", "Room104")))


def test_rejects_achieve_condition(hospital_output, tmp_path, capsys, monkeypatch):
    """Edited goal model: G14 (restocking) must also make the room available, which only the
    report (G15) does."""
    mission = _copy_mission(HOSPITAL, tmp_path)
    gm = mission / "gm" / "hospital-disinfection-gm.json"
    doc = json.loads(gm.read_text())
    node = next(n for a in doc["actors"] for n in a["nodes"] if n["text"].startswith("G14:"))
    node["customProperties"].update({"GoalType": "Achieve", "AchieveCondition": "current_room.is_available"})
    gm.write_text(json.dumps(doc))
    _rejected(capsys, monkeypatch, mission, hospital_output,
              "decomposition 0: G14: achieve condition of goal G14 (current_room.is_available; "
              "current_room = Room101) does not hold after the tasks of G14")


def test_rejects_context_condition(hospital_output, tmp_path, capsys, monkeypatch):
    """Without the context dependency AT6 -> AT7, the report starts before the room is restocked."""
    def edit(d):
        at6, at7 = task_key(d, "AT6_1|1"), task_key(d, "AT7_1|1")
        d["constraints"].remove({"type": "SEQ", "task_instances": {"t0": at6, "t1": at7}})
    broken = broken_copy(hospital_output, tmp_path, edit)
    lines = _rejected(capsys, monkeypatch, HOSPITAL, broken,
                      "decomposition 0: G15: context condition of goal G15 (current_room.is_restocked; "
                      "current_room = Room101) does not hold where AT7_1|1 starts")
    assert not any("Room102" in line or "Room104" in line for line in lines)


def test_rejects_context_condition_of_reference(room_prep, tmp_path, capsys, monkeypatch):
    """Room Preparation: G10 (furniture moving) has the context ``current_room.is_clean``; without
    the SEQ cleaning -> moving of RoomB, AT3_2|1 starts in the initial world, where RoomB is not
    clean."""
    def edit(d):
        d["constraints"] = [c for c in d["constraints"]
                            if c["task_instances"] not in ({"t0": "t4", "t1": "t7"}, {"t0": "t5", "t1": "t7"})]
    broken = broken_copy(room_prep, tmp_path, edit)
    lines = _rejected(capsys, monkeypatch, ROOM_PREP, broken,
                      "decomposition 0: G10: context condition of goal G10 (current_room.is_clean; "
                      "current_room = RoomB) does not hold where AT3_2|1 starts")
    assert [line for line in lines if ": decomposition " in line] == [
        f"{broken}: decomposition 0: G10: context condition of goal G10 (current_room.is_clean; current_room = RoomB) "
        "does not hold where AT3_2|1 starts"]
    # and the file misses the two constraints the goal model implies (a context dependency)
    assert sorted(line for line in lines if ": decomposition " not in line) == [
        f"{broken}: AT1_2|{n}: constraints: SEQ AT1_2|{n} -> AT3_2|1 is missing (the goal model implies it)"
        for n in (1, 2)]


@pytest.mark.parametrize("robots,shown", [
    ({"fixed": "True", "num": "2"}, "2"),
    ({"fixed": "False", "min": "2", "max": "3"}, "[2,3]"),
], ids=["fixed", "range"])
def test_rejects_incompatible_robot_numbers(robots, shown, room_prep, tmp_path, capsys, monkeypatch):
    # EC t1 (AT1_1|2, one robot) with t2 (AT2_1|1)
    broken = broken_copy(room_prep, tmp_path, lambda d: d["tasks"]["t2"].__setitem__("robots_num", robots))
    _rejected(capsys, monkeypatch, ROOM_PREP, broken,
              f"decomposition 0: AT1_1|2: execution-constrained with AT2_1|1, but their robot numbers (1 and {shown}) "
              "are incompatible")


def test_compatible_robot_ranges_are_accepted(room_prep, tmp_path, capsys, monkeypatch):
    """Robot numbers of execution-constrained tasks that overlap do not conflict; the changed
    field is reported as not the mission's, and nothing else."""
    broken = broken_copy(room_prep, tmp_path, lambda d: d["tasks"]["t2"].__setitem__(
        "robots_num", {"fixed": "False", "min": "1", "max": "3"}))
    lines = _rejected(capsys, monkeypatch, ROOM_PREP, broken)
    assert lines == [f"{broken}: AT2_1|1: robots_num (tasks.t2): is [1,3], the mission's is 1"]


def test_rejects_constraint_naming_unknown_task(room_prep, tmp_path, capsys, monkeypatch):
    def edit(d):
        d["constraints"].append({"type": "SEQ", "task_instances": {"t0": "t1", "t1": "t42"}})
    broken = broken_copy(room_prep, tmp_path, edit)
    lines = _rejected(capsys, monkeypatch, ROOM_PREP, broken, "AT1_1|2: constraints[12]: constraint names unknown task t42")
    assert len(lines) == 1


def test_rejects_in_xml(tmp_path, capsys, monkeypatch, reference):
    """The XML form: task keys task<i>, fallbacks as EC without group/divisible."""
    golden = (ROOM_PREP / "output" / "task_output.xml").read_text()
    broken = tmp_path / "broken.xml"
    broken.write_text(golden.replace("<t5>task7</t5>", "<t5>task7</t5>\n            <t6>task0</t6>", 1))
    assert broken.read_text() != golden
    _rejected(capsys, monkeypatch, ROOM_PREP, broken,
              "decomposition 0: AT1_1|1: task instance AT1_1 is decomposed twice (AT1_1|2 and AT1_1|1)",
              cfg="configuration.xml")


def test_fallback_in_xml(hospital_output, tmp_path):
    """Both forms read a fallback (an EC without group/divisible) as FB, an EC with them as EC."""
    out = tmp_path / "out.xml"
    assert main(["decompose", str(HOSPITAL), "-q", "--algorithm", "exploratory", "--format", "xml", "-o", str(out)]) == 0

    def kinds(path: Path) -> set[tuple[str, str, str]]:
        d = load_decomposition_output(str(path))
        return {(d.tasks[c.first].id, d.tasks[c.second].id, c.kind) for c in d.constraints}
    xml, js = kinds(out), kinds(hospital_output)
    assert xml == js
    assert ("AT3_1|1", "AT4_1|1", "FB") in xml and ("AT1_1|1", "AT2_1|1", "EC") in xml


# ---------------------------------------------------------------------------------------------
# 3. bad input


def _bad(capsys, monkeypatch, output: Path, expected: str) -> str:
    rc, out, err = _validate(capsys, monkeypatch, ROOM_PREP, output)
    assert rc == 2, out + err
    assert out == ""
    assert expected in err, err
    return err


def test_truncated_json(room_prep, tmp_path, capsys, monkeypatch):
    path = tmp_path / "truncated.json"
    text = room_prep.read_text()
    path.write_text(text[: len(text) // 2])
    err = _bad(capsys, monkeypatch, path, "invalid JSON")
    assert re.search(re.escape(str(path)) + r":\d+:\d+: invalid JSON", err), err
    assert "truncated" in err


def test_non_utf8_output(tmp_path, capsys, monkeypatch, reference):
    path = tmp_path / "latin1.json"
    path.write_bytes('{"tasks": {},\n "mission_decompositions": "Zürich"}'.encode("latin-1"))
    err = _bad(capsys, monkeypatch, path, f"{path}:2:30: ")
    assert "not UTF-8 text" in err


def test_malformed_xml(tmp_path, capsys, monkeypatch, reference):
    path = tmp_path / "bad.xml"
    text = (ROOM_PREP / "output" / "task_output.xml").read_text()
    assert "</task2>" in text
    path.write_text(text.replace("</task2>", "</task3>", 1))
    line = text[: text.index("</task2>")].count("\n") + 1
    err = _bad(capsys, monkeypatch, path, "XML syntax error in the output")
    assert f"{path}:{line}:" in err, err


def test_output_that_is_not_an_object(tmp_path, capsys, monkeypatch, reference):
    path = tmp_path / "list.json"
    path.write_text("[]")
    _bad(capsys, monkeypatch, path, f"{path}: expected a JSON object")


def test_missing_output_file(tmp_path, capsys, monkeypatch, reference):
    _bad(capsys, monkeypatch, tmp_path / "nowhere.json", str(tmp_path / "nowhere.json"))


@pytest.mark.parametrize("count", [1, 3, 5])
def test_wrong_number_of_arguments(count, room_prep, capsys):
    hddl, gm, cfg = find_mission_files(ROOM_PREP, "configuration.json")
    args = {1: [str(ROOM_PREP)], 3: [str(hddl), str(gm), str(cfg)],
            5: [str(hddl), str(gm), str(cfg), str(room_prep), str(room_prep)]}[count]
    rc, out, err = _run(capsys, "validate", *args)
    assert rc == 2 and out == ""
    assert "expected HDDL GM CONFIG OUTPUT, or MISSION_DIR OUTPUT" in err


def test_no_arguments(capsys):
    rc, _, err = _run(capsys, "validate")
    assert rc == 2 and "the following arguments are required" in err


# ---------------------------------------------------------------------------------------------
# 4. --json-summary


def test_json_summary(food, tmp_path, capsys, monkeypatch):
    cfg = "configurationDelivery.json"
    rc, out, _ = _validate(capsys, monkeypatch, FOOD, food, "--json-summary", cfg=cfg)
    assert rc == 0
    summary = json.loads(out)
    assert (summary["command"], summary["valid"], summary["checked"], summary["invalid_decompositions"]) == \
        ("validate", True, 6, [])
    assert summary["violations"] == []

    def edit(d):  # decomposition 1 lists a key that is no task; decomposition 4 decomposes AT3_1 twice
        d["mission_decompositions"][1].append("t99")
        d["mission_decompositions"][4].append("t3")
    broken = broken_copy(food, tmp_path, edit)
    rc, out, _ = _validate(capsys, monkeypatch, FOOD, broken, "--json-summary", cfg=cfg)
    assert rc == 1
    *violations, last = out.splitlines()
    summary = json.loads(last)
    assert (summary["valid"], summary["checked"], summary["invalid_decompositions"]) == (False, 6, [1, 4])
    assert [f"{broken}: {v}" for v in summary["violations"]] == violations
    assert "decomposition 1: t99: not a task of the file" in summary["violations"]


# ---------------------------------------------------------------------------------------------
# 5. Replaying one explanation of a task (the validator's own state bookkeeping)


def _replayed(steps, facts=None, values=None, bound=None):
    from mutrose_cp.validate.replay import StepReplay
    from mutrose_cp.validate.state import State

    replay = StepReplay(bound or {"?r": ("r1",)}, State(dict(facts or {}), dict(values or {})), "AT1_1|1")
    for step in steps:
        replay.step(step)
    return replay


def _step(pre=(), eff=(), num=(), name="move"):
    """An action step (the replay counts the actions: the k-th step given is action k)."""
    from mutrose_cp.validate.steps import Step

    return Step("action", name, (), tuple(pre), tuple(eff), tuple(num))


def test_replay_assumes_an_unknown_atom_once_and_then_holds_to_it():
    from mutrose_cp.model import Literal

    replay = _replayed([_step(pre=[Literal("at", ("?r",))]),
                        _step(pre=[Literal("at", ("?r",), False)], name="leave")])
    assert replay.assumed == {("at", ("r1",)): True}
    assert replay.failures == ["precondition not at(r1) of action leave (action 2) does not hold"]


def test_replay_reads_its_own_effects_before_the_start_state():
    from mutrose_cp.model import Literal

    replay = _replayed([_step(eff=[Literal("at", ("?r",), False)]), _step(pre=[Literal("at", ("?r",))])],
                       facts={("at", ("r1",)): True})
    assert replay.changed.facts == {("at", ("r1",)): False}
    assert replay.failures == ["precondition at(r1) of action move (action 2) does not hold"]


def test_replay_numeric_values():
    """An unknown value is fixed by a required equality; an increase changes a known value
    only; every numeric effect is recorded for the tasks after."""
    from mutrose_cp.model import Comparison, NumericEffect

    battery, charge = ("battery", ("r1",)), ("charge", ("r1",))
    replay = _replayed([_step(pre=[Comparison("battery", ("?r",), "=", 5, False)]),
                        _step(num=[NumericEffect("increase", "battery", ("?r",), 2),
                                   NumericEffect("increase", "charge", ("?r",), 1)]),
                        _step(pre=[Comparison("battery", ("?r",), ">", 9, False)], name="lift")])
    assert replay.nums == {battery: 7.0}
    assert replay.changed.numeric == [(battery, "increase", 2.0), (charge, "increase", 1.0)]
    assert replay.failures == ["precondition battery(r1) > 9 of action lift (action 3) does not hold: the value is 7"]


def test_replay_numeric_preconditions_on_an_unknown_value_must_allow_one_value_together():
    """Whatever their order: (> 0) then (= 0) cannot hold, nor (> 3), an increase by 2, then
    (< 4) (the start value would be above 3 and below 2); (> 0) then (< 5) can."""
    from mutrose_cp.model import Comparison, NumericEffect

    def level(op, value):
        return _step(pre=[Comparison("level", ("?r",), op, value, False)], name="check")

    assert len(_replayed([level(">", 0), level("=", 0)]).failures) == 1
    assert len(_replayed([level("=", 0), level(">", 0)]).failures) == 1
    assert _replayed([level(">", 0), level("<", 5)]).failures == []
    raised = _replayed([level(">", 3), _step(num=[NumericEffect("increase", "level", ("?r",), 2)]),
                        level("<", 4)])
    assert raised.failures == ["precondition level(r1) < 4 of action check (action 3) cannot hold together with the "
                               "task's earlier preconditions on it (the world does not know it)"]


def test_replay_skips_conditions_on_unbound_variables():
    from mutrose_cp.model import Literal

    replay = _replayed([_step(pre=[Literal("at", ("?x",))], eff=[Literal("done", ("?x",))])])
    assert (replay.assumed, replay.changed.facts, replay.failures) == ({}, {}, [])


# ---------------------------------------------------------------------------------------------
# 6. What a decomposition number stands for (the validator's own listing of a task's paths)

NUMBERING = """(define (domain numbering)
    (:types room - object)
    (:predicates (busy ?r - robot) (p ?r - robot))
    (:functions (n ?r - robot))
    (:task T :parameters (?r - robot))
    (:task A :parameters (?r - robot))
    (:task B :parameters (?r - robot))
    (:task R :parameters (?r - robot))
    (:task Q :parameters (?r - robot))
    (:task Q2 :parameters (?r - robot))
    (:task U :parameters (?r - robot))
    (:task V :parameters (?r - robot))
    (:method t :parameters (?r - robot) :task (T ?r) :ordered-subtasks (and (A ?r) (B ?r)))
    (:method a1 :parameters (?r - robot) :task (A ?r) :ordered-subtasks (and (x1 ?r)))
    (:method a2 :parameters (?r - robot) :task (A ?r) :ordered-subtasks (and (x2 ?r)))
    (:method b1 :parameters (?r - robot) :task (B ?r) :ordered-subtasks (and (y1 ?r)))
    (:method b2 :parameters (?r - robot) :task (B ?r) :ordered-subtasks (and (y2 ?r)))
    (:method r-again :parameters (?r - robot) :task (R ?r)
        :precondition (and (not (busy ?r))) :effect (and (busy ?r))
        :subtasks (and (s1 (x1 ?r)) (s2 (R ?r))))
    (:method r-once :parameters (?r - robot) :task (R ?r) :ordered-subtasks (and (y1 ?r)))
    (:method q :parameters (?r - robot) :task (Q ?r) :precondition (and (= (n ?r) 1))
        :ordered-subtasks (and (set-p ?r) (not-p-then-n ?r)))
    (:method q2 :parameters (?r - robot) :task (Q2 ?r) :precondition (and (= (n ?r) 1))
        :ordered-subtasks (and (set-p ?r) (n-then-not-p ?r)))
    (:method u :parameters (?r - robot) :task (U ?r) :subtasks (and (s1 (x1 ?r)) (s2 (y1 ?r))))
    (:method v :parameters (?r - robot) :task (V ?r) :subtasks (and (s1 (x1 ?r)) (s2 (y1 ?r)))
        :ordering (and (< s1 s2)))
    (:action set-p :parameters (?r - robot) :effect (and (p ?r)))
    (:action not-p-then-n :parameters (?r - robot) :precondition (and (not (p ?r)) (= (n ?r) 1)))
    (:action n-then-not-p :parameters (?r - robot) :precondition (and (= (n ?r) 1) (not (p ?r))))
    (:action x1 :parameters (?r - robot))
    (:action x2 :parameters (?r - robot))
    (:action y1 :parameters (?r - robot))
    (:action y2 :parameters (?r - robot))
)"""


def _numbered(task: str) -> list[tuple[str, ...]]:
    """The actions of ``task``'s decompositions |1, |2, ... by the validator, and the same by the
    decomposers' HTN module (two readings of one rule, docs/formats/hddl.md)."""
    from mutrose_cp.pipeline import htn
    from mutrose_cp.io.hddl import parse_domain
    from mutrose_cp.validate.numbering import task_decompositions

    domain = parse_domain(NUMBERING, "numbering.hddl")
    listed = [tuple(s.name for s in d.actions) for d in task_decompositions(domain, task)]
    assert listed == [tuple(s.name for s in p.actions) for p in htn.task_paths(domain, task)]
    return listed


def test_the_later_subtask_choice_varies_slowest():
    assert _numbered("T") == [("x1", "y1"), ("x2", "y1"), ("x1", "y2"), ("x2", "y2")]


def test_a_subtask_that_recurses_is_tried_first():
    """R's unordered method runs its recursive subtask first in its first order: the inner R
    finds busy set by the outer checkpoint, so only r-once decomposes it there."""
    assert _numbered("R") == [("y1", "x1"), ("x1", "y1"), ("y1",)]


def test_a_comparison_on_a_known_value_decides_a_step_alone():
    """The original's verdict (docs/deviations.md, fix 12): a comparison that holds after a
    literal that fails lets the step run, and so the path keeps its number; the other way round
    the step does not run."""
    assert _numbered("Q") == [("set-p", "not-p-then-n")]
    assert _numbered("Q2") == []


def _explained(task: str, actions: list[str]) -> int:
    from mutrose_cp.io.decomposition_output import OutputAction
    from mutrose_cp.io.hddl import parse_domain
    from mutrose_cp.validate.htn_match import Matcher

    domain = parse_domain(NUMBERING, "numbering.hddl")
    return len(Matcher(domain, ["?r"], [OutputAction(a, ("?r",)) for a in actions]).explain(task))


def test_actions_are_explained_in_every_order_the_method_allows():
    assert _explained("U", ["x1", "y1"]) == _explained("U", ["y1", "x1"]) == 1
    assert (_explained("V", ["x1", "y1"]), _explained("V", ["y1", "x1"])) == (1, 0)


def test_comparisons_tolerate_rounding_on_equality_only():
    from mutrose_cp.validate.numbers import compare

    assert compare(0.1 + 0.2, "=", 0.3) and compare(0.1 + 0.2, "<=", 0.3) and compare(0.3, ">=", 0.1 + 0.2)
    assert compare(1, ">=", 1) and compare(1, "<=", 1) and not compare(1, ">", 1) and not compare(1, "<", 1)
    assert compare(2, "<>", 1) and not compare(1, "<>", 1)


# ---------------------------------------------------------------------------------------------
# 7. What the goal model implies (the validator's own expansion and Task Graph)


def _implied(spec, folder: Path, trigger: str | None = None):
    """The validator's reading of a generated mission; ``trigger``: a trigger context on the
    goal that iterates the rooms."""
    from mutrose_cp.validate.expected import ExpectedMission

    hddl, gm, cfg = spec.write(folder)
    if trigger is not None:
        doc = json.loads(Path(gm).read_text())
        goal = next(n for n in doc["actors"][0]["nodes"] if "Every Room Is Handled" in n["text"])
        goal["customProperties"]["CreationCondition"] = f'assertion trigger "{trigger}"'
        Path(gm).write_text(json.dumps(doc))
    m = Mission.load(hddl, gm, cfg)
    return ExpectedMission(m.domain, m.goal_model, m.config, m.initial_state, m.knowledge)


def _generated(tree, *, facts=()):
    """One room, the tasks Work (runs ``work``) and SetP (sets the room's ``p``)."""
    from missiongen import Action, Lit, Method, MissionSpec, Room, Task

    tasks = (Task("Work", (Method("work", (), ("work",)),)), Task("SetP", (Method("set", (), ("set-p",)),)))
    actions = (Action("work"), Action("set-p", eff=(Lit("p", "?rm"),)))
    return MissionSpec(("p",), (), actions, tasks, (Room("Room1", True, facts),), True, "", tree)


@pytest.mark.parametrize("op,events", [(";", ()), ("#", ("E1",))])
def test_a_step_of_a_sequence_takes_no_trigger_event(op, events, tmp_path):
    from missiongen import GoalNode, TaskNode

    expected = _implied(_generated(GoalNode((TaskNode("Work"), TaskNode("Work")), annotation=("flat", op))),
                        tmp_path, trigger="E1")
    assert [i.events for i in expected.instances.values()] == [events, events]


def test_a_non_group_goal_inside_a_non_divisible_one_takes_over(tmp_path):
    """semantics.md §5.4 (the dissertation's example): AT1 and AT2 under the Group=False goal
    are one robot's; each with AT3 after them, one team's (the enclosing Divisible=False goal)."""
    from missiongen import GoalNode, TaskNode

    inner = GoalNode((TaskNode("Work"), TaskNode("Work")), group=False)
    expected = _implied(_generated(GoalNode((inner, TaskNode("Work")), divisible=False)), tmp_path)
    assert {tuple(sorted(i for i, _ in pair)): flags for pair, flags in expected.constraints.execution.items()} == {
        ("AT1_1", "AT2_1"): (False, True), ("AT1_1", "AT3_1"): (True, False), ("AT2_1", "AT3_1"): (True, False)}


@pytest.mark.parametrize("refinement,kept", [("or", False), ("and", True)])
def test_an_or_goal_cannot_enable_a_creation_condition_to_its_right(refinement, kept, tmp_path):
    """The search for a task that makes a false creation condition true jumps over OR goals
    (semantics.md §5.2): behind an OR goal, SetP does not keep the conditioned goal; behind a
    parallel AND goal it does, and its decomposition must then come first (a SEQ)."""
    from missiongen import GoalNode, TaskNode

    tree = GoalNode((GoalNode((TaskNode("SetP"), TaskNode("Work")), refinement=refinement),
                     GoalNode((TaskNode("Work"),), condition="current_room.is_p")))
    expected = _implied(_generated(tree, facts=(("p", False),)), tmp_path)
    assert ("AT3_1" in expected.instances) == kept and "AT3_1" in expected.generated
    assert ((("AT1_1", 1), ("AT3_1", 1)) in expected.constraints.ordered) == kept
