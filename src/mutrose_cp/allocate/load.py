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
from typing import Any

from ortools.sat.python import cp_model

from ..solve.embedding import cp_literal
from ..solve.native import cmh

from .budget import Budget
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
    bound, the rest for the decomposition of least work among the best relaxed ones."""
    from ..solve.run import FEASIBLE, OPTIMAL

    started = time.perf_counter()
    m, chosen, goal = _relaxation(problem, objective)
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


def _relaxation(problem: AllocationProblem, objective: Objective
                ) -> tuple[cp_model.CpModel, dict[str, Any], cp_model.LinearExpr]:
    """The relaxed model on a copy of the decomposition model, the literals of the jobs and the
    relaxed objective."""
    m = problem.dm.model.clone()
    chosen = {d: cp_literal(m, problem.dm.decomposition[d].index) for d in problem.jobs}
    for d in problem.dm.decomposition:
        if d not in problem.jobs or len(problem.jobs[d].candidates) < problem.jobs[d].robots.min:
            m.add_bool_or([cp_literal(m, problem.dm.decomposition[d].index).Not()])
    _shared_robots(m, problem, chosen)
    longest = horizon(problem)  # the joint model's: every schedule of it fits, so the bound stays one
    makespan = m.new_int_var(0, longest, "load_makespan")
    ways = ways_in(problem)
    _pools(m, problem, chosen, ways, makespan)
    _chains(m, problem, chosen, makespan, longest)
    travel = _visits(m, problem, chosen, ways, list(problem.fleet.robots), "all")
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
        both = frozenset(a.candidates) & frozenset(b.candidates)
        for job, partner in ((a, b), (b, a)):
            if both and both < frozenset(job.candidates):
                out.setdefault(job.id, {})[partner.id] = both
    return out


def pools(problem: AllocationProblem, linked: dict[str, dict[str, frozenset[str]]]) -> list[frozenset[str]]:
    """The candidate sets of the jobs, alone and with the jobs they must share robots with
    (``linked``: :func:`linked_candidates`), and, while there are few, their unions (in a fixed
    order)."""
    together = {s for partners in linked.values() for s in partners.values()}
    found = sorted({frozenset(j.candidates) for j in problem.jobs.values() if j.candidates} | together, key=sorted)
    closed = set(found)
    frontier = list(found)
    while frontier and len(closed) < MAX_POOLS:
        grown = [a | b for a in frontier for b in found if not b <= a]
        frontier = sorted({s for s in grown if s not in closed}, key=sorted)[:MAX_POOLS - len(closed)]
        closed.update(frontier)
    return sorted(closed, key=lambda s: (len(s), sorted(s)))


def _pools(m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any],
           ways: dict[str, dict[str, int]], makespan: cp_model.IntVar) -> None:
    """Each pool's work and ways in fit in ``|S| * makespan``."""
    robots = problem.robots
    linked = linked_candidates(problem)
    members = _PoolMembers(m, problem, chosen, linked)
    for number, pool in enumerate(pools(problem, linked)):
        inside = members.of(pool, number)
        if not inside:
            continue
        work = cp_model.LinearExpr.weighted_sum(
            list(inside.values()), [problem.jobs[d].duration * problem.jobs[d].robots.min for d in inside])
        entered = _visits(m, problem, inside, ways, [robots[r] for r in sorted(pool)], f"pool{number}",
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
            if job.candidates and set(job.candidates) <= pool:
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


def _visits(m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any],
            ways: dict[str, dict[str, int]], members: list[Robot], name: str,
            jobs: list[Job] | None = None) -> cp_model.LinearExpr:
    """The cheapest ways in, for ``members``, to the places of ``jobs`` (default: every job) that
    are chosen (0 when one of them has no start)."""
    at: dict[str, list[str]] = {}
    for job in jobs if jobs is not None else problem.jobs.values():
        if job.location is not None:
            at.setdefault(job.location, []).append(job.id)
    costs, visits = [], []
    for place in sorted(at):
        cost = min((ways.get(r.name, {}).get(place, 0) for r in members), default=0)
        if cost == 0:
            continue
        visit = m.new_bool_var(f"visit[{name},{place}]")
        for d in at[place]:
            m.add_implication(chosen[d], visit)
        costs.append(cost)
        visits.append(visit)
    return cp_model.LinearExpr.weighted_sum(visits, costs)


def ways_in(problem: AllocationProblem) -> dict[str, dict[str, int]]:
    """For each robot with a start, the shortest trip into each place: from its start or from a
    place where it could have worked before (0 at its start).  A robot without a start reaches
    its first place for free and is left out."""
    import numpy as np

    places = list(problem.travel.places)
    index = {p: i for i, p in enumerate(places)}
    distance = np.array(problem.travel.base, dtype=float).reshape(len(places), len(places))
    out: dict[str, dict[str, int]] = {}
    for robot in problem.fleet.robots:
        if robot.start is None:
            continue
        if not problem.travel.modelled:
            out[robot.name] = dict.fromkeys(places, 0)
            continue
        trips = np.ceil(distance / robot.speed - 1e-9)
        np.fill_diagonal(trips, np.inf)  # a way in comes from another place
        sources = {robot.start} | {j.location for j in problem.jobs.values()
                                   if j.location is not None and robot.name in j.candidates}
        rows = trips[sorted(index[s] for s in sources)]
        cheapest = rows.min(axis=0)
        cheapest[index[robot.start]] = 0
        out[robot.name] = {p: int(cheapest[index[p]]) if np.isfinite(cheapest[index[p]]) else 0 for p in places}
    return out


def _shared_robots(m: cp_model.CpModel, problem: AllocationProblem, chosen: dict[str, Any]) -> None:
    """Two jobs that must share their robots are not both chosen when too few robots can do
    both."""
    for first, second in problem.same_robots:
        a, b = problem.jobs[first], problem.jobs[second]
        if len(set(a.candidates) & set(b.candidates)) < max(a.robots.min, b.robots.min):
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
    inequality, so a detour through other places is never quicker)."""
    a, b = problem.jobs[first], problem.jobs[second]
    robots = problem.robots
    return min((problem.time(robots[r], a.location, b.location) for r in a.candidates if r in b.candidates),
               default=0)
