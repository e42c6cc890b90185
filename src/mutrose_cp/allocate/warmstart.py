"""A first schedule, handed to CP-SAT as a hint: decomposition first, then list scheduling.

1. The decomposition: the least total work, found exactly by the decomposer's optimisation
   (``decompose --optimize`` with the fleet's action durations as costs), or the one of the
   load relaxation (:mod:`.load`), which spreads the work over the robots able to do it; the
   one whose schedule ends first is kept.
2. The allocation, by list scheduling: of the jobs whose predecessors are placed, the one that
   can end soonest goes next, on the able robots that can be there first (where it must share
   robots with a job already placed, those robots); it starts when its predecessors have ended
   and its robots arrived.  Taking the jobs in mission order instead would send each robot to
   all its first tasks before any second one, far and back.
3. Local moves (:mod:`.improve`): tasks moved off the robot that finishes last, each move
   evaluated exactly, while the schedule gets better.

The hint only guides the search: CP-SAT checks it like any other assignment, and a mission
where the greedy step gets stuck (a decomposition needs robots that the greedy choice used up)
is simply searched without a hint.
"""
from __future__ import annotations

import heapq
import time
from dataclasses import dataclass
from graphlib import TopologicalSorter
from typing import Sequence

from ..errors import MissionError
from ..solve.decompose import DecompositionRequest, decompose
from ..solve.optimize import CostModel
from ..solve.run import IncompleteSolveError
from .budget import NEVER, Budget, Deadline, OutOfTime
from .improve import improve_schedule
from .model import START, AllocationModel
from .options import Objective
from .problem import AllocationProblem
from .schedule import Schedule, chosen_predecessors, compact, robot_sequences

Plan = tuple[dict[str, tuple[str, ...]], dict[str, int]]  # teams and start times of the chosen jobs
MIN_IMPROVEMENT = 0.01  # seconds: a clock budget below this leaves the list schedule unimproved
MOVES_SHARE = 0.9  # of the budget, for the local moves: the rest is kept for the hint's decomposition values


@dataclass(frozen=True)
class WarmStart:
    """The greedy schedule: the chosen jobs, their teams and start times."""

    chosen: list[str]
    teams: dict[str, tuple[str, ...]]
    start: dict[str, int]
    # every variable of the decomposition model, by proto index (None: not found in time, the hint
    # leaves them to CP-SAT)
    decomposition_values: list[int] | None
    improvement: str = "done"  # the local moves: "done", "cut" by their budget, or "skipped" (no time)

    def schedule(self, problem: AllocationProblem) -> Schedule:
        """The warm start as a schedule of its own (compacted like a search's solution)."""
        end = {j: self.start[j] + problem.jobs[j].duration for j in self.chosen}
        return compact(problem, self.chosen, self.teams, self.start, end)

    def route_arcs(self, problem: AllocationProblem) -> set[tuple[str, str, str]]:
        """``(robot, source, target)`` for the arcs of every robot's route (from ``START`` for
        its first located job)."""
        arcs: set[tuple[str, str, str]] = set()
        for robot, route in _routes(problem, self).items():
            arcs |= {(robot, a, b) for a, b in zip([START] + route, route)}
        return arcs


def warm_start(problem: AllocationProblem, balanced: Sequence[list[str]] = (), objective: Objective = Objective(),
               budget: Budget = Budget(10.0), seed: int = 0, floor: float | None = None,
               deadline: Deadline = NEVER) -> WarmStart | None:
    """The list schedule of the least-work decomposition or of one of ``balanced`` (the load
    relaxation's), whichever is best for ``objective`` once improved by local moves
    (:mod:`.improve`): a quarter of ``budget`` shared by all, the rest for the best of them,
    none once one reaches ``floor`` (a lower bound on the objective); None when there is
    none.  The list schedules are made by the ``deadline``: those made by then are all there
    is (:class:`~.budget.OutOfTime` when not even the first is); the decomposition's values too
    (without them the hint leaves those variables to CP-SAT).  The local moves take
    :data:`MOVES_SHARE` of ``budget``; a clock budget too short for any move leaves the list
    schedule as it is (``improvement`` "skipped")."""
    started = time.perf_counter()
    deadline.check()
    candidates = [c for c in (*balanced, least_work_decomposition(problem))
                  if c is not None and all(d in problem.jobs for d in c)]
    budget = budget.part(MOVES_SHARE) if not budget.deterministic else budget
    moves = budget.deterministic or budget.rest(started).seconds >= MIN_IMPROVEMENT
    plans: list[tuple[float, int, list[str], Plan]] = []
    cut = False
    for number, chosen in enumerate(candidates):
        try:
            plan = greedy_plan(problem, chosen, deadline)
        except OutOfTime:
            if not plans:
                raise
            break  # the schedules made so far are all there is time for
        if plan is None:
            continue
        left = len(candidates) - number  # an equal part, for each candidate left, of the quarter left
        share = budget.part(0.25).rest(started, left / len(candidates)).part(1 / left) if moves else Budget(0.0)
        found = improve_schedule(problem, chosen, *plan, objective, share, seed, floor)  # no budget: its value
        plans.append((found.value, len(plans), chosen, (found.teams, found.start)))
        cut = cut or found.cut
    plans.sort(key=lambda p: p[:2])
    if plans and moves:
        _, _, chosen, plan = plans[0]
        found = improve_schedule(problem, chosen, *plan, objective, budget.rest(started, 0.75), seed + 1, floor)
        plans[0] = (found.value, 0, chosen, (found.teams, found.start))
        cut = cut or found.cut
    improvement = "skipped" if not moves else "cut" if cut else "done"
    for _, _, chosen, plan in plans:
        try:
            values = _decomposition_values(problem, set(chosen), deadline)
        except OutOfTime:  # a schedule all the same: the hint leaves the decomposition model's variables open
            return WarmStart(chosen, *plan, None, improvement)
        if values is not None:
            return WarmStart(chosen, *plan, values, improvement)
    return None


