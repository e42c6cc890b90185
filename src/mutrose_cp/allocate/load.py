"""The load relaxation: the decomposition chosen, the robots pooled by what they can do.

A second lower bound, independent of the search and cheap on large fleets where the LP
(:mod:`.bounds`) is slow, and a decomposition that spreads the work over the fleet for the warm
start (:mod:`.warmstart`).  A small CP-SAT model on a copy of the decomposition model keeps the
choice of decomposition exact and forgets which robot does what and when:

* **pools**: for every set ``S`` of robots that is the candidate set of a job, or the robots
  able to do two jobs that must share their robots (or a union of such sets), the jobs only
  robots of ``S`` can execute keep those robots busy for ``duration * RobotNumber.min`` each (a
  job that must share its robots with a chosen job counts in the pool of the robots able to do
  both), and every place where such a job is done must be reached by one of them, at least at
  its *cheapest way in* for ``S`` (0 when one of them starts there); all of that fits in
  ``|S| * makespan``;
* **chains**: a job starts after the earliest arrival of an able robot and after its
  predecessors end, and, when a predecessor must be done by the same robots (an execution
  constraint), after their quickest trip from its place; it ends by the makespan;
* **travel**: every place where a chosen job is done is reached once, at its cheapest way in;
* **shared robots**: two jobs that must share their robots are not both chosen when fewer
  robots than either needs can do both.

Each is a consequence of every rule of the allocation, so the relaxation's optimum, and
*CP-SAT's proven bound* on it when the search is cut short, bound the objective from below.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Iterable

from ortools.sat.python import cp_model

from ..solve.embedding import cp_literal
from ..solve.native import cmh

from .budget import NEVER, Budget, Deadline, OutOfTime
from .fleet import Robot
from .model import horizon, literal_value
from .options import Objective
from .problem import AllocationProblem, Job

MAX_POOLS = 64  # candidate sets and their unions; beyond it only the candidate sets themselves


@dataclass(frozen=True)
class LoadBound:
    """The relaxation's proven lower bound on the objective, and the decompositions of the best
    relaxed solution and of the least work among the best (none when none was found in time)."""

    value: float | None  # None: the relaxation is infeasible, or nothing was found in time
    status: str  # "OPTIMAL" (the relaxation solved), "FEASIBLE" (CP-SAT's bound at its limit), ...
    decompositions: tuple[list[str], ...]
    seconds: float


def load_bound(problem: AllocationProblem, objective: Objective, budget: Budget, workers: int = 1,
               seed: int = 0) -> LoadBound:
    """Solve the relaxation (see the module docstring) within ``budget``: half of it for the
    bound, the rest for the decomposition of least work among the best relaxed ones.  A
    relaxation whose building outlasts ``budget`` gives nothing (status ``MaxTime``)."""
    from ..solve.run import FEASIBLE, OPTIMAL

    started = time.perf_counter()
    try:
        m, chosen, goal = _relaxation(problem, objective, NEVER if budget.deterministic else budget.deadline())
    except OutOfTime:
        return LoadBound(None, "MaxTime", (), time.perf_counter() - started)
    response = _solve(m, budget.part(0.5), workers, seed)
    if response.status not in (OPTIMAL, FEASIBLE):  # infeasible: the search says why
        return LoadBound(None, response.status.name, (), time.perf_counter() - started)
    bound = float(response.best_objective_bound)
    status = "OPTIMAL" if response.status == OPTIMAL else "FEASIBLE"
    values = list(response.solution)
    m.add(goal <= round(response.objective_value))
    m.minimize(cp_model.LinearExpr.weighted_sum(list(chosen.values()), [problem.jobs[d].duration * problem.jobs[d].robots.min
                                                                        for d in chosen]))
    for index, value in enumerate(values):
        m.proto.solution_hint.vars.append(index)
        m.proto.solution_hint.values.append(value)
    lighter = _solve(m, budget.rest(started, 0.5), workers, seed)
    solutions = [values] + ([list(lighter.solution)] if lighter.status in (OPTIMAL, FEASIBLE) else [])
    picked = tuple([d for d, literal in chosen.items() if literal_value(solution, literal)] for solution in solutions)
    return LoadBound(bound, status, picked, time.perf_counter() - started)


def _relaxation(problem: AllocationProblem, objective: Objective, deadline: Deadline = NEVER
                ) -> tuple[cp_model.CpModel, dict[str, Any], cp_model.LinearExpr]:
    """The relaxed model on a copy of the decomposition model, the literals of the jobs and the
    relaxed objective; :class:`~.budget.OutOfTime` when the ``deadline`` passes first."""
    m = problem.dm.model.clone()
    chosen = {d: cp_literal(m, problem.dm.decomposition[d].index) for d in problem.jobs}
    for d in problem.dm.decomposition:
        if d not in problem.jobs or len(problem.jobs[d].candidates) < problem.jobs[d].robots.min:
            m.add_bool_or([cp_literal(m, problem.dm.decomposition[d].index).Not()])
    _shared_robots(m, problem, chosen)
    longest = horizon(problem)  # the joint model's: every schedule of it fits, so the bound stays one
    makespan = m.new_int_var(0, longest, "load_makespan")
    ways = ways_in(problem, deadline)
    _pools(m, problem, chosen, ways, makespan, deadline)
    deadline.check()
    _chains(m, problem, chosen, makespan, longest)
    travel = _visits(m, problem, chosen, _distinct(problem.fleet.robots, ways, deadline), "all")
    goal = objective.makespan_weight * makespan + objective.travel_weight * travel
    m.minimize(goal)
    return m, chosen, goal


def _solve(m: cp_model.CpModel, budget: Budget, workers: int, seed: int) -> cmh.CpSolverResponse:
    from ..solve.run import FEASIBLE, INFEASIBLE, OPTIMAL, run_solver

    parameters = cmh.SatParameters()
    budget.limit(parameters, workers)
    parameters.num_workers = workers
    parameters.random_seed = seed
    return run_solver(m.proto, accept=(OPTIMAL, FEASIBLE, INFEASIBLE, cmh.CpSolverStatus.UNKNOWN),
                      parameters=parameters, what="the load relaxation")


def linked_candidates(problem: AllocationProblem) -> dict[str, dict[str, frozenset[str]]]:
    """For each job, the robots able to do it together with each job it must share its robots
    with (when both are chosen, its robots are among these), where they are fewer than its own
    candidates."""
    out: dict[str, dict[str, frozenset[str]]] = {}
    for first, second in problem.same_robots:
        a, b = problem.jobs[first], problem.jobs[second]
        both = problem.able(first) & problem.able(second)
        for job, partner in ((a, b), (b, a)):
            if both and both < problem.able(job.id):
                out.setdefault(job.id, {})[partner.id] = both
    return out


def pools(problem: AllocationProblem, linked: dict[str, dict[str, frozenset[str]]],
          deadline: Deadline = NEVER) -> list[frozenset[str]]:
    """The candidate sets of the jobs, alone and with the jobs they must share robots with
    (``linked``: :func:`linked_candidates`), and, while there are few, their unions (in a fixed
    order)."""
    together = {s for partners in linked.values() for s in partners.values()}
    found = sorted({problem.able(j) for j in problem.jobs if problem.jobs[j].candidates} | together, key=sorted)
    closed = set(found)
    frontier = list(found)
    while frontier and len(closed) < MAX_POOLS:
        deadline.check()
        grown = [a | b for a in frontier for b in found if not b <= a]
        frontier = sorted({s for s in grown if s not in closed}, key=sorted)[:MAX_POOLS - len(closed)]
        closed.update(frontier)
    return sorted(closed, key=lambda s: (len(s), sorted(s)))


def _pools(m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any],
           ways: dict[str, dict[str, int]], makespan: cp_model.IntVar, deadline: Deadline = NEVER) -> None:
    """Each pool's work and ways in fit in ``|S| * makespan``."""
    robots = problem.robots
    linked = linked_candidates(problem)
    members = _PoolMembers(m, problem, chosen, linked)
    for number, pool in enumerate(pools(problem, linked, deadline)):
        deadline.check()
        inside = members.of(pool, number)
        if not inside:
            continue
        work = cp_model.LinearExpr.weighted_sum(
            list(inside.values()), [problem.jobs[d].duration * problem.jobs[d].robots.min for d in inside])
        entered = _visits(m, problem, inside, _distinct((robots[r] for r in pool), ways, deadline), f"pool{number}",
                          [problem.jobs[d] for d in inside])
        m.add(work + entered <= len(pool) * makespan)


