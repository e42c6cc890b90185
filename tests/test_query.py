"""Select evaluation (spec goal-model.md §8, §8.1) on the reference worlds and on synthetic
worlds exercising each atom form and the reproduced quirks."""
from __future__ import annotations

from pathlib import Path

import pytest
from conftest import require_reference as reference_dir

from mutrose_cp.errors import MissionError
from mutrose_cp.io.knowledge import load_knowledge
from mutrose_cp.model import Atom, Binding, BoolOp, Condition, Select, WorldKnowledge
from mutrose_cp.pipeline.query import run_select


def _world(mission: str, name: str = "world_db.xml") -> WorldKnowledge:
    return load_knowledge(reference_dir() / "missions" / mission / "knowledge" / name, "world_db")


def sel(queried: str, var: str, qtype: str, cond: Condition | None) -> Select:
    return Select(queried=queried, variable=var, type=qtype, condition=cond, text=f"{queried}->select(...)")


def a(text: str) -> Atom:
    return Atom(text=text)


def both(*children: Condition) -> BoolOp:
    return BoolOp("&&", children)


def either(*children: Condition) -> BoolOp:
    return BoolOp("||", children)


def bind(k: WorldKnowledge, tag: str, *ids: str, collection: bool = False) -> Binding:
    records = tuple(k.find_record(tag, i) for i in ids)
    assert all(r is not None for r in records)
    if collection:
        return Binding(tuple(ids), f"Sequence({tag})", records)
    return Binding(ids[0] if ids else "", tag, records)


def ids(k: WorldKnowledge, records: list) -> list[str | None]:
    return [k.record_id(r) for r in records]


# ---------------------------------------------------------------------------------------------
# Reference worlds


def test_vital_signs_patients_of_the_current_room() -> None:
    k = _world("vital-signs-monitoring")
    q = sel("world_db", "p", "Patient", both(a("p.name in current_room.patients"), a("!p.checked")))
    result = run_select(q, k, {"current_room": bind(k, "Room", "RoomA")}, "G5")
    assert ids(k, result) == ["Patient1", "Patient2"]
    with pytest.raises(MissionError, match="Cannot solve condition in QueriedProperty of Goal G5"):
        run_select(q, k, {"current_room": bind(k, "Room", "SanitizationRoom")}, "G5")  # no patients field
    occupied = run_select(sel("world_db", "r", "Room", a("r.is_occupied")), k, {}, "G2")
    assert ids(k, occupied) == ["RoomA"]
    named = run_select(sel("world_db", "r", "Room", a('r.name = "SanitizationRoom"')), k, {}, "G3")
    assert ids(k, named) == ["SanitizationRoom"]


def test_room_preparation_not_prepared() -> None:
    k = _world("room-preparation", "World_db.xml")
    assert ids(k, run_select(sel("world_db", "r", "Room", a("!r.is_prepared")), k, {}, "G2")) == ["RoomA", "RoomB"]
    assert ids(k, run_select(sel("world_db", "r", "Room", a("r.is_clean")), k, {}, "G2")) == [
        "RoomC", "SanitizationRoom"]
    assert ids(k, run_select(sel("world_db", "r", "Room", None), k, {}, "G2")) == [
        "RoomA", "RoomB", "RoomC", "SanitizationRoom"]


def test_deliver_goods_equipment_queries() -> None:
    k = _world("deliver-goods-equipment")
    agents = run_select(sel("world_db", "a", "Agent", a("a.requesting_equipment")), k, {}, "G2")
    assert ids(k, agents) == ["Agent1"]
    agent = {"current_agent": Binding("Agent1", "Agent", tuple(agents))}
    objects = run_select(sel("current_agent.requested_objects", "o", "Object", None), k, agent, "G4")
    assert ids(k, objects) == ["SterileEquipment", "CleanLinens"]
    locations = run_select(sel("world_db", "l", "Location", a("l.name in current_agent.location")), k, agent, "G6")
    assert ids(k, locations) == ["Loc1"]
    storage_query = sel("world_db", "s", "Storage", a("current_object.name in s.objects"))
    for obj, storage in (("SterileEquipment", "Storage1"), ("CleanLinens", "Storage2")):
        bindings = dict(agent, current_object=Binding(obj, "Object", (objects[0 if obj == "SterileEquipment" else 1],)))
        assert ids(k, run_select(storage_query, k, bindings, "G8")) == [storage]


