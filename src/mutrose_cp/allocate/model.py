"""The joint CP-SAT model: decomposition, robots and times chosen together, with travel.

It is built on the decomposition model of the embedding API (``dm.model``: its solutions are
exactly the valid mission decompositions) and adds, for every :class:`~.problem.Job`:

* ``start[j]``, and ``end[j] = start[j] + duration[j] * chosen[j]``: a job that is not chosen
  takes no time and only passes precedences on (``end[first] <= start[second]`` for every SEQ
  and FB, which stays transitive through jobs that are not chosen);
* ``assign[j, r]`` for every robot able to execute it, only when ``j`` is chosen, as many as its
  RobotNumber says; execution constraints (same robot, same team) equate the assignments of
  both jobs when both are chosen;
* per robot, an optional interval per job and ``AddNoOverlap``: one thing at a time.

Travel is sequence-dependent, so each robot's *route* is a circuit (``AddCircuit``) through its
start and the located jobs it executes: the arc ``i -> j`` chosen means ``j`` is the next place
the robot goes to after ``i``, and ``start[j] >= end[i] + travel(i, j)`` (from its start:
``start[j] >= travel(start, j)``).  A job without a place is done wherever the robot is: it is
not on the route, and the trip to the next place, an interval of its own, may not overlap it.
Arcs that precedences rule out (``j`` must end before ``i`` starts) or that join two
decompositions of one task are not created.

The objective is the makespan, the total travel or a weighted sum of both.  Per robot, the
redundant ``work + travel <= makespan`` gives CP-SAT's relaxation the energy argument.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Sequence
from graphlib import CycleError, TopologicalSorter

from ortools.sat.python import cp_model

from ..solve.proto import negated
from .budget import NEVER, Deadline
from .fleet import Robot
from .neighbourhood import Restriction
from .options import Objective
from .problem import AllocationProblem, Job

START = ""  # the route node of a robot's start


@dataclass(frozen=True)
class Arc:
    """One arc of a robot's route: from a job (or the robot's start, ``START``) to a job."""

    source: str
    target: str
    literal: cp_model.IntVar
    time: int


@dataclass
class AllocationModel:
    """The CP-SAT variables of the allocation, by job and robot."""

    problem: AllocationProblem
    model: cp_model.CpModel
    horizon: int
    restriction: Restriction = Restriction()
    start: dict[str, cp_model.IntVar] = field(default_factory=dict)
    end: dict[str, cp_model.IntVar] = field(default_factory=dict)
    assign: dict[tuple[str, str], cp_model.IntVar] = field(default_factory=dict)
    arcs: dict[str, list[Arc]] = field(default_factory=dict)  # robot -> its route's arcs
    idle: dict[str, cp_model.IntVar] = field(default_factory=dict)  # robot -> its route is empty
    last: dict[tuple[str, str], cp_model.IntVar] = field(default_factory=dict)  # (job, robot): the route ends there
    travel: dict[str, cp_model.LinearExprT] = field(default_factory=dict)  # robot -> its travel time
    makespan: cp_model.IntVar | None = None


def horizon(problem: AllocationProblem) -> int:
    """A time by which some schedule surely ends: every job one after the other, each after
    the longest trip (the slowest robot's over the longest distance: a trip's time grows with
    its distance and falls with the speed, so no pass over robots and pairs of places)."""
    travel = problem.travel
    longest = 0
    if travel.modelled and travel.base and problem.fleet.robots:
        slowest = min(problem.fleet.robots, key=lambda r: r.speed)
        far = max(range(len(travel.places)), key=lambda i: max(travel.base[i]))
        to = max(range(len(travel.places)), key=lambda k: travel.base[far][k])
        longest = problem.time(slowest, travel.places[far], travel.places[to])
    return sum(j.duration + longest for j in problem.jobs.values()) + longest + 1


def build_model(problem: AllocationProblem, objective: Objective,
                restriction: Restriction = Restriction(), deadline: Deadline = NEVER) -> AllocationModel:
    """Add the allocation to ``problem.dm.model`` and set ``objective`` (see the module
    docstring), within ``restriction`` (large missions, ``neighbourhood.py``).  A job with
    fewer able robots than it needs is excluded.  Raises :class:`~.budget.OutOfTime` when the
    ``deadline`` passes first (``problem.dm.model`` is then left half built: it serves no
    search)."""
    dm = problem.dm
    am = AllocationModel(problem, dm.model, horizon(problem), restriction)
    for job in problem.jobs.values():
        deadline.check()
        _add_job(am, job)
    m = am.model
    for first, second in problem.precedences:
        m.add(am.end[first] <= am.start[second])
    for first, second in problem.same_robots:
        deadline.check()
        both = [dm.decomposition[first], dm.decomposition[second]]
        # a robot kept for neither job is assigned to neither: nothing to equate
        robots = set(restriction.robots_of(problem, first)) | set(restriction.robots_of(problem, second))
        for name in sorted(robots):
            m.add(am.assign.get((first, name), dm.false) == am.assign.get((second, name), dm.false)
                  ).only_enforce_if(both)
    ruled_out = _ruled_out_arcs(problem)
    mine = _jobs_by_robot(am)
    for robot in problem.fleet.robots:
        if robot.name in mine:  # a robot without any job has no route, no work and no travel
            deadline.check()
            _add_robot(am, robot, mine[robot.name], ruled_out)
    am.makespan = m.new_int_var(0, am.horizon, "makespan")
    m.add_max_equality(am.makespan, list(am.end.values()))
    total_travel = cp_model.LinearExpr.sum(list(am.travel.values()))
    if objective.makespan_weight:
        for robot in problem.fleet.robots:
            jobs = mine.get(robot.name, [])
            if jobs:
                work = cp_model.LinearExpr.weighted_sum([am.assign[(j.id, robot.name)] for j in jobs],
                                                        [j.duration for j in jobs])
                m.add(cp_model.LinearExpr.sum([work, am.travel[robot.name]]) <= am.makespan)
    m.minimize(objective.makespan_weight * am.makespan + objective.travel_weight * total_travel)
    return am


def _jobs_by_robot(am: AllocationModel) -> dict[str, list[Job]]:
    """Each robot's jobs (those it may be assigned), in job order: one pass over the
    assignments rather than one per robot."""
    out: dict[str, list[Job]] = {}
    for (j, r) in am.assign:
        out.setdefault(r, []).append(am.problem.jobs[j])
    return out


def _add_job(am: AllocationModel, job: Job) -> None:
    m, dm = am.model, am.problem.dm
    chosen = dm.decomposition[job.id]
    start = m.new_int_var(0, am.horizon, f"start[{job.id}]")
    end = m.new_int_var(0, am.horizon, f"end[{job.id}]")
    m.add(end == start + job.duration * chosen)
    am.start[job.id], am.end[job.id] = start, end
    team = []
    for robot in am.restriction.robots_of(am.problem, job.id):
        a = m.new_bool_var(f"assign[{job.id},{robot}]")
        m.add_implication(a, chosen)
        am.assign[(job.id, robot)] = a
        team.append(a)
    if len(team) < job.robots.min:  # not enough able robots: never chosen
        m.add_bool_or([chosen.Not()])
        return
    m.add(sum(team) >= job.robots.min).only_enforce_if(chosen)
    m.add(sum(team) <= job.robots.max)


def _add_robot(am: AllocationModel, robot: Robot, jobs: list[Job], ruled_out: set[tuple[str, str]]) -> None:
    """The robot's intervals (``jobs``: those it may be assigned), and its route when it travels."""
    m, problem = am.model, am.problem
    intervals = [m.new_optional_fixed_size_interval_var(am.start[j.id], j.duration, am.assign[(j.id, robot.name)],
                                                        f"busy[{j.id},{robot.name}]") for j in jobs]
    located = [j for j in jobs if j.location is not None]
    places = {j.location for j in located} | {robot.start}
    travels = any(problem.time(robot, a, b) for a in places for b in places)
    if not travels:
        am.travel[robot.name] = 0
        am.arcs[robot.name] = []
        if len(intervals) > 1:
            m.add_no_overlap(intervals)
        return
    arcs = _route(am, robot, located, ruled_out)
    am.arcs[robot.name] = arcs
    am.travel[robot.name] = cp_model.LinearExpr.weighted_sum([a.literal for a in arcs], [a.time for a in arcs])
    if len(located) < len(jobs):  # jobs without a place: the trips are intervals too
        intervals += _trip_intervals(am, robot, located, arcs)
    if len(intervals) > 1:
        m.add_no_overlap(intervals)


