"""The schedule read from a solution: chosen jobs, teams, times, and each robot's route.

CP-SAT's start times are only as early as its objective asked (with the travel objective, a
job may start anywhere before the horizon).  The schedule is therefore *compacted*: the jobs
are taken in the order of the solution and each starts as early as its precedences and its
robots allow (each robot leaves when its previous job ends and travels from where it is).  The
robots' sequences, and so the travel, stay those of the solution; no time gets later.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

from .fleet import Robot
from .problem import AllocationProblem


@dataclass(frozen=True)
class Visit:
    """One job on one robot's timeline, and the trip that takes the robot there."""

    job: str
    start: int
    end: int
    travel: int  # time units of the trip right before the job (0: no trip)
    departure: int  # when the trip starts: the end of the robot's previous job (or 0)
    origin: str | None  # where the trip starts (the robot's place after its previous job)
    location: str | None


@dataclass(frozen=True)
class Schedule:
    """The chosen jobs (in mission order), their teams and times, and the robots' routes."""

    jobs: tuple[str, ...]
    teams: Mapping[str, tuple[str, ...]]
    start: Mapping[str, int]
    end: Mapping[str, int]
    routes: Mapping[str, tuple[Visit, ...]]  # robot -> its visits in time order (every robot listed)

    @property
    def makespan(self) -> int:
        return max(self.end.values(), default=0)

    @property
    def travel(self) -> int:
        return sum(v.travel for visits in self.routes.values() for v in visits)


def compact(problem: AllocationProblem, jobs: Sequence[str], teams: Mapping[str, tuple[str, ...]],
            start: Mapping[str, int], end: Mapping[str, int]) -> Schedule:
    """The schedule with the solution's sequences and every job as early as possible (see the
    module docstring); the solution's own times when that is not earlier (ties of jobs that
    take no time can order them differently)."""
    position = {j: i for i, j in enumerate(problem.jobs)}
    order = sorted(jobs, key=lambda j: (start[j], end[j], position[j]))
    predecessors = chosen_predecessors(problem, set(jobs))
    early_start: dict[str, int] = {}
    early_end: dict[str, int] = {}
    robots = problem.robots
    free = {r.name: 0 for r in problem.fleet.robots}
    place = {r.name: r.start for r in problem.fleet.robots}
    for j in order:
        job = problem.jobs[j]
        ready = max((early_end.get(i, end[i]) for i in predecessors[j]), default=0)
        for r in teams[j]:
            ready = max(ready, free[r] + problem.time(robots[r], place[r], job.location))
        early_start[j], early_end[j] = ready, ready + job.duration
        for r in teams[j]:
            free[r] = early_end[j]
            place[r] = job.location or place[r]
    if max(early_end.values(), default=0) > max(end.values(), default=0):
        early_start, early_end = dict(start), dict(end)
    return Schedule(tuple(sorted(jobs, key=position.__getitem__)), dict(teams), early_start, early_end,
                    _routes(problem, order, teams, early_start, early_end, robots))


def robot_sequences(problem: AllocationProblem, chosen: Sequence[str], teams: Mapping[str, tuple[str, ...]],
                    start: Mapping[str, int]) -> dict[str, list[str]]:
    """Each robot's jobs of ``chosen`` in the order it starts them (ties by job id).  Read from
    the teams, so that a large fleet costs one pass, not one per job."""
    out: dict[str, list[str]] = {r.name: [] for r in problem.fleet.robots}
    for j in chosen:
        for r in teams[j]:
            out[r].append(j)
    for jobs in out.values():
        if len(jobs) > 1:
            jobs.sort(key=lambda j: (start[j], j))
    return out


def robot_teams(sequences: Mapping[str, Sequence[str]], chosen: Sequence[str]) -> dict[str, tuple[str, ...]]:
    """The robots of each job of ``chosen``, from each robot's sequence of jobs (robots in the
    order of ``sequences``)."""
    teams: dict[str, list[str]] = {j: [] for j in chosen}
    for r, sequence in sequences.items():
        for j in sequence:
            if j in teams:
                teams[j].append(r)
    return {j: tuple(robots) for j, robots in teams.items()}


def chosen_predecessors(problem: AllocationProblem, chosen: set[str]) -> dict[str, list[str]]:
    """For each chosen job, the chosen jobs it must follow, also through jobs that are not
    chosen (those take no time and pass precedences on)."""
    before: dict[str, list[str]] = {}
    for first, second in problem.precedences:
        before.setdefault(second, []).append(first)
    out: dict[str, list[str]] = {}
    for j in chosen:
        found, seen, stack = [], set(), list(before.get(j, []))
        while stack:
            i = stack.pop()
            if i in seen:
                continue
            seen.add(i)
            if i in chosen:
                found.append(i)
            else:
                stack.extend(before.get(i, []))
        out[j] = found
    return out


def _routes(problem: AllocationProblem, order: list[str], teams: Mapping[str, tuple[str, ...]],
            start: Mapping[str, int], end: Mapping[str, int], robots: Mapping[str, Robot]) -> dict[str, tuple[Visit, ...]]:
    routes: dict[str, list[Visit]] = {r: [] for r in robots}
    place = {r.name: r.start for r in robots.values()}
    free = dict.fromkeys(robots, 0)
    rank = {j: i for i, j in enumerate(order)}
    for j in sorted(order, key=lambda j: (start[j], end[j], rank[j])):
        job = problem.jobs[j]
        for r in teams[j]:
            trip = problem.time(robots[r], place[r], job.location)
            routes[r].append(Visit(j, start[j], end[j], trip, free[r], place[r] if trip else None, job.location))
            free[r] = end[j]
            place[r] = job.location or place[r]
    return {r: tuple(v) for r, v in routes.items()}
