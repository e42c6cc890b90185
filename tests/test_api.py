"""The embedding API: ``DecompositionModel`` is the whole decomposition space as one CP-SAT model.

Its solutions, projected on the decomposition literals, must be exactly the valid mission
decompositions that ``mission.decomposition_space()`` lists (the component-wise solver), and
user constraints added to ``model`` must act on that space.
"""
from __future__ import annotations

from pathlib import Path

import pytest
from ortools.sat.python import cp_model

from mutrose_cp.api import DecompositionModel, Mission, find_mission_files

ROOT = Path(__file__).resolve().parent.parent
ITEM_DELIVERY = ROOT / "examples" / "item-delivery"
HOSPITAL = ROOT / "examples" / "hospital-disinfection"


def load(folder: Path) -> Mission:
    return Mission.load(*find_mission_files(folder))


class _Collect(cp_model.CpSolverSolutionCallback):
    def __init__(self, dm: DecompositionModel) -> None:
        super().__init__()
        self.dm = dm
        self.solutions: list[frozenset[str]] = []
        self.or_consistent = True

    def on_solution_callback(self) -> None:
        chosen = frozenset(d for d, lit in self.dm.decomposition.items() if self.BooleanValue(lit))
        self.solutions.append(chosen)
        # a task is active iff exactly one of its decompositions is chosen
        for t, lit in self.dm.task.items():
            n = sum(1 for d in chosen if self.dm.decompositions_info[d].task == t)
            if n != (1 if self.BooleanValue(lit) else 0):
                self.or_consistent = False


def enumerate_all(dm: DecompositionModel) -> _Collect:
    solver = cp_model.CpSolver()
    solver.parameters.enumerate_all_solutions = True
    solver.parameters.num_workers = 1
    cb = _Collect(dm)
    status = solver.Solve(dm.model, cb)
    assert status in (cp_model.OPTIMAL, cp_model.INFEASIBLE)
    return cb


def reference_space(mission: Mission) -> set[frozenset[str]]:
    tg = mission.task_graph
    return {frozenset(tg.vertices[d].content for d in sol) for sol in mission.decomposition_space()}


@pytest.fixture(scope="module")
def delivery() -> Mission:
    return load(ITEM_DELIVERY)


@pytest.mark.parametrize("folder, count", [(ITEM_DELIVERY, 8), (HOSPITAL, 36)], ids=["item-delivery", "hospital"])
def test_enumeration_matches_decomposition_space(folder: Path, count: int) -> None:
    mission = load(folder)
    dm = mission.decomposition_model()
    cb = enumerate_all(dm)
    ref = reference_space(mission)
    assert len(ref) == count
    assert len(cb.solutions) == len(set(cb.solutions)) == count  # one solution per decomposition
    assert set(cb.solutions) == ref
    assert cb.or_consistent


def test_forbidding_a_decomposition_reduces_the_count(delivery: Mission) -> None:
    ref = reference_space(delivery)
    dm = delivery.decomposition_model()
    # AT1_1|1 (robot fetches delivery 1 itself) is in half of the 8 decompositions
    dm.model.AddBoolOr([dm.decomposition["AT1_1|1"].Not()])
    sols = set(enumerate_all(dm).solutions)
    assert sols == {s for s in ref if "AT1_1|1" not in s}
    assert len(sols) == 4
    # and a second, pairwise exclusion through the helper
    dm.forbid(["AT3_2|1", "AT3_3|1"])
    sols = set(enumerate_all(dm).solutions)
    assert sols == {s for s in ref if "AT1_1|1" not in s and not {"AT3_2|1", "AT3_3|1"} <= s}
    assert len(sols) == 3


def test_each_build_is_independent(delivery: Mission) -> None:
    a = delivery.decomposition_model()
    b = DecompositionModel.build(delivery)
    assert a.model is not b.model
    a.model.AddBoolOr([a.decomposition["AT1_1|1"].Not()])
    assert len(enumerate_all(b).solutions) == 8


