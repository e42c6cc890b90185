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
what is left, at least a tenth.  A work limit instead of the time limit (:mod:`.budget`) is
shared the same way, the search taking the shares the others leave, so that the schedule does not
depend on the machine.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

from ..solve.run import IncompleteSolveError
from .bounds import LpBound, lp_bound
from .budget import Budget
from .fleet import Fleet
from .load import LoadBound, load_bound
from .model import AllocationModel, build_model, literal_value
from .options import AllocationOptions
from .problem import AllocationProblem, build_problem
from .schedule import Schedule, compact
from .search import Progress, SearchLimits, relative_gap, search
from .neighbourhood import restrict
from .warmstart import WarmStart, add_hint, warm_start

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
    status: str  # "OPTIMAL" (proven) or "FEASIBLE" (best found at the time or work limit)
    schedule: Schedule
    cp_bound: float | None  # CP-SAT's proven bound (None: a restricted search, or the warm start's schedule)
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
    budget = options.budget
    problem = build_problem(mission.decomposition_model(), fleet, travel)
    load = None
    if options.lp_bound or options.warm_start:
        load = load_bound(problem, options.objective, budget.part(LOAD_SHARE), options.workers, options.seed)
        seconds["load"] = load.seconds
    warming = time.perf_counter()
    share = LARGE_IMPROVE_SHARE if restrict(problem).active else IMPROVE_SHARE
    warm = (warm_start(problem, load.decompositions if load else (), options.objective, budget.part(share),
                       options.seed, load.value if load else None) if options.warm_start else None)
    if warm is not None:
        seconds["warm"] = time.perf_counter() - warming
    lp = lp_bound(problem, options.objective, budget.part(LP_SHARE)) if options.lp_bound else None
    if lp is not None:
        seconds["lp"] = lp.seconds
    restriction = restrict(problem, warm.teams if warm else None,
                           {(a, b) for _, a, b in warm.route_arcs(problem)} if warm else None)
    am = build_model(problem, options.objective, restriction)
    if warm is not None:
        add_hint(am, warm)
    seconds["model"] = time.perf_counter() - clock - sum(seconds.values())
    improve_only = restriction.active and warm is not None  # large-neighbourhood search from the hint
    limits = SearchLimits(_search_budget(budget, clock, share), options.workers, options.seed, improve_only)
    status, bound, schedule, seconds["search"] = _best_schedule(am, limits, progress, warm)
    if not options.lp_bound:
        load = None
    if restriction.active:  # the restricted model's optimum and bound say nothing of the mission's
        return Allocation(problem, options, "FEASIBLE", schedule, None, lp, load, seconds, restricted=True)
    return Allocation(problem, options, status, schedule, bound, lp, load, seconds)


def _best_schedule(am: AllocationModel, limits: SearchLimits, progress: Callable[[Progress], None] | None,
                   warm: WarmStart | None) -> tuple[str, float | None, Schedule, float]:
    """The search's status, bound and best schedule, and its seconds.  When the search ends
    before it has any schedule (a short limit can end it in CP-SAT's presolve), the warm start's
    schedule, a complete one that the search was given as its hint, is the best found: FEASIBLE,
    without a bound from the search."""
    started = time.perf_counter()
    try:
        outcome = search(am, limits, progress)
    except IncompleteSolveError:
        if warm is None:
            raise
        return "FEASIBLE", None, warm.schedule(am.problem), time.perf_counter() - started
    return outcome.status, outcome.bound, _schedule(am, outcome.values), outcome.seconds


def _search_budget(budget: Budget, started: float, improve_share: float) -> Budget:
    """The search's budget: what the clock has left since ``started`` (at least a tenth of the
    time limit), or the work left over by the other phases' shares."""
    left = budget.rest(started, 1 - LOAD_SHARE - improve_share)  # in work: the LP counts iterations instead
    return left if budget.deterministic or left.seconds >= SEARCH_SHARE * budget.seconds else budget.part(SEARCH_SHARE)


def _schedule(am: AllocationModel, values: list[int]) -> Schedule:
    """The schedule of a solution (``values`` by proto variable index), compacted."""
    problem, dm = am.problem, am.problem.dm
    jobs = [j for j in problem.jobs if literal_value(values, dm.decomposition[j])]
    teams = {j: tuple(r for r in am.restriction.robots_of(problem, j) if literal_value(values, am.assign[(j, r)])) for j in jobs}
    start = {j: values[am.start[j].index] for j in jobs}
    end = {j: values[am.end[j].index] for j in jobs}
    return compact(problem, jobs, teams, start, end)
