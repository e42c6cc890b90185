"""``examples/allocation.py``: decomposition, robot allocation and schedule chosen together.

The example's ``main`` runs in-process; every property of the returned solution is checked
against the mission (robot numbers, capabilities, execution constraints, precedences, no
overlap) rather than trusted, and the LP bound must not exceed the makespan found.
"""
from __future__ import annotations

import importlib.util
import json
import sys
from pathlib import Path

import pytest

from mutrose_cp.api import Mission, find_mission_files

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"


@pytest.fixture(scope="module")
def allocation():
    spec = importlib.util.spec_from_file_location("allocation_example", EXAMPLES / "allocation.py")
    module = importlib.util.module_from_spec(spec)
    sys.modules[spec.name] = module  # dataclasses look their module up while being defined
    old = sys.dont_write_bytecode
    sys.dont_write_bytecode = True  # keep examples/ free of __pycache__
    try:
        spec.loader.exec_module(module)
    finally:
        sys.dont_write_bytecode = old
    return module


def reference_space(folder: Path) -> set[frozenset[str]]:
    mission = Mission.load(*find_mission_files(folder))
    tg = mission.task_graph
    return {frozenset(tg.vertices[d].content for d in sol) for sol in mission.decomposition_space()}


def check_solution(res) -> None:
    """Every rule of the allocation, verified on the returned solution."""
    dm = res.dm
    assert res.status in ("OPTIMAL", "FEASIBLE")
    assert res.objective is not None and res.objective > 0
    chosen = set(res.chosen)
    assert frozenset(chosen) in reference_space(Path(res.mission))  # a valid mission decomposition
    robots = {r.name: r for r in res.robots}
    for d in chosen:
        info = dm.decompositions_info[d]
        team = res.assignment[d]
        rn = info.robot_number
        assert len(set(team)) == len(team)
        if rn.fixed:
            assert len(team) == rn.min, d
        else:
            assert rn.min <= len(team) <= rn.max, d
        for r in team:
            assert info.capabilities <= robots[r].capabilities, (d, r)
        assert res.end[d] == res.start[d] + res.durations[d]
        assert res.end[d] <= res.objective
    assert max(res.end.values()) == res.objective
    for c in dm.constraints:
        if c.first not in chosen or c.second not in chosen:
            continue
        if c.kind in ("SEQ", "FB"):
            assert res.end[c.first] <= res.start[c.second], c
        elif c.kind == "EC" and not c.group:
            assert len(res.assignment[c.first]) == 1 and res.assignment[c.first] == res.assignment[c.second], c
        elif c.kind == "EC" and not c.divisible:
            assert set(res.assignment[c.first]) == set(res.assignment[c.second]), c
    for r in robots:  # a robot does one thing at a time
        busy = sorted((res.start[d], res.end[d]) for d in chosen if r in res.assignment[d])
        for (s1, e1), (s2, e2) in zip(busy, busy[1:]):
            assert e1 <= s2, (r, busy)
    # bounds: CP-SAT's and the LP relaxation's are lower bounds of the makespan found
    assert res.cp_bound <= res.objective + 1e-9
    assert res.lp_bound == res.lp_bound  # not NaN: Clarabel solved the LP
    assert 0 < res.lp_bound <= res.objective + 1e-6
    assert res.lp_bound_int <= res.objective


def test_default_example(allocation, capsys) -> None:
    res = allocation.main(["--time-limit", "5"])
    check_solution(res)
    assert res.mission.endswith("item-delivery")
    assert res.status == "OPTIMAL"  # small: solved to optimality well within the limit
    out = capsys.readouterr().out
    assert "CP-SAT objective (makespan):" in out and "LP bound (Clarabel):" in out
    # deterministic: the same run gives the same decomposition, allocation and schedule
    again = allocation.main(["--time-limit", "5"])
    assert (again.objective, again.chosen, again.assignment, again.start) == \
           (res.objective, res.chosen, res.assignment, res.start)


def test_team_tasks_and_fallbacks(allocation) -> None:
    """Hospital disinfection: RobotNumber ranges ([2,3] spray/fog teams), FB and Group=False."""
    res = allocation.main([str(EXAMPLES / "hospital-disinfection"), "--robots", "4", "--time-limit", "5"])
    check_solution(res)


def test_fleet_capabilities_drive_the_decomposition(allocation, tmp_path) -> None:
    """Without a robot that can both pick and talk, delivery 1 (to the staffed WardA, where only
    hand-to-person is valid) cannot be done by one robot fetching it itself (G8: same robot for
    FetchItem and HandOver), so the staff-loading alternative G11 is chosen for it."""
    fleet = tmp_path / "fleet.json"
    fleet.write_text(json.dumps({"robots": {"picker": ["navigation", "manipulation"],
                                            "talker": ["navigation", "communication"]},
                                 "durations": {"navigate": 1}}))
    res = allocation.main(["--fleet", str(fleet), "--time-limit", "5"])
    check_solution(res)
    assert "AT3_1|1" in res.chosen and "AT1_1|1" not in res.chosen
    assert res.durations["AT1_2|1"] == 1 + 2  # navigate overridden, pick-item from the table


def test_unit_durations(allocation) -> None:
    res = allocation.main(["--durations", "unit", "--robots", "2", "--time-limit", "5"])
    check_solution(res)
    assert all(res.durations[d] == len(res.dm.decompositions_info[d].actions) for d in res.chosen)


def test_scaled_copy(allocation, tmp_path) -> None:
    folder = allocation.make_item_delivery_copy(5, tmp_path)
    assert len(reference_space(folder)) == 2 ** 5
    res = allocation.solve(folder, robots=3, time_limit=5)
    check_solution(res)