def test_maps_are_complete_and_keyed_as_documented(delivery: Mission) -> None:
    dm = delivery.decomposition_model()
    tg = delivery.task_graph
    assert isinstance(dm.model, cp_model.CpModel)
    assert set(dm.decomposition) == {v.content for v in tg.decompositions()}
    assert list(dm.decomposition) == [v.content for v in tg.decompositions()]  # Task Graph order
    assert len(dm.decomposition) == 18
    assert set(dm.task) == {f"AT{k}_{i}" for k in range(1, 5) for i in range(1, 4)}
    # G7 (OR) is copied once per delivery by the forAll of G3: keys carry the forAll index
    assert set(dm.or_choice) == {(f"G7_{i}", child) for i in range(1, 4) for child in ("G8", "G11")}
    assert set(dm.decompositions_info) == set(dm.decomposition)
    info = dm.decompositions_info["AT2_1|1"]
    assert info.task == "AT2_1" and info.task_name == "HandOver"
    assert info.actions == ("navigate", "give-item")
    assert info.capabilities == frozenset({"navigation", "communication"})
    assert (info.robot_number.min, info.robot_number.max, info.robot_number.fixed) == (1, 1, True)
    assert len(dm.constraints) == len(delivery.constraints) == 18
    kinds = {(c.kind, c.group, c.divisible) for c in dm.constraints}
    assert kinds == {("SEQ", True, True), ("EC", False, True)}
    assert ("EC", "AT1_1|1", "AT2_1|2", False, True) in dm.constraints
    for c in dm.constraints:
        assert c.first in dm.decomposition and c.second in dm.decomposition


def test_or_choice_literals_follow_the_decompositions(delivery: Mission) -> None:
    dm = delivery.decomposition_model()
    dm.model.Add(dm.or_choice[("G7_2", "G11")] == 1)
    solver = cp_model.CpSolver()
    solver.parameters.num_workers = 1
    assert solver.Solve(dm.model) in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    chosen = dm.solution(solver)
    assert "AT3_2|1" in chosen and "AT1_2|1" not in chosen
    assert dm.chosen_or(solver)["G7_2"] == "G11"
    assert len(chosen) == 6  # two task instances per delivery
    assert chosen == [d for d in dm.decomposition if d in chosen]  # Task Graph order


def test_constant_literals_are_real_cpsat_constants() -> None:
    mission = load(HOSPITAL)
    dm = mission.decomposition_model()
    # AT1 (clear the room) is executed in every decomposition: its activity folds to TRUE
    assert dm.task["AT1_1"] is dm.true
    assert dm.task["AT6_2"] is dm.true  # every occurrence is the same shared constant
    # usable like any literal: in enforcement, negation and linear expressions
    x = dm.model.NewBoolVar("user")
    dm.model.Add(x == 1).OnlyEnforceIf(dm.task["AT1_1"])
    dm.model.AddBoolOr([dm.false.Not()])
    dm.model.Add(dm.true + dm.false + x >= 2)
    solver = cp_model.CpSolver()
    solver.parameters.num_workers = 1
    assert solver.Solve(dm.model) == cp_model.OPTIMAL
    assert solver.BooleanValue(x) and solver.BooleanValue(dm.true) and not solver.BooleanValue(dm.false)
    assert "AT1_1|1" in dm.solution(solver)


def test_user_objective_over_the_decomposition_space(delivery: Mission) -> None:
    """An optimiser adds its own cost: fewest HandOver decompositions with a drop box."""
    dm = delivery.decomposition_model()
    drop = [lit for d, lit in dm.decomposition.items() if "drop-item" in dm.decompositions_info[d].actions]
    dm.model.Minimize(sum(drop))
    solver = cp_model.CpSolver()
    solver.parameters.num_workers = 1
    assert solver.Solve(dm.model) == cp_model.OPTIMAL
    # deliveries 2 and 3 go to unattended destinations: only the drop-box method is valid there
    assert solver.ObjectiveValue() == 2
