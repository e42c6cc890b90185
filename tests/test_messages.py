"""Error messages read like documentation: what is wrong, where, and how to fix it.

The full text printed by ``mutrose-cp check`` is pinned for typical mistakes in each input
format.  Each message starts with the original tool's wording (scripts grep for it), then says
how to fix the input.  The temporary mission folder is shown as ``<mission>``.
"""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.errors import MissionError
from mutrose_cp.io.config import parse_configuration_json
from mutrose_cp.io.knowledge import load_knowledge

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
BILLION_LAUGHS = Path(__file__).resolve().parent / "bad_inputs" / "billion-laughs.xml"


def check_stderr(tmp_path: Path, capsys: pytest.CaptureFixture[str], example: str, file: str,
                 old: str, new: str | None = None, content: str | None = None) -> str:
    """stderr of ``check`` on ``example`` after replacing ``old`` by ``new`` in ``file`` (or the
    whole file by ``content``)."""
    mission = tmp_path / "mission"
    shutil.copytree(EXAMPLES / example, mission)
    path = mission / file
    if content is None:
        text = path.read_text(encoding="utf-8")
        assert text.count(old) == 1
        content = text.replace(old, new)
    path.write_text(content, encoding="utf-8")
    capsys.readouterr()
    assert main(["check", str(mission)]) == 2
    return capsys.readouterr().err.replace(str(mission), "<mission>")


# ---------------------------------------------------------------------------------------------
# HDDL


def test_hddl_unknown_predicate(tmp_path, capsys):
    err = check_stderr(tmp_path, capsys, "item-delivery", "hddl/delivery.hddl",
                       "(reachable ?l)\n        )", "(reachble ?l)\n        )")
    assert err == (
        "error: <mission>/hddl/delivery.hddl:92:14: undeclared predicate 'reachble' in the precondition "
        "of action 'navigate': did you mean 'reachable'? If not, declare it in (:predicates ...)\n"
    )


def test_hddl_subtask_arity(tmp_path, capsys):
    err = check_stderr(tmp_path, capsys, "item-delivery", "hddl/delivery.hddl",
                       "(navigate ?r ?src)\n            (pick-item", "(navigate ?r ?src ?d)\n            (pick-item")
    assert err == (
        "error: <mission>/hddl/delivery.hddl:42:14: subtask navigate in method 'fetch-from-shelf' is given "
        "3 arguments but declares only 2 parameters: (navigate ?r - DeliveryRobot ?l - location); remove "
        "the extra arguments\n"
    )


# ---------------------------------------------------------------------------------------------
# Goal model


def test_goal_model_undeclared_variable(tmp_path, capsys):
    err = check_stderr(
        tmp_path, capsys, "hospital-disinfection", "gm/hospital-disinfection-gm.json",
        '"Monitors": "current_room",\n                        "Group": "False"',
        '"Monitors": "current_rom",\n                        "Group": "False"',
    )
    assert err == (
        "error: <mission>/gm/hospital-disinfection-gm.json: goal G5: Undeclared variable [current_rom] of "
        "type [] in goal G5: Did you mean current_room? Otherwise declare it in the Controls of a goal "
        "visited earlier (an ancestor, or a goal to the left of one) or fix the name in Monitors\n"
    )


def test_goal_model_invalid_robot_number(tmp_path, capsys):
    err = check_stderr(tmp_path, capsys, "hospital-disinfection", "gm/hospital-disinfection-gm.json",
                       '"RobotNumber": "[2,3]"', '"RobotNumber": "[2, 3]"')
    assert err == (
        "error: <mission>/gm/hospital-disinfection-gm.json: task AT5: Invalid declaration of robot number: "
        "[2, 3]. Write a number of robots such as 2, or a range such as [2,4], with no spaces.\n"
    )


def test_goal_model_truncated(tmp_path, capsys):
    text = (EXAMPLES / "item-delivery/gm/delivery-gm.json").read_text(encoding="utf-8")
    err = check_stderr(tmp_path, capsys, "item-delivery", "gm/delivery-gm.json", "", content=text[:3000])
    assert err == (
        "error: <mission>/gm/delivery-gm.json:68:114: invalid JSON: Expecting ',' delimiter. The text ends "
        "before the JSON document is complete: the file looks truncated; restore its end (every '{' and "
        "'[' needs its closing '}' and ']').\n"
    )


