"""World objects and initial state (spec config-and-knowledge.md §5.1, §6) on the reference
missions and on small synthetic worlds."""
from __future__ import annotations

import dataclasses
from pathlib import Path

import pytest
from conftest import require_reference as reference_dir

from mutrose_cp.errors import MissionError
from mutrose_cp.io.config import load_configuration
from mutrose_cp.io.hddl import load_domain
from mutrose_cp.io.knowledge import load_knowledge
from mutrose_cp.model import (
    Configuration,
    Domain,
    GroundLiteral,
    InitialState,
    OutputConfig,
    SemanticMapping,
    WorldDbConfig,
)
from mutrose_cp.pipeline.initial_state import build_initial_state


def _mission_state(mission: str, config_name: str = "configuration.json", base: str = "missions") -> InitialState:
    folder = reference_dir() / base / mission
    [hddl] = sorted((folder / "hddl").glob("*.hddl"))
    config = load_configuration(folder / "configuration" / config_name)
    knowledge = load_knowledge(folder / config.world_db.path, config.world_db.xml_root, config.world_db.unique_id)
    return build_initial_state(load_domain(hddl), config, knowledge)


def _lits(state: InitialState) -> list[str]:
    return [str(lit) for lit in state.literals]


# ---------------------------------------------------------------------------------------------
# Reference missions


@pytest.mark.parametrize("config_name", ["configuration.json", "configuration.xml"])
def test_room_preparation(config_name: str) -> None:
    state = _mission_state("room-preparation", config_name)
    assert state.sorts["room"] == {"RoomA", "RoomB", "RoomC", "SanitizationRoom"}
    assert state.sorts["robot"] == frozenset()
    assert _lits(state) == [
        "not clean(RoomA)", "not clean(RoomB)", "clean(RoomC)", "clean(SanitizationRoom)",
        "not prepared(RoomA)", "not prepared(RoomB)", "prepared(RoomC)", "prepared(SanitizationRoom)",
        "not door-open(RoomA)", "door-open(RoomB)", "door-open(RoomC)", "door-open(SanitizationRoom)",
    ]
    assert state.functions == ()
    assert state.value_of("door-open", ("RoomB",)) is True
    assert state.value_of("clean", ["RoomA"]) is False
    assert state.value_of("sanitized", ("r1",)) is None  # robot attributes add nothing


def test_deliver_goods_equipment_ownership() -> None:
    state = _mission_state("deliver-goods-equipment")
    assert state.sorts["obj"] == {"SterileEquipment", "CleanLinens"}
    assert state.sorts["storage"] == {"Storage1", "Storage2"}
    assert state.sorts["location"] == {"Loc1"}
    assert state.sorts["agent"] == {"Agent1"}
    assert state.literals == (
        GroundLiteral("requestingequipment", ("Agent1",), True),
        # owner Storage1 lists SterileEquipment; CleanLinens is not there (local closed world,
        # negatives in std::set order)
        GroundLiteral("at", ("SterileEquipment", "Storage1"), True),
        GroundLiteral("at", ("CleanLinens", "Storage1"), False),
        GroundLiteral("at", ("CleanLinens", "Storage2"), True),
        GroundLiteral("at", ("SterileEquipment", "Storage2"), False),
        GroundLiteral("requested", ("SterileEquipment", "Agent1"), True),
        GroundLiteral("requested", ("CleanLinens", "Agent1"), True),
        # the relationship mapping (Agent location) adds nothing
    )
    assert state.value_of("at", ("CleanLinens", "Storage1")) is False
    assert state.value_of("at", ("Loc1", "Agent1")) is None


def test_object_picking_function_values() -> None:
    state = _mission_state("object-picking-function")
    assert state.literals == ()
    assert state.functions == ((("objects", ("RoomA",)), 1),)
    assert state.function_value("objects", ("RoomA",)) == 1
    assert state.function_value("objects", ("RoomB",)) is None


def test_object_picking_nested_records() -> None:
    state = _mission_state("object-picking")
    assert state.sorts["obj"] == {"obj1", "obj2"}
    assert _lits(state) == ["not picked(obj1)", "not picked(obj2)"]


def test_vital_signs_monitoring() -> None:
    state = _mission_state("vital-signs-monitoring")
    assert _lits(state) == [
        "occupied(RoomA)",
        "available(Patient1)", "not available(Patient2)",
        "infectiousdisease(Patient1)", "not infectiousdisease(Patient2)",
        "not diabetes(Patient1)", "diabetes(Patient2)",
        "not postsurgical(Patient1)", "not postsurgical(Patient2)",
        "not checked(Patient1)", "not checked(Patient2)",
    ]


def test_largest_scalability_world() -> None:
    folder = reference_dir() / "scalability" / "vital-signs-monitoring"
    domain = load_domain(folder / "hddl" / "VitalSignsMonitoring.hddl")
    config = load_configuration(folder / "configuration" / "configuration12.json")
    knowledge = load_knowledge(folder / config.world_db.path, config.world_db.xml_root)
    state = build_initial_state(domain, config, knowledge)
    assert len(state.sorts["patient"]) == 10000 and len(state.sorts["room"]) == 5001
    assert state.value_of("checked", ("Patient10000",)) is False


# ---------------------------------------------------------------------------------------------
# Synthetic


def _domain(constants: tuple[tuple[str, str], ...] = ()) -> Domain:
    return Domain(
        name="d", source="d.hddl",
        types=(("place", None), ("room", "place"), ("obj", None), ("box", "obj")),
        constants=constants, predicates=(), functions=(), capabilities=(), tasks=(), actions=(), methods=(),
    )


