"""Recursive methods: one unrolling in the decomposition paths, expanded per task instance by
the value of the numeric function that guards the recursion (semantics §7.6)."""
from __future__ import annotations

import shutil

from conftest import require_reference

from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files

# the storage domain of the HDDL specification: pick objects while more than one is left
RECURSIVE_DOMAIN = """(define (domain storage)
    (:types room - object)
    (:predicates (clean ?r - robot))
    (:functions (objects ?rm - room))
    (:capabilities pickobject)
    (:task PickObject :parameters (?r - robot ?rm - room))
    (:method object-pick-multiple :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :precondition (and (> (objects ?rm) 1))
        :ordered-subtasks (and (pick-object ?r ?rm) (PickObject ?r ?rm)))
    (:method object-pick-single :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :precondition (and (= (objects ?rm) 1))
        :ordered-subtasks (and (pick-object ?r ?rm)))
    (:action pick-object :parameters (?r - robot ?rm - room)
        :required-capabilities (pickobject)
        :effect (and (decrease (objects ?rm) 1)))
)
"""

WORLD = """<world_db>
    <Room><name>RoomA</name><num_objects>6</num_objects><needs_picking>True</needs_picking></Room>
    <Room><name>RoomB</name><num_objects>3</num_objects><needs_picking>True</needs_picking></Room>
</world_db>
"""


def test_recursive_method_expanded_by_world_value(tmp_path, monkeypatch):
    source = require_reference() / "missions" / "object-picking-function"
    folder = tmp_path / "mission"
    shutil.copytree(source, folder, ignore=shutil.ignore_patterns("output"))
    next((folder / "hddl").glob("*.hddl")).write_text(RECURSIVE_DOMAIN)
    next((folder / "knowledge").glob("*.xml")).write_text(WORLD)
    (folder / "configuration" / "configuration.xml").unlink()
    monkeypatch.chdir(folder)
    mission = Mission.load(*find_mission_files(folder))
    paths = mission.paths["PickObject"]
    # one unrolling: multiple -> pick -> (recursion) single -> pick, plus the single method
    assert [[s.name for s in p.actions] for p in paths] == [["pick-object", "pick-object"], ["pick-object"]]
    assert paths[0].needs_expansion and not paths[1].needs_expansion
    decs = {d.content: d.decomposition for d in mission.task_graph.decompositions()}
    # (6 - 1) / 1 - 1 = 4 more repetitions of [guard, pick] for RoomA: six picks; RoomB: three
    assert len(decs["AT1_1|1"].path.actions) == 6
    assert len(decs["AT1_2|1"].path.actions) == 3
    assert decs["AT1_1|1"].predicates.numeric_effects == (("objects", ("RoomA",), "increase", -6),)
    # only the expanded decompositions empty the rooms, as the achieve condition demands
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    found = {frozenset(ids[d] for d in md) for md in mission.exploratory()}
    assert found == {frozenset({"AT1_1|1", "AT1_2|1"})}
    assert {frozenset(ids[d] for d in md) for md in mission.decomposition_space()} == found
