"""Components coupled through a few wide definitions are counted without enumeration
(solve/hubs.py): the count must equal the enumerated one, on generated missions and on the
coupled-deliveries family, whose count is known in closed form."""
from __future__ import annotations

import os
import sys
from pathlib import Path

import pytest
from unittest.mock import patch

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from conftest import require_reference
from missiongen import MissionSpec, load_mission, missions
from mutrose_cp.mission import Mission
from mutrose_cp.solve.cpsat import _block_solutions, split_components, _simple_choice, enumerate_with_cp_sat
from mutrose_cp.solve import tiny
from mutrose_cp.solve.boolean_model import TRUE, AndOf, BoolModel, Clause, Exactly, OrOf
from mutrose_cp.solve.hubs import count_by_hubs

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = int(os.environ.get("MUTROSE_HUB_EXAMPLES", "60"))


def _coupled(n: int, folder: Path) -> Mission:
    require_reference()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from generate import generate

    return Mission.load(*generate("coupled", n, folder))


def _check(mission: Mission, hub_min: int, max_hubs: int = 4) -> int:
    """Compare both counts on every component hubs can count; returns how many were compared."""
    if mission.task_graph.unique_branch or not mission.task_graph.tasks():
        return 0
    enc = mission.encoding()
    compared = 0
    for comp in split_components(enc):
        if len(comp.records) < 2 or _simple_choice(comp) is not None:
            continue
        counted = count_by_hubs(enc.model, comp.records,
                                lambda records, watched: _block_solutions(enc.model, records, watched), hub_min,
                                max_hubs)
        if counted is None:
            continue
        assert counted == enumerate_with_cp_sat(enc.model, comp, keep=False)[0]
        compared += 1
    return compared


@pytest.mark.parametrize("n", [5, 6, 8])  # below 5 the conflict is posted as pairwise clauses
def test_hub_count_equals_enumeration_on_coupled_deliveries(tmp_path, n):
    assert _check(_coupled(n, tmp_path), hub_min=2) == 1


@pytest.mark.parametrize("n", [9, 40])
def test_coupled_deliveries_counted_in_closed_form(tmp_path, n):
    """n parallel deliveries, each fetching in one of 3 ways and getting food in one of 3 ways,
    two of which set and clear the shared kitchen: 3^n (2^(n+1) - 1) (no mix of both)."""
    space = _coupled(n, tmp_path).decomposition_space(keep=False)
    assert space.count == 3**n * (2 ** (n + 1) - 1)


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(missions())
def test_hub_count_equals_enumeration_on_generated_missions(spec: MissionSpec):
    """Generated missions reach hubs only through wide parallel conflicts (a fact's value is a
    chain of two-literal steps, no wide definition), so most draws compare nothing; the coupled
    family and the hand-made models below cover the rest."""
    _check(load_mission(spec), hub_min=2, max_hubs=8)


@st.composite
def hub_models(draw) -> tuple[BoolModel, list]:
    """Blocks of choices (an exactly-one, sometimes a clause inside the block), OR and AND hubs
    over literals of several blocks (either sign), and clauses over the hubs."""
    bm = BoolModel()
    records: list = []
    literals: list[int] = []
    for b in range(draw(st.integers(1, 4))):
        choices = [bm.new_bool(f"b{b}c{i}") for i in range(draw(st.integers(2 if b == 0 else 1, 3)))]
        records.append(Exactly(tuple(choices), TRUE))
        if draw(st.booleans()):
            records.append(Clause((-choices[0], choices[-1])))
        literals += choices
    hubs = []
    for h in range(draw(st.integers(1, 3))):
        over = draw(st.lists(st.sampled_from(literals), min_size=2, max_size=5, unique=True))
        signed = tuple(v if draw(st.booleans()) else -v for v in over)
        target = bm.new_bool(f"hub{h}")
        records.append((OrOf if draw(st.booleans()) else AndOf)(signed, target))
        hubs.append(target)
    for _ in range(draw(st.integers(0, 2))):
        over = draw(st.lists(st.sampled_from(hubs), min_size=1, max_size=2, unique=True))
        records.append(Clause(tuple(v if draw(st.booleans()) else -v for v in over)))
    return bm, records


@settings(max_examples=300, deadline=None)
@given(hub_models())
def test_hub_count_equals_brute_force_on_hand_made_models(model) -> None:
    bm, records = model
    with patch.object(tiny, "MAX_WORK", 10**9):
        expected = tiny.enumerate_tiny(bm, records, [])
        counted = count_by_hubs(bm, records, lambda rs, watched: tiny.enumerate_tiny(bm, rs, watched)[1],
                                hub_min=2)
    assert expected is not None and counted == expected[0]


def test_optimum_of_a_coupled_component_without_its_list(tmp_path, monkeypatch):
    """--optimize leaves a large coupled component unlisted and lets CP-SAT find its best
    solution: the same least cost as when every solution is listed and compared (the layered
    solver, which would take the component first, is left out here)."""
    from mutrose_cp.solve import cpsat, decompose
    from mutrose_cp.solve.decompose import DecompositionRequest

    monkeypatch.setattr(cpsat, "layered_space", lambda *args: None)

    mission = _coupled(9, tmp_path)
    listed = mission.decompose(DecompositionRequest(optimize=True))
    assert all(c.solutions is not None for c in listed.space.components)
    monkeypatch.setattr(decompose, "OPTIMIZE_LIST_LIMIT", 10)
    unlisted = _coupled(9, tmp_path / "again").decompose(DecompositionRequest(optimize=True))
    assert any(c.solutions is None for c in unlisted.space.components)
    assert unlisted.total == listed.total
    assert unlisted.optimum[1] == listed.optimum[1]
