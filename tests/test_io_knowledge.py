"""World knowledge reader: reference worlds load, the parser is hardened and lenient like the
original's, and the value helpers follow C++ stream semantics."""
from __future__ import annotations

from pathlib import Path

import pytest
from conftest import REFERENCE as _REFERENCE
from conftest import require_reference as reference_dir

from mutrose_cp.errors import MissionError
from mutrose_cp.io.knowledge import load_knowledge, parse_bool, parse_number, split_list
from mutrose_cp.model import WorldKnowledge, base_type
from mutrose_cp.model.records import record_id, text_of


def _reference_root() -> Path | None:
    root = _REFERENCE
    return root if root.is_dir() else None



def _knowledge_files() -> list[str]:
    root = _reference_root()
    if root is None:
        return ["<missing>"]
    mission = sorted(root.glob("missions/*/knowledge/*.xml"))
    # scalability worlds are large: the small ones, the one with a broken end tag, the largest
    scal = [p for p in sorted(root.glob("scalability/*/knowledge/*.xml"))
            if p.stem in ("world_db0", "world_db1", "world_db5", "world_db_original")]
    return [str(p.relative_to(root)) for p in mission + scal]


def _write(tmp_path: Path, text: str, name: str = "world.xml") -> Path:
    path = tmp_path / name
    path.write_text(text)
    return path


# ---------------------------------------------------------------------------------------------
# Reference corpus


@pytest.mark.parametrize("rel", _knowledge_files())
def test_every_reference_world_loads(rel: str) -> None:
    lenient = rel.endswith("food-logistics-delivery/knowledge/world_db5.xml")  # see below
    k = load_knowledge(reference_dir() / rel, "world_db", lenient=lenient)
    assert k.root.tag == "world_db"
    assert k.records
    for r in k.records:
        assert isinstance(r.tag, str)  # comments are never records


def test_room_preparation_world() -> None:
    k = load_knowledge(reference_dir() / "missions/room-preparation/knowledge/World_db.xml", "world_db")
    assert len(k.records_of("location")) == 25  # the leading comment is skipped
    rooms = k.records_of("Room")
    assert [k.record_id(r) for r in rooms] == ["RoomA", "RoomB", "RoomC", "SanitizationRoom"]
    assert k.field_text(rooms[1], "door_open") == "True"
    assert k.field_text(rooms[1], "location") == "c6"
    assert k.find_record("Room", "RoomC") is rooms[2]
    assert k.find_record("Room", "RoomZ") is None
    assert k.records_of("Nothing") == ()


def test_vital_signs_lists() -> None:
    k = load_knowledge(reference_dir() / "missions/vital-signs-monitoring/knowledge/world_db.xml", "world_db")
    room = k.find_record("Room", "RoomA")
    assert split_list(k.field_text(room, "patients")) == ["Patient1", "Patient2"]


def test_scalability_world_with_unclosed_record_needs_lenient_xml() -> None:
    # <Location> Location12 is never closed: the </world_db> end tag closes it (innermost open
    # element), the rest of the document becomes its content.  That changes which records exist,
    # so it is an error unless --lenient-xml asks for the original's reading (with a warning).
    path = reference_dir() / "scalability/food-logistics-delivery/knowledge/world_db5.xml"
    with pytest.raises(MissionError) as info:
        load_knowledge(path, "world_db")
    assert f"{path}:173:13: world knowledge: <Location> (line 106) is never closed" in str(info.value)
    assert "--lenient-xml" in str(info.value)
    k = load_knowledge(path, "world_db", lenient=True)
    assert any("<Location> (line 106) is never closed" in w for w in k.warnings)
    last = k.records_of("Location")[-1]
    assert k.record_id(last) == "Location12"
    assert k.records_of("Patient") == ()
    assert [c.tag for c in last][-1] == "Patient"


def test_largest_world_loads() -> None:
    path = reference_dir() / "scalability/vital-signs-monitoring/knowledge/world_db12.xml"
    k = load_knowledge(path, "world_db")
    assert len(k.records_of("Room")) == 5001  # 5000 + SanitizationRoom
    assert len(k.records_of("Patient")) == 10000
    index = k.field_index("Patient", "name")
    assert index["Patient7"] == [6]


