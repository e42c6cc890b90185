"""Task entries formatted once per template (``entry_templates.py``) give exactly the bytes of
formatting each entry on its own (``OutputBuilder.task_entry`` through ``boost_json``): on every
reference mission, on scaled worlds with thousands of identical instances, on random missions,
and where a value's sorts change which attribute mapping prints it."""
from __future__ import annotations

import dataclasses
import shutil
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from mutrose_cp.output.entry_templates import EntryTemplates
from mutrose_cp.errors import MissionError
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.model.configuration import SemanticMapping
from mutrose_cp.output.builder import OutputBuilder, OutputModel
from mutrose_cp.output.predicates import PredicatePrinter
from mutrose_cp.output.boost_json import boost_json

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(Path(__file__).resolve().parent))
from missiongen import load_mission, missions  # noqa: E402

sys.path.insert(0, str(ROOT / "benchmarks"))
import generate  # noqa: E402


def _entries(mission: Mission, printer: PredicatePrinter | None = None) -> tuple[list[str], list[str], EntryTemplates]:
    """Every task entry formatted alone and through templates."""
    builder = OutputBuilder(OutputModel(mission.task_graph, [], [], mission.domain, mission.config,
                                        mission.initial_state))
    if printer is not None:
        builder.printer = printer
    templates = EntryTemplates(mission.domain, builder.printer, builder.printer.sorts)
    alone = [boost_json(builder.task_entry(d.decomposition, d.group, d.divisible), 8) for d in builder.decs]
    stamped = [templates.entry(d.decomposition, d.group, d.divisible) for d in builder.decs]
    return alone, stamped, templates


def _reference_missions(reference: Path) -> list[tuple[Path, str | None]]:
    cases = []
    for folder in sorted(p for p in (reference / "missions").iterdir() if p.is_dir()):
        configs = sorted((folder / "configuration").glob("*.json"))
        cases += [(folder, c.name if len(configs) > 1 else None) for c in configs]
    return cases


def test_every_reference_mission(reference):
    for folder, config in _reference_missions(reference):
        mission = Mission.load(*find_mission_files(folder, config))
        alone, stamped, templates = _entries(mission)
        assert stamped == alone, folder
        assert None not in templates._predicates.values(), folder  # every template passed its self-check


@pytest.mark.parametrize("family, n", [("vital-signs", 40), ("delivery", 12), ("pickup", 12)])
def test_scaled_worlds_share_templates(reference, tmp_path, family, n):
    """Many instances of one goal-model task: far fewer templates than entries, same bytes."""
    hddl, gm, config = generate.generate(family, n, tmp_path)
    mission = Mission.load(hddl, gm, config)
    alone, stamped, templates = _entries(mission)
    assert stamped == alone
    used = [t for t in templates._predicates.values() if t is not None]
    assert used and len(templates._predicates) * 4 < len(alone)


def test_a_value_in_another_sort_gets_its_own_template(reference):
    """An attribute mapping is chosen by the sorts of the values: a room that also belongs to a
    sort with a mapping of its own prints differently, so it cannot share the others' template."""
    mission = Mission.load(*find_mission_files(ROOT / "examples" / "hospital-disinfection"))
    state = mission.initial_state
    sorts = dict(state.sorts) | {"isolation": frozenset({"Room102"})}
    lab = SemanticMapping("attribute", "predicate", "disinfected", ("isolation",), "world_db", "sealed_off", "Room")
    config = dataclasses.replace(mission.config, semantic_mapping=(lab, *mission.config.semantic_mapping))
    printer = PredicatePrinter(mission.domain, config, dataclasses.replace(state, sorts=sorts))
    alone, stamped, _ = _entries(mission, printer)
    assert stamped == alone
    assert any('"Room102.sealed_off"' in e for e in alone)
    assert not any('"Room101.sealed_off"' in e for e in alone)


@settings(max_examples=40, deadline=None, suppress_health_check=[HealthCheck.too_slow])
@given(missions())
def test_random_missions(spec):
    mission = load_mission(spec)
    try:
        mission.task_graph
    except Exception:  # noqa: BLE001 - missions the pipeline refuses have no output to compare
        return
    alone, stamped, _ = _entries(mission)
    assert stamped == alone


def test_a_value_that_is_a_constant_of_the_path(tmp_path):
    """A value equal to a constant the path names is kept as itself: for that room the two
    effects fall on one atom (``cleared Room102`` set, then cleared), for the others they do not."""
    folder = tmp_path / "mission"
    shutil.copytree(ROOT / "examples" / "hospital-disinfection", folder)
    hddl = next((folder / "hddl").glob("*.hddl"))
    text = hddl.read_text()
    # room without a supertype, so that the constant has the sorts of the other rooms
    text = text.replace("        room - object\n        UVRobot SprayRobot ServiceRobot - robot\n",
                        "        UVRobot SprayRobot ServiceRobot - robot\n        room\n", 1)
    text = text.replace("    (:predicates", "    (:constants Room102 - room)\n\n    (:predicates", 1)
    text = text.replace("            (cleared ?rm)\n", "            (cleared ?rm)\n            (not (cleared Room102))\n", 1)
    hddl.write_text(text)
    mission = Mission.load(*find_mission_files(folder))
    alone, stamped, _ = _entries(mission)
    assert stamped == alone
    clear = [e for e in alone if '"name": "ClearRoom"' in e]
    room102 = [e for e in clear if '"?rm": "Room102"' in e]
    assert len(room102) == 1 and len(clear) > 1
    assert all(e.count(".is_cleared") == 2 for e in clear if e not in room102)
    assert room102[0].count(".is_cleared") == 1


def test_a_value_named_like_a_variable_is_printed_alone(tmp_path):
    """A world value starting with "?" reads as a variable to the printer, which refuses it when
    no mapping fits: that instance is not filled from the others' template."""
    folder = tmp_path / "mission"
    shutil.copytree(ROOT / "examples" / "hospital-disinfection", folder)
    world = next((folder / "knowledge").glob("*.xml"))
    world.write_text(world.read_text().replace("<name>Room104</name>", "<name>?Room104</name>"))
    mission = Mission.load(*find_mission_files(folder))
    builder = OutputBuilder(OutputModel(mission.task_graph, [], [], mission.domain, mission.config,
                                        mission.initial_state))
    templates = EntryTemplates(mission.domain, builder.printer, builder.printer.sorts)
    for d in builder.decs:
        try:
            alone = boost_json(builder.task_entry(d.decomposition, d.group, d.divisible), 8)
        except MissionError as err:
            with pytest.raises(MissionError, match="No Semantic Mapping"):
                templates.entry(d.decomposition, d.group, d.divisible)
            assert "?Room104" in str(err)
        else:
            assert templates.entry(d.decomposition, d.group, d.divisible) == alone