def _route(am: AllocationModel, robot: Robot, located: list[Job], ruled_out: set[tuple[str, str]]) -> list[Arc]:
    """``AddCircuit`` through the robot's start (node 0) and its located jobs; a job the robot
    does not execute loops on itself, and so does the start when the robot goes nowhere."""
    m, problem = am.model, am.problem
    node = {j.id: i + 1 for i, j in enumerate(located)}
    idle = am.idle[robot.name] = m.new_bool_var(f"idle[{robot.name}]")
    circuit: list[tuple[int, int, cp_model.LiteralT]] = [(0, 0, idle)]
    arcs: list[Arc] = []
    presence = []
    for job in located:
        a = am.assign[(job.id, robot.name)]
        presence.append(a)
        m.add_implication(a, idle.Not())
        circuit.append((node[job.id], node[job.id], a.Not()))
        last = am.last[(job.id, robot.name)] = m.new_bool_var(f"last[{job.id},{robot.name}]")
        circuit.append((node[job.id], 0, last))
        candidates = [(START, robot.start)] + [(i.id, i.location) for i in located if i.id != job.id]
        for source, place in candidates:
            if (source, job.id) in ruled_out or not (source == START or am.restriction.allows(source, job.id)):
                continue
            literal = m.new_bool_var(f"route[{source or robot.name},{job.id}]")
            time = problem.time(robot, place, job.location)
            after = am.end[source] if source != START else 0
            m.add(am.start[job.id] >= after + time).only_enforce_if(literal)
            circuit.append((node.get(source, 0), node[job.id], literal))
            arcs.append(Arc(source, job.id, literal, time))
    m.add_bool_or([idle, *presence])
    m.add_circuit(circuit)
    return arcs