def _decomposition_values(problem: AllocationProblem, chosen: set[str], deadline: Deadline = NEVER) -> list[int] | None:
    """The values of all the decomposition model's variables for ``chosen`` (its auxiliary
    variables included), so that the hint is complete: found by CP-SAT on a copy of the model
    (before the allocation is added to it) with the decompositions fixed, by the ``deadline``."""
    from ..solve.native import cmh
    from ..solve.run import FEASIBLE, INFEASIBLE, OPTIMAL, run_solver

    proto = cmh.CpModelProto()
    proto.copy_from(problem.dm.model.proto)
    for d, literal in problem.dm.decomposition.items():
        index = literal.index
        c = proto.constraints.add()
        c.bool_or.literals.append(index if (d in chosen) else -index - 1)
    parameters = cmh.SatParameters()
    parameters.num_workers = 1
    if deadline.passed():
        raise OutOfTime
    if deadline.left() < float("inf"):
        parameters.max_time_in_seconds = deadline.left()
    try:
        response = run_solver(proto, accept=(OPTIMAL, FEASIBLE, INFEASIBLE), parameters=parameters,
                              what="the warm start")
    except IncompleteSolveError:
        raise OutOfTime from None
    return None if response.status == INFEASIBLE else list(response.solution)


def least_work_decomposition(problem: AllocationProblem) -> list[str] | None:
    """The valid mission decomposition with the least total work (ids, in mission order)."""
    mission = problem.dm.mission
    durations = problem.fleet.durations
    costs = CostModel(actions={a.name: durations.of_action(a.name, a.capabilities) for a in mission.domain.actions})
    try:
        result = decompose(mission, DecompositionRequest(optimize=True, costs=costs))
    except MissionError:
        return None
    if result.optimum is None:
        return None
    tg = mission.task_graph
    ids = [tg.vertices[v].content for v in result.optimum[0]]
    return ids if all(d in problem.jobs for d in ids) else None


def greedy_plan(problem: AllocationProblem, chosen: list[str], deadline: Deadline = NEVER) -> Plan | None:
    """Teams and start times for ``chosen`` by list scheduling (see the module docstring), None
    when stuck; :class:`~.budget.OutOfTime` when the ``deadline`` passes first."""
    return _ListScheduler(problem, chosen, deadline).run()


