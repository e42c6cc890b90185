"""Large missions: the search restricted to near robots and near predecessors.

Each robot's route has an arc for every pair of jobs it may do one after the other, so the
model grows with the square of the jobs per robot: 80 deliveries on 10 robots make half a
million arcs, which CP-SAT cannot even presolve within a minute.  Above a budget, the model
keeps only

* for each job, the robots that can be there soonest from their start (at least as many as
  it needs, and at least ``CANDIDATE_BUDGET / jobs``), and
* for each job, the arcs from the jobs at the nearest places (at least ``ARC_BUDGET`` arcs in
  all, spread over the jobs), and from every robot's start,

plus, always, the robots and arcs of the warm start, so the restricted model keeps a known
schedule.  The restriction is a heuristic: its optimum can be worse than the mission's, so a
restricted search never reports its own bound or optimality, only the LP bound, which holds
for the whole problem.
"""
from __future__ import annotations

from dataclasses import dataclass

from .budget import NEVER, Deadline
from .problem import AllocationProblem

CANDIDATE_BUDGET = 6_000  # (job, robot) pairs
ARC_BUDGET = 60_000  # route arcs over all robots


@dataclass(frozen=True)
class Restriction:
    """The robots kept per job and the predecessors kept per job; ``None``: all of them."""

    candidates: dict[str, tuple[str, ...]] | None = None
    predecessors: dict[str, set[str]] | None = None

    @property
    def active(self) -> bool:
        return self.candidates is not None or self.predecessors is not None

    def robots_of(self, problem: AllocationProblem, job: str) -> tuple[str, ...]:
        return problem.jobs[job].candidates if self.candidates is None else self.candidates[job]

    def allows(self, source: str, target: str) -> bool:
        return self.predecessors is None or source in self.predecessors[target]


def restrict(problem: AllocationProblem, keep_teams: dict[str, tuple[str, ...]] | None = None,
             keep_arcs: set[tuple[str, str]] | None = None, deadline: Deadline = NEVER) -> Restriction:
    """The restriction for ``problem`` (none when it is small enough), keeping the warm start's
    teams and route arcs; :class:`~.budget.OutOfTime` when the ``deadline`` passes first."""
    candidates = _near_robots(problem, keep_teams or {}, deadline)
    per_robot = _located_jobs_per_robot(problem, candidates)
    arcs = sum(n * n for n in per_robot.values())
    predecessors = None
    if arcs > ARC_BUDGET:
        nodes = sum(per_robot.values())
        predecessors = _near_predecessors(problem, max(3, ARC_BUDGET // max(nodes, 1)), keep_arcs or set(), deadline)
    return Restriction(candidates, predecessors)


def is_large(problem: AllocationProblem) -> bool:
    """Whether :func:`restrict` restricts ``problem``, without building the restriction (the
    allocation shares its time limit by it before the warm start)."""
    if sum(len(j.candidates) for j in problem.jobs.values()) > CANDIDATE_BUDGET:
        return True
    return sum(n * n for n in _located_jobs_per_robot(problem, None).values()) > ARC_BUDGET


def _located_jobs_per_robot(problem: AllocationProblem, candidates: dict[str, tuple[str, ...]] | None
                            ) -> dict[str, int]:
    per_robot: dict[str, int] = {}
    for job in problem.jobs.values():
        if job.location is None:
            continue
        for r in (job.candidates if candidates is None else candidates[job.id]):
            per_robot[r] = per_robot.get(r, 0) + 1
    return per_robot


def _near_robots(problem: AllocationProblem, keep: dict[str, tuple[str, ...]],
                 deadline: Deadline) -> dict[str, tuple[str, ...]] | None:
    """For each job, the robots that can be there first from their start (ties by name), and
    the warm start's, in fleet order."""
    pairs = sum(len(j.candidates) for j in problem.jobs.values())
    if pairs <= CANDIDATE_BUDGET:
        return None
    per_job = max(3, CANDIDATE_BUDGET // len(problem.jobs))
    index = problem.index
    out = {}
    for job in problem.jobs.values():
        deadline.check()
        near = problem.nearest(job.candidates, job.location, max(per_job, job.robots.max), deadline=deadline)
        kept = set(near) | set(keep.get(job.id, ()))
        out[job.id] = tuple(sorted(kept, key=index.__getitem__))
    return out


def _near_predecessors(problem: AllocationProblem, k: int, keep: set[tuple[str, str]],
                       deadline: Deadline = NEVER) -> dict[str, set[str]]:
    """For each job, the jobs at the places nearest to it (its own first) until ``k`` are
    found, and the warm start's predecessor; every job without a place is kept."""
    at: dict[str, list[str]] = {}
    unplaced = []
    for job in problem.jobs.values():
        if job.location is None:
            unplaced.append(job.id)
        else:
            at.setdefault(job.location, []).append(job.id)
    unit = problem.fleet.robots[0]
    nearest: dict[str, list[str]] = {}
    for place in at:
        deadline.check()
        order = sorted(at, key=lambda p: (problem.travel.time(unit, p, place), p))
        found: list[str] = []
        for p in order:
            found += at[p]
            if len(found) >= k:
                break
        nearest[place] = found
    out = {}
    for job in problem.jobs.values():
        out[job.id] = set(nearest.get(job.location, [])) | set(unplaced) if job.location else set(problem.jobs)
    for source, target in keep:
        out[target].add(source)
    return out