class _PoolMembers:
    """Which chosen jobs keep a pool's robots busy: those only its robots can do, and those that
    must share their robots with a chosen job such that only the pool's robots can do both (an
    item fetched and handed over by one robot needs a robot that can do both)."""

    def __init__(self, m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any],
                 linked: dict[str, dict[str, frozenset[str]]]) -> None:
        self.m = m
        self.problem = problem
        self.chosen = chosen
        self.linked = linked
        self.together: dict[tuple[str, str], Any] = {}

    def of(self, pool: frozenset[str], number: int) -> dict[str, Any]:
        """Job id -> the literal that puts its work in ``pool``."""
        inside: dict[str, Any] = {}
        for job in self.problem.jobs.values():
            if job.candidates and self.problem.able(job.id) <= pool:
                inside[job.id] = self.chosen[job.id]
                continue
            pairs = [self._both(job.id, e) for e, both in self.linked.get(job.id, {}).items() if both <= pool]
            if pairs:  # in the pool exactly when it is chosen with one of these partners
                member = inside[job.id] = self.m.new_bool_var(f"in_pool[{number},{job.id}]")
                self.m.add_bool_or(pairs).only_enforce_if(member)
                for pair in pairs:
                    self.m.add_implication(pair, member)
        return inside

    def _both(self, job: str, partner: str) -> Any:
        """A literal true exactly when ``job`` and ``partner`` are both chosen."""
        key = (min(job, partner), max(job, partner))
        if key not in self.together:
            both = self.together[key] = self.m.new_bool_var(f"together[{key[0]},{key[1]}]")
            self.m.add_bool_and([self.chosen[job], self.chosen[partner]]).only_enforce_if(both)
            self.m.add_bool_or([self.chosen[job].Not(), self.chosen[partner].Not(), both])
        return self.together[key]


