"""A lower bound on the objective from the LP relaxation of the allocation, solved by Clarabel.

It is independent of CP-SAT: a cheap certificate that the schedule found is within a given gap
of the optimum, whatever the search did.  Variables in [0, 1]:

* the boolean variables of the decomposition model (``dm.encoding``), with its clauses,
  exactly-ones and AND/OR definitions relaxed linearly (numeric world records are dropped,
  which only enlarges the set); ``y[d]`` is the relaxed "decomposition ``d`` is chosen";
* ``x[d, r]``: robot ``r`` executes ``d``, with ``x <= y``, ``min y <= sum_r x <= max y``, and
  ``x[d1, r] - x[d2, r] <= 1 - y[d2]`` for jobs that share their robots;
* ``v[l, r]``: robot ``r`` visits place ``l``, ``v >= x[d, r]`` for each job ``d`` at ``l``.
  Each place a robot visits costs at least its *cheapest way in*: the shortest trip to it from
  the robot's start or another place it may work at (``in[l, r]``).

Constraints on the makespan ``M``: each robot's work and trips, ``sum_d dur_d x[d, r] + sum_l
in[l, r] v[l, r] <= M``; start times after the earliest arrival of a robot and along the
precedence chains, ``s[d] + dur_d y[d] <= M``; and chains along the goal model's operators (a
task lasts ``sum_d dur_d y[d]``; ``;``, FALLBACK and OR add their children up, ``#`` takes the
largest), which keep the OR choice exact where fractional ``y`` would lose it.  The total
travel is bounded by ``sum in[l, r] v[l, r]``.  The LP minimises the objective's weighted sum.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Iterable

from ..model.task_graph import OperatorVertex, TaskGraph, TaskVertex
from ..solve.boolean_model import FALSE, TRUE, AndOf, Clause, Exactly, Lit, OrOf
from .budget import LP_ITERATIONS, Budget
from .load import ways_in
from .model import Objective
from .problem import AllocationProblem

Expr = tuple[dict[int, float], float]  # a linear expression: coefficients by column, constant


@dataclass(frozen=True)
class LpBound:
    """The LP optimum (``None`` when Clarabel did not solve it), Clarabel's status and time."""

    value: float | None
    status: str
    seconds: float


class _Lp:
    """Rows ``sum coef * var (<= | ==) rhs`` over named continuous variables."""

    def __init__(self) -> None:
        self.index: dict[object, int] = {}
        self.le: list[tuple[dict[int, float], float]] = []
        self.eq: list[tuple[dict[int, float], float]] = []

    def var(self, key: object, low: float | None = 0.0, high: float | None = None) -> Expr:
        if key not in self.index:
            j = self.index[key] = len(self.index)
            if low is not None:
                self.le.append(({j: -1.0}, -low))
            if high is not None:
                self.le.append(({j: 1.0}, high))
        return {self.index[key]: 1.0}, 0.0

    @staticmethod
    def _linear(terms: Iterable[tuple[float, Expr]]) -> tuple[dict[int, float], float]:
        row: dict[int, float] = {}
        constant = 0.0
        for coef, (linear, c) in terms:
            constant += coef * c
            for j, v in linear.items():
                row[j] = row.get(j, 0.0) + coef * v
        return row, constant

    def add_le(self, terms: Iterable[tuple[float, Expr]], rhs: float = 0.0) -> None:
        row, constant = self._linear(terms)
        self.le.append((row, rhs - constant))

    def add_eq(self, terms: Iterable[tuple[float, Expr]], rhs: float = 0.0) -> None:
        row, constant = self._linear(terms)
        self.eq.append((row, rhs - constant))


def lp_bound(problem: AllocationProblem, objective: Objective, budget: Budget | None = None) -> LpBound:
    """The LP relaxation's optimum, a lower bound on ``objective`` (see the module docstring).
    Clarabel stops at the clock ``budget`` (building the LP included), or after
    :data:`~.budget.LP_ITERATIONS` iterations on a work budget; an LP it did not solve gives no
    bound (``value`` None, ``status`` says why)."""
    started = time.perf_counter()
    lp = _Lp()
    y = _decomposition_relaxation(lp, problem)
    x = _assignments(lp, problem, y)
    visits = _visits(lp, problem, x)
    makespan = lp.var("M")
    for robot in problem.fleet.robots:
        load = [(float(problem.jobs[d].duration), e) for (d, r), e in x.items() if r == robot.name]
        load += [(cost, e) for (place, r), (cost, e) in visits.items() if r == robot.name]
        if load:
            lp.add_le(load + [(-1.0, makespan)])
    _start_times(lp, problem, y, makespan)
    _operator_chains(lp, problem, y, makespan)
    travel = [(cost, e) for cost, e in visits.values()]
    goal = [(float(objective.makespan_weight), makespan)] + [(objective.travel_weight * c, e) for c, e in travel]
    return _solve(lp, goal, started, budget)


