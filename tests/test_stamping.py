"""Template stamping of forAll copies gives the Task Graph of the full construction.

``stamped_task_graph`` builds a few copies of each forAll and stamps the others; it must give
exactly the graph ``build_task_graph(..., stamp=False)`` gives (vertices with their content,
edges and partner lists in order, carried achieve goals), or None where its rules rule it out.

* random missions from ``missiongen.repeated_rooms`` (rooms repeated, so that forAll goals have
  three copies or more, most of them identical up to renaming, and some rooms of their own);
  a seeded run checks that stamping is really used on a fair share of them;
* every configuration of the reference corpus, and the vital-signs, delivery and pickup
  benchmark worlds (where stamping must be used);
* the rules that rule stamping out: a creation condition inside the copies, and an execution
  scope above the forAll (whose constraints join the copies).
"""
from __future__ import annotations

import json
import os
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings

from mutrose_cp.output.constraint_texts import SEPARATOR, constraint_texts
from mutrose_cp.pipeline.constraints import _stamped, generate_constraints
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.model.task_graph import TaskGraph
from mutrose_cp.pipeline.stamping import plan_stamping
from mutrose_cp.pipeline.task_graph_builder import build_task_graph, stamped_task_graph

from conftest import ROOT, require_reference
from missiongen import (Action, GoalNode, Lit, Method, MissionSpec, Room, Task, TaskNode, load_mission, repeated_rooms,
                        seeded_draws)

sys.path.insert(0, str(ROOT / "benchmarks"))
from generate import generate  # noqa: E402

EXAMPLES = int(os.environ.get("MUTROSE_STAMP_EXAMPLES", "60"))


def _stages(m: Mission) -> tuple:
    return m.expansion, m.goal_model, m.config, m.initial_state, m.paths


def _same_graph(a: TaskGraph, b: TaskGraph) -> None:
    """Equal vertices, successor lists, partner lists (in the order added) and carried achieve
    goals: what every later stage reads."""
    assert len(a.vertices) == len(b.vertices)
    for x, y in zip(a.vertices, b.vertices):
        assert x == y
    assert [list(s) for s in a._edges.successors] == [list(s) for s in b._edges.successors]
    assert list(a.execution_partners()) == list(b.execution_partners())
    assert list(a.achieve_carried.items()) == list(b.achieve_carried.items())
    assert a.unique_branch == b.unique_branch
    assert a.decomposition_keys == b.decomposition_keys


def _agree(m: Mission) -> bool:
    """Whether stamping was used; either way the graph is the full construction's, and so are
    the constraints (made from the source copies' where stamped)."""
    full = build_task_graph(*_stages(m), stamp=False)
    stamped = stamped_task_graph(*_stages(m))
    if stamped is not None:
        _same_graph(full, stamped)
        made, built = generate_constraints(stamped), generate_constraints(full)
        assert made.count_by_kind() == built.count_by_kind() and len(made) == len(built)
        key = full.decomposition_keys.__getitem__
        assert SEPARATOR.join(constraint_texts(made, key)) == SEPARATOR.join(constraint_texts(built, key))
        assert made == built
    _same_graph(full, build_task_graph(*_stages(m)))
    return stamped is not None


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(repeated_rooms())
def test_stamped_graph_is_the_full_construction_on_random_missions(spec: MissionSpec) -> None:
    try:
        m = load_mission(spec)
        m.expansion
    except Exception as e:  # a drawn mission the expansion refuses has no graph to compare
        event(f"refused: {type(e).__name__}")
        return
    event("stamped" if _agree(m) else "built in full")


def test_stamping_is_used_on_random_missions() -> None:
    """The property above is not vacuous: stamping is used on a fair share of the draws."""
    used = seeded_draws(20261201, 40, "expansion", _agree)
    assert len(used) >= 20
    assert sum(used) >= len(used) // 4, (sum(used), len(used))


def test_reference_corpus(monkeypatch: pytest.MonkeyPatch) -> None:
    reference = require_reference()
    configurations = sorted(c for c in (reference / "missions").glob("*/configuration/*")
                            if c.suffix.lower() in (".json", ".xml"))
    for cfg in configurations:
        folder = cfg.parent.parent
        monkeypatch.chdir(folder)  # configuration paths are relative to the mission folder
        _agree(Mission.load(*find_mission_files(folder, cfg.name)))
    assert len(configurations) >= 7


@pytest.mark.parametrize("family,n", [("vital-signs", 12), ("delivery", 9), ("pickup", 9)])
def test_benchmark_worlds_are_stamped(tmp_path: Path, family: str, n: int) -> None:
    require_reference()
    m = Mission.load(*generate(family, n, tmp_path))
    assert _agree(m), "stamping was not used"
    assert _stamped(m.task_graph) is not None, "the constraints were not stamped"


