"""Configuration reader: every reference configuration loads, JSON and XML forms agree, and bad
configurations are reported with located, collected problems."""
from __future__ import annotations

import dataclasses
import json
from pathlib import Path

import pytest
from conftest import REFERENCE as _REFERENCE
from conftest import require_reference as reference_dir

from mutrose_cp.errors import MissionError
from mutrose_cp.io.config import load_configuration, parse_configuration_json, parse_configuration_xml
from mutrose_cp.model import Configuration, SemanticMapping


def _reference_root() -> Path | None:
    root = _REFERENCE
    return root if root.is_dir() else None



def _reference_configs() -> list[str]:
    root = _reference_root()
    if root is None:
        return ["<missing>"]
    files = sorted(p for p in root.glob("*/*/configuration/*") if p.suffix in (".json", ".xml"))
    return [str(p.relative_to(root)) for p in files]


# ---------------------------------------------------------------------------------------------
# Reference corpus


@pytest.mark.parametrize("rel", _reference_configs())
def test_every_reference_configuration_loads(rel: str) -> None:
    path = reference_dir() / rel
    config = load_configuration(path)
    assert config.world_db.type == "file"
    assert config.world_db.file_type == "xml"
    assert config.world_db.path.startswith("knowledge/")
    assert config.world_db.xml_root == "world_db"
    assert config.world_db.unique_id == "name"
    assert config.output.file_type in ("json", "xml")
    assert config.type_mapping  # every mission maps at least one type
    # the shipped XML configurations close <location_types> with </location_type> (and one
    # more such typo): harmless repairs, each a located warning
    assert all(": configuration: </" in w and "; read as </" in w for w in config.warnings)
    assert bool(config.warnings) == rel.endswith(".xml")
    for m in config.semantic_mapping:
        assert m.type in ("attribute", "ownership", "relationship")
        assert m.mapped_type in ("predicate", "function")
        assert m.pred and m.arg_sorts


@pytest.mark.parametrize("mission", ["room-preparation", "object-picking", "object-picking-function"])
def test_xml_and_json_forms_are_equal_except_source_and_output(mission: str) -> None:
    folder = reference_dir() / "missions" / mission / "configuration"
    from_json = load_configuration(folder / "configuration.json")
    from_xml = load_configuration(folder / "configuration.xml")
    assert from_xml.source.endswith("configuration.xml")
    strip = dict(source="", output=None, warnings=())  # only the XML has repaired end tags
    assert dataclasses.replace(from_json, **strip) == dataclasses.replace(from_xml, **strip)


def test_room_preparation_values() -> None:
    config = load_configuration(reference_dir() / "missions/room-preparation/configuration/configuration.xml")
    assert config.output.file_type == "xml"
    assert config.output.file_path == "output/task_output.xml"
    # the mismatched </location_type> closes <location_types>: type_mapping is a sibling
    assert config.location_types == ("Room",)
    assert config.type_mapping == {"Room": "room"}
    assert [(v.task_id, v.pairs) for v in config.var_mapping] == [
        ("AT1", (("current_room", "?rm"),)),
        ("AT2", (("sanitization_room", "?srm"),)),
        ("AT3", (("current_room", "?rm"),)),
    ]
    names = [(m.name, m.relates_to, m.pred, m.arg_sorts, m.belongs_to) for m in config.semantic_mapping]
    assert names == [
        ("is_clean", "Room", "clean", ("room",), "world_db"),
        ("is_prepared", "Room", "prepared", ("room",), "world_db"),
        ("is_sanitized", "robot", "sanitized", ("robot",), "robots_db"),
        ("door_open", "Room", "door-open", ("room",), "world_db"),
    ]
    assert config.semantic_mapping[3].where == "semantic_mapping[3]"
    assert config.locate(config.semantic_mapping[3].where).endswith("configuration.xml: semantic_mapping[3]")


def test_deliver_goods_ownership_and_relationship_fields() -> None:
    config = load_configuration(reference_dir() / "missions/deliver-goods-equipment/configuration/configuration.json")
    own = config.semantic_mapping[1]
    assert (own.type, own.owner, own.owned, own.relationship_type, own.attribute_name) == (
        "ownership", "Storage", "Object", "attribute", "objects")
    rel = config.semantic_mapping[3]
    assert (rel.type, rel.main_entity, rel.related_entity, rel.attribute_name, rel.arg_sorts) == (
        "relationship", "Agent", "Location", "location", ("location", "agent"))
    assert config.location_types == ("Location", "Storage")
    assert config.type_mapping == {"Agent": "agent", "Location": "location", "Storage": "storage", "Object": "obj"}


# ---------------------------------------------------------------------------------------------
# Synthetic configurations


def _base() -> dict:
    return {
        "world_db": {"type": "file", "file_type": "xml", "path": "knowledge/w.xml", "xml_root": "world_db"},
        "output": {"output_type": "file", "file_path": "out.json", "file_type": "json"},
        "location_types": ["Room"],
        "type_mapping": [{"hddl_type": "room", "ocl_type": "Room"}],
        "var_mapping": [{"task_id": "AT1", "map": [{"gm_var": "r", "hddl_var": "?r"}]}],
        "semantic_mapping": [
            {"type": "attribute", "name": "is_clean", "relates_to": "Room", "belongs_to": "world_db",
             "mapped_type": "predicate", "map": {"pred": "clean", "arg_sorts": ["room"]}},
        ],
    }


