"""``mutrose-cp validate`` against forged outputs: one hand-broken copy of a real output per task
field and per kind of constraint (in JSON, and for the XML reader's own paths in XML), each
rejected with exit 1 and a message naming the task (or the goal), and documents that are no
decomposition output at all, refused with exit 2.

The base output is the exploratory decomposition of examples/hospital-disinfection (21 task
instances in three rooms, 27 task decompositions, 36 mission decompositions): keys t0..t8 are
the first room's ``AT1_1|1`` (ClearRoom), ``AT2_1|1`` (DisposeWaste), ``AT3_1|1`` and ``AT3_1|2``
(UVDisinfection), ``AT4_1|1`` (SprayDisinfection, the fallback of AT3), ``AT5_1|1`` and
``AT5_1|2`` (TeamDisinfection, 2 to 3 robots, the OR alternative of G9), ``AT6_1|1`` (restock)
and ``AT7_1|1`` (report, enabled by the restock through a context dependency); AT1 and AT2 are
execution-constrained (G5 is Group=False).  Robot parameters are typed ServiceRobot, UVRobot and
SprayRobot, subtypes of ``robot``.
"""
from __future__ import annotations

import re
import shutil
from functools import partial
from pathlib import Path
from typing import Callable

import pytest
from conftest import ROOT
from lxml import etree
from test_validate import broken_copy, task_key

from mutrose_cp.cli.program import main
from mutrose_cp.io.decomposition_output import load_decomposition_output
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.validate import validate

HOSPITAL = ROOT / "examples" / "hospital-disinfection"
Edit = Callable[[dict], None]


