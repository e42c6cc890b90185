"""Stamped forAll copies written from their source copy's entries (``copy_blocks.py``) give the
bytes of writing every task entry on its own: on the benchmark worlds (where the blocks must be
used), on the reference corpus, on random missions with repeated rooms, and where a rule of
``copy_blocks`` keeps a copy from being filled (a value in another sort, two patients that are
one, a value that is a constant of a path)."""
from __future__ import annotations

import dataclasses
import io
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

from mutrose_cp.output.copy_blocks import CopyBlocks
from mutrose_cp.output.entry_templates import EntryTemplates
from mutrose_cp.errors import MissionError
from mutrose_cp.pipeline.htn import ground_path
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.model.configuration import SemanticMapping
from mutrose_cp.model.task_graph import DecompositionVertex
from mutrose_cp.output.builder import OutputBuilder, OutputModel
from mutrose_cp.output.predicates import PredicatePrinter

from conftest import ROOT, require_reference
from missiongen import MissionSpec, load_mission, repeated_rooms

sys.path.insert(0, str(ROOT / "benchmarks"))
from generate import generate  # noqa: E402


def _builder(mission: Mission, printer: PredicatePrinter | None = None) -> OutputBuilder:
    tg = mission.task_graph
    builder = OutputBuilder(OutputModel(tg, mission.constraints, [], mission.domain, mission.config,
                                        mission.initial_state))
    if printer is not None:
        builder.printer = printer
    return builder


def _json(builder: OutputBuilder) -> str:
    out = io.StringIO()
    builder.write_json(out)
    return out.getvalue()


def _filled(builder: OutputBuilder) -> list[int]:
    """The first decomposition of each stamped copy filled from its source."""
    blocks = CopyBlocks(builder.m.tg, builder.decs, builder.key,
                        EntryTemplates(builder.m.domain, builder.printer, builder.printer.sorts))
    return [first for first in sorted(blocks.copies) if blocks.entries(first) is not None]


def _same_as_entry_by_entry(builder: OutputBuilder, monkeypatch: pytest.MonkeyPatch) -> str:
    """The JSON with the copies filled, checked against the JSON written entry by entry."""
    filled = _json(builder)
    with monkeypatch.context() as patch:
        patch.setattr(CopyBlocks, "entries", lambda self, first: None)
        assert filled == _json(builder)
    return filled


@pytest.mark.parametrize("family, n", [("vital-signs", 12), ("delivery", 9), ("pickup", 9)])
def test_benchmark_worlds_fill_their_copies(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, family: str, n: int) -> None:
    require_reference()
    builder = _builder(Mission.load(*generate(family, n, tmp_path)))
    _same_as_entry_by_entry(builder, monkeypatch)
    copies = [c for region in builder.m.tg.stamped_copies for c in region if c.start != c.source]
    assert copies and len(_filled(builder)) == len(copies)


def test_reference_corpus(monkeypatch: pytest.MonkeyPatch) -> None:
    reference = require_reference()
    for cfg in sorted((reference / "missions").glob("*/configuration/*.json")):
        folder = cfg.parent.parent
        monkeypatch.chdir(folder)
        _same_as_entry_by_entry(_builder(Mission.load(*find_mission_files(folder, cfg.name))), monkeypatch)


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(repeated_rooms())
def test_random_missions_with_repeated_rooms(spec: MissionSpec) -> None:
    try:
        mission = load_mission(spec)
        builder = _builder(mission)
        alone = _json(builder)
    except Exception:  # noqa: BLE001 - missions the pipeline refuses have no output to compare
        return
    with pytest.MonkeyPatch.context() as patch:
        patch.setattr(CopyBlocks, "entries", lambda self, first: None)
        assert _json(builder) == alone


def _vital_signs(tmp_path: Path, edit_world=None) -> Mission:
    """Vital signs at 6 rooms: rooms 0, 1, 2 and 5 are built, 3 and 4 stamped from room 0."""
    hddl, gm, cfg = generate("vital-signs", 6, tmp_path)
    if edit_world is not None:
        world = tmp_path / "vital-signs-6.xml"
        world.write_text(edit_world(world.read_text(encoding="utf-8")), encoding="utf-8")
    return Mission.load(hddl, gm, cfg)


def _copy_of(builder: OutputBuilder, room: str) -> int:
    """The first decomposition of the stamped copy of ``room``."""
    blocks = CopyBlocks(builder.m.tg, builder.decs, builder.key,
                        EntryTemplates(builder.m.domain, builder.printer, builder.printer.sorts))
    firsts = [f for f in blocks.copies if builder.decs[f].instance.location == room]
    assert len(firsts) == 1
    return firsts[0]