def _parse(data: dict) -> Configuration:
    return parse_configuration_json(json.dumps(data), "configuration.json")


def _problems(data: dict) -> list[tuple[str, str]]:
    with pytest.raises(MissionError) as exc:
        _parse(data)
    return [(p.where, p.message) for p in exc.value.problems]


def test_minimal_json() -> None:
    config = _parse(_base())
    assert config.semantic_mapping == (
        SemanticMapping("attribute", "predicate", "clean", ("room",), belongs_to="world_db", name="is_clean",
                        relates_to="Room", where="semantic_mapping[0]"),
    )
    assert config.agent_types == ()


def test_values_are_lower_cased_where_the_spec_says() -> None:
    data = _base()
    data["world_db"].update(type="FILE", file_type="Xml")
    data["output"].update(output_type="File", file_type="JSON")
    data["semantic_mapping"][0].update(type="Attribute", mapped_type="PREDICATE")
    config = _parse(data)
    assert (config.world_db.type, config.world_db.file_type) == ("file", "xml")
    assert (config.output.output_type, config.output.file_type) == ("file", "json")
    assert (config.semantic_mapping[0].type, config.semantic_mapping[0].mapped_type) == ("attribute", "predicate")
    assert config.semantic_mapping[0].relates_to == "Room"  # verbatim


def test_truncated_json_is_located() -> None:
    text = json.dumps(_base(), indent=2)[:-40]
    with pytest.raises(MissionError) as exc:
        parse_configuration_json(text, "configuration.json")
    where = exc.value.problems[0].where
    file, line, col = where.split(":")
    assert file == "configuration.json" and int(line) > 1 and int(col) >= 1
    assert "invalid JSON" in exc.value.problems[0].message


def test_unknown_mapping_type() -> None:
    data = _base()
    data["semantic_mapping"].append(dict(data["semantic_mapping"][0], type="Composition"))
    assert _problems(data) == [
        ("configuration.json: semantic_mapping[1].type", "No mapping type [Composition] for semantic mappings.")
    ]


def test_unsupported_output_and_database_types_are_collected_together() -> None:
    data = _base()
    data["output"]["output_type"] = "socket"
    data["output"]["file_type"] = "yaml"
    data["world_db"]["type"] = "sql"
    data["world_db"]["file_type"] = "csv"
    assert _problems(data) == [
        ("configuration.json: world_db.type", "Database type [sql] is not supported"),
        ("configuration.json: world_db.file_type", "Database file type [csv] is not supported"),
        ("configuration.json: output.output_type", "Output type [socket] is not supported"),
        ("configuration.json: output.file_type", "File type [yaml] is not supported"),
    ]


def test_missing_world_db_keys() -> None:
    data = _base()
    del data["world_db"]["path"]
    del data["world_db"]["type"]
    assert _problems(data) == [
        ("configuration.json: world_db.type", "Database type for [world_db] was not defined"),
        ("configuration.json: world_db.path", "Missing attributes [path] in world_db definition"),
    ]
    data = _base()
    del data["world_db"]
    assert _problems(data) == [
        ("configuration.json: world_db", "Knowledge [world_db] was not defined in the configuration file")
    ]


def test_missing_semantic_mapping_keys() -> None:
    data = _base()
    del data["semantic_mapping"][0]["map"]["pred"]
    del data["semantic_mapping"][0]["name"]
    data["semantic_mapping"].append({"type": "ownership", "owner": "Room", "mapped_type": "predicate",
                                     "relationship_type": "attribute",
                                     "map": {"pred": "at", "arg_sorts": ["obj", "room"]}})
    assert _problems(data) == [
        ("configuration.json: semantic_mapping[0].map.pred", "missing key map.pred"),
        ("configuration.json: semantic_mapping[0].name", "missing key name"),
        ("configuration.json: semantic_mapping[1].owned", "missing key owned"),
        ("configuration.json: semantic_mapping[1].attribute_name", "missing key attribute_name"),
        ("configuration.json: semantic_mapping[1].belongs_to", "missing key belongs_to"),
    ]


def test_robot_attribute_needs_no_belongs_to() -> None:
    data = _base()
    data["semantic_mapping"][0].update(relates_to="ROBOT")
    del data["semantic_mapping"][0]["belongs_to"]
    assert _parse(data).semantic_mapping[0].belongs_to == ""


def test_missing_required_sections() -> None:
    data = _base()
    del data["var_mapping"]
    del data["semantic_mapping"]
    del data["output"]["file_path"]
    problems = _problems(data)
    assert ("configuration.json: output.file_path", "missing key output.file_path") in problems
    assert ("configuration.json: var_mapping", "missing key var_mapping") in problems
    assert ("configuration.json: semantic_mapping", "missing key semantic_mapping") in problems


