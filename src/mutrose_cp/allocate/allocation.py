"""Allocating a mission to a fleet: the pipeline from the mission and fleet to a schedule.

    decomposition model (solve/embedding.py) + fleet
        --problem.py-->  jobs, candidates, precedences, travel times
        --model.py-->    the joint CP-SAT model   --warmstart.py--> a first schedule as a hint
        --search.py-->   the best schedule within the time limit, and CP-SAT's bound
        --schedule.py--> chosen jobs, teams, compacted times, routes
        --bounds.py-->   the LP bound (Clarabel)
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

from .bounds import LpBound, lp_bound
from .fleet import Fleet
from .model import AllocationModel, build_model
from .options import AllocationOptions
from .problem import AllocationProblem, build_problem
from .schedule import Schedule, compact
from .search import Progress, SearchLimits, relative_gap, search
from .neighbourhood import restrict
from .warmstart import add_hint, warm_start

if TYPE_CHECKING:
    from ..mission import Mission


@dataclass(frozen=True)
class Allocation:
    """A schedule and what is proven about it."""

    problem: AllocationProblem
    options: AllocationOptions
    status: str  # "OPTIMAL" (proven) or "FEASIBLE" (best found at the time limit)
    schedule: Schedule
    cp_bound: float | None  # CP-SAT's proven lower bound on the objective (None: restricted search)
    lp: LpBound | None
    seconds: dict[str, float] = field(default_factory=dict)
    restricted: bool = False  # a large mission searched within near robots and places

    @property
    def objective(self) -> int:
        """The objective's value on the schedule."""
        return round(self.options.objective.value(self.schedule.makespan, self.schedule.travel))

    @property
    def lp_value(self) -> float | None:
        return self.lp.value if self.lp is not None else None

    @property
    def gap(self) -> float | None:
        """The gap to CP-SAT's bound (0 when proven optimal)."""
        if self.status == "OPTIMAL":
            return 0.0
        return relative_gap(self.objective, self.cp_bound)

    @property
    def lp_gap(self) -> float | None:
        return relative_gap(self.objective, self.lp_value)

    @property
    def decomposition(self) -> list[str]:
        """The chosen decomposition ids, in mission order."""
        return list(self.schedule.jobs)


def allocate(mission: Mission, fleet: Fleet, options: AllocationOptions = AllocationOptions(),
             progress: Callable[[Progress], None] | None = None) -> Allocation:
    """Choose a valid mission decomposition, the robots of each task and the times together
    (see the package docstring).  Raises :class:`~.problem.NoAllocationError` (exit 3) when the
    fleet cannot execute any valid decomposition, and
    :class:`~mutrose_cp.solve.run.IncompleteSolveError` (exit 4) when the time limit passes
    before any schedule is found."""
    seconds: dict[str, float] = {}
    clock = time.perf_counter()
    problem = build_problem(mission.decomposition_model(), fleet)
    warm = warm_start(problem) if options.warm_start else None
    restriction = restrict(problem, warm.teams if warm else None,
                           {(a, b) for _, a, b in warm.route_arcs(problem)} if warm else None)
    am = build_model(problem, options.objective, restriction)
    if warm is not None:
        add_hint(am, warm)
    seconds["model"] = time.perf_counter() - clock
    outcome = search(am, SearchLimits(options.time_limit, options.workers, options.seed), progress)
    seconds["search"] = outcome.seconds
    schedule = _schedule(am, outcome.values)
    lp = lp_bound(problem, options.objective) if options.lp_bound else None
    if lp is not None:
        seconds["lp"] = lp.seconds
    if restriction.active:  # the restricted model's optimum and bound say nothing of the mission's
        return Allocation(problem, options, "FEASIBLE", schedule, None, lp, seconds, restricted=True)
    return Allocation(problem, options, outcome.status, schedule, outcome.bound, lp, seconds)


def _schedule(am: AllocationModel, values: list[int]) -> Schedule:
    """The schedule of a solution (``values`` by proto variable index), compacted."""
    def true(literal: object) -> bool:
        index = literal.index  # type: ignore[attr-defined]
        return bool(values[index]) if index >= 0 else not values[-index - 1]

    problem, dm = am.problem, am.problem.dm
    jobs = [j for j in problem.jobs if true(dm.decomposition[j])]
    teams = {j: tuple(r for r in am.restriction.robots_of(problem, j) if true(am.assign[(j, r)])) for j in jobs}
    start = {j: values[am.start[j].index] for j in jobs}
    end = {j: values[am.end[j].index] for j in jobs}
    return compact(problem, jobs, teams, start, end)
