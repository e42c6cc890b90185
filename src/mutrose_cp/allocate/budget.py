"""How long each phase of an allocation may run: seconds on the clock, or units of work.

A clock budget makes the allocation *anytime*: each phase stops when its share of the time limit
has passed, so the schedule found depends on how fast the machine was at that moment.  A work
budget (``--work-limit``) counts what the phases do instead, so that the same inputs and seed
give the same schedule, byte for byte, on any machine and under any load:

* CP-SAT (the load relaxation and the search) stops at its *deterministic time*, which counts
  the solver's elementary operations (a unit is roughly a second on a current machine); with
  several workers it interleaves them in a fixed order (``interleave_search``);
* the local moves stop after a number of schedule evaluations, each weighted by the number of
  jobs it schedules (:data:`JOB_STEPS_PER_UNIT` per unit, again about a second here);
* Clarabel (the LP bound) stops after :data:`LP_ITERATIONS` interior-point iterations instead of
  at a time: it runs to its answer, however long that takes.

Phases that take "what is left" of a clock budget take a fixed share of a work budget.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:
    from ..solve.native import cmh

JOB_STEPS_PER_UNIT = 500_000  # job schedulings by the local moves' evaluator per unit of work (about a second here)
LP_ITERATIONS = 200  # Clarabel's iterations in a work budget (its default limit)


@dataclass(frozen=True)
class Budget:
    """``seconds`` on the clock, or, when ``work`` is set, that many units of deterministic work
    (see the module docstring) and no clock at all."""

    seconds: float
    work: float | None = None

    @property
    def deterministic(self) -> bool:
        return self.work is not None

    def part(self, fraction: float) -> Budget:
        """A share of this budget, for one phase."""
        return Budget(self.seconds * fraction, None if self.work is None else self.work * fraction)

    def rest(self, started: float, share: float = 1.0) -> Budget:
        """What a phase that follows others since ``started`` (``time.perf_counter()``) may
        take: on the clock, what is left of this budget; in work, which nothing measures as it
        goes, the ``share`` of it fixed in advance."""
        if self.work is not None:
            return self.part(share)
        return replace(self, seconds=max(0.0, self.seconds - (time.perf_counter() - started)))

    def limit(self, parameters: cmh.SatParameters, workers: int) -> None:
        """Put the limit on CP-SAT's parameters."""
        if self.work is None:
            parameters.max_time_in_seconds = self.seconds
        else:
            parameters.max_deterministic_time = self.work
            if workers > 1:
                parameters.interleave_search = True

    def job_steps(self) -> int | None:
        """The local moves' allowance in scheduled jobs (None on a clock budget)."""
        return None if self.work is None else int(self.work * JOB_STEPS_PER_UNIT)

    def running(self) -> Callable[[int], bool]:
        """A test the local moves call with the job steps spent so far: whether there is budget
        left (the clock, from now, or the steps)."""
        steps = self.job_steps()
        if steps is not None:
            return lambda spent: spent < steps
        deadline = time.perf_counter() + self.seconds
        return lambda _spent: time.perf_counter() < deadline

    @property
    def option(self) -> str:
        """The command-line option that sets this kind of budget."""
        return "--time-limit" if self.work is None else "--work-limit"

    def describe(self) -> str:
        return f"{self.seconds:g} s" if self.work is None else f"{self.work:g} units of work"