def test_missing_xml_root_is_a_warning_not_a_prompt() -> None:
    data = _base()
    del data["world_db"]["xml_root"]
    data["world_db"]["unique_id"] = ""
    config = _parse(data)
    assert config.world_db.xml_root is None
    assert config.world_db.unique_id == "name"
    assert len(config.warnings) == 1 and "xml_root" in config.warnings[0]


def test_scalars_are_strings_and_last_duplicate_wins() -> None:
    text = json.dumps(_base())[:-1] + ', "location_types": ["A", 7, true]}'
    config = parse_configuration_json(text, "c.json")
    assert config.location_types == ("A", "7", "true")
    data = _base()
    data["type_mapping"].append({"hddl_type": "place", "ocl_type": "Room"})
    assert _parse(data).type_mapping == {"Room": "place"}


def test_missing_file(tmp_path: Path) -> None:
    with pytest.raises(MissionError) as exc:
        load_configuration(tmp_path / "nope.json")
    assert "cannot read configuration file" in str(exc.value)


def test_format_by_extension(tmp_path: Path) -> None:
    (tmp_path / "c.JSON").write_text(json.dumps(_base()))
    assert load_configuration(tmp_path / "c.JSON").source.endswith("c.JSON")
    (tmp_path / "c.cfg").write_text(json.dumps(_base()))
    with pytest.raises(MissionError) as exc:  # not .json: read as XML
        load_configuration(tmp_path / "c.cfg")
    assert "XML" in str(exc.value)


# ---------------------------------------------------------------------------------------------
# XML


_XML = """<configuration>
  <world_db><type>file</type><file_type>xml</file_type><path>k.xml</path><xml_root>world_db</xml_root></world_db>
  <output><output_type>file</output_type><file_path>o.xml</file_path><file_type>xml</file_type></output>
  <location_types><type>Room</type></location_type>
  <agent_types><type>Nurse</type><t>Doctor</t></agent_types>
  <type_mapping><mapping><hddl_type>room</hddl_type><ocl_type>Room</ocl_type></mapping></type_mapping>
  <var_mapping><mapping><task_id>AT1</task_id><map gm_var="r" hddl_var="?r"/><map gm_var="s" hddl_var="?s"/></mapping></var_mapping>
  <semantic_mapping>
    <!-- a comment is not a mapping -->
    <mapping><type>attribute</type><name>is_clean</name><relates_to>Room</relation>
      <belongs_to>world_db</belongs_to><mapped_type>predicate</mapped_type>
      <map><pred>clean</pred><arg_sorts number="1">room extra</arg_sorts></map></mapping>
  </semantic_mapping>
</configuration>
"""


def test_xml_lenient_end_tags_give_the_intended_tree() -> None:
    config = parse_configuration_xml(_XML, "configuration.xml")
    assert config.location_types == ("Room",)
    assert config.agent_types == ("Nurse", "Doctor")
    assert config.type_mapping_entries == (("room", "Room"),)
    assert config.var_mapping[0].pairs == (("r", "?r"), ("s", "?s"))
    m = config.semantic_mapping[0]
    assert (m.relates_to, m.belongs_to, m.arg_sorts) == ("Room", "world_db", ("room",))


def test_xml_values_are_verbatim() -> None:
    text = _XML.replace("<type>attribute</type>", "<type>\n   attribute\n</type>")
    with pytest.raises(MissionError) as exc:
        parse_configuration_xml(text, "configuration.xml")
    assert "No mapping type [\n   attribute\n]" in exc.value.problems[0].message


def test_xml_arg_sorts_number() -> None:
    text = _XML.replace('number="1">room extra', 'number="3">room extra')
    with pytest.raises(MissionError) as exc:
        parse_configuration_xml(text.encode(), "configuration.xml")
    assert exc.value.problems[0].where == "configuration.xml: semantic_mapping[0].map.arg_sorts"


def test_xml_missing_attributes_of_map() -> None:
    text = _XML.replace('<map gm_var="s" hddl_var="?s"/>', '<map gm_var="s"/>')
    with pytest.raises(MissionError) as exc:
        parse_configuration_xml(text, "configuration.xml")
    assert [(p.where, p.message) for p in exc.value.problems] == [
        ("configuration.xml: var_mapping[0].map[1].hddl_var", "missing key map[1].hddl_var")
    ]


@pytest.mark.parametrize(
    "text",
    [
        _XML[:300],  # truncated
        "",
        "<configuration><world_db x=1/></configuration>",
        '<!DOCTYPE c [<!ENTITY e "x">]><configuration>&e;</configuration>',
    ],
)
def test_broken_xml_is_a_mission_error(text: str) -> None:
    with pytest.raises(MissionError) as exc:
        parse_configuration_xml(text, "configuration.xml")
    assert exc.value.problems[0].where.startswith("configuration.xml")


def test_xml_root_must_be_configuration() -> None:
    with pytest.raises(MissionError, match="missing key configuration"):
        parse_configuration_xml("<config/>", "c.xml")
