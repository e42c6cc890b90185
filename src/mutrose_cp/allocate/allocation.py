"""Allocating a mission to a fleet: the pipeline from the mission and fleet to a schedule.

    decomposition model (solve/embedding.py) + fleet
        --problem.py-->  jobs, candidates, precedences, travel times
        --load.py-->     the load bound, and a decomposition that spreads the work
        --warmstart.py--> a first schedule (list scheduling, improved by local moves in
                          improve.py), a hint for the search
        --bounds.py-->   the LP bound (Clarabel)
        --model.py-->    the joint CP-SAT model
        --search.py-->   the best schedule within the time left, and CP-SAT's bound
        --schedule.py--> chosen jobs, teams, compacted times, routes

The time limit is the whole run's: the load relaxation may take a tenth of it, the warm start's
local moves about a seventh (two fifths on a large mission, whose restricted search rarely
improves a good hint) and the LP a quarter (an LP cut short gives no bound), and the search has
what is left, at least a tenth.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

from .bounds import LpBound, lp_bound
from .fleet import Fleet
from .load import LoadBound, load_bound
from .model import AllocationModel, build_model, literal_value
from .options import AllocationOptions
from .problem import AllocationProblem, build_problem
from .schedule import Schedule, compact
from .search import Progress, SearchLimits, relative_gap, search
from .neighbourhood import restrict
from .warmstart import add_hint, warm_start

if TYPE_CHECKING:
    from ..mission import Mission
    from .travel import TravelTimes

LOAD_SHARE = 0.1  # of the time limit, at most, for the load relaxation
LP_SHARE = 0.25  # for the LP
IMPROVE_SHARE = 0.15  # for the local improvement of the warm start, at most
LARGE_IMPROVE_SHARE = 0.4  # for it on a mission searched within near robots and places
SEARCH_SHARE = 0.1  # for the search, at least


@dataclass(frozen=True)
class Allocation:
    """A schedule and what is proven about it."""

    problem: AllocationProblem
    options: AllocationOptions
    status: str  # "OPTIMAL" (proven) or "FEASIBLE" (best found at the time limit)
    schedule: Schedule
    cp_bound: float | None  # CP-SAT's proven lower bound on the objective (None: restricted search)
    lp: LpBound | None
    load: LoadBound | None = None
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
    def load_value(self) -> float | None:
        return self.load.value if self.load is not None else None

    @property
    def load_gap(self) -> float | None:
        return relative_gap(self.objective, self.load_value)

    @property
    def decomposition(self) -> list[str]:
        """The chosen decomposition ids, in mission order."""
        return list(self.schedule.jobs)


def allocate(mission: Mission, fleet: Fleet, options: AllocationOptions = AllocationOptions(),
             progress: Callable[[Progress], None] | None = None, travel: TravelTimes | None = None) -> Allocation:
    """Choose a valid mission decomposition, the robots of each task and the times together
    (see the package docstring).  ``travel``: the fleet's :func:`~.problem.mission_travel`, when
    the caller has built it to check the fleet (built here otherwise).  Raises
    :class:`~.problem.NoAllocationError` (exit 3) when the fleet cannot execute any valid
    decomposition, and :class:`~mutrose_cp.solve.run.IncompleteSolveError` (exit 4) when the
    time limit passes before any schedule is found."""
    seconds: dict[str, float] = {}
    clock = time.perf_counter()
    budget = options.time_limit
    problem = build_problem(mission.decomposition_model(), fleet, travel)
    load = None
    if options.lp_bound or options.warm_start:
        load = load_bound(problem, options.objective, LOAD_SHARE * budget, options.workers, options.seed)
        seconds["load"] = load.seconds
    warming = time.perf_counter()
    share = LARGE_IMPROVE_SHARE if restrict(problem).active else IMPROVE_SHARE
    warm = (warm_start(problem, load.decompositions if load else (), options.objective, share * budget, options.seed,
                       load.value if load else None) if options.warm_start else None)
    if warm is not None:
        seconds["warm"] = time.perf_counter() - warming
    lp = lp_bound(problem, options.objective, LP_SHARE * budget) if options.lp_bound else None
    if lp is not None:
        seconds["lp"] = lp.seconds
    restriction = restrict(problem, warm.teams if warm else None,
                           {(a, b) for _, a, b in warm.route_arcs(problem)} if warm else None)
    am = build_model(problem, options.objective, restriction)
    if warm is not None:
        add_hint(am, warm)
    seconds["model"] = time.perf_counter() - clock - sum(seconds.values())
    left = max(SEARCH_SHARE * budget, budget - (time.perf_counter() - clock))
    improve_only = restriction.active and warm is not None  # large-neighbourhood search from the hint
    outcome = search(am, SearchLimits(left, options.workers, options.seed, improve_only), progress)
    seconds["search"] = outcome.seconds
    schedule = _schedule(am, outcome.values)
    if not options.lp_bound:
        load = None
    if restriction.active:  # the restricted model's optimum and bound say nothing of the mission's
        return Allocation(problem, options, "FEASIBLE", schedule, None, lp, load, seconds, restricted=True)
    return Allocation(problem, options, outcome.status, schedule, outcome.bound, lp, load, seconds)


def _schedule(am: AllocationModel, values: list[int]) -> Schedule:
    """The schedule of a solution (``values`` by proto variable index), compacted."""
    problem, dm = am.problem, am.problem.dm
    jobs = [j for j in problem.jobs if literal_value(values, dm.decomposition[j])]
    teams = {j: tuple(r for r in am.restriction.robots_of(problem, j) if literal_value(values, am.assign[(j, r)])) for j in jobs}
    start = {j: values[am.start[j].index] for j in jobs}
    end = {j: values[am.end[j].index] for j in jobs}
    return compact(problem, jobs, teams, start, end)