def test_a_patient_in_another_sort_is_written_entry_by_entry(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """An attribute mapping is chosen by the sorts of the values: a patient of a stamped room
    that also belongs to a sort with a mapping of its own prints differently from its source."""
    require_reference()
    mission = _vital_signs(tmp_path)
    state = mission.initial_state
    sorts = dict(state.sorts) | {"isolation": frozenset({"Patient9"})}  # in Room4
    sealed = SemanticMapping("attribute", "predicate", "available", ("isolation",), "world_db", "sealed", "Patient")
    config = dataclasses.replace(mission.config, semantic_mapping=(sealed, *mission.config.semantic_mapping))
    builder = _builder(mission, PredicatePrinter(mission.domain, config, dataclasses.replace(state, sorts=sorts)))
    text = _same_as_entry_by_entry(builder, monkeypatch)
    assert _copy_of(builder, "Room4") not in _filled(builder)
    assert _copy_of(builder, "Room3") in _filled(builder)
    assert '"Patient9.sealed"' in text and '"Patient10.sealed"' not in text


def test_two_patients_that_become_one_are_written_entry_by_entry(tmp_path: Path,
                                                                  monkeypatch: pytest.MonkeyPatch) -> None:
    """Equal values can print differently from distinct ones (two effects on one atom are one
    effect): a copy whose two patients are one name (Room3's, renamed here in its task
    instances) cannot be filled from a source with two patients."""
    require_reference()
    mission = _vital_signs(tmp_path)
    tg = mission.task_graph
    vertices = list(tg.vertices)
    for i, v in enumerate(vertices):
        if isinstance(v, DecompositionVertex) and v.instance.location == "Room3":
            inst = v.instance
            inst = dataclasses.replace(inst, parameters=tuple(
                dataclasses.replace(p, value="Patient7") if p.value == "Patient8" else p for p in inst.parameters))
            dec = dataclasses.replace(v.decomposition, instance=inst, predicates=ground_path(v.decomposition.path, inst.binding))
            vertices[i] = dataclasses.replace(v, decomposition=dec)
    mission.task_graph = dataclasses.replace(tg, vertices=tuple(vertices), stamped_copies=tg.stamped_copies)
    builder = _builder(mission)
    _same_as_entry_by_entry(builder, monkeypatch)
    assert _copy_of(builder, "Room3") not in _filled(builder)
    assert _copy_of(builder, "Room4") in _filled(builder)


def test_a_value_that_is_a_constant_of_a_path_is_written_entry_by_entry(tmp_path: Path,
                                                                         monkeypatch: pytest.MonkeyPatch) -> None:
    """A value equal to a constant a path names stays itself in the printed predicates: the room
    whose patient is that constant cannot be filled from another room's entries."""
    require_reference()
    hddl, gm, cfg = generate("vital-signs", 6, tmp_path)
    text = hddl.read_text(encoding="utf-8")
    edited = text.replace("\t(:predicates", "\t(:constants Patient9 - patient)\n\t(:predicates", 1)
    # patients without a supertype, so that the constant has the sorts of the other patients
    edited = edited.replace("(:types patient room - object)", "(:types patient room)", 1)
    # marking a patient as done unmarks Patient9 (in Room4): for Patient9 itself, the two
    # effects fall on one atom, and one effect is printed instead of two
    edited = edited.replace("\t\t\t(checked ?p)\n", "\t\t\t(checked ?p)\n\t\t\t(not (checked Patient9))\n", 1)
    assert edited.count("Patient9") == 2 and "(:types patient room)" in edited
    local = tmp_path / "domain.hddl"
    local.write_text(edited, encoding="utf-8")
    builder = _builder(Mission.load(local, gm, cfg))
    text = _same_as_entry_by_entry(builder, monkeypatch)
    assert _copy_of(builder, "Room4") not in _filled(builder)
    assert _copy_of(builder, "Room3") in _filled(builder)
    assert text.count('"not Patient9.checked"') > text.count('"Patient9.checked"') > 0


def test_a_value_named_like_a_variable_is_printed_alone(tmp_path: Path) -> None:
    """A world value starting with "?" reads as a variable to the printer, which refuses it when
    no mapping fits: the copy holding it is not filled from its source, and the output is refused
    as when every entry is written on its own."""
    require_reference()
    mission = _vital_signs(tmp_path, lambda w: w.replace("Patient9", "?Patient9"))
    builder = _builder(mission)
    assert builder.m.tg.stamped_copies
    with pytest.raises(MissionError, match=r"No Semantic Mapping .*\?Patient9"):
        _json(builder)