def _attr(name: str, relates_to: str, pred: str, sorts: tuple[str, ...], mapped: str = "predicate") -> SemanticMapping:
    return SemanticMapping("attribute", mapped, pred, sorts, belongs_to="world_db", name=name, relates_to=relates_to)


def _config(*mappings: SemanticMapping, types: tuple[tuple[str, str], ...] = (("room", "Room"), ("obj", "Object")),
            location_types: tuple[str, ...] = ("Room",)) -> Configuration:
    return Configuration(
        source="c.json",
        world_db=WorldDbConfig("file", "xml", "w.xml", "world_db"),
        output=OutputConfig("file", "json", "o.json"),
        location_types=location_types, agent_types=(), type_mapping_entries=types,
        var_mapping=(), semantic_mapping=tuple(mappings),
    )


def _world(tmp_path: Path, body: str):
    path = tmp_path / "w.xml"
    path.write_text(f"<world_db>{body}</world_db>")
    return load_knowledge(path, "world_db")


def test_constants_propagate_to_supertypes_world_objects_do_not(tmp_path: Path) -> None:
    k = _world(tmp_path, "<Room><name>R1</name></Room>")
    state = build_initial_state(_domain(constants=(("hall", "room"),)), _config(), k)
    assert state.sorts["room"] == {"R1", "hall"}
    assert state.sorts["place"] == {"hall"}
    assert state.objects_of("unknown") == frozenset()


def test_traversal_rules(tmp_path: Path) -> None:
    k = _world(tmp_path, """
      <Room><name>R1</name><clean>true</clean>
        <Room><name>R9</name><clean>true</clean></Room>
        <objects><Object><name>o1</name><picked>TRUE</picked></Object></objects>
        <mixed>text<Object><name>o2</name><picked>true</picked></Object></mixed>
      </Room>
      <Storage><shelf><Object><name>o3</name><picked>no</picked></Object></shelf></Storage>
      <Room><name>R2</name></Room>""")
    config = _config(_attr("clean", "Room", "clean", ("room",)), _attr("picked", "Object", "picked", ("obj",)))
    state = build_initial_state(_domain(), config, k)
    # sorts descend into every whitespace-only container, records included (R9 found)
    assert state.sorts["room"] == {"R1", "R9", "R2"}
    assert state.sorts["obj"] == {"o1", "o3"}  # o2 sits in a mixed-content element
    # the literal traversal does not descend into Room elements: R9 is never reached; R2 has no
    # clean field (unknown)
    assert _lits(state) == ["clean(R1)", "picked(o1)", "not picked(o3)"]


def test_argument_copies_per_matching_sort(tmp_path: Path) -> None:
    k = _world(tmp_path, "<Room><name>R1</name><n>2.5</n><m>7</m><c>true</c></Room>")
    config = _config(
        _attr("c", "Room", "same", ("room", "room")),
        _attr("c", "Room", "none", ("obj",)),
        _attr("n", "Room", "f", ("room",), "function"),
        _attr("m", "Room", "g", ("room",), "function"),
        _attr("c", "robot", "r", ("robot",)),
        SemanticMapping("relationship", "predicate", "at", ("obj", "room"), belongs_to="world_db",
                        main_entity="Room", related_entity="Object", relationship_type="attribute",
                        attribute_name="objects"),
    )
    state = build_initial_state(_domain(), config, k)
    assert state.literals == (GroundLiteral("same", ("R1", "R1")), GroundLiteral("none", ()))
    assert state.functions == ((("f", ("R1",)), 2.5), (("g", ("R1",)), 7))


def test_records_outside_the_sort_and_duplicates(tmp_path: Path) -> None:
    # Room is mapped but not a location type: still in the sort through the traversal; a
    # repeated record gives a duplicate literal and the first one decides look-ups
    k = _world(tmp_path, "<Room><name>R1</name><c>false</c></Room><Room><name>R1</name><c>true</c></Room>")
    state = build_initial_state(_domain(), _config(_attr("c", "Room", "c", ("room",)), location_types=()), k)
    assert _lits(state) == ["not c(R1)", "c(R1)"]
    assert state.value_of("c", ("R1",)) is False


def test_ownership_negatives_over_the_whole_owned_sort(tmp_path: Path) -> None:
    k = _world(tmp_path, """
      <Room><name>R1</name><objects><Object><name>b</name></Object><Thing><name>x</name></Thing></objects></Room>
      <Room><name>R2</name></Room>
      <Object><name>a</name></Object><Object><name>c</name></Object>""")
    own = SemanticMapping("ownership", "predicate", "in", ("obj", "room"), belongs_to="world_db", owner="Room",
                          owned="Object", relationship_type="attribute", attribute_name="objects")
    state = build_initial_state(_domain(), _config(own), k)
    assert _lits(state) == ["in(b, R1)", "not in(a, R1)", "not in(c, R1)",
                            "not in(a, R2)", "not in(b, R2)", "not in(c, R2)"]
    # function ownership mappings add nothing
    state = build_initial_state(_domain(), _config(dataclasses.replace(own, mapped_type="function")), k)
    assert state.literals == () and state.functions == ()


def test_type_mapped_tag_without_name_is_an_error(tmp_path: Path) -> None:
    k = _world(tmp_path, "<Agent><name>A</name>\n<Room>RoomA</Room></Agent>")
    with pytest.raises(MissionError) as exc:
        build_initial_state(_domain(), _config(), k)
    [problem] = exc.value.problems
    assert problem.where == f"{k.source}:2"
    assert "<Room>" in problem.message and "<name>" in problem.message
