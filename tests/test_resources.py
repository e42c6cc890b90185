"""Resources: memory grows linearly with the goal model, inputs that are not regular files or
are too large are refused before they are read, deep goal models are handled."""
from __future__ import annotations

import json
import shutil
import tracemalloc
from pathlib import Path

from mutrose_cp.mission import Mission, find_mission_files

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
