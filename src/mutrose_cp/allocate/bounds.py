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

Robots of one *kind* (the same capabilities, start and speed) are one column each: ``x[d, k]``
in ``[0, n_k]`` is the sum of the ``x[d, r]`` of the kind's ``n_k`` robots, and every row above
is summed over the kind (``x <= n_k y``, ``work + trips <= n_k M``, ...).  That LP has the same
optimum: a solution of the robots' LP sums into one of the kinds', and a kinds' solution shared
out equally among its robots is one of the robots' (they are interchangeable), with the same
objective.  So a fleet of thousands of robots of a few kinds costs the LP what a few robots do.
"""
from __future__ import annotations

import time
from dataclasses import dataclass
from typing import Any, Iterable

from ..model.task_graph import OperatorVertex, TaskGraph, TaskVertex
from ..solve.boolean_model import FALSE, TRUE, AndOf, Clause, Exactly, Lit, OrOf
from .budget import LP_ITERATIONS, NEVER, Budget, Deadline, OutOfTime
from .load import ways_in
from .options import Objective
from .problem import AllocationProblem
from .timed import run_within

Expr = tuple[dict[int, float], float]  # a linear expression: coefficients by column, constant


@dataclass(frozen=True)
class LpBound:
    """The LP optimum (``None`` when Clarabel did not solve it), Clarabel's status and time."""

    value: float | None
    status: str
    seconds: float


CHECK_ROWS = 4096  # rows added between two looks at the clock
LATE = 0.05  # seconds Clarabel may overrun its time limit (its last iteration) before it is stopped
LARGE_LP = 50_000  # non-zeros from which Clarabel runs in a child process the deadline can end (its setup is long)


class _Lp:
    """Rows ``sum coef * var (<= | ==) rhs`` over named continuous variables.  Building stops
    (:class:`~.budget.OutOfTime`) at the ``deadline``: on a large fleet the rows alone can take
    longer than the LP's share of the time limit."""

    def __init__(self, deadline: Deadline = NEVER) -> None:
        self.index: dict[object, int] = {}
        self.le: list[tuple[dict[int, float], float]] = []
        self.eq: list[tuple[dict[int, float], float]] = []
        self.deadline = deadline
        self.rows = 0

    def _count(self) -> None:
        self.rows += 1
        if self.rows % CHECK_ROWS == 0:
            self.deadline.check()

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
        self._count()
        row, constant = self._linear(terms)
        self.le.append((row, rhs - constant))

    def add_eq(self, terms: Iterable[tuple[float, Expr]], rhs: float = 0.0) -> None:
        self._count()
        row, constant = self._linear(terms)
        self.eq.append((row, rhs - constant))


def lp_bound(problem: AllocationProblem, objective: Objective, budget: Budget | None = None) -> LpBound:
    """The LP relaxation's optimum, a lower bound on ``objective`` (see the module docstring).
    Clarabel stops at the clock ``budget`` (building the LP included), or after
    :data:`~.budget.LP_ITERATIONS` iterations on a work budget; an LP it did not solve gives no
    bound (``value`` None, ``status`` says why: ``MaxTime`` also when the clock ran out while the
    LP was being built)."""
    started = time.perf_counter()
    lp = _Lp(budget.deadline() if budget is not None else NEVER)
    try:
        goal = _build(lp, problem, objective)
        return _solve(lp, goal, started, budget)
    except OutOfTime:
        return LpBound(None, "MaxTime", time.perf_counter() - started)


def _build(lp: _Lp, problem: AllocationProblem, objective: Objective) -> list[tuple[float, Expr]]:
    """The LP's rows (see the module docstring); its objective."""
    y = _decomposition_relaxation(lp, problem)
    kinds = robot_kinds(problem, lp.deadline)
    x = _assignments(lp, problem, y, kinds)
    visits = _visits(lp, problem, x, kinds)
    makespan = lp.var("M")
    loads: dict[str, list[tuple[float, Expr]]] = {}
    for (d, k), e in x.items():
        loads.setdefault(k, []).append((float(problem.jobs[d].duration), e))
    for (_, k), (cost, e) in visits.items():
        loads[k].append((cost, e))
    for k, load in loads.items():
        lp.add_le(load + [(-float(kinds[k]), makespan)])
    _start_times(lp, problem, y, makespan)
    _operator_chains(lp, problem, y, makespan)
    travel = [(cost, e) for cost, e in visits.values()]
    return [(float(objective.makespan_weight), makespan)] + [(objective.travel_weight * c, e) for c, e in travel]


