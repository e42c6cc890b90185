"""The Python examples of the documentation run as written (docs/api.md), from the project root,
in order, in one namespace: a user copying them gets what the text says."""
from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent


def _python_blocks(path: Path) -> list[str]:
    return re.findall(r"```python\n(.*?)```", path.read_text(encoding="utf-8"), flags=re.S)


def test_api_guide_examples_run(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    blocks = _python_blocks(ROOT / "docs" / "api.md")
    assert len(blocks) >= 3
    namespace: dict = {}
    for block in blocks:
        exec(compile(block, "docs/api.md", "exec"), namespace)  # noqa: S102 - our own documentation
    printed = capsys.readouterr().out.splitlines()
    # the solve printed the chosen decompositions and OR choices the text describes
    assert printed[0].startswith("['AT") and "'G7_2': 'G11'" in printed[1]
    # Mission.allocate: proven optimal, three robots' routes, the teams
    assert printed[2].startswith("OPTIMAL 136 136.0 ")
    assert [line.split(" ", 1)[0] for line in printed[3:6]] == ["picker", "talker", "allrounder"]
    assert printed[6].startswith("{'AT")
    del printed[2:7]
    # Mission.decompose: the first two of the eight, the least cost, a sample of three
    assert printed[2].startswith("8 [['AT1_1|1'") and printed[2].count("[") == 3
    mission, best, costs = namespace["mission"], namespace["best"], namespace["costs"]
    per_decomposition = costs.decomposition_costs(mission.task_graph)
    listed = mission.decompose(namespace["DecompositionRequest"](limit=None)).decompositions
    every = [sum(per_decomposition[d] for d in ds) for ds in listed]
    assert printed[3].split(" ", 1)[0] == str(best.optimum[1]) == str(min(every))
    assert printed[4] == "3"
    # Mission.verify: every decomposition drops an item; the witness is one of them
    assert printed[5].startswith("fails 8 8 ['AT1_1|1'")
    # uncertain worlds: no robust plan of 4, the likeliest at 0.48, two facts to sense
    assert printed[6] == "0 4 0.48 ['door-locked(Room202)', 'patient-present(Room203)']"


def test_readme_example_runs(monkeypatch, capsys):
    monkeypatch.chdir(ROOT)
    (block,) = _python_blocks(ROOT / "README.md")
    exec(compile(block, "README.md", "exec"), {})  # noqa: S102 - our own documentation
    total, cost, chosen = capsys.readouterr().out.split(" ", 2)
    assert total == "36" and int(cost) > 0 and chosen.startswith("['AT")


def test_guide_allocation_runs_as_written(tmp_path, capsys):
    """Section 8 of the guide: its fleet, on the guide's mission with the wards' coordinates the
    text gives, allocates as the summary line it shows (a fleet the mission cannot use was
    published once: unknown capabilities, no lab robots)."""
    import json
    import shutil

    from mutrose_cp.cli.program import main

    guide = (ROOT / "docs" / "guide.md").read_text(encoding="utf-8")
    section = guide[guide.index("## 8. Allocate it to a fleet"):guide.index("## 9.")]
    fleet = json.loads(re.search(r"```json\n(.*?)```", section, flags=re.S).group(1))
    shown = re.search(r"^allocated: .*? robots", section, flags=re.M).group(0)
    mission = tmp_path / "lab-samples"
    shutil.copytree(ROOT / "docs" / "guide-mission", mission)
    world = mission / "knowledge" / "world_db.xml"
    text = world.read_text(encoding="utf-8")
    for ward, (x, y) in {"Ward1": (0, 40), "Ward2": (30, 40), "Ward3": (60, 40)}.items():
        assert f"<x>{x}</x> <y>{y}</y>" in section  # the coordinates the text gives
        text = text.replace(f"<name>{ward}</name>", f"<name>{ward}</name> <x>{x}</x> <y>{y}</y>", 1)
    world.write_text(text, encoding="utf-8")
    (tmp_path / "fleet.json").write_text(json.dumps(fleet), encoding="utf-8")
    assert main(["allocate", str(mission), "--fleet", str(tmp_path / "fleet.json"), "-o", str(tmp_path / "o.json")]) == 0
    assert capsys.readouterr().err.startswith(shown)
