"""Goal-model expansion (``expansion.py``): triggering events and the sequential rule, instance
ids outside any forAll, a forAll over a single element, single-valued queries, unbound
parameters, and the OR-annotation guard of ``expand`` itself."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.errors import MissionError, NoDecompositionError
from mutrose_cp.pipeline.expansion import expand
from mutrose_cp.io.config import load_configuration
from mutrose_cp.io.goal_model import load_goal_model
from mutrose_cp.io.hddl import load_domain
from mutrose_cp.io.knowledge import load_knowledge
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files

from missiongen import Action, GoalNode, Lit, Method, MissionSpec, Room, Task, TaskNode

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"

CLEAN = Action("act0", (), (Lit("clean", "?rm"),))
NOOP = Action("act1", (), ())


def _rooms(n: int) -> tuple[Room, ...]:
    return tuple(Room(f"Room{i + 1}", True, (("clean", False),), 0) for i in range(n))


def _spec(tree: GoalNode, *tasks: Task, rooms: int = 1, forall: str = "") -> MissionSpec:
    tasks = tasks or (Task("TaskA", (Method("mA0", (), ("act1",)),)),)
    return MissionSpec(("clean",), ("charged",), (CLEAN, NOOP), tasks, _rooms(rooms), True, forall, tree)


def _load(spec: MissionSpec, folder: Path, triggers: dict[str, str] | None = None) -> Mission:
    """Write ``spec`` and add ``assertion trigger`` contexts (goal id -> event) to its goal model."""
    hddl, gm, config = spec.write(folder)
    if triggers:
        doc = json.loads(gm.read_text())
        for node in doc["actors"][0]["nodes"]:
            goal = node["text"].split(":")[0]
            if goal in triggers:
                node["customProperties"]["CreationCondition"] = f'assertion trigger "{triggers[goal]}"'
        gm.write_text(json.dumps(doc))
    return Mission.load(hddl, gm, config)


def _events(mission: Mission) -> dict[str, tuple[str, ...]]:
    return {i.id: i.triggering_events for i in mission.expansion.instances}


def _variant(tmp_path: Path, *edits: tuple[str, str, str]) -> Path:
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    for pattern, old, new in edits:
        path = next(folder.glob(pattern))
        text = path.read_text()
        assert old in text, f"{old!r} not in {path}"
        path.write_text(text.replace(old, new, 1))
    return folder


# ---------------------------------------------------------------------------------------------
# Triggering events
#
# G3 (the forAll goal) refines into G4 (over AT1, AT2) and AT3; G3's annotation puts them in
# sequence or in parallel, G4's annotation is parametrised.


@pytest.mark.parametrize("inner, inner_events", [(";", ()), ("#", ("Spill",)), ("FALLBACK", ("Spill",))],
                         ids=["inner-seq", "inner-par", "inner-fallback"])
@pytest.mark.parametrize("outer, outer_events", [(";", ()), ("#", ("Spill",))], ids=["outer-seq", "outer-par"])
def test_trigger_reaches_tasks_unless_their_parent_goal_is_sequential(tmp_path, inner, inner_events, outer,
                                                                      outer_events):
    """A trigger on G3 is copied to every task below it, except the tasks whose own parent goal
    has a ``;`` annotation: an ancestor's ``;`` does not matter, only the parent's."""
    g4 = GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), annotation=("flat", inner))
    spec = _spec(GoalNode((g4, TaskNode("TaskA")), annotation=("flat", outer)))
    events = _events(_load(spec, tmp_path, {"G3": "Spill"}))
    assert events == {"AT1_1": inner_events, "AT2_1": inner_events, "AT3_1": outer_events}


def test_triggers_of_nested_goals_are_collected_outermost_first(tmp_path):
    g4 = GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), annotation=("flat", "#"))
    spec = _spec(GoalNode((g4, TaskNode("TaskA")), annotation=("flat", "#")))
    events = _events(_load(spec, tmp_path, {"G3": "Discharged", "G4": "Spill"}))
    assert events == {"AT1_1": ("Discharged", "Spill"), "AT2_1": ("Discharged", "Spill"), "AT3_1": ("Discharged",)}


def test_trigger_in_the_output(tmp_path):
    """``decompose`` prints the events of a parallel task and ``""`` for a sequential one."""
    g4 = GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), annotation=("flat", "#"))
    spec = _spec(GoalNode((g4, TaskNode("TaskA")), annotation=("flat", ";")))
    mission = _load(spec, tmp_path / "m", {"G3": "Spill"})
    out = tmp_path / "out.json"
    assert main(["decompose", str(tmp_path / "m"), "-q", "-o", str(out)]) == 0
    tasks = json.loads(out.read_text())["tasks"].values()
    by_id = {t["id"]: t["triggering_events"] for t in tasks}
    assert by_id == {"AT1_1|1": ["Spill"], "AT2_1|1": ["Spill"], "AT3_1|1": ""}
    assert len(mission.expansion.instances) == 3


def test_annotation_of_a_single_child_goal_orders_nothing(tmp_path):
    """G4 has one child (AT1) but the annotation ``[AT1;AT1]``: a one-child goal is a means-end
    goal, not a sequence, so its task keeps the trigger of G3."""
    g4 = GoalNode((TaskNode("TaskA"),))
    hddl, gm, config = _spec(GoalNode((g4, TaskNode("TaskA")), annotation=("flat", "#"))).write(tmp_path)
    doc = json.loads(gm.read_text())
    for node in doc["actors"][0]["nodes"]:
        if node["text"].startswith("G4:"):
            node["text"] += " [AT1;AT1]"
        elif node["text"].startswith("G3:"):
            node["customProperties"]["CreationCondition"] = 'assertion trigger "Spill"'
    gm.write_text(json.dumps(doc))
    mission = Mission.load(hddl, gm, config)
    assert mission.goal_model.node("G4").annotation.op == ";"
    assert _events(mission) == {"AT1_1": ("Spill",), "AT2_1": ("Spill",)}


# ---------------------------------------------------------------------------------------------
# Instance ids and forAll


HDDL_PLAIN = """(define (domain plain)
    (:types Bot - robot)
    (:predicates (ready ?r - robot))
    (:capabilities work)
    (:task TaskA :parameters (?r - Bot))
    (:method mA0 :parameters (?r - Bot) :task (TaskA ?r) :ordered-subtasks (and (act0 ?r)))
    (:action act0 :parameters (?r - Bot) :required-capabilities (work) :precondition () :effect ())
)
"""


def _node(i: int, text: str, kind: str = "istar.Goal") -> dict:
    return {"id": f"n{i}", "text": text, "type": kind, "x": 100 * i, "y": 60, "customProperties": {"Description": ""}}


def test_instances_outside_any_forall_get_suffix_1(tmp_path):
    """A root goal [AT1#AT2] without queries or forAll: the ids are ``AT1_1`` and ``AT2_1``."""
    gm = {"actors": [{"id": "actor", "text": "Plain", "type": "istar.Actor", "x": 40, "y": 20,
                      "customProperties": {"Description": ""},
                      "nodes": [_node(1, "G1: Root [AT1#AT2]"), _node(2, "AT1: TaskA", "istar.Task"),
                                _node(3, "AT2: TaskA", "istar.Task")]}],
          "orphans": [], "dependencies": [], "display": {}, "tool": "pistar.2.0.0", "istar": "2.0",
          "links": [{"id": "l1", "type": "istar.AndRefinementLink", "source": "n2", "target": "n1"},
                    {"id": "l2", "type": "istar.AndRefinementLink", "source": "n3", "target": "n1"}],
          "saveDate": "Sat, 22 Nov 2025 12:00:00 GMT",
          "diagram": {"width": 500, "height": 300, "customProperties": {"Description": ""}}}
    (tmp_path / "domain.hddl").write_text(HDDL_PLAIN)
    (tmp_path / "gm.json").write_text(json.dumps(gm))
    (tmp_path / "world.xml").write_text('<?xml version="1.0"?>\n<world_db></world_db>\n')
    config = {"world_db": {"type": "file", "file_type": "xml", "path": str(tmp_path / "world.xml"),
                           "xml_root": "world_db", "unique_id": "name"},
              "output": {"output_type": "file", "file_path": "output/mission.json", "file_type": "json"},
              "location_types": [], "type_mapping": [], "var_mapping": [], "semantic_mapping": []}
    (tmp_path / "configuration.json").write_text(json.dumps(config))
    mission = Mission.load(tmp_path / "domain.hddl", tmp_path / "gm.json", tmp_path / "configuration.json")
    assert [i.id for i in mission.expansion.instances] == ["AT1_1", "AT2_1"]
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    assert [sorted(ids[d] for d in md) for md in mission.decomposition_space()] == [["AT1_1|1", "AT2_1|1"]]


@pytest.mark.parametrize("rooms", [1, 2])
@pytest.mark.parametrize("cleans", [True, False])
def test_forall_condition_with_one_or_more_elements(tmp_path, rooms, cleans):
    """forAll(current_room | current_room.is_clean) over [AT1;AT2]: it holds only when TaskA
    cleans the room, also when the forAll iterates over a single room."""
    tasks = (Task("TaskA", (Method("mA0", (), ("act0" if cleans else "act1",)),)),
             Task("TaskB", (Method("mB0", (), ("act1",)),)))
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskB")), annotation=("flat", ";"))
    mission = _load(_spec(tree, *tasks, rooms=rooms, forall="current_room.is_clean"), tmp_path)
    assert len(mission.expansion.instances) == 2 * rooms
    expected = 1 if cleans else 0
    assert mission.decomposition_space().count == expected
    try:
        assert len(mission.exploratory()) == expected
    except NoDecompositionError:
        assert expected == 0


# ---------------------------------------------------------------------------------------------
# Query bindings (item-delivery variants)


def test_single_valued_query_takes_the_first_record(tmp_path):
    """``pickup_point : Location`` filled by a query that selects every staffed location takes
    the first one in world order (CentralPharmacy, then SupplyRoom and WardA)."""
    folder = _variant(tmp_path, ("gm/*", "l.name in current_delivery.pickup", "l.staffed"))
    mission = Mission.load(*find_mission_files(folder))
    fetches = [i for i in mission.expansion.instances if i.gm_task in ("AT1", "AT3")]
    assert len(fetches) == 6
    assert all(i.location == "CentralPharmacy" and i.binding["?src"] == "CentralPharmacy" for i in fetches)


def test_query_without_match_leaves_the_parameter_unbound(tmp_path, capsys):
    """Delivery1's pickup names no location: ``pickup_point`` is empty, so ``?src`` of its
    FetchItem stays a variable (printed as ``?src``) and the mission still decomposes."""
    folder = _variant(tmp_path, ("knowledge/*.xml", "<pickup>CentralPharmacy</pickup>", "<pickup>Nowhere</pickup>"))
    mission = Mission.load(*find_mission_files(folder))
    at1 = next(i for i in mission.expansion.instances if i.id == "AT1_1")
    assert at1.location == ""
    assert at1.binding == {"?d": "Delivery1"}
    out = tmp_path / "out.json"
    assert main(["decompose", str(folder), "-q", "-o", str(out)]) == 0
    task = next(t for t in json.loads(out.read_text())["tasks"].values() if t["id"] == "AT1_1|1")
    assert task["arguments_values"] == {"?r": "", "?d": "Delivery1", "?src": ""}
    assert task["preconditions"][0]["predicate"] == "?src.reachable"


def test_first_variable_mapped_to_a_parameter_wins(tmp_path):
    """AT1 maps both its location ``pickup_point`` and an extra parameter ``destination`` to
    ``?src``: the location comes first, so ``?src`` is the pickup point."""
    mapped = '{"gm_var": "pickup_point", "hddl_var": "?src"}'
    also = '{"gm_var": "destination", "hddl_var": "?src"}'
    folder = _variant(tmp_path, ("configuration/*", f"{mapped}\n        ]}},", f"{mapped},\n            {also}\n        ]}},"))
    gm = next(folder.glob("gm/*"))
    doc = json.loads(gm.read_text())
    for node in doc["actors"][0]["nodes"]:
        if node["text"].startswith("AT1:"):
            node["customProperties"]["Params"] = "current_delivery, destination"
    gm.write_text(json.dumps(doc))
    mission = Mission.load(*find_mission_files(folder))
    at1 = next(i for i in mission.expansion.instances if i.id == "AT1_1")
    assert [(p.hddl_param, p.value) for p in at1.parameters] == [
        ("?src", "CentralPharmacy"), ("?d", "Delivery1"), ("?src", "WardA")]
    assert at1.binding == {"?src": "CentralPharmacy", "?d": "Delivery1"}


# ---------------------------------------------------------------------------------------------
# The guard of expand()


@pytest.mark.parametrize("op, kind", [(";", "sequential"), ("FALLBACK", "fallback")])
def test_expand_refuses_ordered_or_alternatives(tmp_path, op, kind):
    """``expand`` itself rejects an OR-refined goal with a ``;`` or FALLBACK annotation (the
    alternatives cannot run in order), even when called without ``Mission.load``'s checks."""
    alternatives = GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), "or", ("flat", op))
    hddl, gm_path, config_path = _spec(GoalNode((alternatives,))).write(tmp_path)
    config = load_configuration(config_path)
    world = load_knowledge(config.world_db.path, config.world_db.xml_root, config.world_db.unique_id)
    with pytest.raises(MissionError, match=f"OR decomposed goal cannot have {kind} runtime annotations"):
        expand(load_goal_model(gm_path), load_domain(hddl), config, world)