def _distinct(members: Iterable[Robot], ways: dict[str, dict[str, int]], deadline: Deadline = NEVER
              ) -> list[dict[str, int]]:
    """The ways in of ``members`` (:func:`ways_in`), each table once: robots of one kind share
    theirs, so a pool of thousands of robots has a few.  A robot without a start has none (an
    empty table: every place is free to it)."""
    out: dict[int, dict[str, int]] = {}
    for number, robot in enumerate(members):
        if number % 4096 == 0:
            deadline.check()
        table = ways.get(robot.name, NO_WAYS)
        out.setdefault(id(table), table)
    return list(out.values())


NO_WAYS: dict[str, int] = {}  # the ways in of a robot without a start: none cost anything


def _visits(m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any],
            tables: list[dict[str, int]], name: str, jobs: list[Job] | None = None) -> cp_model.LinearExpr:
    """The cheapest ways in, for the robots whose ways in are ``tables`` (:func:`_distinct`), to
    the places of ``jobs`` (default: every job) that are chosen (0 when one of them has no
    start)."""
    at: dict[str, list[str]] = {}
    for job in jobs if jobs is not None else problem.jobs.values():
        if job.location is not None:
            at.setdefault(job.location, []).append(job.id)
    costs, visits = [], []
    for place in sorted(at):
        cost = min((table.get(place, 0) for table in tables), default=0)
        if cost == 0:
            continue
        visit = m.new_bool_var(f"visit[{name},{place}]")
        for d in at[place]:
            m.add_implication(chosen[d], visit)
        costs.append(cost)
        visits.append(visit)
    return cp_model.LinearExpr.weighted_sum(visits, costs)


