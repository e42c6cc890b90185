"""The exploratory order (:mod:`mutrose_cp.solve.listing_order`): the CP-SAT decomposer's
listing sorted by :class:`ExploratoryOrder` is the exploratory algorithm's listing, in its order,
on every reference mission and on generated missions (which the ``mutrose`` drop-in relies on:
its ``ihtn_N.json`` and ``mission_decompositions[N]`` are the original's)."""
from __future__ import annotations

import os
import tempfile
from pathlib import Path

import pytest
from hypothesis import HealthCheck, given, settings

import missiongen
from conftest import require_reference
from test_conformance import _cases
from mutrose_cp.errors import NoDecompositionError
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.solve.listing_order import ExploratoryOrder

EXAMPLES = int(os.environ.get("MUTROSE_DIFF_EXAMPLES", "120"))


def _both_in_order(mission: Mission) -> tuple[list[list[int]], list[list[int]]]:
    try:
        explored = [sorted(md) for md in mission.exploratory()]
    except NoDecompositionError:
        explored = []
    order = ExploratoryOrder(mission.task_graph)
    listed = [sorted(md) for md in sorted((list(md) for md in mission.decomposition_space()), key=order.key)]
    return explored, listed


@pytest.mark.parametrize(("folder", "config"), _cases("missions"))
def test_sorted_listing_is_the_exploratory_order_on_the_corpus(folder, config, monkeypatch):
    require_reference()
    monkeypatch.chdir(folder)
    explored, listed = _both_in_order(Mission.load(*find_mission_files(folder, config.name)))
    assert listed == explored


@settings(max_examples=EXAMPLES, deadline=None, database=None,
          suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
@given(missiongen.missions())
def test_sorted_listing_is_the_exploratory_order_on_generated_missions(spec):
    with tempfile.TemporaryDirectory(prefix="mutrose-order-") as d:
        mission = Mission.load(*spec.write(Path(d)))
        explored, listed = _both_in_order(mission)
        assert listed == explored, spec.dump()


def test_an_or_choice_is_more_significant_than_what_precedes_it():
    """Three rooms, each an OR of two tasks: the exploratory walk concatenates each OR's
    alternatives, so the last room's choice varies slowest, where the CP-SAT listing varies it
    fastest.  Sorted, the CP-SAT listing follows the walk."""
    with tempfile.TemporaryDirectory(prefix="mutrose-order-") as d:
        mission = Mission.load(*missiongen.or_choices_mission(rooms=3, alternatives=2).write(Path(d)))
        explored, listed = _both_in_order(mission)
        assert len(explored) == 8 and listed == explored
        assert [sorted(md) for md in mission.decomposition_space()] != explored  # the sort matters