class _ListScheduler:
    """Earliest finish first: of the jobs whose predecessors are placed, the one that can end
    soonest is placed next, on the robots that get it done soonest.  Estimates are refreshed
    lazily: a job whose estimate grew since it was queued goes back into the queue.  The robots
    that have not moved yet are taken by kind (start and speed, :meth:`~.problem.AllocationProblem.nearest`),
    the others one by one, so that a fleet of thousands costs little more than its busy robots."""

    def __init__(self, problem: AllocationProblem, chosen: list[str], deadline: Deadline = NEVER) -> None:
        self.problem = problem
        self.deadline = deadline
        self.moved: set[str] = set()  # robots placed on a job: no longer where they started
        self.able: dict[str, tuple[tuple[str, ...], frozenset[str]]] = {}
        self.robots = problem.robots
        self.free = dict.fromkeys(self.robots, 0)
        self.place = {r.name: r.start for r in problem.fleet.robots}
        self.partners = _partners(problem, set(chosen))
        self.before = chosen_predecessors(problem, set(chosen))
        self.position = {j: i for i, j in enumerate(problem.jobs)}
        self.teams: dict[str, tuple[str, ...]] = {}
        self.start: dict[str, int] = {}
        self.chosen = chosen

    def run(self) -> Plan | None:
        after: dict[str, list[str]] = {}
        waiting = {j: len(self.before[j]) for j in self.chosen}
        for j in self.chosen:
            for i in self.before[j]:
                after.setdefault(i, []).append(j)
        queue = [(0, self.position[j], j) for j in self.chosen if not waiting[j]]
        heapq.heapify(queue)
        while queue:
            self.deadline.check()
            _, rank, j = heapq.heappop(queue)
            option = self._best(j)
            if option is None:
                return None
            ready, team = option
            finish = ready + self.problem.jobs[j].duration
            if queue and (finish, rank) > queue[0][:2]:
                heapq.heappush(queue, (finish, rank, j))  # another job may end sooner now
                continue
            self._place(j, ready, team)
            for k in after.get(j, []):
                waiting[k] -= 1
                if not waiting[k]:
                    heapq.heappush(queue, (0, self.position[k], k))
        return (self.teams, self.start) if len(self.teams) == len(self.chosen) else None

    def _arrival(self, r: str, location: str | None) -> int:
        return self.free[r] + self.problem.time(self.robots[r], self.place[r], location)

    def _best(self, j: str) -> tuple[int, tuple[str, ...]] | None:
        """The earliest start of ``j`` and its team: the robots already bound to it by a shared
        robot rule, or else the able ones that can be there first."""
        job, problem = self.problem.jobs[j], self.problem
        ready = max((self.start[i] + problem.jobs[i].duration for i in self.before[j]), default=0)
        placed = [self.teams[p] for p in self.partners.get(j, []) if p in self.teams]
        if placed:
            team = placed[0]
        else:
            able, members = self._able(j)
            first = problem.nearest(able, job.location, job.robots.min, ready, self.moved, self.deadline)
            options = first + [r for r in self.moved if r in members]
            team = tuple(sorted(options, key=lambda r: (max(ready, self._arrival(r, job.location)), r))[:job.robots.min])
        if len(team) < job.robots.min or not set(team) <= problem.able(j) or len(team) > job.robots.max:
            return None
        return max([ready] + [self._arrival(r, job.location) for r in team]), team

    def _able(self, j: str) -> tuple[tuple[str, ...], frozenset[str]]:
        """The robots able to do ``j`` and every job it must share its robots with (in fleet
        order, and as a set), once per job."""
        if j not in self.able:
            jobs = self.problem.jobs
            needed = jobs[j].capabilities.union(*(jobs[p].capabilities for p in self.partners.get(j, [])))
            able = self.problem.having(needed)  # the robots able to do every one of them
            self.able[j] = (able, self.problem.members(able))
        return self.able[j]

    def _place(self, j: str, start: int, team: tuple[str, ...]) -> None:
        job = self.problem.jobs[j]
        self.teams[j], self.start[j] = team, start
        self.moved.update(team)
        for r in team:
            self.free[r] = start + job.duration
            self.place[r] = job.location or self.place[r]


def _partners(problem: AllocationProblem, chosen: set[str]) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for a, b in problem.same_robots:
        if a in chosen and b in chosen:
            out.setdefault(a, []).append(b)
            out.setdefault(b, []).append(a)
    return out


def add_hint(am: AllocationModel, warm: WarmStart) -> None:
    """Every variable of the model, from the warm start (a complete hint is one CP-SAT can take
    as its first solution without a search)."""
    m, problem = am.model, am.problem
    teams = warm.teams
    picked = set(warm.chosen)
    for index, value in enumerate(warm.decomposition_values or ()):
        m.proto.solution_hint.vars.append(index)
        m.proto.solution_hint.values.append(value)
    for (j, r), a in am.assign.items():
        m.add_hint(a, j in picked and r in teams[j])
    start = _all_starts(problem, warm)
    for j in problem.jobs:
        m.add_hint(am.start[j], start[j])
        m.add_hint(am.end[j], start[j] + (problem.jobs[j].duration if j in picked else 0))
    used = warm.route_arcs(problem)
    for robot, arcs in am.arcs.items():
        for arc in arcs:
            m.add_hint(arc.literal, (robot, arc.source, arc.target) in used)
    routes = _routes(problem, warm)
    for robot, idle in am.idle.items():
        m.add_hint(idle, robot not in routes)
    for (j, robot), literal in am.last.items():
        m.add_hint(literal, robot in routes and routes[robot][-1] == j)
    if am.makespan is not None:
        m.add_hint(am.makespan, max((start[j] + problem.jobs[j].duration for j in picked), default=0))


def _routes(problem: AllocationProblem, warm: WarmStart) -> dict[str, list[str]]:
    """The located jobs of each robot that has any, in order (an idle robot is left out)."""
    return {r: route for r, jobs in robot_sequences(problem, warm.chosen, warm.teams, warm.start).items()
            if jobs and (route := [j for j in jobs if problem.jobs[j].location is not None])}


def _all_starts(problem: AllocationProblem, warm: WarmStart) -> dict[str, int]:
    """The warm start's times, and for the jobs not chosen the end of their latest predecessor
    (they take no time and pass the precedences on)."""
    before: dict[str, list[str]] = {}
    for first, second in problem.precedences:
        before.setdefault(second, []).append(first)
    order = TopologicalSorter({j: before.get(j, []) for j in problem.jobs}).static_order()
    start: dict[str, int] = {}
    end: dict[str, int] = {}
    for j in order:
        if j in warm.start:
            start[j] = warm.start[j]
            end[j] = start[j] + problem.jobs[j].duration
        else:
            start[j] = end[j] = max((end[i] for i in before.get(j, [])), default=0)
    return start