@pytest.fixture(scope="module")
def output(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("forged") / "mission.json"
    assert main(["decompose", str(HOSPITAL), "-q", "--algorithm", "exploratory", "-o", str(out)]) == 0
    return out


@pytest.fixture(scope="module")
def xml_output(tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("forged") / "mission.xml"
    assert main(["decompose", str(HOSPITAL), "-q", "--algorithm", "exploratory", "--format", "xml", "-o",
                 str(out)]) == 0
    return out


def _run(capsys, *argv: str) -> tuple[int, list[str], str]:
    capsys.readouterr()
    rc = main(list(argv))
    out, err = capsys.readouterr()
    assert "Traceback" not in out + err
    return rc, out.splitlines(), err


def _forged(source: Path, tmp_path: Path, edit: Edit) -> Path:
    return broken_copy(source, tmp_path, edit, "forged.json")


def _task(doc: dict, task_id: str) -> dict:
    return doc["tasks"][task_key(doc, task_id)]


def _rejected(capsys, path: Path, mission: Path = HOSPITAL) -> list[str]:
    rc, lines, err = _run(capsys, "validate", str(mission), str(path), "-q")
    assert rc == 1, "\n".join(lines) + err
    assert lines and all(line.startswith(f"{path}: ") for line in lines)
    return [line.removeprefix(f"{path}: ") for line in lines]


def test_the_base_output_is_valid(output, xml_output, capsys):
    for path in (output, xml_output):
        rc, lines, err = _run(capsys, "validate", str(HOSPITAL), str(path), "-q")
        assert rc == 0 and lines == [], "\n".join(lines) + err


# ---------------------------------------------------------------------------------------------
# task fields: one forgery per field


def _rename_task(d: dict) -> None:  # the reviewed case: AT1_1|1 turned into a DisposeWaste
    t = _task(d, "AT1_1|1")
    t["name"] = "DisposeWaste"
    t["decomposition"] = {"a0": {"name": "dispose-waste", "arguments": "?r ?rm"}}


def _swap(first: str, second: str, d: dict) -> None:
    a, b = _task(d, first), _task(d, second)
    a["id"], b["id"] = b["id"], a["id"]


def _set(task_id: str, field: str, value: object, d: dict) -> None:
    _task(d, task_id)[field] = value


def _set_in(task_id: str, field: str, member: str, value: object, d: dict) -> None:
    _task(d, task_id)[field][member] = value


def _effects(d: dict) -> None:
    effect = _task(d, "AT1_1|1")["effects"][0]
    effect["predicate"] = "not " + effect["predicate"]


def _action_name(d: dict) -> None:  # a real decomposition of another task's shape
    _task(d, "AT3_2|2")["decomposition"]["a1"]["name"] = "spray-surfaces"


def _action_arguments(d: dict) -> None:
    _task(d, "AT6_2|1")["decomposition"]["a0"]["arguments"] = "?rm ?r"


def _action_without_arguments(d: dict) -> None:
    del _task(d, "AT6_2|1")["decomposition"]["a0"]["arguments"]


def _dropped_action(d: dict) -> None:
    del _task(d, "AT3_3|2")["decomposition"]["a0"]


def _missing_field(d: dict) -> None:
    del _task(d, "AT6_3|1")["effects"]


@pytest.mark.parametrize("edit,expected", [
    (_rename_task, ["AT1_1|1: name (tasks.t0): is DisposeWaste, the mission's is ClearRoom",
                    "AT1_1|1: decomposition (tasks.t0): is dispose-waste(?r ?rm), the mission's is strip-bed(?r ?rm), "
                    "bag-waste(?r ?rm)"]),
    (partial(_swap, "AT1_1|1", "AT1_2|1"),  # the first room's ClearRoom swapped with the second's
     ["AT1_2|1: arguments_values (tasks.t0): is ?r = \"\", ?rm = Room101, the mission's is ?r = \"\", ?rm = Room102",
      "AT1_1|1: locations (tasks.t9): is Room102, the mission's is Room101"]),
    (partial(_swap, "AT3_1|1", "AT3_1|2"),  # the two decompositions of AT3_1 swapped
     ["AT3_1|2: decomposition (tasks.t2): is irradiate-room(?r ?rm), the mission's is open-door(?r ?rm), "
      "irradiate-room(?r ?rm)",
      "AT3_1|1: decomposition (tasks.t3): is open-door(?r ?rm), irradiate-room(?r ?rm), the mission's is "
      "irradiate-room(?r ?rm)"]),
    (partial(_set, "AT3_1|2", "id", "AT3_1|3"),
     ["AT3_1|3: id (tasks.t3): 3 names no decomposition of UVDisinfection, which has 2 (|1 to |2)",
      "AT3_1|2: tasks: the mission's decomposition AT3_1|2 (UVDisinfection) is missing"]),
    (partial(_set, "AT7_3|1", "id", "AT7_4|1"),
     ["AT7_4|1: id (tasks.t26): the mission has no task instance AT7_4",
      "AT7_3|1: tasks: the mission's decomposition AT7_3|1 (ReportRoomReady) is missing"]),
    (partial(_set, "AT1_1|1", "id", "AT9_1|1"), ["AT9_1|1: id (tasks.t0): the mission has no task instance AT9_1"]),
    (partial(_set_in, "AT2_1|1", "arguments", "?rm", "ward"),
     ["AT2_1|1: arguments (tasks.t1): is ?r - ServiceRobot, ?rm - ward, the mission's is ?r - ServiceRobot, "
      "?rm - room"]),
    (partial(_set_in, "AT2_1|1", "arguments", "?r", "robot"),  # a supertype is not the parameter's type
     ["AT2_1|1: arguments (tasks.t1): is ?r - robot, ?rm - room, the mission's is ?r - ServiceRobot, ?rm - room"]),
    (partial(_set_in, "AT4_2|1", "arguments_values", "?rm", "Room104"),
     ["AT4_2|1: arguments_values (tasks.t13): is ?r = \"\", ?rm = Room104, the mission's is ?r = \"\", "
      "?rm = Room102"]),
    (partial(_set_in, "AT4_2|1", "arguments_values", "?r", "Robot7"),
     ["AT4_2|1: arguments_values (tasks.t13): is ?r = Robot7, ?rm = Room102, the mission's is ?r = \"\", "
      "?rm = Room102"]),
    (partial(_set, "AT6_1|1", "locations", "Room102"),
     ["AT6_1|1: locations (tasks.t7): is Room102, the mission's is Room101"]),
    (partial(_set, "AT5_1|2", "robots_num", {"fixed": "True", "num": "2"}),
     ["AT5_1|2: robots_num (tasks.t6): is 2, the mission's is [2,3]"]),
    (partial(_set, "AT6_3|1", "robots_num", {"fixed": "maybe"}),
     ["AT6_3|1: robots_num (tasks.t25): is not a robot number: {'fixed': 'maybe'}"]),
    (partial(_set, "AT6_3|1", "robots_num", {"num": "1"}),  # without its "fixed"
     ["AT6_3|1: robots_num (tasks.t25): is not a robot number: {'num': '1'}"]),
    (partial(_set, "AT1_3|1", "preconditions", ""),
     ["AT1_3|1: preconditions (tasks.t18): is none, the mission's is not Room104.occupied (vars Room104, "
      "var_types room)"]),
    (_effects, ["AT1_1|1: effects (tasks.t0): is not Room101.is_cleared (vars Room101, var_types room); "
                "?r.is_loaded (vars ?r, var_types robot), the mission's is Room101.is_cleared (vars Room101, "
                "var_types room); ?r.is_loaded (vars ?r, var_types robot)"]),
    (partial(_set, "AT2_2|1", "triggering_events", ["PatientAdmitted"]),
     ["AT2_2|1: triggering_events (tasks.t10): is PatientAdmitted, the mission's is PatientDischarged"]),
    (_action_name, ["AT3_2|2: decomposition (tasks.t12): is open-door(?r ?rm), spray-surfaces(?r ?rm), the "
                    "mission's is open-door(?r ?rm), irradiate-room(?r ?rm)"]),
    (_action_arguments, ["AT6_2|1: decomposition (tasks.t16): is restock(?rm ?r), the mission's is "
                         "restock(?r ?rm)"]),
    (_action_without_arguments, ["AT6_2|1: decomposition (tasks.t16): action restock has no arguments"]),
    (_dropped_action, ["AT3_3|2: decomposition (tasks.t21): is irradiate-room(?r ?rm), the mission's is "
                       "open-door(?r ?rm), irradiate-room(?r ?rm)"]),
    (partial(_set, "AT2_1|1", "group", "False"),  # the flags of its parent goal G7, not of G5 above
     ["AT2_1|1: group (tasks.t1): is False, the mission's is True"]),
    (partial(_set, "AT7_1|1", "divisible", "False"), ["AT7_1|1: divisible (tasks.t8): is False, the mission's is True"]),
    (_missing_field, ["AT6_3|1: effects (tasks.t25): is missing"]),
], ids=["renamed-task", "swapped-instances", "swapped-numbers", "number-out-of-range", "unknown-instance",
        "unknown-task", "argument-type", "argument-supertype", "argument-value", "bound-robot", "locations",
        "robots-num", "unreadable-robots", "robots-without-fixed", "preconditions", "effects", "events",
        "action-name", "action-arguments", "action-without-arguments", "dropped-action", "group", "divisible",
        "missing-field"])
def test_forged_task_field(edit, expected, output, tmp_path, capsys):
    lines = _rejected(capsys, _forged(output, tmp_path, edit))
    file_level = [line for line in lines if not line.startswith("decomposition ")]
    for message in expected:
        assert message in file_level, "\n".join(lines)


def test_a_task_listed_twice_or_left_out(output, tmp_path, capsys):
    def twice(d: dict) -> None:
        d["tasks"]["t27"] = dict(_task(d, "AT7_1|1"))

    assert "AT7_1|1: id (tasks.t27): listed twice, also as tasks.t8" in _rejected(capsys, _forged(output, tmp_path,
                                                                                                     twice))

    def left_out(d: dict) -> None:
        del d["tasks"][task_key(d, "AT4_1|1")]

    assert "AT4_1|1: tasks: the mission's decomposition AT4_1|1 (SprayDisinfection) is missing" in \
        _rejected(capsys, _forged(output, tmp_path, left_out))


ACTIONS = ("bag-waste", "dispose-waste", "fog-room", "irradiate-room", "open-door", "restock", "seal-room",
           "spray-surfaces", "strip-bed", "team-spray", "team-wipe", "update-bed-board", "wipe-surfaces")


def _bare_name(d: dict) -> None:
    d["actions"][0] = d["actions"][0]["name"]


def _no_capabilities(d: dict) -> None:
    del d["actions"][0]["capabilities"]


def _capability(d: dict) -> None:
    d["actions"][0]["capabilities"] = "flying"


@pytest.mark.parametrize("edit,expected", [
    (_capability, "actions: bag-waste has capabilities flying, the domain's are waste-handling"),
    (_bare_name, "actions: bag-waste gives no capabilities (an entry is an object with the action's name and "
                 "capabilities)"),
    (_no_capabilities, "actions: bag-waste gives no capabilities (an entry is an object with the action's name and "
                       "capabilities)"),
    (lambda d: d["actions"].pop(0), f"actions: lists {', '.join(ACTIONS[1:])}; the mission's decompositions use "
                                    f"{', '.join(ACTIONS)} (sorted by name)"),
    (lambda d: d.pop("actions"), "actions: the section is missing or is no list of actions"),
], ids=["capability", "bare-name", "no-capabilities", "dropped", "no-section"])
def test_forged_actions_section(edit, expected, output, tmp_path, capsys):
    assert _rejected(capsys, _forged(output, tmp_path, edit)) == [expected]


# ---------------------------------------------------------------------------------------------
# constraints: one forgery per kind


def _pair(d: dict, first: str, second: str) -> dict[str, str]:
    return {"t0": task_key(d, first), "t1": task_key(d, second)}


def _constraint(d: dict, first: str, second: str, execution: bool = False) -> dict:
    """The constraint between two tasks: an execution constraint (an EC with flags) or not."""
    pair = _pair(d, first, second)
    return next(c for c in d["constraints"] if c["task_instances"] == pair and ("group" in c) == execution)


def _reverse(first: str, second: str, d: dict) -> None:
    _constraint(d, first, second)["task_instances"] = _pair(d, second, first)


def _drop(first: str, second: str, execution: bool, d: dict) -> None:
    d["constraints"].remove(_constraint(d, first, second, execution))


def _add(kind: str, first: str, second: str, flags: dict[str, str], d: dict) -> None:
    d["constraints"].append({"type": kind, "task_instances": _pair(d, first, second), **flags})


def _change(first: str, second: str, execution: bool, changes: dict[str, str], d: dict) -> None:
    _constraint(d, first, second, execution).update(changes)


def _unflag(first: str, second: str, flag: str, d: dict) -> None:
    del _constraint(d, first, second, True)[flag]


def _duplicate(d: dict) -> None:
    d["constraints"].append(dict(_constraint(d, "AT6_1|1", "AT7_1|1")))


NON_GROUP = {"group": "False", "divisible": "True"}


@pytest.mark.parametrize("edit,expected", [
    (partial(_reverse, "AT1_1|1", "AT2_1|1"),
     "AT2_1|1: constraints[{i}]: SEQ AT2_1|1 -> AT1_1|1 is reversed: the goal model puts AT1_1|1 first (SEQ)"),
    (partial(_drop, "AT2_2|1", "AT3_2|2", False),
     "AT2_2|1: constraints: SEQ AT2_2|1 -> AT3_2|2 is missing (the goal model implies it)"),
    (partial(_add, "SEQ", "AT6_1|1", "AT6_2|1", {}),  # two rooms run in parallel
     "AT6_1|1: constraints[{i}]: SEQ AT6_1|1 -> AT6_2|1 is not implied by the goal model"),
    (partial(_drop, "AT6_3|1", "AT7_3|1", False),  # the restock enables the report: SEQ from the context
     "AT6_3|1: constraints: SEQ AT6_3|1 -> AT7_3|1 is missing (the goal model implies it)"),
    (partial(_change, "AT6_1|1", "AT7_1|1", False, NON_GROUP),  # flags only an execution constraint has
     "AT6_1|1: constraints[{i}]: SEQ AT6_1|1 and AT7_1|1 has group/divisible flags, which only an execution "
     "constraint has"),
    (partial(_change, "AT6_1|1", "AT7_1|1", False, {"type": "AFTER"}),
     "AT6_1|1: constraints[{i}]: unknown constraint type 'AFTER' between AT6_1|1 and AT7_1|1"),
    (partial(_reverse, "AT3_1|2", "AT4_1|1"),
     "AT4_1|1: constraints[{i}]: FB AT4_1|1 -> AT3_1|2 is reversed: the goal model puts AT3_1|2 first (FB)"),
    (partial(_drop, "AT3_2|1", "AT4_2|1", False),
     "AT3_2|1: constraints: FB AT3_2|1 -> AT4_2|1 is missing (the goal model implies it)"),
    (partial(_add, "EC", "AT4_1|1", "AT5_1|1", {}),  # OR alternatives are no fallbacks
     "AT4_1|1: constraints[{i}]: FB AT4_1|1 -> AT5_1|1 is not implied by the goal model"),
    (partial(_change, "AT3_3|1", "AT4_3|1", False, {"type": "SEQ"}),
     "AT3_3|1: constraints[{i}]: SEQ AT3_3|1 and AT4_3|1 should be FB"),
    (partial(_drop, "AT1_2|1", "AT2_2|1", True),
     "AT1_2|1: constraints: the execution constraint between AT1_2|1 and AT2_2|1 (group False, divisible True) is "
     "missing"),
    (partial(_change, "AT1_1|1", "AT2_1|1", True, {"group": "True", "divisible": "False"}),
     "AT1_1|1: constraints[{i}]: execution constraint between AT1_1|1 and AT2_1|1 has group True, divisible False; "
     "the goal model's are group False, divisible True"),
    (partial(_unflag, "AT1_1|1", "AT2_1|1", "divisible"),
     "AT1_1|1: constraints[{i}]: execution constraint between AT1_1|1 and AT2_1|1: divisible is missing or is "
     "neither True nor False"),
    (partial(_change, "AT1_1|1", "AT2_1|1", True, {"group": "maybe"}),
     "AT1_1|1: constraints[{i}]: execution constraint between AT1_1|1 and AT2_1|1: group is missing or is neither "
     "True nor False"),
    (partial(_add, "EC", "AT6_1|1", "AT7_1|1", NON_GROUP),
     "AT6_1|1: constraints[{i}]: execution constraint between AT6_1|1 and AT7_1|1: the goal model's Group/Divisible "
     "flags imply none"),
    (_duplicate, "AT6_1|1: constraints[{i}]: SEQ AT6_1|1 and AT7_1|1 is listed twice"),
], ids=["reversed-seq", "dropped-seq", "added-seq", "dropped-context-dependency", "seq-with-flags", "unknown-type",
        "reversed-fallback", "dropped-fallback", "added-fallback", "fallback-as-seq", "dropped-execution",
        "execution-flags", "execution-flag-missing", "execution-flag-unreadable", "added-execution", "duplicate"])
def test_forged_constraint(edit, expected, output, tmp_path, capsys):
    lines = _rejected(capsys, _forged(output, tmp_path, edit))
    pattern = re.compile(re.escape(expected).replace(re.escape("{i}"), r"\d+"))
    assert any(pattern.fullmatch(line) for line in lines), "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# the XML form: its reader's own paths, one forgery each


def _xml_forged(source: Path, tmp_path: Path, edit: Callable[[etree._Element], None]) -> Path:
    """A copy of an XML output (several top-level elements) with one thing changed by ``edit``
    on a tree that holds them under one root."""
    body = re.sub(rb"^<\?xml[^>]*\?>", b"", source.read_bytes())
    root = etree.fromstring(b"<output>" + body + b"</output>")
    edit(root)
    path = tmp_path / "forged.xml"
    path.write_bytes(b'<?xml version="1.0" encoding="utf-8"?>\n' + b"".join(etree.tostring(c) for c in root))
    return path


def _xml_task(root: etree._Element, task_id: str) -> etree._Element:
    return next(t for t in root.find("tasks") if t.findtext("id") == task_id)


def _xml_set(task_id: str, path: str, text: str, root: etree._Element) -> None:
    _xml_task(root, task_id).find(path).text = text


def _xml_attribute(task_id: str, path: str, name: str, value: str | None, root: etree._Element) -> None:
    el = _xml_task(root, task_id).find(path)
    if value is None:
        del el.attrib[name]
    else:
        el.set(name, value)


def _xml_drop(task_id: str, path: str, root: etree._Element) -> None:
    el = _xml_task(root, task_id).find(path)
    el.getparent().remove(el)


def _xml_constraint(root: etree._Element, first: str, second: str) -> etree._Element:
    keys = {t.findtext("id"): t.tag for t in root.find("tasks")}
    return next(c for c in root.find("constraints") if [e.text for e in c.find("task_instances")] == [keys[first],
                                                                                                     keys[second]])


def _xml_reverse(first: str, second: str, root: etree._Element) -> None:
    ends = _xml_constraint(root, first, second).find("task_instances")
    ends[0].text, ends[1].text = ends[1].text, ends[0].text


def _xml_constraint_set(first: str, second: str, field: str, text: str, root: etree._Element) -> None:
    _xml_constraint(root, first, second).find(field).text = text


@pytest.mark.parametrize("edit,expected", [
    (partial(_xml_set, "AT1_1|1", "name", "DisposeWaste"), "AT1_1|1: name (line N): is DisposeWaste, the mission's "
                                                           "is ClearRoom"),
    (partial(_xml_set, "AT2_1|1", "arguments/arg0/type", "robot"),
     "AT2_1|1: arguments (line N): is ?r - robot, ?rm - room, the mission's is ?r - ServiceRobot, ?rm - room"),
    (partial(_xml_set, "AT4_2|1", "arguments/arg1/value", "Room104"),
     "AT4_2|1: arguments_values (line N): is ?r = \"\", ?rm = Room104, the mission's is ?r = \"\", ?rm = Room102"),
    (partial(_xml_set, "AT6_1|1", "locations/t0", "Room102"),
     "AT6_1|1: locations (line N): is Room102, the mission's is Room101"),
    (partial(_xml_attribute, "AT6_3|1", "robots_num", "num", "2"),
     "AT6_3|1: robots_num (line N): is 2, the mission's is 1"),
    (partial(_xml_attribute, "AT6_3|1", "robots_num", "fixed", None),
     "AT6_3|1: robots_num (line N): is not a robot number: [('num', '1')]"),
    (partial(_xml_set, "AT1_3|1", "preconditions/prec0", "Room104.occupied"),
     "AT1_3|1: preconditions (line N): is Room104.occupied (vars Room104, var_types room), the mission's is not "
     "Room104.occupied (vars Room104, var_types room)"),
    (partial(_xml_attribute, "AT1_1|1", "effects/eff0", "vars", "Room102"),
     "AT1_1|1: effects (line N): is Room101.is_cleared (vars Room102, var_types room); ?r.is_loaded (vars ?r, "
     "var_types robot), the mission's is Room101.is_cleared (vars Room101, var_types room); ?r.is_loaded (vars ?r, "
     "var_types robot)"),
    (partial(_xml_drop, "AT2_2|1", "triggering_events"),
     "AT2_2|1: triggering_events (line N): is none, the mission's is PatientDischarged"),
    (partial(_xml_set, "AT3_2|2", "decomposition/action1", "spray-surfaces"),
     "AT3_2|2: decomposition (line N): is open-door, spray-surfaces, the mission's is open-door, irradiate-room"),
    (partial(_xml_set, "AT7_1|1", "divisible", "False"), "AT7_1|1: divisible (line N): is False, the mission's is True"),
    (partial(_xml_drop, "AT7_1|1", "group"), "AT7_1|1: group (line N): is missing"),
    (partial(_xml_reverse, "AT1_1|1", "AT2_1|1"),
     "AT2_1|1: line N: SEQ AT2_1|1 -> AT1_1|1 is reversed: the goal model puts AT1_1|1 first (SEQ)"),
    (partial(_xml_constraint_set, "AT1_1|1", "AT2_1|1", "type", "EC"),  # an EC without flags is a fallback
     "AT1_1|1: line N: FB AT1_1|1 and AT2_1|1 should be SEQ"),
], ids=["name", "argument-type", "argument-value", "locations", "robots-num", "robots-without-fixed",
        "preconditions", "effects", "events", "decomposition", "divisible", "missing-group", "reversed-seq",
        "seq-as-fallback"])
def test_forged_xml(edit, expected, xml_output, tmp_path, capsys):
    lines = _rejected(capsys, _xml_forged(xml_output, tmp_path, edit))
    pattern = re.compile(re.escape(expected).replace("line\\ N", r"line\ \d+"))
    assert any(pattern.fullmatch(line) for line in lines), "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# mission decompositions


def test_no_mission_decomposition_listed_for_a_mission_with_tasks(output, tmp_path, capsys):
    """An output with task instances but no mission decomposition: decompose writes none such
    (no valid decomposition is exit 3, without output), so the file is not valid."""
    for empty in ([], ""):
        path = _forged(output, tmp_path, lambda d, empty=empty: d.update(mission_decompositions=empty))
        assert _rejected(capsys, path) == [
            "mission_decompositions: none listed, but the mission has 21 task instances (an output lists valid "
            "mission decompositions; without any, decompose writes no output and exits with 3)"]


def _no_rooms(tmp_path: Path) -> Path:
    """The hospital mission in a world where no room needs disinfection: no task instance."""
    mission = tmp_path / "no-rooms"
    shutil.copytree(HOSPITAL, mission)
    world = mission / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace("<needs_disinfection>True", "<needs_disinfection>False"))
    return mission


def test_a_mission_without_task_instances_has_empty_lists(tmp_path, capsys):
    mission = _no_rooms(tmp_path)
    for fmt in ("json", "xml"):
        out = tmp_path / f"out.{fmt}"
        assert main(["decompose", str(mission), "-q", "--format", fmt, "-o", str(out)]) == 0
        rc, lines, err = _run(capsys, "validate", str(mission), str(out))
        assert rc == 0 and lines == [], err
        assert "valid: 0 of 0 mission decompositions valid (the mission has no task instance)" in err


def test_an_output_of_another_world_is_rejected(output, tmp_path, capsys):
    lines = _rejected(capsys, output, _no_rooms(tmp_path))
    assert "AT1_1|1: id (tasks.t0): the mission has no task instance AT1_1" in lines


def test_one_broken_decomposition_among_many_is_found(output, tmp_path, capsys):
    """The checks are made once per distinct choice of each independent part of the mission:
    a broken choice in one decomposition is found there, and only there, and repeated
    decompositions are each reported."""
    def edit(d: dict) -> None:
        md = d["mission_decompositions"]
        at3 = task_key(d, "AT3_1|1")
        md[30] = [k for k in md[30] if k != at3] + [task_key(d, "AT5_1|1")] if at3 in md[30] else md[30] + [at3]
        md.append(list(md[30]))
    path = _forged(output, tmp_path, edit)
    lines = _rejected(capsys, path)
    assert {line.split(":")[0] for line in lines} == {"decomposition 30", "decomposition 36"}, "\n".join(lines)


def test_progress_is_reported(output, monkeypatch):
    monkeypatch.chdir(HOSPITAL)
    mission = Mission.load(*find_mission_files(HOSPITAL))
    calls: list[tuple[int, int]] = []
    report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state,
                      load_decomposition_output(str(output)), world=mission.knowledge,
                      progress=lambda done, total: calls.append((done, total)))
    assert report.valid and report.checked == 36 and calls[-1] == (36, 36)


