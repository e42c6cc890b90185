"""Each stage of an allocation, run within its share of the limit and recorded (:mod:`.phases`).

One function per stage of the pipeline (:mod:`.allocation`): it asks :class:`~.phases.Phases`
for its budget, skips the stage when there is none, runs it against the budget's deadline, and
records whether it was done, cut or skipped.  A stage that runs out of time while building
(:class:`~.budget.OutOfTime`) gives nothing and the next ones go on; only the problem itself
is indispensable.
"""
from __future__ import annotations

import time
from typing import TYPE_CHECKING, Callable

from ..solve.embedding import DecompositionModel
from ..solve.run import IncompleteSolveError
from .bounds import LpBound, lp_bound
from .budget import NEVER, Budget, OutOfTime
from .fleet import Fleet
from .load import LoadBound, load_bound
from .model import AllocationModel, build_model
from .neighbourhood import is_large, restrict
from .options import AllocationOptions
from .phases import CUT, DONE, Phases
from .problem import AllocationProblem, build_problem
from .search import Progress, SearchLimits, SearchOutcome, search
from .warmstart import WarmStart, add_hint, warm_start

if TYPE_CHECKING:
    from ..pipeline.stages import MissionStages
    from .travel import TravelTimes

LOAD_SHARE = 0.1  # of the time limit, at most, for the load relaxation
LP_SHARE = 0.25  # for the LP
IMPROVE_SHARE = 0.15  # for the local improvement of the warm start, at most
LARGE_IMPROVE_SHARE = 0.4  # for it on a mission searched within near robots and places
SEARCH_SHARE = 0.1  # kept for the search by the stages before the model
MODEL_KEEP = 0.05  # kept for the search by the model
END_KEEP = 0.02  # kept by the search for reading its schedule out


def problem_stage(phases: Phases, mission: MissionStages, fleet: Fleet, travel: TravelTimes | None) -> AllocationProblem:
    """The decomposition model and the allocation problem, within the whole time left: without
    them there is nothing to allocate, so running out of time is :class:`IncompleteSolveError`
    (exit 4)."""
    budget = phases.share(1.0)
    if budget is None:
        raise no_time(phases, "before the allocation problem was built (loading the solvers and reading the inputs took it all)")
    started = time.perf_counter()
    try:
        deadline = NEVER if budget.deterministic else budget.deadline()
        problem = build_problem(DecompositionModel.build(mission), fleet, travel, deadline)
    except OutOfTime:
        raise no_time(phases, "while the allocation problem was being built") from None
    phases.record("problem", DONE, time.perf_counter() - started)
    return problem


def no_time(phases: Phases, when: str) -> IncompleteSolveError:
    """The failure of an allocation whose time ran out before it had any schedule, with what
    became of each phase."""
    budget = phases.budget
    done = ", ".join(f"{p.name} {p.status}" + (f" ({p.note})" if p.note else "") + f" {p.seconds:.2f} s"
                     for p in phases.outcomes)
    return IncompleteSolveError(f"no schedule was found within {budget.describe()}: the time ran out {when}"
                                + (f" (phases: {done})" if done else "") + f"; raise {budget.option}")


def load_stage(phases: Phases, problem: AllocationProblem, options: AllocationOptions) -> LoadBound | None:
    """The load relaxation (:mod:`.load`), for its bound and the decompositions it suggests."""
    budget = phases.begin("load", LOAD_SHARE, SEARCH_SHARE, enabled=options.lp_bound or options.warm_start)
    if budget is None:
        return None
    load = load_bound(problem, options.objective, budget, options.workers, options.seed)
    finished = load.status in ("OPTIMAL", "INFEASIBLE")
    phases.record("load", DONE if finished else CUT, load.seconds, "" if finished else load.status)
    return load


def improve_share(problem: AllocationProblem) -> float:
    """The warm start's share of the limit: more on a large mission, whose search is restricted."""
    return LARGE_IMPROVE_SHARE if is_large(problem) else IMPROVE_SHARE


def warm_stage(phases: Phases, problem: AllocationProblem, options: AllocationOptions,
               load: LoadBound | None, share: float) -> WarmStart | None:
    """The warm start (:mod:`.warmstart`): a first schedule, the search's hint."""
    budget = phases.begin("warm", share, SEARCH_SHARE, enabled=options.warm_start)
    if budget is None:
        return None
    started = time.perf_counter()
    try:
        warm = warm_start(problem, load.decompositions if load else (), options.objective, budget, options.seed,
                          load.value if load else None, budget.deadline())
    except OutOfTime:
        phases.record("warm", CUT, time.perf_counter() - started, "no schedule yet")
        return None
    seconds = time.perf_counter() - started
    if warm is None:
        phases.record("warm", DONE, seconds, "list scheduling found no schedule")
    elif warm.improvement == "done":
        phases.record("warm", DONE, seconds)
    else:
        phases.record("warm", CUT, seconds, f"local moves {warm.improvement}")
    return warm


def lp_stage(phases: Phases, problem: AllocationProblem, options: AllocationOptions) -> LpBound | None:
    """The LP bound (:mod:`.bounds`)."""
    budget = phases.begin("lp", LP_SHARE, SEARCH_SHARE, enabled=options.lp_bound)
    if budget is None:
        return None
    lp = lp_bound(problem, options.objective, budget)
    cut = lp.status in ("MaxTime", "MaxIterations")
    phases.record("lp", CUT if cut else DONE, lp.seconds, lp.status if lp.status != "Solved" else "")
    return lp


def model_stage(phases: Phases, problem: AllocationProblem, options: AllocationOptions,
                warm: WarmStart | None) -> AllocationModel | None:
    """The restriction of a large mission (:mod:`.neighbourhood`) and the joint model, hinted
    by the warm start; None when the time ran out before it was built."""
    budget = phases.begin("model", 1.0, MODEL_KEEP)
    if budget is None:
        return None
    deadline = NEVER if budget.deterministic else budget.deadline()
    started = time.perf_counter()
    try:
        restriction = restrict(problem, warm.teams if warm else None,
                               {(a, b) for _, a, b in warm.route_arcs(problem)} if warm else None, deadline)
        am = build_model(problem, options.objective, restriction, deadline)
        if warm is not None:
            add_hint(am, warm)
    except OutOfTime:
        phases.record("model", CUT, time.perf_counter() - started, "not built in time")
        return None
    phases.record("model", DONE, time.perf_counter() - started)
    return am


def search_stage(phases: Phases, am: AllocationModel | None, options: AllocationOptions, share: float,
                 progress: Callable[[Progress], None] | None, warm: WarmStart | None) -> SearchOutcome | None:
    """CP-SAT's search (:mod:`.search`) with what is left (in work, the shares the other stages
    leave); None when it was skipped or found nothing in time, and the warm start serves
    instead (without one, :class:`IncompleteSolveError`)."""
    if phases.budget.deterministic:
        budget: Budget | None = phases.budget.part(1 - LOAD_SHARE - share)  # the LP counts iterations instead
    else:
        budget = phases.share(1.0, END_KEEP)
    if am is None or budget is None:
        phases.skip("search", "no time left" if budget is None else "no model")
        if warm is None:
            raise no_time(phases, "before the search")
        return None
    limits = SearchLimits(budget, options.workers, options.seed, am.restriction.active and warm is not None)
    started = time.perf_counter()
    try:
        outcome = search(am, limits, progress)
    except IncompleteSolveError:
        phases.record("search", CUT, time.perf_counter() - started, "no schedule found")
        if warm is None:
            raise
        return None
    phases.record("search", DONE if outcome.status == "OPTIMAL" else CUT, outcome.seconds)
    return outcome