@pytest.mark.parametrize("example", ["hospital-disinfection", "item-delivery"])
def test_the_expansion_leaves_no_reference_cycles(example):
    """The command line pauses the cyclic collector, so whatever the walk left in reference
    cycles would stay until the process ends (on large missions, one per goal with children).
    The walk leaves none: nothing is unreachable after it."""
    import gc

    from mutrose_cp.mission import Mission
    from mutrose_cp.io.mission_files import find_mission_files

    mission = Mission.load(*find_mission_files(Path(__file__).resolve().parent.parent / "examples" / example))
    collecting = gc.isenabled()
    gc.collect()
    gc.disable()
    try:
        assert mission.expansion.instances
        assert gc.collect() == 0
    finally:
        if collecting:
            gc.enable()


def test_instances_of_a_task_share_its_inferred_robot_number(reference):
    """Without ``RobotNumber``, a task's robot number is inferred from its parameters, once per
    abstract task: its instances (thousands on large missions) share the one record."""
    from mutrose_cp.pipeline.expansion import infer_robot_number
    from mutrose_cp.mission import Mission
    from mutrose_cp.io.mission_files import find_mission_files

    mission = Mission.load(*find_mission_files(reference / "missions" / "vital-signs-monitoring"))
    by_task: dict[str, list] = {}
    for inst in mission.expansion.instances:
        if mission.goal_model.node(inst.gm_task).robot_number is None:
            by_task.setdefault(inst.name, []).append(inst.robot_number)
    assert any(len(numbers) > 1 for numbers in by_task.values())
    for name, numbers in by_task.items():
        assert all(n is numbers[0] for n in numbers) and numbers[0] == infer_robot_number(mission.domain, name)


def test_a_query_that_reads_no_variable_is_run_once_and_one_that_does_per_element(tmp_path, monkeypatch):
    """Vital signs with 6 occupied rooms: the sanitization room (G17) is the same record
    whatever the room, so the forAll over rooms runs its query once; the patients of the room
    (G5) are queried per room.  (The conformance and scaled tests check the outputs' bytes.)"""
    import sys

    from conftest import ROOT
    from mutrose_cp.pipeline import expansion

    sys.path.insert(0, str(ROOT / "benchmarks"))
    from generate import generate

    mission = Mission.load(*generate("vital-signs", 6, tmp_path))
    asked: list[str] = []
    run_select = expansion.run_select

    def counted(select, world, bindings, goal_id):
        asked.append(goal_id)
        return run_select(select, world, bindings, goal_id)

    monkeypatch.setattr(expansion, "run_select", counted)
    rooms = sum(1 for inst in mission.expansion.instances if inst.gm_task == "AT1")  # EnterRoom, once per room
    assert rooms > 1
    assert asked.count("G5") == rooms  # each room's own patients
    assert asked.count("G17") == 1  # asked in every room, run once
