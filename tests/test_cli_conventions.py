"""Command-line conventions: ``--json-summary`` on failure, the output format from the ``-o``
suffix, and ``--json-style standard``."""
from __future__ import annotations

import json
import re
from pathlib import Path

from mutrose_cp.cli.program import main


def _summary(out: str) -> dict:
    (line,) = [line for line in out.splitlines() if line.startswith("{")]
    return json.loads(line)


def test_json_summary_lists_the_problems_of_a_failure(mission, capsys):
    hddl = next((mission / "hddl").glob("*.hddl"))
    hddl.write_text(hddl.read_text().replace("(:method", "(:methd", 1))
    assert main(["check", str(mission), "-q", "--json-summary"]) == 2
    captured = capsys.readouterr()
    summary = _summary(captured.out)
    assert (summary["command"], summary["ok"], summary["status"]) == ("check", False, 2)
    (problem,) = summary["problems"]
    assert problem["file"] == str(hddl) and isinstance(problem["line"], int) and isinstance(problem["column"], int)
    assert problem["message"] and set(problem) == {"file", "line", "column", "message", "hint"}
    assert f"{hddl}:{problem['line']}:{problem['column']}" in captured.err  # the same problem as printed


def test_json_summary_of_a_goal_model_problem_keeps_the_goal(mission, capsys):
    gm = next((mission / "gm").iterdir())
    data = json.loads(gm.read_text())
    task = next(n for a in data["actors"] for n in a["nodes"] if n["type"] == "istar.Task")
    task.setdefault("customProperties", {})["RobotNumber"] = "[3,one]"
    gm.write_text(json.dumps(data))
    assert main(["decompose", str(mission), "-q", "--json-summary", "-o", str(mission / "x.json")]) == 2
    (problem,) = _summary(capsys.readouterr().out)["problems"]
    assert problem["file"] == str(gm) and problem["line"] is None
    assert re.match(r"(goal|task) \w+: ", problem["message"]), problem


def test_output_format_follows_the_suffix_of_o(mission, tmp_path, capsys):
    assert main(["decompose", str(mission), "-o", str(tmp_path / "x.xml"), "--limit", "1"]) == 0
    assert (tmp_path / "x.xml").read_text().startswith("<?xml")
    err = capsys.readouterr().err
    assert f"warning: {tmp_path / 'x.xml'}: writing xml, as the suffix says, although" in err
    assert "asks for json (output.file_type)" in err
    assert main(["decompose", str(mission), "-o", str(tmp_path / "x.json"), "--limit", "1"]) == 0
    assert (tmp_path / "x.json").read_text().startswith("{") and "warning" not in capsys.readouterr().err
    assert main(["decompose", str(mission), "-o", str(tmp_path / "x.out"), "--limit", "1"]) == 0
    assert (tmp_path / "x.out").read_text().startswith("{")  # no known suffix: the configuration's
    assert main(["decompose", str(mission), "-o", str(tmp_path / "y.xml"), "--format", "json", "--limit", "1"]) == 0
    assert (tmp_path / "y.xml").read_text().startswith("{") and "warning" not in capsys.readouterr().err


def test_standard_json_style(mission, tmp_path):
    standard, boost = tmp_path / "standard.json", tmp_path / "boost.json"
    assert main(["decompose", str(mission), "-q", "-o", str(standard), "--json-style", "standard"]) == 0
    assert main(["decompose", str(mission), "-q", "-o", str(boost)]) == 0
    data, original = json.loads(standard.read_bytes().decode("utf-8")), json.loads(boost.read_text())
    assert list(data) == list(original)
    task = data["tasks"]["t0"]
    assert isinstance(task["robots_num"]["fixed"], bool) and isinstance(task["locations"], list)
    assert all(isinstance(v, int) for k, v in task["robots_num"].items() if k != "fixed")
    assert isinstance(task["group"], bool) and task["triggering_events"] == [] != original["tasks"]["t0"]["triggering_events"]
    assert all(isinstance(c.get("group", False), bool) for c in data["constraints"])
    assert [t["id"] for t in data["tasks"].values()] == [t["id"] for t in original["tasks"].values()]
    assert data["mission_decompositions"] == original["mission_decompositions"]
    assert isinstance(data["mission_decomposition_space"]["count"], str)


def test_standard_json_style_of_an_empty_mission(mission, tmp_path):
    """The original's style writes ``"tasks": ""`` (which the 2D simulator's reader cannot
    iterate); the standard style writes empty containers."""
    world = next((mission / "knowledge").glob("*.xml"))
    world.write_text(world.read_text().replace("<is_delivered>False</is_delivered>", "<is_delivered>True</is_delivered>"))
    standard, boost = tmp_path / "standard.json", tmp_path / "boost.json"
    assert main(["decompose", str(mission), "-q", "-o", str(boost)]) == 0
    assert main(["decompose", str(mission), "-q", "-o", str(standard), "--json-style", "standard"]) == 0
    assert json.loads(boost.read_text())["tasks"] == ""
    data = json.loads(standard.read_text())
    assert (data["tasks"], data["constraints"], data["mission_decompositions"]) == ({}, [], [])
    assert isinstance(data["actions"], list)


def test_standard_json_style_needs_json_output(mission, tmp_path, capsys):
    assert main(["decompose", str(mission), "-q", "-o", str(tmp_path / "x.xml"), "--json-style", "standard"]) == 2
    assert "--json-style standard applies to JSON output" in capsys.readouterr().err
    assert not Path(tmp_path / "x.xml").exists()