def _decomposition_relaxation(lp: _Lp, problem: AllocationProblem) -> dict[str, Expr]:
    """The decomposition model's records, relaxed; the expression of each job's ``y``."""
    enc = problem.dm.encoding

    def lit(literal: Lit) -> Expr:
        if literal is TRUE:
            return {}, 1.0
        if literal is FALSE or not isinstance(literal, int):
            return {}, 0.0
        column, _ = lp.var(("b", abs(literal)), 0.0, 1.0)
        return (column, 0.0) if literal > 0 else ({j: -1.0 for j in column}, 1.0)

    for r in enc.model.records:
        match r:
            case Clause(lits=lits):
                lp.add_le([(-1.0, lit(v)) for v in lits], -1.0)  # at least one
            case Exactly(lits=lits, target=target):
                lp.add_eq([(1.0, lit(v)) for v in lits] + [(-1.0, lit(target))])
            case AndOf(lits=lits, target=target):
                _relaxed_and(lp, [lit(v) for v in lits], lit(target))
            case OrOf(lits=lits, target=target):
                _relaxed_or(lp, [lit(v) for v in lits], lit(target))
            case _:
                pass  # numeric world values: dropped, which only enlarges the set
    tg = problem.dm.mission.task_graph
    literal_of = {tg.vertices[v].content: literal for v, literal in enc.decomposition_lit.items()}
    return {d: lit(literal_of.get(d, FALSE)) for d in problem.jobs}


def _relaxed_and(lp: _Lp, parts: list[Expr], target: Expr) -> None:
    for e in parts:
        lp.add_le([(1.0, target), (-1.0, e)])
    lp.add_le([(1.0, e) for e in parts] + [(-1.0, target)], len(parts) - 1.0)


def _relaxed_or(lp: _Lp, parts: list[Expr], target: Expr) -> None:
    for e in parts:
        lp.add_le([(1.0, e), (-1.0, target)])
    lp.add_le([(1.0, target)] + [(-1.0, e) for e in parts])


def _assignments(lp: _Lp, problem: AllocationProblem, y: dict[str, Expr]) -> dict[tuple[str, str], Expr]:
    x: dict[tuple[str, str], Expr] = {}
    for d, job in problem.jobs.items():
        team = []
        for r in job.candidates:
            x[(d, r)] = lp.var(("x", d, r), 0.0, 1.0)
            team.append(x[(d, r)])
            lp.add_le([(1.0, x[(d, r)]), (-1.0, y[d])])
        lp.add_le([(float(job.robots.min), y[d])] + [(-1.0, e) for e in team])
        lp.add_le([(1.0, e) for e in team] + [(-float(job.robots.max), y[d])])
    none: Expr = ({}, 0.0)
    for d1, d2 in problem.same_robots:
        for r in set(problem.jobs[d1].candidates) | set(problem.jobs[d2].candidates):
            a1, a2 = x.get((d1, r), none), x.get((d2, r), none)
            lp.add_le([(1.0, a1), (-1.0, a2), (1.0, y[d2])], 1.0)
            lp.add_le([(1.0, a2), (-1.0, a1), (1.0, y[d1])], 1.0)
    return x


def _visits(lp: _Lp, problem: AllocationProblem, x: dict[tuple[str, str], Expr]) -> dict[tuple[str, str], tuple[float, Expr]]:
    """``(place, robot) -> (cheapest way in, v[place, robot])`` for the places that cost a trip."""
    out: dict[tuple[str, str], tuple[float, Expr]] = {}
    ways = ways_in(problem)  # a robot without a start reaches its first place for free: none there
    for robot in problem.fleet.robots:
        places = {p for (d, r) in x if r == robot.name and (p := problem.jobs[d].location) is not None}
        for place in places:
            cheapest = ways.get(robot.name, {}).get(place, 0)
            if cheapest > 0:
                out[(place, robot.name)] = (float(cheapest), lp.var(("v", place, robot.name), 0.0, 1.0))
    for (d, r), e in x.items():
        at = problem.jobs[d].location
        if at is not None and (at, r) in out:
            lp.add_le([(1.0, e), (-1.0, out[(at, r)][1])])
    return out


