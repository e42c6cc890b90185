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

The time limit is the whole run's, and it holds whatever the size of the fleet (:mod:`.phases`):
the load relaxation may take a tenth of it, the warm start about a seventh (two fifths on a
large mission, whose restricted search rarely improves a good hint) and the LP a quarter (an LP
cut short gives no bound), each never more than what leaves the search a tenth; the model takes
what it needs of the rest, and the search has what is left.  A phase with no time left is
skipped, one whose share ends first is cut, and each is reported so.  A search that has no time
left, or finds nothing in it, gives the warm start's schedule.  A work limit instead of the time
limit (:mod:`.budget`) is shared the same way, the search taking the shares the others leave,
so that the schedule does not depend on the machine.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Callable

from .bounds import LpBound
from .fleet import Fleet
from .load import LoadBound
from .model import AllocationModel, literal_value
from .options import AllocationOptions
from .phases import PhaseOutcome, Phases
from .problem import AllocationProblem
from .schedule import Schedule, compact
from .search import Progress, SearchOutcome, relative_gap
from .stages import improve_share, load_stage, lp_stage, model_stage, problem_stage, search_stage, warm_stage
from .warmstart import WarmStart

if TYPE_CHECKING:
    from ..pipeline.stages import MissionStages
    from .travel import TravelTimes


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
    phases: tuple[PhaseOutcome, ...] = ()  # in order, each done, cut, skipped or off (.phases)

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


def allocate(mission: MissionStages, fleet: Fleet, options: AllocationOptions | None = None,
             progress: Callable[[Progress], None] | None = None, travel: TravelTimes | None = None) -> Allocation:
    """Choose a valid mission decomposition, the robots of each task and the times together
    (see the module docstring).  ``travel``: the fleet's :func:`~.problem.mission_travel`, when
    the caller has built it to check the fleet (built here otherwise).  Raises
    :class:`~.problem.NoAllocationError` (exit 3) when the fleet cannot execute any valid
    decomposition, and :class:`~mutrose_cp.solve.run.IncompleteSolveError` (exit 4) when the
    time limit passes before any schedule is found.  Default options when none are given."""
    options = options if options is not None else AllocationOptions()
    phases = Phases(options.budget, options.counted_from)
    problem = problem_stage(phases, mission, fleet, travel)
    load = load_stage(phases, problem, options)
    share = improve_share(problem)
    warm = warm_stage(phases, problem, options, load, share)
    lp = lp_stage(phases, problem, options)
    am = model_stage(phases, problem, options, warm)
    outcome = search_stage(phases, am, options, share, progress, warm)
    status, bound, schedule = _result(problem, am, outcome, warm)
    restricted = am is not None and am.restriction.active
    return Allocation(problem, options, "FEASIBLE" if restricted else status, schedule,
                      None if restricted else bound,  # a restricted model's optimum and bound say nothing of the mission's
                      lp, load if options.lp_bound else None, phases.seconds, restricted, tuple(phases.outcomes))


def _result(problem: AllocationProblem, am: AllocationModel | None, outcome: SearchOutcome | None,
            warm: WarmStart | None) -> tuple[str, float | None, Schedule]:
    """The status, bound and schedule of the search's solution; without one (skipped, or
    stopped before its first schedule: a short limit can end it in CP-SAT's presolve), the warm
    start's schedule, a complete one that the search was given as its hint: FEASIBLE, without a
    bound from the search."""
    if outcome is None or am is None:
        assert warm is not None  # search_stage raised otherwise
        return "FEASIBLE", None, warm.schedule(problem)
    return outcome.status, outcome.bound, _schedule(am, outcome.values)


def _schedule(am: AllocationModel, values: list[int]) -> Schedule:
    """The schedule of a solution (``values`` by proto variable index), compacted."""
    problem, dm = am.problem, am.problem.dm
    jobs = [j for j in problem.jobs if literal_value(values, dm.decomposition[j])]
    teams = {j: tuple(r for r in am.restriction.robots_of(problem, j) if literal_value(values, am.assign[(j, r)])) for j in jobs}
    start = {j: values[am.start[j].index] for j in jobs}
    end = {j: values[am.end[j].index] for j in jobs}
    return compact(problem, jobs, teams, start, end)