def test_object_picking_path_query() -> None:
    k = _world("object-picking", "World_db.xml")
    room = {"current_room": bind(k, "Room", "RoomA")}
    q = sel("current_room.objects", "o", "Object", a("!o.is_picked"))
    assert ids(k, run_select(q, k, room, "G3")) == ["obj1", "obj2"]


def test_many_selects_on_the_largest_world() -> None:
    k = load_knowledge(reference_dir() / "scalability/vital-signs-monitoring/knowledge/world_db12.xml", "world_db")
    q = sel("world_db", "p", "Patient", both(a("p.name in current_room.patients"), a("!p.checked")))
    total = 0
    for room in k.records_of("Room"):
        result = run_select(q, k, {"current_room": Binding(k.record_id(room), "Room", (room,))}, "G5")
        total += len(result)
    assert total == 10000  # whitespace separated patients are accepted too


# ---------------------------------------------------------------------------------------------
# Synthetic: atom forms and quirks

_BODY = """
<Room><name>R1</name><flag>True</flag><clean>false</clean><n>3</n><x>2.7</x><label>Kitchen</label><e></e>
  <patients>P1, P3</patients><staff><who>P2</who><who>P1</who></staff>
  <boxes><Box><name>b1</name><tag>red</tag></Box><Box><name>b2</name><tag>blue</tag></Box></boxes></Room>
<Room><name>R2</name><flag>false</flag><clean>TRUE</clean><n>1</n><x>1</x><label>5</label><e>x</e></Room>
<Room><name>R3</name><n>10</n><label>Kitchen </label><boxes><Box><name>b3</name><tag>red</tag></Box></boxes></Room>
<Patient><name>P1</name></Patient><Patient><name>P2</name></Patient><Patient><name>P3</name></Patient>
<Crate><name>C1</name><tag>red blue</tag></Crate>
"""


@pytest.fixture()
def k(tmp_path: Path) -> WorldKnowledge:
    path = tmp_path / "w.xml"
    path.write_text(f"<world_db>{_BODY}</world_db>")
    return load_knowledge(path, "world_db")


def rooms(k: WorldKnowledge, cond: Condition | None, bindings: dict | None = None) -> list[str | None]:
    return ids(k, run_select(sel("world_db", "r", "Room", cond), k, bindings or {}, "G1"))


@pytest.mark.parametrize(
    ("cond", "expected"),
    [
        ("r.flag", ["R1"]),
        ("!r.flag", ["R2"]),  # R3 has no flag: not selected
        ("!r.clean", ["R1"]),
        ("r.clean", ["R2"]),
        ("not r.clean", ["R2"]),  # "not" is no negation in selects: read as r.clean
        ("r.label = Kitchen", ["R1"]),  # verbatim: "Kitchen " does not match
        ('r.label = "Kitchen"', ["R1"]),
        ("r.label = 5", []),  # the right side must start with a letter
        ("r.n > 2", ["R1", "R3"]),
        ("r.n < 3", ["R2"]),
        ("r.x > 2.5", ["R1"]),  # threshold 2: 2.7 > 2
        ("r.x < 1.9", []),  # threshold 1: 1 < 1 is false
        ("r.e >= 1", ["R1"]),  # read as "= <empty>": only the empty field matches
        ("r.e <= 1", ["R1"]),
        ("q.label = Kitchen", ["R1"]),  # the left operand's variable prefix is ignored
    ],
)
def test_atom_forms(k: WorldKnowledge, cond: str, expected: list[str]) -> None:
    assert rooms(k, a(cond)) == expected


def test_not_equal_is_reported(k: WorldKnowledge) -> None:
    with pytest.raises(MissionError) as exc:
        rooms(k, a("r.n <> 2"))
    [problem] = exc.value.problems
    assert problem.where == "G1"
    assert problem.message == "Goal G1: operator <> is not supported in select conditions"


def test_and_keeps_left_order_and_or_is_a_union(k: WorldKnowledge) -> None:
    assert rooms(k, both(a("r.n > 0"), a("r.label = Kitchen"))) == ["R1"]
    assert rooms(k, both(a("r.name in rs"), a("r.n > 0")), {"rs": Binding(("R3", "R1"), "Sequence(Room)")}) == [
        "R1", "R3"]
    # deliberate fix: the union, left result first, then the right side's new records
    assert rooms(k, either(a("r.clean"), a("r.flag"))) == ["R2", "R1"]
    assert rooms(k, either(a("r.n > 2"), a("r.n < 5"))) == ["R1", "R3", "R2"]
    # a && (b || c) keeps a's order
    assert rooms(k, both(a("r.n > 0"), either(a("r.clean"), a("r.flag")))) == ["R1", "R2"]