# ---------------------------------------------------------------------------------------------
# Hardening and leniency


def _billion_laughs() -> str:
    ents = ['<!ENTITY lol "lol">'] + [
        f'<!ENTITY lol{i} "{("&lol" + (str(i - 1) if i > 1 else "") + ";") * 10}">' for i in range(1, 10)
    ]
    return ('<?xml version="1.0"?>\n<!DOCTYPE lolz [\n' + "\n".join(ents) + "\n]>\n"
            "<world_db><Room><name>&lol9;</name></Room></world_db>\n")


def test_billion_laughs_is_rejected_before_expansion(tmp_path: Path) -> None:
    path = _write(tmp_path, _billion_laughs())
    with pytest.raises(MissionError) as exc:
        load_knowledge(path, "world_db")
    [problem] = exc.value.problems
    assert problem.where == f"{path}:2"
    assert problem.message == "DTD and entity declarations are not allowed in world knowledge"


def test_external_entity_is_rejected(tmp_path: Path) -> None:
    path = _write(tmp_path, '<!DOCTYPE w [<!ENTITY x SYSTEM "file:///etc/passwd">]>\n<world_db><R><name>&x;</name></R></world_db>')
    with pytest.raises(MissionError, match="DTD and entity declarations are not allowed"):
        load_knowledge(path, "world_db")


def test_undeclared_entity_is_a_syntax_error(tmp_path: Path) -> None:
    path = _write(tmp_path, "<world_db>\n<R><name>&x;</name></R></world_db>")
    with pytest.raises(MissionError) as exc:
        load_knowledge(path, "world_db")
    assert exc.value.problems[0].where.startswith(f"{path}:2:")


def test_truncated_world_is_a_syntax_error(tmp_path: Path) -> None:
    path = _write(tmp_path, "<world_db>\n<Room><name>A</name>")
    with pytest.raises(MissionError, match="XML syntax error in world knowledge"):
        load_knowledge(path, "world_db")


def test_missing_and_empty_files(tmp_path: Path) -> None:
    with pytest.raises(MissionError, match="cannot read world knowledge file"):
        load_knowledge(tmp_path / "absent.xml", "world_db")
    with pytest.raises(MissionError):
        load_knowledge(_write(tmp_path, ""), "world_db")


def test_mismatched_end_tags_close_the_innermost_element(tmp_path: Path) -> None:
    path = _write(tmp_path, "<world_db><Room><name>A</nam><x>1</Room></y><Room><name>B</name></Room></world>")
    k = load_knowledge(path, "world_db")
    assert [(r.tag, k.record_id(r)) for r in k.records] == [("Room", "A"), ("Room", "B")]
    assert k.field_text(k.records[0], "x") == "1"


def test_content_after_the_root_needs_lenient_xml(tmp_path: Path) -> None:
    path = _write(tmp_path, "<world_db><Room><name>A</name></Room></world_db>\n<world_db><Room><name>B</name></Room></world_db>")
    with pytest.raises(MissionError, match=r"world.xml:2:1: world knowledge: content after the end of the root "
                                           r"element <world_db> is ignored"):
        load_knowledge(path, "world_db")
    k = load_knowledge(path, "world_db", lenient=True)
    assert [k.record_id(r) for r in k.records] == ["A"]  # the original reads the first element only
    assert len(k.warnings) == 1


def test_a_stray_end_tag_needs_lenient_xml(tmp_path: Path) -> None:
    """A stray </Room> closes the root early: the records after it would be lost."""
    path = _write(tmp_path, "<world_db>\n<Room><name>A</name></Room></Room>\n<Room><name>B</name></Room>\n</world_db>")
    with pytest.raises(MissionError, match=r"world.xml:2:35: world knowledge: </Room> closes the root element "
                                           r"<world_db> early"):
        load_knowledge(path, "world_db")


