"""Fixes of plain bugs of the original decomposer (docs/deviations.md), each on a small variant
of the bundled item-delivery mission, checked with both algorithms."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.errors import MissionError, NoDecompositionError
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.model.task_graph import ScopeVertex

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"


def _variant(tmp_path: Path) -> Path:
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    return folder


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, f"{old!r} not in {path}"
    path.write_text(text.replace(old, new, 1))


def _both(folder: Path) -> tuple[set[frozenset[str]], set[frozenset[str]]]:
    """Valid mission decompositions (as sets of decomposition ids) by both algorithms."""
    mission = Mission.load(*find_mission_files(folder))
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    try:
        exploratory = {frozenset(ids[d] for d in md) for md in mission.exploratory()}
    except NoDecompositionError:
        exploratory = set()
    space = mission.decomposition_space()
    cpsat = {frozenset(ids[d] for d in md) for md in space}
    assert space.count == len(cpsat)
    return exploratory, cpsat


def _hddl(folder: Path) -> Path:
    return next((folder / "hddl").glob("*.hddl"))


def test_impossible_or_alternative_is_dropped(tmp_path):
    """The original aborts the run when one OR alternative has no valid decomposition; the
    other alternative is still a valid way to achieve the goal."""
    folder = _variant(tmp_path)
    _edit(_hddl(folder), """    (:action request-loading
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :required-capabilities (communication)
        :precondition (and
""", """    (:action request-loading
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :required-capabilities (communication)
        :precondition (and
            (staffed ?src)
""")
    world = next((folder / "knowledge").glob("*.xml"))
    _edit(world, "<name>SupplyRoom</name>\n        <reachable>True</reachable>\n        <staffed>True</staffed>",
          "<name>SupplyRoom</name>\n        <reachable>True</reachable>\n        <staffed>False</staffed>")
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat
    # Delivery1 (from the staffed pharmacy) keeps both alternatives, Deliveries 2 and 3 (from the
    # unstaffed supply room) only the robot fetching from the shelf: 2 * 1 * 1
    assert len(cpsat) == 2
    assert all(not any(i.startswith(("AT3_2", "AT3_3")) for i in md) for md in cpsat)
    assert main(["decompose", str(folder), "--algorithm", "exploratory", "-q", "-o", str(tmp_path / "o.json")]) == 0


def test_forall_condition_checked_for_every_element(tmp_path, capsys):
    """The original checks a forAll condition only for the last element; here Delivery1 (handed
    to a person, whose action no longer marks it delivered) violates it while the last delivery
    satisfies it, so no mission decomposition achieves the goal."""
    folder = _variant(tmp_path)
    _edit(_hddl(folder), """            (not (delivered ?d))
        )
        :effect (and
            (delivered ?d)
        )
    )
    (:action drop-item""", """            (not (delivered ?d))
        )
        :effect ()
    )
    (:action drop-item""")
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat == set()
    assert main(["decompose", str(folder), "--algorithm", "exploratory", "-o", str(tmp_path / "o.json")]) == 3
    assert "achieve condition of goal G3" in capsys.readouterr().err
    assert main(["decompose", str(folder), "--explain", "-o", str(tmp_path / "o.json")]) == 3
    err = capsys.readouterr().err
    assert "achieve condition of goal G3" in err and "delivered(Delivery1)" in err


def test_nested_mixed_annotation(tmp_path):
    """`[(G5#G6);G7]` nests a parallel operator in a sequence; the original mis-pairs the
    children. The nested operator belongs to G4 and the mission decomposes as the flat one."""
    folder = _variant(tmp_path)
    gm = next((folder / "gm").glob("*"))
    _edit(gm, "G4: Current Delivery Is Completed [G5;G6;G7]", "G4: Current Delivery Is Completed [(G5#G6);G7]")
    mission = Mission.load(*find_mission_files(folder))
    assert "(G5#G6);" in mission.expansion.rat.render()
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat and len(cpsat) == 8


def test_alternatives_do_not_leak_effects(tmp_path):
    """With two valid decompositions of FetchItem, the original's mission decomposition for the
    second one also carries the first one's id and effects (marking the item delivered too
    early), which makes HandOver fail for both. Each decomposition now stands alone."""
    folder = _variant(tmp_path)
    _edit(_hddl(folder), """    (:method fetch-from-shelf""", """    (:method fetch-with-receipt
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :task (FetchItem ?r ?d ?src)
        :ordered-subtasks (and
            (navigate ?r ?src)
            (pick-and-sign ?r ?d ?src)
        )
    )
    (:action pick-and-sign
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :required-capabilities (manipulation)
        :precondition (and (not (collected ?d)))
        :effect (and (collected ?d) (delivered ?d))
    )
    (:method fetch-from-shelf""")
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat
    assert len(cpsat) == 8  # as in the unmodified example: FetchItem|2 replaces the old FetchItem|1
    assert all(f"AT1_{k}|2" in md for md in cpsat for k in (1, 2, 3) if any(i.startswith(f"AT1_{k}") for i in md))
    assert not any(i.endswith("|1") and i.startswith("AT1_") for md in cpsat for i in md)


# ---------------------------------------------------------------------------------------------
# A tiny numeric mission (after the reference Object Picking Function): a query lists the rooms
# that need picking, a forAll runs PickObject once per room; the world gives each room a
# `level` (HDDL function `level`). With one room the Task Graph is unique-branch (§5.5).

_PICKING_CONFIG = {
    "world_db": {"type": "file", "file_type": "xml", "path": "knowledge/world_db.xml",
                 "xml_root": "world_db", "unique_id": "name"},
    "output": {"output_type": "file", "file_path": "output/mission.json", "file_type": "json"},
    "location_types": ["Room"],
    "type_mapping": [{"hddl_type": "room", "ocl_type": "Room"}],
    "var_mapping": [{"task_id": "AT1", "map": [{"gm_var": "current_room", "hddl_var": "?rm"}]}],
    "semantic_mapping": [{"type": "attribute", "name": "level", "relates_to": "Room", "belongs_to": "world_db",
                          "mapped_type": "function", "map": {"pred": "level", "arg_sorts": ["room"]}}],
}

_PICKING_GM_NODES = [
    ("g1", "G1: Objects Are Picked [G2;G3]", {}),
    ("g2", "G2: Rooms Are Listed", {"GoalType": "Query", "Controls": "rooms : Sequence(Room)",
                                    "QueriedProperty": "world_db->select(r:Room | r.needs_picking)"}),
    ("g3", "G3: Objects Are Picked In Every Room", {
        "GoalType": "Achieve", "Monitors": "rooms", "Controls": "current_room : Room",
        "AchieveCondition": "rooms->forAll(current_room | )"}),
    ("at1", "AT1: PickObject", {"Location": "current_room"}),
]

_PICKING_DOMAIN = """(define (domain picking)
    (:types room - object)
    (:functions (level ?rm - room))
    (:capabilities manipulation)
    (:task PickObject :parameters (?r - robot ?rm - room))
%s
)
"""


def _picking(tmp_path: Path, methods_and_actions: str, levels: dict[str, int]) -> Path:
    """The numeric mission with the given methods and actions and one room per ``levels`` entry."""
    folder = tmp_path / "picking"
    for sub in ("configuration", "gm", "hddl", "knowledge"):
        (folder / sub).mkdir(parents=True)
    (folder / "configuration" / "configuration.json").write_text(json.dumps(_PICKING_CONFIG, indent=1))
    nodes = [{"id": i, "text": text, "type": "istar.Task" if i.startswith("at") else "istar.Goal",
              "x": 0, "y": 0, "customProperties": {"Description": "", **props}}
             for i, text, props in _PICKING_GM_NODES]
    links = [{"id": f"l{k}", "type": "istar.AndRefinementLink", "source": s, "target": t}
             for k, (s, t) in enumerate((("g2", "g1"), ("g3", "g1"), ("at1", "g3")))]
    gm = {"actors": [{"id": "a", "text": "Picking", "type": "istar.Actor", "x": 0, "y": 0,
                      "customProperties": {"Description": ""}, "nodes": nodes}],
          "orphans": [], "dependencies": [], "links": links, "display": {}, "tool": "pistar.2.0.0",
          "istar": "2.0", "saveDate": "", "diagram": {"width": 100, "height": 100, "customProperties": {}}}
    (folder / "gm" / "picking-gm.json").write_text(json.dumps(gm, indent=1))
    (folder / "hddl" / "picking.hddl").write_text(_PICKING_DOMAIN % methods_and_actions)
    rooms = "".join(f"    <Room><name>{name}</name><level>{level}</level><needs_picking>True</needs_picking></Room>\n"
                    for name, level in levels.items())
    (folder / "knowledge" / "world_db.xml").write_text(f"<world_db>\n{rooms}</world_db>\n")
    return folder


def _actions(mission: Mission, task: str) -> list[tuple[str, ...]]:
    """The primitive actions of each decomposition path of ``task``."""
    return [tuple(s.name for s in p.steps if not s.pseudo) for p in mission.paths[task]]


def test_every_numeric_precondition_must_hold_in_path_generation(tmp_path):
    """After `count-objects` assigns level 2, `pick-exactly-five` requires `(= (level ?rm) 5)`,
    which fails, and then `(> (level ?rm) 0)`, which holds. The original overwrites the
    executable flag with the last comparison and keeps the path; it is not executable, so it
    stays listed with the original's number (|1) and is part of no valid mission decomposition."""
    folder = _picking(tmp_path, """
    (:method count-then-pick-five
        :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :ordered-subtasks (and (count-objects ?r ?rm) (pick-exactly-five ?r ?rm)))
    (:method count-then-pick-any
        :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :ordered-subtasks (and (count-objects ?r ?rm) (pick-any ?r ?rm)))
    (:action count-objects
        :parameters (?r - robot ?rm - room)
        :required-capabilities (manipulation)
        :precondition ()
        :effect (and (assign (level ?rm) 2)))
    (:action pick-exactly-five
        :parameters (?r - robot ?rm - room)
        :required-capabilities (manipulation)
        :precondition (and (= (level ?rm) 5) (> (level ?rm) 0))
        :effect (and (decrease (level ?rm) 1)))
    (:action pick-any
        :parameters (?r - robot ?rm - room)
        :required-capabilities (manipulation)
        :precondition (and (> (level ?rm) 0))
        :effect (and (decrease (level ?rm) 1)))""", {"RoomA": 2, "RoomB": 3})
    mission = Mission.load(*find_mission_files(folder))
    assert _actions(mission, "PickObject") == [("count-objects", "pick-exactly-five"), ("count-objects", "pick-any")]
    assert [bool(p.never_valid) for p in mission.paths["PickObject"]] == [True, False]
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat == {frozenset({"AT1_1|2", "AT1_2|2"})}


def test_every_numeric_precondition_must_hold_in_unique_branch(tmp_path):
    """One room with level 2 (a unique-branch Task Graph, checked by §7.7): `pick-five`
    requires `(= (level RoomA) 5)`, which fails, then `(> (level RoomA) 0)`, which holds. The
    original lets the last comparison decide and accepts `AT1_1|1`; only `AT1_1|2` is valid."""
    folder = _picking(tmp_path, """
    (:method pick-five
        :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :precondition (and (= (level ?rm) 5) (> (level ?rm) 0))
        :ordered-subtasks (and (pick-object ?r ?rm)))
    (:method pick-some
        :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :precondition (and (> (level ?rm) 0))
        :ordered-subtasks (and (pick-object ?r ?rm)))
    (:action pick-object
        :parameters (?r - robot ?rm - room)
        :required-capabilities (manipulation)
        :precondition ()
        :effect (and (decrease (level ?rm) 1)))""", {"RoomA": 2})
    mission = Mission.load(*find_mission_files(folder))
    assert mission.task_graph.unique_branch
    assert [d.content for d in mission.task_graph.decompositions()] == ["AT1_1|1", "AT1_1|2"]
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat == {frozenset({"AT1_1|2"})}


def test_assumed_greater_than_value_counts_later_decrements(tmp_path):
    """The method guard `(> (level ?rm) 0)` is assumed at 0 + 1 (the later `decrease` by 1),
    so the action's own `(> (level ?rm) 0)` still holds. The original sums the decrements of
    the wrong TDG vertices (ordering position used as vertex id), assumes 0, and finds no
    path."""
    folder = _picking(tmp_path, """
    (:method guarded-pick
        :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :precondition (and (> (level ?rm) 0))
        :ordered-subtasks (and (pick-object ?r ?rm)))
    (:action pick-object
        :parameters (?r - robot ?rm - room)
        :required-capabilities (manipulation)
        :precondition (and (> (level ?rm) 0))
        :effect (and (decrease (level ?rm) 1)))""", {"RoomA": 2, "RoomB": 2})
    mission = Mission.load(*find_mission_files(folder))
    assert _actions(mission, "PickObject") == [("pick-object",)]
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat == {frozenset({"AT1_1|1", "AT1_2|1"})}


_RESTOCK = """
    (:method restock-and-pick
        :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :ordered-subtasks (and (restock ?r ?rm) (pick-object ?r ?rm)))
    (:method guarded-restock-and-pick
        :parameters (?r - robot ?rm - room)
        :task (PickObject ?r ?rm)
        :precondition (and (> (level ?rm) 0))
        :ordered-subtasks (and (restock ?r ?rm) (pick-object ?r ?rm)%s))
    (:action restock
        :parameters (?r - robot ?rm - room)
        :required-capabilities (manipulation)
        :precondition ()
        :effect (and (increase (level ?rm) 2)))
    (:action pick-object
        :parameters (?r - robot ?rm - room)
        :required-capabilities (manipulation)
        :precondition ()
        :effect (and (decrease (level ?rm) 1)))"""


def test_infinite_expansion_check_only_for_recursive_methods(tmp_path):
    """`guarded-restock-and-pick` has a `>` guard and its actions increase the guarded function
    (+2 - 1), but it does not call PickObject again. The original runs the expansion check
    before looking for a cycle (and, reading TDG vertices by ordering position, finds
    `restock` of the first method here) and aborts with `Infinite expansion generated with
    method [guarded-restock-and-pick]`; the check concerns only recursive methods."""
    folder = _picking(tmp_path, _RESTOCK % "", {"RoomA": 2, "RoomB": 2})
    mission = Mission.load(*find_mission_files(folder))
    assert _actions(mission, "PickObject") == [("restock", "pick-object")] * 2
    assert not any(p.fragments for p in mission.paths["PickObject"])
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat
    assert cpsat == {frozenset({f"AT1_1|{i}", f"AT1_2|{j}"}) for i in (1, 2) for j in (1, 2)}
    # the same method calling PickObject again would recurse forever: still an error
    folder = _picking(tmp_path / "recursive", _RESTOCK % " (PickObject ?r ?rm)", {"RoomA": 2})
    with pytest.raises(MissionError, match=r"Infinite expansion generated with method \[guarded-restock-and-pick\]"):
        Mission.load(*find_mission_files(folder)).task_graph


def test_plain_achieve_condition_inside_forall_checked_per_instance(tmp_path):
    """G7 (inside the forAll of G3) gets the plain achieve condition `current_delivery.is_delivered`.
    Handing an item to a person no longer marks it delivered, and WardA (Delivery1's
    destination) may be staffed or not (unknown), so HandOver has two decompositions there.
    The original evaluates G7's condition with the last delivery bound (Delivery3, whose
    delivered state is unknown, so it always holds) and also keeps the combinations that hand
    Delivery1 to a person (16 instead of 8); checked for its own delivery, Delivery1 must use
    the drop box."""
    folder = _variant(tmp_path)
    gm = next((folder / "gm").glob("*"))
    _edit(gm, "current_delivery | current_delivery.is_delivered)", "current_delivery | current_delivery.is_collected)")
    _edit(gm, "select(d:Delivery | !d.is_delivered)", "select(d:Delivery | !d.is_collected)")
    _edit(gm, """"Description": "OR: the choice that doubles the number of mission decompositions per delivery.",""",
          """"Description": "OR: the choice that doubles the number of mission decompositions per delivery.",
                        "GoalType": "Achieve",
                        "AchieveCondition": "current_delivery.is_delivered",""")
    _edit(_hddl(folder), """        :effect (and
            (delivered ?d)
        )
    )
    (:action drop-item""", """        :effect ()
    )
    (:action drop-item""")
    world = next((folder / "knowledge").glob("*.xml"))
    _edit(world, "<name>WardA</name>\n        <reachable>True</reachable>\n        <staffed>True</staffed>\n",
          "<name>WardA</name>\n        <reachable>True</reachable>\n")
    _edit(world, "<destination>Laboratory</destination>\n        <is_collected>False</is_collected>\n"
                 "        <is_delivered>False</is_delivered>\n",
          "<destination>Laboratory</destination>\n        <is_collected>False</is_collected>\n")
    mission = Mission.load(*find_mission_files(folder))
    assert [v.goal for v in mission.task_graph.vertices if isinstance(v, ScopeVertex) and v.achieve] == ["G7"] * 3
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat
    assert len(cpsat) == 8  # Delivery1: 2 ways to collect x drop box; Deliveries 2 and 3: 2 x 1 each
    # HandOver |1 is hand-to-person, |2 leave-in-drop-box
    assert all({"AT2_1|2", "AT4_1|2"} & md and not {"AT2_1|1", "AT4_1|1"} & md for md in cpsat)


def test_whitespace_and_comma_lists_in_select(tmp_path):
    """`l.name in current_delivery.pickup` with a list in the world value: whitespace separates
    values as commas do (the original splits at commas only, so `Nowhere SupplyRoom` matches no
    location and the pickup point stays empty)."""
    results = []
    for k, pickup in enumerate(("Nowhere,SupplyRoom", "Nowhere SupplyRoom", "Nowhere\n            SupplyRoom")):
        folder = _variant(tmp_path / str(k))
        world = next((folder / "knowledge").glob("*.xml"))
        _edit(world, "<pickup>CentralPharmacy</pickup>", f"<pickup>{pickup}</pickup>")
        mission = Mission.load(*find_mission_files(folder))
        instances = {i.id: i for i in mission.expansion.instances}
        assert instances["AT1_1"].location == instances["AT3_1"].location == "SupplyRoom"
        out = tmp_path / f"o{k}.json"
        assert main(["decompose", str(folder), "--algorithm", "exploratory", "-q", "-o", str(out)]) == 0
        results.append((_both(folder), out.read_text()))
    assert results[0] == results[1] == results[2]
    assert len(results[0][0][1]) == 8
