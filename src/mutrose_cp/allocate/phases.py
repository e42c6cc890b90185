"""The phases of one allocation under one limit: what each may take, and what became of it.

An allocation runs its phases one after the other (:mod:`.allocation`): the problem, the load
bound, the warm start, the LP bound, the model and the search.  On the clock, each phase may
take its share of the time the allocation has (the time limit, less what reading the inputs
took when the limit counts from the start of the command), but never more than what is left
once the phases after it have what they are kept (the search, at least a tenth); a phase that would get less
than :data:`MIN_PHASE` is *skipped*, not started.  A phase that its share ends before it is
through (a relaxation still searching, an LP still being built) is *cut*: what it found by then
is used, which may be nothing.  So the phases' seconds add up to the time limit, whatever the
size of the fleet: the work that grows with it (a table per robot, a variable per robot and
task) is checked against the phase's deadline as it goes (:class:`~.budget.Deadline`).

A work budget has no clock: each phase takes its fixed share and none is skipped, so that the
same inputs give the same schedule on any machine (:mod:`.budget`).

Every phase is recorded in order as a :class:`PhaseOutcome`, which the summary reports.
"""
from __future__ import annotations

import math
import time
from dataclasses import dataclass

from .budget import Budget

MIN_PHASE = 0.005  # seconds: a phase given less than this is skipped (nothing useful fits in it)

DONE, CUT, SKIPPED, OFF = "done", "cut", "skipped", "off"
STATUSES = (DONE, CUT, SKIPPED, OFF)


@dataclass(frozen=True)
class PhaseOutcome:
    """What became of one phase: ``done`` (through within its share), ``cut`` (its share ended
    it), ``skipped`` (no time was left for it) or ``off`` (not asked for); ``note`` says more."""

    name: str
    status: str
    seconds: float
    note: str = ""


class Phases:
    """The limit of one allocation, shared phase by phase, and the outcome of each phase.
    ``started`` (``time.perf_counter()``) is when the time limit started counting: the command
    line counts it from the start of the command, so that reading a large fleet counts too."""

    def __init__(self, budget: Budget, started: float | None = None) -> None:
        self.budget = budget
        self.started = time.perf_counter() if started is None else started
        self.outcomes: list[PhaseOutcome] = []
        self.total = self.left()  # what the shares are shares of

    def left(self) -> float:
        """Seconds left of the time limit (infinite on a work budget)."""
        if self.budget.deterministic:
            return math.inf
        return max(0.0, self.started + self.budget.seconds - time.perf_counter())

    def share(self, fraction: float, keep: float = 0.0) -> Budget | None:
        """The budget of a phase that may take ``fraction`` of the limit and must leave ``keep``
        of it to the phases after it: on the clock, the lesser of its share and what is left
        beyond ``keep`` (None when that is less than :data:`MIN_PHASE`: the phase is skipped);
        in work, its fixed share."""
        if self.budget.deterministic:
            return self.budget.part(fraction)
        seconds = min(fraction * self.total, self.left() - keep * self.total)
        return Budget(seconds) if seconds >= MIN_PHASE else None

    def begin(self, name: str, fraction: float, keep: float = 0.0, enabled: bool = True) -> Budget | None:
        """The budget of phase ``name`` (:meth:`share`), or None when it does not run: turned
        off by its option (recorded off) or without time left (recorded skipped)."""
        if not enabled:
            self.record(name, OFF, 0.0)
            return None
        budget = self.share(fraction, keep)
        if budget is None:
            self.skip(name)
        return budget

    def record(self, name: str, status: str, seconds: float, note: str = "") -> None:
        self.outcomes.append(PhaseOutcome(name, status, seconds, note))

    def skip(self, name: str, note: str = "no time left") -> None:
        self.record(name, SKIPPED, 0.0, note)

    @property
    def seconds(self) -> dict[str, float]:
        """Each phase that ran, by name: its seconds."""
        return {p.name: p.seconds for p in self.outcomes if p.status in (DONE, CUT)}