def _start_times(lp: _Lp, problem: AllocationProblem, y: dict[str, Expr], makespan: Expr) -> None:
    start = {d: lp.var(("s", d)) for d in problem.jobs}
    for d, job in problem.jobs.items():
        lp.add_le([(1.0, start[d]), (float(job.duration), y[d]), (-1.0, makespan)])
        arrival = problem.earliest_arrival(job)
        if arrival:
            lp.add_le([(float(arrival), y[d]), (-1.0, start[d])])
    for first, second in problem.precedences:
        lp.add_le([(1.0, start[first]), (float(problem.jobs[first].duration), y[first]), (-1.0, start[second])])


def _operator_chains(lp: _Lp, problem: AllocationProblem, y: dict[str, Expr], makespan: Expr) -> None:
    """The longest chain along the goal model's operators must fit in the makespan."""
    tg = problem.dm.mission.task_graph
    if not tg.vertices or tg.unique_branch:
        return
    memo: dict[int, Expr] = {}
    for v in _post_order(tg):
        vertex = tg.vertices[v]
        length = lp.var(("L", v))
        if isinstance(vertex, TaskVertex):
            lp.add_eq([(1.0, length)] + [(-float(problem.jobs[dv.content].duration), y[dv.content])
                                         for dv in tg.decompositions_of(v) if dv.content in problem.jobs])
        elif tg.is_or(v) or (isinstance(vertex, OperatorVertex) and vertex.content in (";", "FALLBACK")):
            lp.add_le([(-1.0, length)] + [(1.0, memo[c]) for c in tg.children(v)])
        else:
            for c in tg.children(v):
                lp.add_le([(-1.0, length), (1.0, memo[c])])
        memo[v] = length
    lp.add_le([(1.0, memo[0]), (-1.0, makespan)])


def _post_order(tg: TaskGraph) -> list[int]:
    """The vertices below the root, children before their parent (iteratively: goal models can
    be deep)."""
    order: list[int] = []
    stack: list[tuple[int, bool]] = [(0, False)]
    while stack:
        v, expanded = stack.pop()
        if expanded or isinstance(tg.vertices[v], TaskVertex):
            order.append(v)
            continue
        stack.append((v, True))
        stack.extend((c, False) for c in tg.children(v))
    return order


def _solve(lp: _Lp, goal: list[tuple[float, Expr]], started: float, budget: Budget | None) -> LpBound:
    import clarabel  # type: ignore[import-untyped]
    import numpy as np
    import scipy.sparse as sp  # type: ignore[import-untyped]

    n = len(lp.index)
    rows = lp.eq + lp.le
    data, row_index, column_index, rhs = [], [], [], []
    for i, (row, b) in enumerate(rows):
        for j, v in row.items():
            if v != 0.0:
                data.append(v)
                row_index.append(i)
                column_index.append(j)
        rhs.append(b)
    a = sp.csc_matrix((data, (row_index, column_index)), shape=(len(rows), n))
    q = np.zeros(n)
    for coef, (linear, _) in goal:
        for j, v in linear.items():
            q[j] += coef * v
    cones = ([clarabel.ZeroConeT(len(lp.eq))] if lp.eq else []) + [clarabel.NonnegativeConeT(len(lp.le))]
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    if budget is not None and budget.deterministic:
        settings.max_iter = LP_ITERATIONS
    elif budget is not None:
        left = budget.rest(started).seconds
        if left <= 0:
            return LpBound(None, "MaxTime", time.perf_counter() - started)
        settings.time_limit = left
    solution = clarabel.DefaultSolver(sp.csc_matrix((n, n)), q, a, np.array(rhs, dtype=float), cones, settings).solve()
    status = str(solution.status)
    # the solver's tolerance, taken off so that the bound stays a bound
    value = float(solution.obj_val) - 1e-6 * max(1.0, abs(solution.obj_val)) if status == "Solved" else None
    return LpBound(value, status, time.perf_counter() - started)