def _vital_signs(tmp_path: Path, edit_goal_model=None, edit_world=None) -> Mission:
    """Vital signs at 6 rooms (patients 2i+1 and 2i+2 in room i), with its goal model and
    world text edited."""
    hddl, gm, cfg = generate("vital-signs", 6, tmp_path)
    if edit_goal_model is not None:
        text = edit_goal_model(gm.read_text(encoding="utf-8"))
        gm = tmp_path / "gm.txt"
        gm.write_text(text, encoding="utf-8")
    if edit_world is not None:
        world = tmp_path / "vital-signs-6.xml"
        world.write_text(edit_world(world.read_text(encoding="utf-8")), encoding="utf-8")
    return Mission.load(hddl, gm, cfg)


def test_a_creation_condition_inside_the_copies_rules_stamping_out(tmp_path: Path) -> None:
    """A condition on a goal inside the copies that is false for one patient of the fifth room
    only: the built rooms (the first two) never ask, the fifth room's graph loses the branch."""
    m = _vital_signs(
        tmp_path,
        lambda t: t.replace('"CreationCondition": "assertion trigger \\"NoResponse\\""',
                            '"CreationCondition": "assertion condition \\"current_patient.available\\""'),
        lambda t: t.replace("<name>Patient9</name><infectious_disease>true</infectious_disease><diabetes>false</diabetes>"
                            "<post_surgical>false</post_surgical><available>true",
                            "<name>Patient9</name><infectious_disease>true</infectious_disease><diabetes>false</diabetes>"
                            "<post_surgical>false</post_surgical><available>false"))
    full = build_task_graph(*_stages(m), stamp=False)
    alerts = [v.instance.id for v in full.tasks() if v.instance.name == "SendAlert"]
    assert len(alerts) == 11 and "AT6_5_1" not in alerts, alerts
    assert plan_stamping(m.expansion.rat, {i.id: i for i in m.expansion.instances}, m.goal_model, m.paths) is None
    assert not _agree(m)


def test_an_execution_scope_above_the_forall_rules_stamping_out(tmp_path: Path) -> None:
    """With Group=False on the root goal, the rooms' tasks are constrained with each other."""
    def root_not_group(text: str) -> str:
        head, sep, rest = text.partition('"text": "G1: ')
        return head + sep + rest.replace('"customProperties": {', '"customProperties": {\n            "Group": "False",', 1)

    m = _vital_signs(tmp_path, root_not_group)
    full = build_task_graph(*_stages(m), stamp=False)
    assert any(p.task - t > 40 for t, ps in full.execution_partners() for p in ps), "the rooms are not joined"
    assert plan_stamping(m.expansion.rat, {i.id: i for i in m.expansion.instances}, m.goal_model, m.paths) is not None
    assert not _agree(m)


def _rooms_then_g9(tmp_path: Path, rooms: int, context: str | None) -> Mission:
    """G1 is [G2;G3;G9]: G3 cleans every room (TaskA), then G9's task (TaskA again, in the last
    room: current_room after the forAll), with ``context`` as G9's creation condition."""
    clean = Task("TaskA", (Method("mA0", (), ("act0",)),))
    listed = tuple(Room(f"Room{i}", True, (("clean", False),), 0) for i in range(1, rooms + 1))
    spec = MissionSpec(("clean",), (), (Action("act0", (), (Lit("clean", "?rm"),)),), (clean,), listed, True, "",
                       GoalNode((TaskNode("TaskA"),)))
    hddl, gm, cfg = spec.write(tmp_path)
    model = json.loads(gm.read_text(encoding="utf-8"))
    nodes, links = model["actors"][0]["nodes"], model["links"]
    root = next(n for n in nodes if n["text"].startswith("G1:"))
    root["text"] = root["text"].replace("[G2;G3]", "[G2;G3;G9]")
    properties = {"Description": "", "Monitors": "current_room"}
    if context is not None:
        properties["CreationCondition"] = f'assertion condition "{context}"'
    nodes += [{"id": "g9", "text": "G9: Report", "type": "istar.Goal", "x": 900, "y": 170,
               "customProperties": properties},
              {"id": "at9", "text": "AT9: TaskA", "type": "istar.Task", "x": 1000, "y": 280,
               "customProperties": {"Description": "", "Location": "current_room"}}]
    links += [{"id": "l9", "type": "istar.AndRefinementLink", "source": "g9", "target": root["id"]},
              {"id": "l10", "type": "istar.AndRefinementLink", "source": "at9", "target": "g9"}]
    gm.write_text(json.dumps(model), encoding="utf-8")
    return Mission.load(hddl, gm, cfg)


def test_a_false_context_after_the_forall_rules_stamping_out(tmp_path: Path) -> None:
    """G9 after the rooms needs the last room (current_room after the forAll) clean, which only
    that room's task makes true: the built rooms (the first two) cannot enable it."""
    m = _rooms_then_g9(tmp_path, 4, "current_room.is_clean")
    full = build_task_graph(*_stages(m), stamp=False)
    assert "AT9_1" in {v.content for v in full.tasks()}, "G9 is not enabled"
    assert plan_stamping(m.expansion.rat, {i.id: i for i in m.expansion.instances}, m.goal_model, m.paths) is not None
    assert not _agree(m)


