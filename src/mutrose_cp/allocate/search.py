"""Solving the allocation model: anytime, within a time limit, never reporting a guess.

CP-SAT runs in a worker thread (``solve/run.py``), so an interrupt stops it at once and nothing
is written.  Every improvement of the incumbent or of the proven bound is passed to
``progress``.  The outcome is one of:

* ``OPTIMAL``: the schedule is proven optimal;
* ``FEASIBLE``: the time limit came first; the schedule is the best one found, proven feasible,
  and the gap to the proven bound is reported with it;
* infeasible: :class:`~.problem.NoAllocationError`, naming what the fleet lacks (exit 3);
* nothing found in time: :class:`~mutrose_cp.solve.run.IncompleteSolveError` (exit 4).
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Callable

from ..errors import Problem
from ..solve.native import cmh
from ..solve.run import FEASIBLE, INFEASIBLE, OPTIMAL, IncompleteSolveError, run_solver
from .budget import Budget
from .model import AllocationModel
from .problem import NoAllocationError, impossibilities


LARGE_MODEL = 20_000  # variables


@dataclass(frozen=True)
class Progress:
    """The state of the search when the incumbent or the bound improves."""

    objective: float | None  # None until a first schedule is found
    bound: float
    seconds: float

    @property
    def gap(self) -> float | None:
        return relative_gap(self.objective, self.bound)


def relative_gap(objective: float | None, bound: float | None) -> float | None:
    """``(objective - bound) / objective``: 0 when proven optimal, None when unknown."""
    if objective is None or bound is None:
        return None
    if objective <= 0:
        return 0.0 if bound >= objective else None
    return max(0.0, (objective - bound) / objective)


@dataclass(frozen=True)
class SearchLimits:
    budget: Budget = Budget(10.0)
    workers: int = 1
    seed: int = 0
    improve_only: bool = False  # every worker improves the hinted schedule (no proof is wanted)


@dataclass(frozen=True)
class SearchOutcome:
    status: str  # "OPTIMAL" or "FEASIBLE"
    bound: float  # CP-SAT's proven lower bound on the objective
    values: list[int]  # the solution, by proto variable index
    seconds: float


class _Watcher(cmh.SolutionCallback):
    """Passes each new incumbent, with the bound at that moment, to ``progress``."""

    def __init__(self, report: Callable[[Progress], None], started: float) -> None:
        super().__init__()
        self.report = report
        self.started = started
        self.objective: float | None = None
        self.bound = float("-inf")

    def OnSolutionCallback(self) -> None:  # noqa: N802 - the helper module's callback name
        self.objective = self.ObjectiveValue()
        self.bound = max(self.bound, self.BestObjectiveBound())
        self.report(Progress(self.objective, self.bound, time.monotonic() - self.started))

    def on_bound(self, bound: float) -> None:
        self.bound = max(self.bound, bound)
        self.report(Progress(self.objective, self.bound, time.monotonic() - self.started))


def search(am: AllocationModel, limits: SearchLimits,
           progress: Callable[[Progress], None] | None = None) -> SearchOutcome:
    """Solve ``am`` within ``limits`` (see the module docstring)."""
    parameters = cmh.SatParameters()
    limits.budget.limit(parameters, limits.workers)
    parameters.num_workers = limits.workers
    parameters.random_seed = limits.seed
    if len(am.model.proto.variables) > LARGE_MODEL:
        # probing and symmetry detection take most of a minute on large routes, before any search
        parameters.cp_model_probing_level = 0
        parameters.symmetry_level = 0
    if limits.improve_only:
        # a restricted search reports no bound: workers spent on proofs would only be lost
        parameters.use_lns_only = True
    started = time.monotonic()
    watcher = _Watcher(progress or (lambda _: None), started)
    try:
        response = run_solver(am.model.proto, accept=(OPTIMAL, FEASIBLE, INFEASIBLE), callback=watcher,
                              parameters=parameters, bound_callback=watcher.on_bound, what="the allocation")
    except IncompleteSolveError:
        raise IncompleteSolveError(f"no schedule was found within {limits.budget.describe()}; nothing is reported "
                                   f"from an unfinished search: raise {limits.budget.option}") from None
    if response.status == INFEASIBLE:
        raise _no_allocation(am)
    return SearchOutcome("OPTIMAL" if response.status == OPTIMAL else "FEASIBLE",
                         response.best_objective_bound, list(response.solution),
                         time.monotonic() - started)


def _no_allocation(am: AllocationModel) -> NoAllocationError:
    """Why no schedule exists: what the fleet lacks for the jobs it cannot staff."""
    source = am.problem.fleet.source
    reasons = impossibilities(am.problem)
    if not reasons:
        return NoAllocationError(Problem(source, "no valid mission decomposition can be allocated to this fleet: "
                                                 "the robot numbers and execution constraints conflict"))
    return NoAllocationError([Problem(source, "no valid mission decomposition can be allocated to this fleet"),
                              *(Problem(source, r) for r in reasons)])