def robot_kinds(problem: AllocationProblem, deadline: Deadline = NEVER) -> dict[str, int]:
    """The fleet's kinds of robot (the same capabilities, start and speed: interchangeable in
    the LP), each by its first robot's name, in fleet order: how many robots it has."""
    first: dict[tuple[frozenset[str], str | None, float], str] = {}
    out: dict[str, int] = {}
    for number, robot in enumerate(problem.fleet.robots):
        if number % CHECK_ROWS == 0:
            deadline.check()
        name = first.setdefault((robot.capabilities, robot.start, robot.speed), robot.name)
        out[name] = out.get(name, 0) + 1
    return out


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


def _assignments(lp: _Lp, problem: AllocationProblem, y: dict[str, Expr], kinds: dict[str, int]
                 ) -> dict[tuple[str, str], Expr]:
    """``x[d, k]`` for each job and kind of robot able to do it (its first robot a candidate)."""
    x: dict[tuple[str, str], Expr] = {}
    for d, job in problem.jobs.items():
        able = problem.able(d)
        team = []
        for k, size in kinds.items():
            if k not in able:
                continue
            x[(d, k)] = lp.var(("x", d, k), 0.0, float(size))
            team.append(x[(d, k)])
            lp.add_le([(1.0, x[(d, k)]), (-float(size), y[d])])
        lp.add_le([(float(job.robots.min), y[d])] + [(-1.0, e) for e in team])
        lp.add_le([(1.0, e) for e in team] + [(-float(job.robots.max), y[d])])
    none: Expr = ({}, 0.0)
    for d1, d2 in problem.same_robots:
        for k, size in kinds.items():
            a1, a2 = x.get((d1, k), none), x.get((d2, k), none)
            if a1 is none and a2 is none:
                continue
            lp.add_le([(1.0, a1), (-1.0, a2), (float(size), y[d2])], float(size))
            lp.add_le([(1.0, a2), (-1.0, a1), (float(size), y[d1])], float(size))
    return x


def _visits(lp: _Lp, problem: AllocationProblem, x: dict[tuple[str, str], Expr], kinds: dict[str, int]
            ) -> dict[tuple[str, str], tuple[float, Expr]]:
    """``(place, kind) -> (cheapest way in, v[place, kind])`` for the places that cost a trip."""
    out: dict[tuple[str, str], tuple[float, Expr]] = {}
    ways = ways_in(problem, lp.deadline)  # a robot without a start reaches its first place for free: none there
    visited: dict[str, set[str]] = {}
    for (d, k) in x:
        if (p := problem.jobs[d].location) is not None:
            visited.setdefault(k, set()).add(p)
    for k, places in visited.items():
        for place in sorted(places):
            cheapest = ways.get(k, {}).get(place, 0)
            if cheapest > 0:
                out[(place, k)] = (float(cheapest), lp.var(("v", place, k), 0.0, float(kinds[k])))
    for (d, k), e in x.items():
        at = problem.jobs[d].location
        if at is not None and (at, k) in out:
            lp.add_le([(1.0, e), (-1.0, out[(at, k)][1])])
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
    """Clarabel on the LP, within the ``budget``: a large LP in a child process that the
    deadline ends (:mod:`.timed`: Clarabel's setup does not stop at its time limit)."""
    import clarabel  # type: ignore[import-untyped]

    p, q, a, b, cones = _matrices(lp, goal)
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    left = None
    if budget is not None and budget.deterministic:
        settings.max_iter = LP_ITERATIONS
    elif budget is not None:
        left = budget.rest(started).seconds
        if left <= 0:
            return LpBound(None, "MaxTime", time.perf_counter() - started)
        settings.time_limit = left

    def run() -> tuple[str, float]:
        solution = clarabel.DefaultSolver(p, q, a, b, cones, settings).solve()
        return str(solution.status), float(solution.obj_val)

    if left is None or a.nnz < LARGE_LP:
        status, value = run()
    else:
        finished, outcome = run_within(run, left + LATE)
        if not finished:
            return LpBound(None, "MaxTime", time.perf_counter() - started)
        status, value = outcome
    # the solver's tolerance, taken off so that the bound stays a bound
    bound = value - 1e-6 * max(1.0, abs(value)) if status == "Solved" else None
    return LpBound(bound, status, time.perf_counter() - started)


def _matrices(lp: _Lp, goal: list[tuple[float, Expr]]) -> tuple[Any, Any, Any, Any, list[Any]]:
    """Clarabel's data for the LP: ``P`` (none), ``q``, ``A``, ``b`` and the cones (the
    equalities, then the inequalities)."""
    import clarabel
    import numpy as np
    import scipy.sparse as sp  # type: ignore[import-untyped]

    n = len(lp.index)
    rows = lp.eq + lp.le
    data, row_index, column_index, rhs = [], [], [], []
    for i, (row, b) in enumerate(rows):
        if i % CHECK_ROWS == 0:
            lp.deadline.check()
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
    return sp.csc_matrix((n, n)), q, a, np.array(rhs, dtype=float), cones