def test_in_variable_collection(k: WorldKnowledge) -> None:
    patients = {"ps": Binding(("P3", "P1"), "Sequence(Patient)")}
    q = sel("world_db", "p", "Patient", a("p.name in ps"))
    assert ids(k, run_select(q, k, patients, "G1")) == ["P1", "P3"]  # document order


def test_in_record_attribute_leaf_and_children(k: WorldKnowledge) -> None:
    room = {"room": bind(k, "Room", "R1")}
    leaf = sel("world_db", "p", "Patient", a("p.name in room.patients"))
    assert ids(k, run_select(leaf, k, room, "G1")) == ["P1", "P3"]
    children = sel("world_db", "p", "Patient", a("p.name in room.staff"))
    assert ids(k, run_select(children, k, room, "G1")) == ["P1", "P2"]
    with pytest.raises(MissionError) as exc:
        run_select(sel("world_db", "p", "Patient", a("p.name in room.absent")), k, room, "G7")
    assert exc.value.problems[0].message.startswith("Cannot solve condition in QueriedProperty of Goal G7")
    assert exc.value.problems[0].where == "G7"
    with pytest.raises(MissionError, match="Cannot solve condition"):
        run_select(sel("world_db", "p", "Patient", a("p.name in nobody")), k, {}, "G7")


def test_ownership_in(k: WorldKnowledge) -> None:
    crate = {"crate": bind(k, "Crate", "C1")}
    q = sel("world_db", "r", "Room", a("crate.tag in r.boxes"))
    assert rooms(k, q.condition, crate) == ["R1", "R3"]  # any box whose tag is red or blue
    q = sel("world_db", "r", "Room", a("crate.tag in r.boxes.inner"))
    with pytest.raises(MissionError) as exc:
        run_select(q, k, crate, "G4")
    assert exc.value.problems[0].message == (
        "The in operator for ownership relations currently only accepts a variable direct attribute ([var].[attr])")


def test_variable_and_path_queries(k: WorldKnowledge) -> None:
    room = {"room": bind(k, "Room", "R1"), "rooms": bind(k, "Room", "R1", "R2", collection=True)}
    boxes = run_select(sel("room.boxes", "b", "Box", a("b.tag = red")), k, room, "G1")
    assert ids(k, boxes) == ["b1"]
    # a variable: its record's children of the query type (none of them is a Box: they are
    # inside <boxes>)
    assert run_select(sel("room", "b", "Box", None), k, room, "G1") == []
    with pytest.raises(MissionError) as exc:
        run_select(sel("room.staff", "b", "Box", None), k, room, "G9")
    assert exc.value.problems[0].message.startswith("Invalid query in Goal G9")
    with pytest.raises(MissionError, match="Invalid query in Goal G9"):
        run_select(sel("room.nothing", "b", "Box", None), k, room, "G9")
    with pytest.raises(MissionError, match="Invalid query in Goal G9"):
        run_select(sel("ghost.boxes", "b", "Box", None), k, room, "G9")
    with pytest.raises(MissionError, match="Invalid query in Goal G9"):
        run_select(sel("rooms", "b", "Box", None), k, room, "G9")
    # an empty single-valued variable selects nothing
    assert run_select(sel("empty", "b", "Box", None), k, {"empty": Binding("", "Room")}, "G1") == []


def test_path_query_uses_the_top_level_record(k: WorldKnowledge) -> None:
    # the binding's record may be a copy: the path starts at the top-level record with the same
    # tag and id
    r1 = k.find_record("Room", "R1")
    assert r1 is not None
    binding = {"room": Binding("R1", "Room", (r1,))}
    assert ids(k, run_select(sel("room.boxes", "b", "Box", None), k, binding, "G1")) == ["b1", "b2"]


def test_bindings_without_records_fall_back_to_the_ids(k: WorldKnowledge) -> None:
    room = {"room": Binding("R1", "Room")}
    assert ids(k, run_select(sel("room.boxes", "b", "Box", None), k, room, "G1")) == ["b1", "b2"]
    q = sel("world_db", "p", "Patient", a("p.name in room.patients"))
    assert ids(k, run_select(q, k, room, "G1")) == ["P1", "P3"]
