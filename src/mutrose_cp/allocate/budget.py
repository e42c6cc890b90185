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

A clock budget also gives each phase a :class:`Deadline`: the work a phase does before it hands
anything to a solver (building a model, a table, a plan) is checked against it, so that a phase
whose time is up stops there (:class:`OutOfTime`) instead of running on past the time limit.  A
work budget has no deadline: what it does must not depend on the clock.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass, replace
from typing import TYPE_CHECKING, Callable

if TYPE_CHECKING:
    from ..solve.native import cmh

JOB_STEPS_PER_UNIT = 500_000  # job schedulings by the local moves' evaluator per unit of work (about a second here)
LP_ITERATIONS = 200  # Clarabel's iterations in a work budget (its default limit)


class OutOfTime(Exception):
    """A phase's deadline passed while it was building: it gives nothing (see :mod:`.phases`)."""


@dataclass(frozen=True)
class Deadline:
    """A moment on ``time.perf_counter()``'s clock (never, by default) that long loops check."""

    at: float = math.inf

    def left(self) -> float:
        """Seconds until the deadline (0 once it has passed; infinite without one)."""
        return max(0.0, self.at - time.perf_counter()) if math.isfinite(self.at) else math.inf

    def passed(self) -> bool:
        return math.isfinite(self.at) and time.perf_counter() >= self.at

    def check(self) -> None:
        """Raise :class:`OutOfTime` once the deadline has passed: called once per job or robot by
        the loops that grow with the fleet, it costs a clock read."""
        if self.passed():
            raise OutOfTime


NEVER = Deadline()


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

    def deadline(self) -> Deadline:
        """The moment this budget ends, from now: none on a work budget (its phases must not
        depend on the clock)."""
        return NEVER if self.work is not None else Deadline(time.perf_counter() + self.seconds)

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
