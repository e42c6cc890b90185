"""Missions whose tasks share state in a sequence: the layered solver (solve/layered.py), CP-SAT
enumeration and the exploratory algorithm give the same valid mission decompositions, the
validator accepts what the layered solver lists, and the output holds the layered graph.

Missions: the ``coupled-sequence`` benchmark family (n GetFood tasks in one ``;`` sequence that
mark the kitchen busy, free it, or need it free; the count follows ``free' = 2 free + busy``,
``busy' = free``) and the generated long sequences of ``missiongen`` (tasks that set, unset and
require one room predicate)."""
from __future__ import annotations

import contextlib
import io
import json
import math
import sys
import tempfile
from collections import Counter
from pathlib import Path
from typing import Iterator
from unittest.mock import patch

import pytest
from hypothesis import HealthCheck, Phase, given, seed, settings

from conftest import ROOT, require_reference
from missiongen import MissionSpec, load_mission, long_sequences
from test_layered import written_paths
from mutrose_cp.cli.program import main
from mutrose_cp.errors import NoDecompositionError
from mutrose_cp.io.decomposition_output import load_decomposition_output
from mutrose_cp.mission import Mission
from mutrose_cp.solve import cpsat
from mutrose_cp.solve.decompose import DecompositionRequest
from mutrose_cp.solve.optimize import CostModel, least_cost
from mutrose_cp.validate import validate

PATHS = ("layered", "layered-listed", "cpsat")


@contextlib.contextmanager
def solved_by(path: str) -> Iterator[None]:
    """Components solved by one path: ``layered`` (lazily, from the layers), ``layered-listed``
    (listed from the layers), ``cpsat`` (CP-SAT enumeration); never by tiny enumeration."""
    with contextlib.ExitStack() as stack:
        stack.enter_context(patch.object(cpsat, "enumerate_tiny", lambda *args: None))
        if path == "layered":
            stack.enter_context(patch.object(cpsat, "LAYERED_LIST_LIMIT", 0))
        elif path == "cpsat":
            stack.enter_context(patch.object(cpsat, "layered_space", lambda *args: None))
        yield


def _sequence_files(n: int, folder: Path) -> tuple[Path, Path, Path]:
    require_reference()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from generate import generate

    return generate("coupled-sequence", n, folder)


def _sequence_count(n: int) -> int:
    free, busy = 1, 0
    for _ in range(n):
        free, busy = 2 * free + busy, free
    return free + busy


def _decompositions(files: tuple[Path, Path, Path], path: str) -> tuple[list[frozenset[int]], int, bool]:
    """(listed decompositions, count, whether some component was solved as layers)."""
    mission = Mission.load(*files)
    with solved_by(path):
        space = mission.decomposition_space()
        listed = [frozenset(d) for d in space]
    return listed, space.count, any(c.layers is not None for c in space.components)


@pytest.mark.parametrize("n", [3, 5])
def test_sequence_family_every_path_agrees(tmp_path, n):
    files = _sequence_files(n, tmp_path)
    explored = [frozenset(d) for d in Mission.load(*files).exploratory()]
    assert len(explored) == _sequence_count(n)
    results = {path: _decompositions(files, path) for path in PATHS}
    for path, (listed, count, layered) in results.items():
        assert layered == (path != "cpsat"), path
        assert count == len(listed) == len(explored), path
        assert Counter(listed) == Counter(explored), path
    # one choice per task, blocks in mission order: the lazy listing is the canonical order
    assert results["layered"][0] == results["cpsat"][0] == results["layered-listed"][0]