# ---------------------------------------------------------------------------------------------
# documents that are no decomposition output: exit 2, located


@pytest.mark.parametrize("text,where", [
    ("", "1:1: invalid JSON"),
    ("  \n", "2:1: invalid JSON"),
    ("[]", "expected a JSON object"),
    ("null", "expected a JSON object"),
    ('"tasks"', "expected a JSON object"),
    ("{}", "tasks"),
    ('{"tasks": {}, "constraints": []}', "mission_decompositions"),
    ('{"actions": [], "tasks": [], "constraints": [], "mission_decompositions": []}', "tasks"),
    ('{"actions": [], "tasks": {}, "constraints": 3, "mission_decompositions": []}', "constraints"),
    ('{"actions": [], "tasks": {}, "constraints": [], "mission_decompositions": [[1, 2]]}', "mission_decompositions[0]"),
    ('{"actions": [], "tasks": {}, "constraints": [], "mission_decompositions": [["t0"], [["t1"]]]}',
     "mission_decompositions[1]"),
    ('{"actions": [], "tasks": {}, "constraints": [], "mission_decompositions": [["t0"] ["t1"]]}',
     "1:83: invalid JSON: Expecting ',' delimiter"),
    ('{"actions": [], "tasks": {}, "constraints": [], "mission_decompositions": [["t0"]]} []', "1:85: invalid JSON: "
                                                                                              "Extra data"),
    ('{"actions": [], "tasks": {"t0": {"name": "ClearRoom"}}, "constraints": [], "mission_decompositions": []}',
     "tasks.t0"),
], ids=["empty-file", "blank", "list", "null", "string", "empty-object", "no-decompositions", "tasks-list",
        "constraints-number", "keys-numbers", "keys-nested", "missing-comma", "extra-data", "task-without-id"])