def _trip_intervals(am: AllocationModel, robot: Robot, located: list[Job], arcs: list[Arc]) -> list[cp_model.IntervalVar]:
    """For each located job, the trip that ends at its start, as an interval a job without a
    place (done where the robot stands) cannot overlap."""
    m = am.model
    incoming: dict[str, list[Arc]] = {}
    for arc in arcs:
        incoming.setdefault(arc.target, []).append(arc)
    out = []
    for job in located:
        longest = max((arc.time for arc in incoming.get(job.id, [])), default=0)
        if longest == 0:
            continue
        trip = m.new_int_var(0, longest, f"trip[{job.id},{robot.name}]")
        m.add(trip == sum(arc.time * arc.literal for arc in incoming[job.id]))
        leave = m.new_int_var(-longest, am.horizon, f"leave[{job.id},{robot.name}]")
        m.add(leave == am.start[job.id] - trip)
        out.append(m.new_optional_interval_var(leave, trip, am.start[job.id], am.assign[(job.id, robot.name)],
                                               f"trip[{job.id},{robot.name}]"))
    return out


def _ruled_out_arcs(problem: AllocationProblem) -> set[tuple[str, str]]:
    """Pairs ``(i, j)`` that can never be consecutive on a route: ``j`` must end before ``i``
    starts (through the precedences, and ``i`` or ``j`` takes time), or both are
    decompositions of one task (only one of them is ever chosen)."""
    successors: dict[str, set[str]] = {j: set() for j in problem.jobs}
    for first, second in problem.precedences:
        successors[first].add(second)
    try:
        order = list(TopologicalSorter({j: s for j, s in successors.items()}).static_order())
    except CycleError:
        return set()  # cyclic precedences: nothing can be scheduled, CP-SAT proves it
    bit = {j: 1 << i for i, j in enumerate(problem.jobs)}
    after: dict[str, int] = {}
    for job in order:  # successors come first in this order
        reach = 0
        for s in successors[job]:
            reach |= bit[s] | after[s]
        after[job] = reach
    ids = list(problem.jobs)
    ruled = set()
    by_task: dict[str, list[str]] = {}
    for j in ids:
        by_task.setdefault(problem.jobs[j].task, []).append(j)
        reach = after[j]
        while reach:  # every job that j must end before
            low = reach & -reach
            reach ^= low
            i = ids[low.bit_length() - 1]
            if problem.jobs[i].duration + problem.jobs[j].duration > 0:
                ruled.add((i, j))  # i comes after j
    for group in by_task.values():
        ruled.update((a, b) for a in group for b in group if a != b)
    return ruled


def literal_value(values: Sequence[int], literal: Any) -> bool:
    """The value of a model literal in a solution given by proto variable index."""
    index = literal.index
    return bool(values[index]) if index >= 0 else not values[negated(index)]
