"""The comparison rules of ``output_compare`` give the verdicts of the corpus's reference tool
(``compare_outputs.py`` beside the corpus, loaded here by path, never by the package) on the
corpus: each golden output against our own output and against edited copies of itself."""
from __future__ import annotations

import copy
import importlib.util
import json
import os
from pathlib import Path
from types import ModuleType
from typing import Callable

import pytest

from conftest import REFERENCE, require_reference
from mutrose_cp.cli.program import main
from mutrose_cp.io.config import load_configuration
from mutrose_cp.io.decomposition_output import load_decomposition_output
from mutrose_cp.compare.outputs import ASPECTS, OutputView, diff_outputs, natural_key, nearest

TOOL = REFERENCE.parent / "tools" / "compare_outputs.py"


def _tool() -> ModuleType:
    require_reference()
    if not TOOL.is_file():
        if os.environ.get("CI") == "true":
            pytest.fail(f"reference comparison tool not found at {TOOL}")
        pytest.skip(f"reference comparison tool not found at {TOOL}")
    spec = importlib.util.spec_from_file_location("reference_compare_outputs", TOOL)
    assert spec and spec.loader
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module


def _goldens() -> list[tuple[Path, Path, Path]]:
    """(mission, configuration, golden JSON output) for every JSON configuration of the corpus."""
    found = []
    for mission in sorted((REFERENCE / "missions").iterdir()) if REFERENCE.is_dir() else []:
        for cfg in sorted((mission / "configuration").glob("*.json")):
            golden = mission / load_configuration(cfg).output.file_path
            if golden.is_file() and golden.read_bytes().lstrip().startswith(b"{"):  # the tool reads JSON only
                found.append((mission, cfg, golden))
    return found


def _first(doc: dict, test: Callable[[dict], bool]) -> dict | None:
    return next((c for c in doc["constraints"] or [] if test(c)), None)


def _swap(c: dict | None) -> None:
    if c is not None:
        inst = c["task_instances"]
        inst["t0"], inst["t1"] = inst["t1"], inst["t0"]


def _rekeyed(doc: dict) -> None:
    """Every task key renumbered (t0 -> t1000, ...) and every list reversed: nothing the rules
    look at changes."""
    new = {key: f"t{1000 + int(key[1:])}" for key in doc["tasks"]}
    doc["tasks"] = {new[k]: t for k, t in reversed(list(doc["tasks"].items()))}
    for c in doc["constraints"] or []:
        c["task_instances"] = {slot: new.get(k, k) for slot, k in c["task_instances"].items()}
    doc["constraints"] = list(reversed(doc["constraints"] or []))
    doc["mission_decompositions"] = [[new.get(k, k) for k in reversed(md)]
                                     for md in reversed(doc["mission_decompositions"] or [])]


def _edit(doc: dict, how: str) -> None:
    tasks = doc["tasks"]
    first = next(iter(tasks.values()))
    match how:
        case "drop a decomposition":
            doc["mission_decompositions"] = doc["mission_decompositions"][:-1]
        case "add a decomposition":
            doc["mission_decompositions"] = [*doc["mission_decompositions"], sorted(tasks)[:1]]
        case "rename a task id":
            first["id"] += "9"
        case "rename a task":
            first["name"] += "-x"
        case "move a task":
            first["locations"] = "Elsewhere"
        case "drop a constraint":
            doc["constraints"] = doc["constraints"][1:] if doc["constraints"] else doc["constraints"]
        case "reverse a SEQ":
            _swap(_first(doc, lambda c: c["type"] == "SEQ"))
        case "reverse an EC":
            _swap(_first(doc, lambda c: c["type"] == "EC"))
        case "flip a group flag":
            c = _first(doc, lambda c: "group" in c)
            if c is not None:
                c["group"] = "False" if c["group"] == "True" else "True"
        case "rekey and reorder":
            _rekeyed(doc)


EDITS = ("drop a decomposition", "add a decomposition", "rename a task id", "rename a task", "move a task",
         "drop a constraint", "reverse a SEQ", "reverse an EC", "flip a group flag", "rekey and reorder")


def _tool_verdict(tool: ModuleType, expected: Path, actual: Path) -> tuple[list[bool], dict[str, int]]:
    """The tool's four results (task ids, task fields, constraints, decompositions) and how many
    difference lines it printed per aspect (it prints at most 40 of each kind)."""
    results, failures = tool.compare(str(expected), str(actual))
    lines = {a: sum(1 for f in failures if f.startswith(a + ":")) for a in ("task ids", "constraints",
                                                                             "mission decompositions")}
    lines["task fields"] = sum(1 for f in failures if f.startswith("task ") and " field " in f)
    return list(results), lines


