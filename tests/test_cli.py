"""The command line on the bundled examples: count, listing, sampling, optimisation, summaries,
graphs and option errors."""
from __future__ import annotations

import json
from collections import Counter
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
HOSPITAL = EXAMPLES / "hospital-disinfection"
DELIVERY = EXAMPLES / "item-delivery"


def _run(capsys, *args: str) -> tuple[int, str, str]:
    code = main(list(args))
    out, err = capsys.readouterr()
    return code, out, err


def _decompositions(path: Path) -> list[frozenset[str]]:
    data = json.loads(path.read_text())
    ids = {k: t["id"] for k, t in data["tasks"].items()}
    return [frozenset(ids[k] for k in md) for md in data["mission_decompositions"]]


def test_count_prints_the_bare_number_last(capsys):
    code, out, err = _run(capsys, "count", str(HOSPITAL))
    assert code == 0
    assert out.splitlines()[-1] == "36"
    assert err.strip().startswith("counted: 36 valid mission decompositions")


def test_a_count_beyond_15_digits_is_summarised_by_its_magnitude(tmp_path, capsys, reference):
    """50 independent deliveries with 3 ways each: 3**50 (24 digits) valid mission decompositions."""
    import sys
    sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
    from generate import generate

    code, out, err = _run(capsys, "count", *map(str, generate("delivery", 50, tmp_path)))
    assert code == 0 and out.splitlines()[-1] == str(3**50)
    assert err.strip().startswith("counted: 7.178e23 (exact: 24 digits) valid mission decompositions in "), err


def test_limit_lists_a_prefix_of_the_full_listing(tmp_path, capsys):
    full, part = tmp_path / "all.json", tmp_path / "part.json"
    assert _run(capsys, "decompose", str(HOSPITAL), "--limit", "0", "-o", str(full))[0] == 0
    assert _run(capsys, "decompose", str(HOSPITAL), "--limit", "5", "-o", str(part))[0] == 0
    everything = _decompositions(full)
    assert len(everything) == len(set(everything)) == 36
    assert _decompositions(part) == everything[:5]
    space = json.loads(part.read_text())["mission_decomposition_space"]
    assert space["count"] == "36"
    assert 36 == eval("*".join(c["count"] for c in space["components"]))


def test_sample_is_seeded_and_draws_valid_decompositions(tmp_path, capsys):
    a, b, full = tmp_path / "a.json", tmp_path / "b.json", tmp_path / "all.json"
    for out in (a, b):
        assert _run(capsys, "decompose", str(HOSPITAL), "--sample", "200", "--seed", "7", "-o", str(out))[0] == 0
    assert _run(capsys, "decompose", str(HOSPITAL), "--limit", "0", "-o", str(full))[0] == 0
    drawn = _decompositions(a)
    assert drawn == _decompositions(b)  # same seed, same draws
    assert len(drawn) == 200 and set(drawn) <= set(_decompositions(full))
    # 200 uniform draws over 36 decompositions reach most of them, none very often
    counts = Counter(drawn)
    assert len(counts) >= 28 and max(counts.values()) <= 20


def test_optimize_fewest_actions_and_cost_file(tmp_path, capsys):
    best = tmp_path / "best.json"
    code, _, err = _run(capsys, "decompose", str(DELIVERY), "--optimize", "-o", str(best))
    assert code == 0 and "optimum cost" in err
    data = json.loads(best.read_text())
    chosen = data["mission_decompositions"][0]
    actions = sum(len(data["tasks"][k]["decomposition"]) for k in chosen)
    mission = Mission.load(*find_mission_files(DELIVERY))
    fewest = min(sum(len(mission.task_graph.vertices[d].decomposition.path.actions) for d in md)
                 for md in mission.decomposition_space())
    assert actions == fewest == int(data["mission_decomposition_space"]["optimum"]["cost"])
    # make the robot fetching from the shelf expensive: the staff-loading alternative wins
    costs = tmp_path / "costs.json"
    costs.write_text(json.dumps({"actions": {"pick-item": 100}}))
    assert _run(capsys, "decompose", str(DELIVERY), "--optimize", "--costs", str(costs), "-o", str(best))[0] == 0
    data = json.loads(best.read_text())
    names = {a["name"] for k in data["mission_decompositions"][0] for a in data["tasks"][k]["decomposition"].values()}
    assert "pick-item" not in names and "request-loading" in names


def test_json_summary_and_quiet(tmp_path, capsys):
    code, out, err = _run(capsys, "decompose", str(DELIVERY), "-q", "--json-summary", "-o", str(tmp_path / "o.json"))
    assert code == 0 and err == ""
    summary = json.loads(out.strip().splitlines()[-1])
    assert summary["mission_decompositions"] == "8" and summary["task_instances"] == 12
    assert summary["constraints"]["EC"] > 0


def test_cpsat_only_options_with_exploratory_are_refused(tmp_path, capsys):
    code, _, err = _run(capsys, "decompose", str(DELIVERY), "--algorithm", "exploratory", "--optimize",
                        "-o", str(tmp_path / "o.json"))
    assert code == 2 and "--optimize needs the CP-SAT decomposer" in err
    assert not (tmp_path / "o.json").exists()


def test_output_goes_where_the_configuration_says(tmp_path, capsys):
    import shutil

    folder = tmp_path / "m"
    shutil.copytree(DELIVERY, folder, ignore=shutil.ignore_patterns("output"))
    assert _run(capsys, "decompose", str(folder), "-q")[0] == 0
    assert (folder / "output" / "mission.json").is_file()


def test_graph_writes_dot(tmp_path, capsys):
    out = tmp_path / "tg.dot"
    code, _, err = _run(capsys, "graph", str(DELIVERY), "--view", "task-graph", "-o", str(out))
    assert code == 0 and "graph: task-graph view written" in err
    text = out.read_text()
    assert text.startswith("digraph") and "AT1_1" in text


@pytest.mark.parametrize("args", [["decompose"], ["check", "a", "b"], ["count", "/no/such/folder"]])
def test_usage_errors_are_clean(capsys, args):
    code, _, err = _run(capsys, *args)
    assert code == 2 and "error:" in err and "Traceback" not in err


def test_world_option_reads_another_world(tmp_path, capsys):
    """``--world FILE`` replaces the configuration's world_db.path (the mission folder is left
    as it is): here a world where the fourth delivery is pending too."""
    world = tmp_path / "four-deliveries.xml"
    original = (DELIVERY / "knowledge" / "world_db.xml").read_text()
    world.write_text(original.replace("<is_collected>True</is_collected>\n        <is_delivered>True</is_delivered>",
                                      "<is_collected>False</is_collected>\n        <is_delivered>False</is_delivered>"))
    assert _run(capsys, "count", str(DELIVERY), "-q")[1].strip() == "8"
    code, out, _ = _run(capsys, "count", str(DELIVERY), "--world", str(world), "-q", "--json-summary")
    summary = json.loads(out.splitlines()[0])
    assert code == 0 and summary["mission_decompositions"] == "16" and summary["inputs"]["world"] == str(world)
    code, _, err = _run(capsys, "check", str(DELIVERY), "--world", str(tmp_path / "missing.xml"))
    assert code == 2 and f"{tmp_path / 'missing.xml'}: cannot read world knowledge file" in err