def test_constraints_joining_the_copies_to_a_later_task_are_not_stamped(tmp_path: Path) -> None:
    """Every room's task comes before G9's: those SEQ constraints leave the copies, so the
    constraints are generated in full (the graph is still stamped)."""
    m = _rooms_then_g9(tmp_path, 5, None)
    assert _agree(m)
    assert _stamped(m.task_graph) is None
    tg = m.task_graph
    later = {(tg.vertices[c.first].content, tg.vertices[c.second].content) for c in m.constraints if c.kind == "SEQ"}
    assert ("AT1_4|1", "AT9_1|1") in later


def test_a_scope_carried_from_copy_to_copy_rules_stamping_out() -> None:
    """Each room is [AT1;G5;G6] with G5 Group=False and G6 (Divisible=False) ending in a
    Group=False goal: the walk of the execution constraints leaves that scope open into the
    next room, so the first room gets no constraints and the others do, although every room has
    the same shape."""
    tree = GoalNode((TaskNode("TaskA"),
                     GoalNode((TaskNode("TaskA"),), group=False),
                     GoalNode((TaskNode("TaskA"), GoalNode((TaskNode("TaskA"),), group=False)),
                              refinement="or", divisible=False)),
                    annotation=("flat", ";"))
    task = Task("TaskA", (Method("mA0", (), ("act0",)),))
    rooms = tuple(Room(f"Room{i}", True, (("clean", None),), 1) for i in range(1, 6))
    m = load_mission(MissionSpec(("clean",), ("charged",), (Action("act0", (), ()),), (task,), rooms, False, "", tree))
    full = build_task_graph(*_stages(m), stamp=False)
    partners = {full.vertices[t].content: len(ps) for t, ps in full.execution_partners()}
    assert partners["AT2_1"] == 0 and partners["AT2_2"] > 0 and partners["AT2_5"] == partners["AT2_2"]
    assert plan_stamping(m.expansion.rat, {i.id: i for i in m.expansion.instances}, m.goal_model, m.paths) is not None
    assert not _agree(m)


def test_foralls_stamped_inside_the_copies_of_another(tmp_path: Path) -> None:
    """Three rooms of five patients, a condition (true) on a goal of each room, and no
    Group=False over the rooms (which would join a room's patients by execution constraints):
    the rooms are not stamped, but the patients of each room are, one forAll after the other
    (in the Task Graph; their constraints are not, see below)."""
    hddl, gm, cfg = generate("vital-signs", 3, tmp_path)
    text = gm.read_text(encoding="utf-8").replace(',\n            "Group": "False"', "")
    for goal, extra in (("G6: Enter the Room", '"CreationCondition": "assertion condition \\"current_room.is_occupied\\""'),
                        ("G9: Approach The Patient",  # a means-end achieve goal: trimming carries it
                         '"GoalType": "Achieve", "AchieveCondition": "current_patient.available"')):
        head, sep, rest = text.partition(f'"text": "{goal}"')
        text = head + sep + rest.replace('"customProperties": {', '"customProperties": {' + extra + ",", 1)
    gm = tmp_path / "gm.txt"  # (the goal model generate names is the corpus's own)
    gm.write_text(text, encoding="utf-8")
    parts = ["<world_db>"]
    for room in range(3):
        names = ",".join(f"Patient{5 * room + k}" for k in range(1, 6))
        parts.append(f"<Room><name>Room{room}</name><is_occupied>true</is_occupied><patients>{names}</patients></Room>")
    parts.append("<Room><name>SanitizationRoom</name><is_occupied>false</is_occupied><patients></patients></Room>")
    for p in range(1, 16):
        parts.append(f"<Patient><name>Patient{p}</name><infectious_disease>{str(p % 3 == 0).lower()}</infectious_disease>"
                     f"<diabetes>{str(p % 3 == 1).lower()}</diabetes><post_surgical>{str(p % 3 == 2).lower()}"
                     "</post_surgical><available>true</available><checked>false</checked></Patient>")
    (tmp_path / "vital-signs-3.xml").write_text("\n".join(parts + ["</world_db>"]) + "\n", encoding="utf-8")
    m = Mission.load(hddl, gm, cfg)
    plan = plan_stamping(m.expansion.rat, {i.id: i for i in m.expansion.instances}, m.goal_model, m.paths)
    assert plan is not None and [len(f.copies) for f in plan.foralls] == [5, 5, 5]
    assert _agree(m)
    assert len(m.task_graph.stamped_copies) == 3
    assert len(m.task_graph.achieve_carried) == 15
    # each room enters before its patients (G4 is [G5;G6;G7;G16]): those constraints leave the
    # patients' copies, so the constraints are generated in full
    assert _stamped(m.task_graph) is None
