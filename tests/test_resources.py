"""Resources: memory grows linearly with the goal model, inputs that are not regular files or
are too large are refused before they are read, deep goal models are handled."""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
import tracemalloc
from pathlib import Path

from mutrose_cp.pipeline import expansion
from mutrose_cp.cli.program import main
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"


def _with_query_goals(folder: Path, n: int) -> Path:
    """The item-delivery mission with ``n`` more query goals under its root (no annotation, so
    every child is visited)."""
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    gm_path = next((folder / "gm").iterdir())
    gm = json.loads(gm_path.read_text())
    nodes = gm["actors"][0]["nodes"]
    root = next(x for x in nodes if x["text"].startswith("G1:"))
    root["text"] = root["text"].split("[")[0].strip()
    for i in range(n):
        nodes.append({"id": f"q-{i}", "text": f"G{1000 + i}: Query {i}", "type": "istar.Goal", "x": 10 * i, "y": 900,
                      "customProperties": {"GoalType": "Query", "Controls": f"v{i} : Sequence(Location)",
                                           "QueriedProperty": "world_db->select(l:Location | )"}})
        gm["links"].append({"id": f"l-{i}", "type": "istar.AndRefinementLink", "source": f"q-{i}",
                            "target": root["id"]})
    gm_path.write_text(json.dumps(gm))
    return folder


def _expansion_peak(folder: Path) -> int:
    mission = Mission.load(*find_mission_files(folder))
    tracemalloc.start()
    try:
        _ = mission.expansion
        return tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()


def test_expansion_memory_is_linear_in_query_goals(tmp_path):
    """Twice the query goals, about twice the memory (each goal used to copy every variable:
    four times the memory, 1.3 GB for 10k goals)."""
    small = _expansion_peak(_with_query_goals(tmp_path / "small", 500))
    large = _expansion_peak(_with_query_goals(tmp_path / "large", 1000))
    assert large < 2.6 * small, (small, large)


def _copy(tmp_path: Path) -> Path:
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    return folder


def _world_path(folder: Path, path: str) -> None:
    cfg = folder / "configuration" / "configuration.json"
    data = json.loads(cfg.read_text())
    data["world_db"]["path"] = path
    cfg.write_text(json.dumps(data))


def test_a_device_as_world_is_refused(tmp_path, capsys):
    """/dev/zero would never end; a FIFO in the temporary folder would wait forever."""
    folder = _copy(tmp_path)
    fifo = tmp_path / "world.fifo"
    os.mkfifo(fifo)
    for path in ("/dev/zero", str(fifo)):
        _world_path(folder, path)
        assert main(["check", str(folder)]) == 2
        assert f"error: {path}: cannot read world knowledge file: it is not a regular file" in capsys.readouterr().err


def test_a_folder_as_goal_model_is_refused(tmp_path, capsys):
    folder = _copy(tmp_path)
    hddl, _gm, cfg = find_mission_files(folder)
    assert main(["check", str(hddl), str(folder / "gm"), str(cfg)]) == 2
    assert "cannot read goal model file: it is not a regular file" in capsys.readouterr().err


def test_inputs_over_the_size_limit_are_refused(tmp_path, capsys):
    folder = _copy(tmp_path)
    world = folder / "knowledge" / "world_db.xml"
    text = world.read_text()
    world.write_text(text.replace("</world_db>", "<!--" + "x" * (2 * 1024 * 1024) + "--></world_db>"))
    assert main(["check", str(folder), "--max-input-mb", "1"]) == 2
    err = capsys.readouterr().err
    assert "the world knowledge file is 2.0 MB, over the input limit of 1 MB" in err and "--max-input-mb" in err
    assert main(["check", str(folder), "--max-input-mb", "3"]) == 0


def _chain(folder: Path, n: int) -> Path:
    """The item-delivery mission with a chain of ``n`` single-child goals below its root."""
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    gm_path = next((folder / "gm").iterdir())
    gm = json.loads(gm_path.read_text())
    nodes, links = gm["actors"][0]["nodes"], gm["links"]
    root = next(x for x in nodes if x["text"].startswith("G1:"))
    below = [link for link in links if link["target"] == root["id"]]
    previous = root["id"]
    for i in range(n):
        nodes.append({"id": f"c-{i}", "text": f"G{2000 + i}: Chain {i}", "type": "istar.Goal", "x": 0, "y": 0,
                      "customProperties": {}})
        links.append({"id": f"cl-{i}", "type": "istar.AndRefinementLink", "source": f"c-{i}", "target": previous})
        previous = f"c-{i}"
    for link in below:
        link["target"] = previous
    nodes[-1]["text"] += " [" + root["text"].split("[", 1)[1]
    root["text"] = root["text"].split("[")[0].strip()
    gm_path.write_text(json.dumps(gm))
    return folder


def test_a_deep_goal_model_is_decomposed(tmp_path, capsys):
    """2000 nested goals: deeper than Python's default recursion limit allows."""
    folder = _chain(tmp_path / "deep", 2000)
    assert main(["count", str(folder), "-q"]) == 0
    assert capsys.readouterr().out.strip() == "8"


def test_a_goal_model_too_deep_names_the_goal(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(expansion, "MAX_GOAL_DEPTH", 50)
    folder = _chain(tmp_path / "deep", 60)
    assert main(["check", str(folder)]) == 2
    assert ": goal G2050: the goal model is nested more than 50 levels deep here" in capsys.readouterr().err


def test_inputs_are_read_under_a_memory_limit_far_below_the_input_limit():
    """Reading a small file reserves a buffer of its size, not of the input limit (256 MB): a
    mission is checked in a process whose data may not exceed 120 MB."""
    code = ("import resource, sys; resource.setrlimit(resource.RLIMIT_DATA, (120 << 20, 120 << 20)); "
            "from mutrose_cp.cli.program import main; sys.exit(main(sys.argv[1:]))")
    run = subprocess.run([sys.executable, "-c", code, "check", str(EXAMPLE), "-q"], capture_output=True, text=True,
                         timeout=120)
    assert run.returncode == 0, run.stderr
