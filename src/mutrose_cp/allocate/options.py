"""What an allocation minimises and how long it searches: the options of ``mutrose-cp
allocate`` and of :meth:`mutrose_cp.mission.Mission.allocate`."""
from __future__ import annotations

import re
from dataclasses import dataclass

from ..errors import MissionError
from .budget import Budget

MAX_WORKERS = 256  # CP-SAT search threads; more only add start-up time
MAX_SEED = 2**31 - 1  # CP-SAT's random_seed is a 32-bit integer


@dataclass(frozen=True)
class Objective:
    """``makespan_weight * makespan + travel_weight * total travel``, minimised."""

    makespan_weight: int = 1
    travel_weight: int = 0

    @classmethod
    def parse(cls, text: str) -> "Objective":
        """``makespan``, ``travel`` or ``weighted:A,B`` (A times the makespan plus B times the
        travel; whole numbers, not both 0)."""
        if text == "makespan":
            return cls(1, 0)
        if text == "travel":
            return cls(0, 1)
        match = re.fullmatch(r"weighted:(\d+),(\d+)", text.strip())
        if match is None or match.group(1) == match.group(2) == "0" or not all(
                int(g) <= 10**6 for g in match.groups()):
            raise MissionError(f"unknown objective {text!r}: expected makespan, travel or weighted:A,B (whole "
                               "weights from 0 to 1000000, not both 0), e.g. weighted:10,1", "--objective")
        return cls(int(match.group(1)), int(match.group(2)))

    @property
    def name(self) -> str:
        if self.travel_weight == 0:
            return "makespan"
        if self.makespan_weight == 0:
            return "travel"
        return f"weighted:{self.makespan_weight},{self.travel_weight}"

    def value(self, makespan: float, travel: float) -> float:
        return self.makespan_weight * makespan + self.travel_weight * travel


@dataclass(frozen=True)
class AllocationOptions:
    """What to minimise and how long the allocation takes (``time_limit``: bounds, model and
    search together, see :mod:`.allocation` and :mod:`.phases`; counted from ``counted_from``
    when given, the command's start on the command line).

    CP-SAT runs with ``seed`` and ``workers`` threads (its portfolio, large-neighbourhood
    search included, from 2 on).  A search that ends before ``time_limit`` with one worker
    always gives the same schedule; a search cut by the time limit depends on the machine.
    ``work_limit`` replaces the clock by units of deterministic work (:mod:`.budget`): the same
    schedule on any machine, with any number of workers."""

    objective: Objective = Objective()
    time_limit: float = 10.0
    workers: int = 1
    seed: int = 0
    lp_bound: bool = True  # also compute the LP bound with Clarabel
    warm_start: bool = True  # give CP-SAT a first schedule (decomposition-first) as a hint
    work_limit: float | None = None  # units of deterministic work instead of time_limit seconds
    # time.perf_counter() when the time limit started counting (None: when the allocation starts);
    # the command line starts it with the command, so that reading a large fleet counts too
    counted_from: float | None = None

    @property
    def budget(self) -> Budget:
        """The whole run's budget: the time limit, or the work limit when one is given."""
        return Budget(self.time_limit, self.work_limit)

    def __post_init__(self) -> None:
        """CP-SAT's own ranges, checked here so that a bad value is the caller's located error
        rather than the solver's failure (a seed over 32 bits is a TypeError inside it; tens of
        thousands of threads fail the search at once, which would read as a timeout)."""
        for name, value, high in (("workers", self.workers, MAX_WORKERS), ("seed", self.seed, MAX_SEED)):
            low = 1 if name == "workers" else 0
            if isinstance(value, bool) or not isinstance(value, int) or not low <= value <= high:
                raise MissionError(f"{value!r} is out of range: give a whole number from {low} to {high}", f"--{name}")
        for name, limit in (("time-limit", self.time_limit), ("work-limit", self.work_limit)):
            if limit is not None and (isinstance(limit, bool) or not isinstance(limit, (int, float))
                                      or not 0 < limit < float("inf")):
                raise MissionError(f"{limit!r} is not a limit: give a positive number", f"--{name}")