def test_a_missing_end_tag_that_nests_records_needs_lenient_xml(tmp_path: Path) -> None:
    path = _write(tmp_path, "<world_db>\n<Room><name>A</name>\n<Room><name>B</name></Room>\n"
                            "<Room><name>C</name></Room>\n</world_db>")
    with pytest.raises(MissionError, match=r"world.xml:5:12: world knowledge: <Room> \(line 2\) is never closed"):
        load_knowledge(path, "world_db")
    k = load_knowledge(path, "world_db", lenient=True)
    assert [k.record_id(r) for r in k.records] == ["A"]  # B and C nest inside A, as in the original
    assert "is never closed" in k.warnings[0]


def test_a_tag_typo_is_a_warning(tmp_path: Path) -> None:
    path = _write(tmp_path, "<world_db>\n<location_types><t>Room</t></location_type>\n<Room><name>A</name></Room>\n</world_db>")
    k = load_knowledge(path, "world_db")
    assert [k.record_id(r) for r in k.records_of("Room")] == ["A"]
    assert k.warnings == (f"{path}:2:44: world knowledge: </location_type> closes <location_types> (line 2); "
                          "read as </location_types>",)


def test_xml_root_lookup(tmp_path: Path) -> None:
    path = _write(tmp_path, "<doc><meta/><inner><world_db><R><name>a</name></R></world_db></inner></doc>")
    assert [r.tag for r in load_knowledge(path, "world_db").records] == ["R"]
    assert load_knowledge(path, None).root.tag == "doc"
    with pytest.raises(MissionError, match=r"Root element \[db\]"):
        load_knowledge(path, "db")


def test_unique_id_and_records(tmp_path: Path) -> None:
    path = _write(tmp_path, "<w><!-- c --><?pi x?><R><id>r1</id><name>other</name></R><R><name>n</name></R></w>")
    k = load_knowledge(path, "w", unique_id="id")
    assert [k.record_id(r) for r in k.records] == ["r1", None]
    assert load_knowledge(path, "w", unique_id="").unique_id == "name"


# ---------------------------------------------------------------------------------------------
# Value helpers


def test_text_is_verbatim_but_blank_only_text_is_empty(tmp_path: Path) -> None:
    path = _write(tmp_path, "<w><R><name> A b </name><e>  \n </e><c>\n <x>1</x>\n</c><m>t<x/>u</m></R></w>")
    k = load_knowledge(path, "w")
    r = k.records[0]
    assert record_id(r) == " A b "
    assert k.field_text(r, "e") == ""
    assert k.field_text(r, "c") == ""
    assert text_of(k.field(r, "m")) == "tu"
    assert k.field_text(r, "absent") is None


@pytest.mark.parametrize(
    ("text", "expected"),
    [("Patient1,Patient2", ["Patient1", "Patient2"]), ("Patient1 Patient2", ["Patient1", "Patient2"]),
     (" a , b,,c\n d ", ["a", "b", "c", "d"]), ("", []), (" , ", [])],
)
def test_split_list(text: str, expected: list[str]) -> None:
    assert split_list(text) == expected


@pytest.mark.parametrize(
    ("text", "expected"),
    [("True", True), ("true", True), ("  TRUE", True), ("trueish", True), ("False", False),
     ("1", False), ("yes", False), ("", False), ("t rue", False)],
)
def test_parse_bool(text: str, expected: bool) -> None:
    assert parse_bool(text) is expected


@pytest.mark.parametrize(
    ("text", "expected"),
    [("3", 3), (" 42abc", 42), ("-7", -7), ("abc", 0), ("", 0), ("2.5", 2.5), (" 1.5e2x", 150.0),
     ("x.5", 0.0), (".5", 0.5), ("+4", 4)],
)
def test_parse_number(text: str, expected: int | float) -> None:
    value = parse_number(text)
    assert value == expected and type(value) is type(expected)


def test_base_type() -> None:
    assert base_type("Sequence(Room)") == "Room"
    assert base_type("Room") == "Room"


def test_knowledge_is_a_value() -> None:
    k = WorldKnowledge.__dataclass_fields__
    assert list(k) == ["source", "root", "unique_id", "warnings"]