def test_not_a_decomposition_output_in_json(text, where, tmp_path, capsys):
    path = tmp_path / "foreign.json"
    path.write_text(text)
    rc, lines, err = _run(capsys, "validate", str(HOSPITAL), str(path))
    assert rc == 2 and lines == [], err
    assert f"error: {path}:{where}" in err or f"error: {path}: {where}" in err, err


def test_a_truncated_output_is_refused(output, tmp_path, capsys):
    for cut in (0.3, 0.95):  # in the tasks, in the mission decompositions
        text = output.read_text()
        path = tmp_path / "truncated.json"
        path.write_text(text[:int(len(text) * cut)])
        rc, lines, err = _run(capsys, "validate", str(HOSPITAL), str(path))
        assert rc == 2 and lines == [] and "the file looks truncated" in err, err


@pytest.mark.parametrize("text", [
    '<?xml version="1.0"?>\n<html><body>not a decomposition</body></html>\n',
    '<?xml version="1.0"?>\n<configuration><world_db/></configuration>\n',
    "<tasks/>\n",
], ids=["html", "configuration", "tasks-only"])
def test_not_a_decomposition_output_in_xml(text, tmp_path, capsys):
    path = tmp_path / "foreign.xml"
    path.write_text(text)
    rc, lines, err = _run(capsys, "validate", str(HOSPITAL), str(path))
    assert rc == 2 and lines == [], err
    assert f"error: {path}: mission_decompositions: the output has no mission_decompositions section" in err


def test_malformed_xml_is_refused_where_it_breaks(xml_output, tmp_path, capsys):
    text = xml_output.read_text()
    path = tmp_path / "broken.xml"
    path.write_text(text.replace("<task3>", "<task3><", 1))
    line = text[:text.index("<task3>")].count("\n") + 1
    rc, lines, err = _run(capsys, "validate", str(HOSPITAL), str(path))
    assert rc == 2 and lines == [] and f"error: {path}:{line}:" in err and "XML syntax error" in err, err