def test_sequence_family_counted_and_optimised_in_closed_form(tmp_path):
    """The least cost is every task's two-action method (the plain pickup keeps the kitchen
    free); with marking and freeing made cheaper, every task marks or frees, and the first
    such decomposition listed alternates them (a mark before a free)."""
    n = 60
    mission = Mission.load(*_sequence_files(n, tmp_path))
    result = mission.decompose(DecompositionRequest(optimize=True))
    assert result.total == _sequence_count(n)
    assert result.space is not None and result.space.components[0].layers is not None
    assert result.optimum is not None and result.optimum[1] == 2 * n
    cheap = CostModel(actions={"mark-busy": -5, "mark-free": -5})
    chosen, cost = least_cost(result.space, cheap.decomposition_costs(mission.task_graph))
    assert cost == n * (2 - 5)
    names = [mission.task_graph.vertices[d].decomposition.path.actions[-1].name for d in chosen]
    assert names == ["mark-busy", "mark-free"] * (n // 2)


def test_sequence_family_least_cost_agrees_with_cp_sat(tmp_path):
    files = _sequence_files(6, tmp_path)
    costs = CostModel(actions={"mark-busy": 0, "wait-for-food": 3, "mark-free": -1})
    found = {}
    for path in ("layered", "cpsat"):
        mission = Mission.load(*files)
        with solved_by(path):
            found[path] = least_cost(mission.decomposition_space(), costs.decomposition_costs(mission.task_graph))[1]
    mission = Mission.load(*files)
    by_decomposition = costs.decomposition_costs(mission.task_graph)
    assert found["layered"] == found["cpsat"] == min(sum(by_decomposition[d] for d in x) for x in mission.exploratory())


def test_sequence_family_samples_uniformly(tmp_path):
    """Mission-level samples of a lazily listed component: chi-square below its 0.999 quantile."""
    mission = Mission.load(*_sequence_files(3, tmp_path))
    with solved_by("layered"):
        space = mission.decomposition_space()
    assert space.components[0].solutions is None and space.components[0].layers is not None
    draws = 300 * space.count
    seen = Counter(frozenset(d) for d in space.sample(draws, seed=7))
    assert len(seen) == space.count == 17
    expected = draws / space.count
    chi2 = sum((k - expected) ** 2 / expected for k in seen.values())
    df = space.count - 1
    assert chi2 < df * (1 - 2 / (9 * df) + 3.09 * math.sqrt(2 / (9 * df))) ** 3
    assert space.sample(5, seed=7) == space.sample(5, seed=7)


def test_sequence_family_output_holds_the_layered_graph(tmp_path):
    """``decompose`` writes one block per task with the kitchen's state between them; the paths
    through the written graph are the count, and every listed decomposition validates."""
    n = 19
    files = _sequence_files(n, tmp_path)
    out = tmp_path / "out.json"
    with contextlib.redirect_stderr(io.StringIO()):
        assert main(["decompose", *map(str, files), "-q", "--limit", "50", "-o", str(out)]) == 0
    section = json.loads(out.read_text())["mission_decomposition_space"]
    (component,) = section["components"]
    assert "alternatives" not in component and len(component["blocks"]) == n
    assert component["count"] == section["count"] == str(_sequence_count(n))
    assert written_paths(component) == _sequence_count(n)
    assert component["states"][1] == [["busy(Kitchen) after AT1_1|3=0"], ["busy(Kitchen) after AT1_1|3=1"]]
    mission = Mission.load(*files)
    report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state,
                      load_decomposition_output(str(out)))
    assert report.valid and report.checked == 50


def test_parallel_coupled_family_is_layered_too(tmp_path):
    """The parallel deliveries that set and clear the kitchen (the ``coupled`` family): their
    conflict passes from delivery to delivery as a chain, so the coupled component of
    2^(n+1) - 1 solutions is written as n blocks; every path lists the exploratory result."""
    require_reference()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from generate import generate

    files = generate("coupled", 4, tmp_path)
    explored = Counter(frozenset(d) for d in Mission.load(*files).exploratory())
    for path in PATHS:
        listed, count, layered = _decompositions(files, path)
        assert layered == (path != "cpsat") and count == 3**4 * (2**5 - 1), path
        assert Counter(listed) == explored, path
    out = tmp_path / "out.json"
    with contextlib.redirect_stderr(io.StringIO()):
        assert main(["decompose", *map(str, generate("coupled", 10, tmp_path / "ten")), "-q", "-o", str(out)]) == 0
    components = json.loads(out.read_text())["mission_decomposition_space"]["components"]
    (coupled,) = [c for c in components if "blocks" in c]
    assert coupled["count"] == str(2**11 - 1) == str(written_paths(coupled)) and len(coupled["blocks"]) == 10


# ---------------------------------------------------------------------------------------------
# Generated long sequences


def _agree_on(spec: MissionSpec) -> bool:
    """Every path lists the exploratory algorithm's decompositions; whether layers were used."""
    try:
        explored = Counter(frozenset(d) for d in load_mission(spec).exploratory())
    except NoDecompositionError:
        explored = Counter()
    layered = False
    for path in PATHS:
        mission = load_mission(spec)
        with solved_by(path):
            space = mission.decomposition_space()
            listed = Counter(frozenset(d) for d in space) if space.count else Counter()
        assert space.count == sum(explored.values()), (path, spec.dump())
        assert listed == explored, (path, spec.dump())
        layered |= any(c.layers is not None for c in space.components)
    return layered


@settings(max_examples=20, deadline=None, suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(long_sequences())
def test_generated_sequences_every_path_agrees(spec: MissionSpec):
    _agree_on(spec)


def test_generated_sequences_are_mostly_layered():
    """The long sequences really take the layered path (with tiny enumeration off): most
    draws of a fixed seed have a component solved as layers."""
    layered = []

    @seed(5)
    @settings(max_examples=15, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(long_sequences())
    def draw(spec: MissionSpec) -> None:
        layered.append(_agree_on(spec))

    draw()
    assert sum(layered) >= 0.6 * len(layered), layered


@settings(max_examples=8, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(long_sequences())
def test_generated_sequences_listed_from_layers_validate(spec: MissionSpec):
    with tempfile.TemporaryDirectory(prefix="mutrose-sequence-") as folder:
        files = spec.write(folder)
        out = Path(folder) / "out.json"
        with solved_by("layered"), contextlib.redirect_stderr(io.StringIO()):
            status = main(["decompose", *map(str, files), "-q", "--limit", "0", "-o", str(out)])
        assert status in (0, 3)
        if status == 0:
            mission = Mission.load(*files)
            report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state,
                              load_decomposition_output(str(out)))
            assert report.valid, "\n".join(map(str, report.violations[:10])) + "\n" + spec.dump()
