"""Tiny components are enumerated in Python (solve/tiny.py) instead of by CP-SAT: both must give
the same number of solutions and the same solutions, on every component of generated missions
(numeric effects and comparisons included) and of the reference corpus."""
from __future__ import annotations

import os

from hypothesis import HealthCheck, given, settings

from conftest import require_reference
from missiongen import MissionSpec, load_mission, missions
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.solve.boolean_model import Compare, ValueAfter
from mutrose_cp.solve.cpsat import split_components, _simple_choice, enumerate_with_cp_sat
from mutrose_cp.solve.tiny import enumerate_tiny, free_variables

EXAMPLES = int(os.environ.get("MUTROSE_TINY_EXAMPLES", "60"))


def _compare(mission: Mission) -> tuple[int, int]:
    """Check every component both ways; returns (components checked, of which numeric)."""
    if mission.task_graph.unique_branch or not mission.task_graph.tasks():
        return 0, 0
    enc = mission.encoding()
    checked = numeric = 0
    for comp in split_components(enc):
        if len(comp.records) < 2 or _simple_choice(comp) is not None:
            continue
        tiny = enumerate_tiny(enc.model, comp.records, comp.choice_vars)
        if tiny is None:
            continue
        count, solutions = enumerate_with_cp_sat(enc.model, comp)
        assert tiny[0] == count
        assert sorted(tiny[1], key=sorted) == sorted(solutions or [], key=sorted)
        checked += 1
        numeric += any(isinstance(r, (ValueAfter, Compare)) for r in comp.records)
    return checked, numeric


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(missions())
def test_tiny_enumeration_agrees_with_cp_sat_on_generated_missions(spec: MissionSpec):
    _compare(load_mission(spec))


def test_tiny_enumeration_agrees_with_cp_sat_on_the_reference_corpus():
    root = require_reference() / "missions"
    checked = 0
    for mission in sorted(root.iterdir()):
        for cfg in sorted((mission / "configuration").glob("*")):
            checked += _compare(Mission.load(*find_mission_files(mission, cfg.name)))[0]
    assert checked >= 8  # the components the decomposer now enumerates without CP-SAT


def test_numeric_components_are_covered():
    """The comparison above also meets numeric records (values after writers, comparisons)."""
    from hypothesis import Phase, seed

    seen = []

    @seed(7)
    @settings(max_examples=150, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(missions())
    def draw(spec: MissionSpec) -> None:
        seen.append(_compare(load_mission(spec)))

    draw()
    assert sum(c for c, _ in seen) >= 50
    assert sum(n for _, n in seen) >= 3, seen


def test_free_variables_are_those_no_record_defines():
    from mutrose_cp.solve.boolean_model import AndOf, BoolModel, Clause, Exactly, TRUE

    bm = BoolModel()
    x, y = bm.new_bool("x"), bm.new_bool("y")
    both = bm.new_bool("both")
    records = [Exactly((x, y), TRUE), AndOf((x, y), both), Clause((-both,))]
    assert free_variables(records) == [x, y]
    count, solutions = enumerate_tiny(bm, records, [x, y])
    assert count == 2 and sorted(solutions, key=sorted) == [frozenset({x}), frozenset({y})]
    assert free_variables([Clause((both,)), AndOf((x, y), both)]) is None  # used before defined