def ways_in(problem: AllocationProblem, deadline: Deadline = NEVER) -> dict[str, dict[str, int]]:
    """For each robot with a start, the shortest trip into each place: from its start or from a
    place where it could have worked before (0 at its start).  A robot without a start reaches
    its first place for free and is left out.  Robots of one kind (start, speed and
    capabilities, hence the same jobs) share one answer, computed once: a fleet of thousands is
    a few kinds.  Raises :class:`~.budget.OutOfTime` when the ``deadline`` passes first."""
    import numpy as np

    places = list(problem.travel.places)
    index = {p: i for i, p in enumerate(places)}
    distance = np.array(problem.travel.base, dtype=float).reshape(len(places), len(places))
    np.fill_diagonal(distance, np.inf)  # a way in comes from another place
    located: dict[frozenset[str], set[str]] = {}  # capabilities -> the places of the jobs they can do
    answers: dict[tuple[str, float, frozenset[str]], dict[str, int]] = {}
    out: dict[str, dict[str, int]] = {}
    for number, robot in enumerate(problem.fleet.robots):
        if number % 4096 == 0:
            deadline.check()
        if robot.start is None:
            continue
        kind = (robot.start, robot.speed, robot.capabilities)
        if kind not in answers:
            deadline.check()
            if not problem.travel.modelled:
                answers[kind] = dict.fromkeys(places, 0)
            else:
                if robot.capabilities not in located:
                    located[robot.capabilities] = {j.location for j in problem.jobs.values() if j.location is not None
                                                   and j.capabilities <= robot.capabilities}
                sources = sorted(index[s] for s in located[robot.capabilities] | {robot.start})
                cheapest = np.ceil(distance[sources] / robot.speed - 1e-9).min(axis=0)
                cheapest[index[robot.start]] = 0
                answers[kind] = {p: int(cheapest[i]) if np.isfinite(cheapest[i]) else 0 for i, p in enumerate(places)}
        out[robot.name] = answers[kind]
    return out


def _shared_robots(m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any]) -> None:
    """Two jobs that must share their robots are not both chosen when too few robots can do
    both."""
    for first, second in problem.same_robots:
        a, b = problem.jobs[first], problem.jobs[second]
        if len(problem.able(first) & problem.able(second)) < max(a.robots.min, b.robots.min):
            m.add_bool_or([chosen[first].Not(), chosen[second].Not()])


def _chains(m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any],
            makespan: cp_model.IntVar, horizon: int) -> None:
    """Starts after the earliest arrival and after the predecessors; ends by the makespan."""
    start = {d: m.new_int_var(0, horizon, f"load_start[{d}]") for d in problem.jobs}
    for d, job in problem.jobs.items():
        arrival = problem.earliest_arrival(job)
        if arrival:
            m.add(start[d] >= arrival).only_enforce_if(chosen[d])
        m.add(makespan >= start[d] + job.duration * chosen[d])
    shared = set(problem.same_robots) | {(b, a) for a, b in problem.same_robots}
    for first, second in problem.precedences:
        m.add(start[second] >= start[first] + problem.jobs[first].duration * chosen[first])
        trip = carry_time(problem, first, second) if (first, second) in shared else 0
        if trip:  # the same robots go from the first's place to the second's in between
            m.add(start[second] >= start[first] + problem.jobs[first].duration + trip).only_enforce_if(
                [chosen[first], chosen[second]])


def carry_time(problem: AllocationProblem, first: str, second: str) -> int:
    """The quickest trip from ``first``'s place to ``second``'s of a robot able to do both: the
    least time between them when the same robots do both (the trip times keep the triangle
    inequality, so a detour through other places is never quicker).  Between two given places
    the fastest robot is the quickest."""
    a, b = problem.jobs[first], problem.jobs[second]
    both = problem.able(second)
    able = [problem.robots[r] for r in a.candidates if r in both]
    if not able:
        return 0
    return problem.time(max(able, key=lambda r: r.speed), a.location, b.location)