# ---------------------------------------------------------------------------------------------
# Configuration


def test_configuration_unknown_mapping_type(tmp_path, capsys):
    err = check_stderr(tmp_path, capsys, "item-delivery", "configuration/configuration.json",
                       '"type": "attribute", "name": "staffed"', '"type": "atribute", "name": "staffed"')
    assert err == (
        "error: <mission>/configuration/configuration.json: semantic_mapping[1].type: No mapping type "
        "[atribute] for semantic mappings. Did you mean attribute? Set semantic_mapping[1].type to "
        "attribute (a field of a record), ownership (records listed inside another record) or "
        "relationship (records related to another record).\n"
    )


def test_configuration_var_mapping_type_error(tmp_path, capsys):
    err = check_stderr(tmp_path, capsys, "item-delivery", "configuration/configuration.json",
                       '{"gm_var": "destination", "hddl_var": "?dst"}\n        ]},\n        {"task_id": "AT3"',
                       '{"gm_var": "destination", "hddl_var": "?d"}\n        ]},\n        {"task_id": "AT3"')
    assert err == (
        "error: <mission>/configuration/configuration.json: var_mapping[1].map[1]: Type error in AT: "
        "HandOver: destination has OCL type Location mapped to HDDL type location, but ?d is a delivery: "
        "map destination to ?dst\n"
    )


# ---------------------------------------------------------------------------------------------
# World knowledge


def test_world_with_a_dtd(tmp_path, capsys):
    err = check_stderr(tmp_path, capsys, "item-delivery", "knowledge/world_db.xml", "",
                       content=BILLION_LAUGHS.read_text(encoding="utf-8"))
    assert err == (
        "error: <mission>/knowledge/world_db.xml:2: DTD and entity declarations are not allowed in world "
        "knowledge. Remove the <!DOCTYPE ...> declaration and write every value out literally: the "
        "decomposer never reads DTDs nor expands entities (this protects against billion-laughs and "
        "external-entity attacks).\n"
    )


def test_world_type_mapped_tag_used_as_a_field(tmp_path, capsys):
    err = check_stderr(tmp_path, capsys, "item-delivery", "knowledge/world_db.xml",
                       "<item>Insulin pens</item>", "<item>Insulin pens</item>\n        <Location>WardA</Location>")
    assert err == (
        "error: <mission>/knowledge/world_db.xml:43: element <Location> is a type-mapped record but has no "
        "<name> child (its unique id); do not use a mapped type name as a plain field tag: every <Location> "
        "element is read as a Location record (type_mapping), so give it a <name> child or rename the "
        "field\n"
    )


# ---------------------------------------------------------------------------------------------
# The original's wording stays first, in ``Problem.message``; the advice comes after it


def test_original_wording_is_the_message_and_advice_follows(tmp_path):
    path = tmp_path / "world_db.xml"
    path.write_bytes(BILLION_LAUGHS.read_bytes())
    with pytest.raises(MissionError) as exc:
        load_knowledge(path, "world_db")
    [problem] = exc.value.problems
    assert problem.message == "DTD and entity declarations are not allowed in world knowledge"
    assert str(problem).startswith(f"{path}:2: DTD and entity declarations are not allowed in world knowledge. ")

    text = (EXAMPLES / "item-delivery/configuration/configuration.json").read_text(encoding="utf-8")
    text = text.replace('"type": "attribute", "name": "staffed"', '"type": "Composition", "name": "staffed"')
    with pytest.raises(MissionError) as exc:
        parse_configuration_json(text, "configuration.json")
    [problem] = exc.value.problems
    assert problem.message == "No mapping type [Composition] for semantic mappings."
    assert str(problem).startswith("configuration.json: semantic_mapping[1].type: No mapping type [Composition] "
                                   "for semantic mappings. Set semantic_mapping[1].type to attribute")
