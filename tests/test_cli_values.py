"""Command-line and input values out of their domain are usage errors (exit 2, one message),
never a traceback nor a silent reinterpretation."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"


@pytest.mark.parametrize("option,value,message", [
    ("--limit", "-1", "-1 is out of range"),
    ("--limit", "99999999999999999999", "is out of range"),
    ("--limit", "ten", "expected a whole number"),
    ("--sample", "-1", "-1 is out of range"),
    ("--sample", "0", "0 is out of range"),
    ("--seed", "-3", "-3 is out of range"),
])
def test_count_options_out_of_range(tmp_path, capsys, option, value, message):
    assert main(["decompose", str(EXAMPLE), "-q", option, value, "-o", str(tmp_path / "o.json")]) == 2
    err = capsys.readouterr().err
    assert f"argument {option}: " in err and message in err
    assert not (tmp_path / "o.json").exists()


@pytest.mark.parametrize("content,message", [
    (b'{"actions": {"navigate": 1.7}}', "actions.navigate: expected a whole number as cost, got 1.7"),
    (b'{"actions": {"navigate": 1e309}}', "actions.navigate: cost inf is out of range"),
    (b'{"methods": {"m": "2"}}', 'methods.m: expected a whole number as cost, got "2"'),
    (b'{"default_action": true}', "default_action: expected a whole number as cost, got true"),
    (b'{"actions": ["navigate"]}', "expected an object"),
    (b'{"actions": {"navigate": "\xff"}}', ":1:27: the cost file is not UTF-8 text"),
])
def test_bad_cost_files(tmp_path, capsys, content, message):
    costs = tmp_path / "costs.json"
    costs.write_bytes(content)
    assert main(["decompose", str(EXAMPLE), "-q", "--optimize", "--costs", str(costs),
                 "-o", str(tmp_path / "o.json")]) == 2
    err = capsys.readouterr().err
    assert message in err, err
    assert "Traceback" not in err


def test_whole_float_cost_is_accepted(tmp_path):
    costs = tmp_path / "costs.json"
    costs.write_text(json.dumps({"actions": {"navigate": 2.0}}))
    assert main(["decompose", str(EXAMPLE), "-q", "--optimize", "--costs", str(costs), "-o", str(tmp_path / "o.json")]) == 0


@pytest.mark.parametrize("robots", ["0", "[0,0]"])
def test_zero_robots_rejected(tmp_path, capsys, robots):
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    gm = next((folder / "gm").iterdir())
    data = json.loads(gm.read_text())
    task = next(n for n in data["actors"][0]["nodes"] if n["type"] == "istar.Task")
    task["customProperties"]["RobotNumber"] = robots
    gm.write_text(json.dumps(data))
    assert main(["check", str(folder)]) == 2
    assert f"Invalid declaration of robot number: {robots} (a task needs at least one robot)" in capsys.readouterr().err


@pytest.mark.parametrize("text,read", [("1e9", "1"), ("NaN", "0"), ("Infinity", "0"), ("12abc", "12")])
def test_world_numbers_read_as_the_original_does_are_warned(tmp_path, capsys, text, read):
    from conftest import require_reference

    folder = tmp_path / "mission"
    shutil.copytree(require_reference() / "missions" / "object-picking-function", folder)
    world = folder / "knowledge" / "World_db.xml"
    world.write_text(world.read_text().replace("<num_objects>1</num_objects>", f"<num_objects>{text}</num_objects>", 1))
    assert main(["check", str(folder)]) == 0
    assert f"{world}:4: Room RoomA: num_objects '{text}' is read as {read}, as the original reads numbers" \
        in capsys.readouterr().err


def test_plain_world_numbers_are_not_warned(tmp_path, capsys):
    from conftest import require_reference

    assert main(["check", str(require_reference() / "missions" / "object-picking-function")]) == 0
    assert "is read as" not in capsys.readouterr().err


def test_the_command_line_leaves_the_interpreter_as_it_found_it(tmp_path):
    import gc
    import sys

    digits, recursion, collecting = sys.get_int_max_str_digits(), sys.getrecursionlimit(), gc.isenabled()
    assert main(["count", str(EXAMPLE), "-q"]) == 0
    assert (sys.get_int_max_str_digits(), sys.getrecursionlimit(), gc.isenabled()) == (digits, recursion, collecting)