def _our_verdict(expected: Path, actual: Path) -> tuple[list[bool], dict[str, int]]:
    d = diff_outputs(OutputView.of(load_decomposition_output(str(expected))),
                     OutputView.of(load_decomposition_output(str(actual))))
    capped = lambda *kinds: sum(min(len(k), 40) for k in kinds)  # noqa: E731
    lines = {"task ids": capped(d.missing_ids, d.unexpected_ids), "task fields": len(d.changed_fields),
             "constraints": capped(d.missing_constraints, d.unexpected_constraints),
             "mission decompositions": capped(d.missing_decompositions, d.unexpected_decompositions)}
    return [d.agrees(a) for a in ASPECTS], lines


@pytest.mark.parametrize("mission,config,golden", _goldens(), ids=lambda v: v.name)
def test_the_rules_give_the_reference_tools_verdicts_on_the_corpus(tmp_path, mission, config, golden):
    tool = _tool()
    ours = tmp_path / "ours.json"
    assert main(["decompose", str(mission), "--config", config.name, "--limit", "0", "-q", "-o", str(ours),
                 "--format", "json"]) == 0
    assert _tool_verdict(tool, golden, ours) == _our_verdict(golden, ours) == ([True] * 4, dict.fromkeys(ASPECTS, 0))
    doc = json.loads(golden.read_text(encoding="utf-8"))
    for how in EDITS:
        edited = copy.deepcopy(doc)
        _edit(edited, how)
        path = tmp_path / f"{how}.json"
        path.write_text(json.dumps(edited), encoding="utf-8")
        verdict = _tool_verdict(tool, golden, path)
        assert _our_verdict(golden, path) == verdict, how
        # the edits do what they say: every change is seen, except those the rules ignore
        changed = {aspect for aspect, agree in zip(ASPECTS, verdict[0]) if not agree}
        assert changed == _changes(doc, how) or (how == "rename a task id" and "task ids" in changed), how


def _changes(doc: dict, how: str) -> set[str]:
    """The aspects an edit of the golden changes (none for a renaming or a reordering, nor for
    a reversed EC: an unordered pair)."""
    has = {"drop a constraint": lambda c: True, "reverse a SEQ": lambda c: c["type"] == "SEQ",
           "flip a group flag": lambda c: "group" in c}
    if how in has:
        return {"constraints"} if _first(doc, has[how]) else set()
    return {"drop a decomposition": {"mission decompositions"}, "add a decomposition": {"mission decompositions"},
            "rename a task": {"task fields"}, "move a task": {"task fields"}}.get(how, set())


@pytest.mark.parametrize("mission", ["room-preparation", "object-picking-function"])
def test_an_xml_output_compares_equal_to_the_json_output_of_the_same_run(mission):
    folder = require_reference() / "missions" / mission
    xml, js = folder / "output" / "task_output.xml", folder / "output" / "task_output.json"
    d = diff_outputs(OutputView.of(load_decomposition_output(str(js))), OutputView.of(load_decomposition_output(str(xml))))
    assert d.agree, d


def test_a_fallback_reads_as_an_unordered_ec_with_both_flags_true(tmp_path):
    """The reference rule: the original writes a fallback constraint as an EC without flags."""
    def output(constraints: list[dict]) -> OutputView:
        path = tmp_path / "o.json"
        path.write_text(json.dumps({"tasks": {"t0": {"id": "A|1", "name": "a"}, "t1": {"id": "B|1", "name": "b"}},
                                    "constraints": constraints, "mission_decompositions": [["t0", "t1"]]}))
        return OutputView.of(load_decomposition_output(str(path)))

    fallback = output([{"type": "EC", "task_instances": {"t0": "t0", "t1": "t1"}}])
    reversed_fallback = output([{"type": "EC", "task_instances": {"t0": "t1", "t1": "t0"}}])
    plain_ec = output([{"type": "EC", "task_instances": {"t0": "t0", "t1": "t1"}, "group": "True", "divisible": "True"}])
    not_group = output([{"type": "EC", "task_instances": {"t0": "t0", "t1": "t1"}, "group": "False"}])
    seq = output([{"type": "SEQ", "task_instances": {"t0": "t0", "t1": "t1"}}])
    reversed_seq = output([{"type": "SEQ", "task_instances": {"t0": "t1", "t1": "t0"}}])
    assert diff_outputs(fallback, reversed_fallback).agree and diff_outputs(fallback, plain_ec).agree
    assert diff_outputs(fallback, not_group).missing_constraints == ("EC A|1 B|1 group=True divisible=True",)
    assert diff_outputs(seq, reversed_seq).missing_constraints == ("SEQ A|1 -> B|1",)


def test_ids_sort_as_people_read_them():
    assert sorted(["AT10_1|1", "AT2_1|2", "AT2_1|10", "AT2_1|1"], key=natural_key) == \
        ["AT2_1|1", "AT2_1|2", "AT2_1|10", "AT10_1|1"]


def test_nearest_names_the_tasks_where_two_decompositions_part():
    assert nearest(("A|1", "B|1", "C|2"), [("A|2", "B|2", "C|1"), ("A|1", "B|1", "C|1")]) == (("C|2",), ("C|1",))
    assert nearest(("A|1",), []) is None
