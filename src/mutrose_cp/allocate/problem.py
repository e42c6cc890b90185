"""The allocation problem: what the mission asks of the fleet, before any solver is involved.

From the decomposition model (``solve/embedding.py``) and the fleet, each decomposition that can
be chosen becomes a :class:`Job`: its duration (the sum of its actions'), its place (the task's
``Location``), how many robots it needs and which robots are able to execute it.  The mission's
constraints become precedences (SEQ, and FB: a fallback is scheduled after its primary, the
worst case) and shared-robot rules (execution constraints).

:func:`impossibilities` names what the fleet lacks for each job it cannot staff, which is how a
mission without any feasible allocation is explained; :func:`fleet_problems` checks the names
in a fleet file against the mission (``check --fleet``).
"""
from __future__ import annotations

import heapq
import math
from dataclasses import dataclass, field
from functools import cached_property
from typing import TYPE_CHECKING, Any, Callable, Mapping, TypeVar

from ..errors import MissionError, Problem, closest
from ..model import RobotNumber
from .budget import NEVER, Deadline
from .fleet import Fleet, Robot
from .travel import TravelTimes, build_travel, world_places

if TYPE_CHECKING:
    from ..pipeline.stages import MissionStages
    from ..solve.embedding import DecompositionModel


class NoAllocationError(MissionError):
    """The mission has valid decompositions, but the fleet cannot execute any of them (exit 3)."""

    exit_code = 3


T = TypeVar("T")  # what a memo entry holds

@dataclass(frozen=True)
class Job:
    """A decomposition the allocation may choose, as the fleet sees it."""

    id: str  # the decomposition id, "AT1_1|1"
    task: str  # the task instance, "AT1_1"
    name: str  # the HDDL task, "FetchItem"
    actions: tuple[str, ...]
    duration: int
    location: str | None  # None: done wherever the robot is
    robots: RobotNumber
    capabilities: frozenset[str]
    candidates: tuple[str, ...]  # robots having every capability, in fleet order


@dataclass(frozen=True)
class AllocationProblem:
    """The jobs, their precedences and shared-robot rules, the fleet and its travel times."""

    dm: DecompositionModel
    fleet: Fleet
    jobs: dict[str, Job]  # in Task Graph order
    travel: TravelTimes
    precedences: tuple[tuple[str, str], ...]  # (first, second): second starts after first ends
    same_robots: tuple[tuple[str, str], ...]  # EC pairs executed by the same robot or team
    # what the phases look up per candidate set, kept once: a fleet of 100,000 robots makes every
    # pass over a job's candidates count (see able, kinds)
    memo: dict[Any, Any] = field(default_factory=dict, init=False, repr=False, compare=False)

    def time(self, robot: Robot, a: str | None, b: str | None) -> int:
        return self.travel.time(robot, a, b)

    @cached_property
    def robots(self) -> dict[str, Robot]:
        """The fleet's robots by name."""
        return {r.name: r for r in self.fleet.robots}

    def able(self, job: str) -> frozenset[str]:
        """The candidates of ``job`` as a set (``r in able`` instead of a scan of the tuple);
        jobs with the same candidates share one set."""
        return self.members(self.jobs[job].candidates)

    def members(self, robots: tuple[str, ...]) -> frozenset[str]:
        """``robots`` (a candidate tuple, kept by the caller) as a set, made once per tuple."""
        return self._memo("members", robots, lambda: frozenset(robots))

    def having(self, capabilities: frozenset[str]) -> tuple[str, ...]:
        """The robots having every capability of ``capabilities``, in fleet order: a job's
        candidates when a job needs exactly those (the same tuple, so that what is kept per
        candidate tuple, :meth:`kinds`, is shared), else found once per set."""
        key = ("having", capabilities)
        if key not in self.memo:
            same = next((j.candidates for j in self.jobs.values() if j.capabilities == capabilities), None)
            self.memo[key] = same if same is not None else tuple(
                r.name for r in self.fleet.robots if capabilities <= r.capabilities)
        found: tuple[str, ...] = self.memo[key]
        return found

    def earliest_arrival(self, job: Job, deadline: Deadline = NEVER) -> int:
        """The quickest trip of an able robot from its start to ``job``'s place.  The candidates
        are grouped by start and speed once per candidate set, so a large fleet costs one pass."""
        if job.location is None:
            return 0
        kinds = self.kinds(job.candidates, deadline)
        return min((self.time(self.robots[names[0]], start, job.location) for (start, _), names in kinds.items()),
                   default=0)

    def kinds(self, robots: tuple[str, ...], deadline: Deadline = NEVER) -> dict[tuple[str | None, float], list[str]]:
        """``robots`` (a candidate tuple, kept by the caller) by start and speed, each kind's
        names in fleet order: robots of one kind take the same time to any place.  Computed once
        per tuple."""
        def group() -> dict[tuple[str | None, float], list[str]]:
            kinds: dict[tuple[str | None, float], list[str]] = {}
            table = self.robots
            for number, name in enumerate(robots):
                if number % 4096 == 0:
                    deadline.check()
                robot = table[name]
                kinds.setdefault((robot.start, robot.speed), []).append(name)
            return kinds

        return self._memo("kinds", robots, group)

    def nearest(self, robots: tuple[str, ...], location: str | None, count: int, ready: int = 0,
                exclude: frozenset[str] | set[str] = frozenset(), deadline: Deadline = NEVER) -> list[str]:
        """The ``count`` robots of ``robots`` (not in ``exclude``) that can be at ``location``
        first, each at the later of ``ready`` and its trip from its start, ties by name: what
        sorting all of them by that key would give first, found per kind of robot
        (:meth:`kinds`) rather than per robot."""
        levels: dict[int, list[str]] = {}
        for (start, speed), names in self.kinds(robots, deadline).items():
            at = max(ready, self.time(self.robots[names[0]], start, location))
            levels.setdefault(at, []).extend(names)
        out: list[str] = []
        for at in sorted(levels):
            need = count - len(out)
            if need <= 0:
                break
            names = levels[at]
            smallest = heapq.nsmallest(need + len(exclude), names) if len(names) > need + len(exclude) else sorted(names)
            out += [n for n in smallest if n not in exclude][:need]
        return out

    def first_idle(self, busy: Mapping[str, object]) -> list[str]:
        """Of each kind of robot (the same capabilities, start and speed: interchangeable), the
        first by name that is not in ``busy``: what a move that sends work to an idle robot needs
        to try, since the others of its kind would give the same schedule."""
        if "by kind" not in self.memo:
            kinds: dict[tuple[frozenset[str], str | None, float], list[str]] = {}
            for r in self.fleet.robots:
                kinds.setdefault((r.capabilities, r.start, r.speed), []).append(r.name)
            self.memo["by kind"] = [sorted(names) for names in kinds.values()]
        out = []
        for names in self.memo["by kind"]:
            idle = next((n for n in names if n not in busy), None)
            if idle is not None:
                out.append(idle)
        return out

    @cached_property
    def index(self) -> dict[str, int]:
        """Each robot's position in the fleet."""
        return {r.name: i for i, r in enumerate(self.fleet.robots)}

    def _memo(self, kind: str, of: object, compute: Callable[[], T]) -> T:
        """``compute()``, kept under ``kind`` for the object ``of`` (by identity: hashing a tuple
        of 100,000 names on every look-up would cost what the memo saves; the entry keeps ``of``
        alive, so its id is not reused)."""
        entry = self.memo.get((kind, id(of)))
        if entry is None or entry[0] is not of:
            entry = self.memo[(kind, id(of))] = (of, compute())
        value: T = entry[1]
        return value


def place_of(location: object) -> str | None:
    """The place of a task: its ``Location`` when that is one world entity; none (done where the
    robot is) when the task has no location or a collection of them."""
    return location if isinstance(location, str) and location else None


def task_places(mission: MissionStages, fleet: Fleet) -> set[str]:
    """Every place a task of the mission is at, and the robots' starts."""
    tasks = {place_of(v.decomposition.instance.location)
             for v in mission.task_graph.decompositions() if v.decomposition is not None}
    return {p for p in tasks if p} | {r.start for r in fleet.robots if r.start}


def mission_travel(mission: MissionStages, fleet: Fleet) -> TravelTimes:
    """The travel times between the places of every task of the mission and the robots' starts.
    Raises :class:`MissionError` naming each place a time is missing for, also where only a
    decomposition no valid mission decomposition uses is: the fleet is checked against the
    whole mission (``check --fleet``), and an allocation takes its times from this one table."""
    return build_travel(mission, fleet, task_places(mission, fleet))


def possible_decompositions(dm: DecompositionModel, deadline: Deadline = NEVER) -> set[str]:
    """The decompositions CP-SAT's presolve does not rule out on the decomposition model alone
    (a method whose precondition the world falsifies, say).  Leaving the others out keeps them
    off every robot's route, which grows with the square of its jobs.  A presolve cut by the
    ``deadline`` rules out less (its domains hold whenever it stops), none once it has passed."""
    from ..errors import NoDecompositionError
    from ..solve.native import cmh
    from ..solve.run import run_solver

    parameters = cmh.SatParameters()
    parameters.stop_after_presolve = True
    parameters.fill_tightened_domains_in_response = True
    parameters.keep_all_feasible_solutions_in_presolve = True  # no solution removed "without loss"
    parameters.num_workers = 1
    if deadline.passed():
        return set(dm.decomposition)
    if deadline.left() < math.inf:
        parameters.max_time_in_seconds = deadline.left()
    response = run_solver(dm.model.proto, accept=list(cmh.CpSolverStatus.__members__.values()), parameters=parameters,
                          what="the presolve")
    if response.status == cmh.CpSolverStatus.INFEASIBLE:
        raise NoDecompositionError("no valid mission decomposition exists")
    domains = response.tightened_variables
    if len(domains) != len(dm.model.proto.variables):
        return set(dm.decomposition)

    def can_be_true(literal: object) -> bool:
        index = literal.index  # type: ignore[attr-defined]
        domain = list(domains[index if index >= 0 else -index - 1].domain)
        return domain != ([0, 0] if index >= 0 else [1, 1])

    return {d for d, literal in dm.decomposition.items() if can_be_true(literal)}


def build_problem(dm: DecompositionModel, fleet: Fleet, travel: TravelTimes | None = None,
                  deadline: Deadline = NEVER) -> AllocationProblem:
    """The jobs of every decomposition that can be chosen, with their candidate robots and the
    travel times between their places and the robots' starts.  ``travel`` is the table of
    :func:`mission_travel` when the caller has built it already (checking the fleet).  Raises
    :class:`~.budget.OutOfTime` when the ``deadline`` passes first."""
    durations = fleet.durations
    instances = {v.decomposition.id: v.decomposition.instance
                 for v in dm.mission.task_graph.decompositions() if v.decomposition is not None}
    jobs: dict[str, Job] = {}
    possible = possible_decompositions(dm, deadline)
    able = _able_robots(fleet, deadline)
    for d, info in dm.decompositions_info.items():
        if d not in possible:
            continue  # never part of a valid mission decomposition
        deadline.check()
        duration = sum(durations.of_action(a, caps) for a, caps in zip(info.actions, info.action_capabilities))
        jobs[d] = Job(d, info.task, info.task_name, info.actions, duration, place_of(instances[d].location),
                      info.robot_number, info.capabilities, able(info.capabilities))
    places = {j.location for j in jobs.values() if j.location} | {r.start for r in fleet.robots if r.start}
    travel = (travel if travel is not None else mission_travel(dm.mission, fleet)).among(places, deadline)
    precedences = tuple((c.first, c.second) for c in dm.constraints
                        if c.kind in ("SEQ", "FB") and c.first in jobs and c.second in jobs)
    same = tuple((c.first, c.second) for c in dm.constraints
                 if c.kind == "EC" and (not c.group or not c.divisible) and c.first in jobs and c.second in jobs)
    return AllocationProblem(dm, fleet, jobs, travel, precedences, same)


def _able_robots(fleet: Fleet, deadline: Deadline) -> Callable[[frozenset[str]], tuple[str, ...]]:
    """The robots having every capability of a set, in fleet order: robots are grouped by their
    capabilities once, and each set asked for is answered once (jobs needing the same
    capabilities share one tuple), so a fleet is read once rather than once per job."""
    groups: dict[frozenset[str], list[int]] = {}
    for number, robot in enumerate(fleet.robots):
        if number % 4096 == 0:
            deadline.check()
        groups.setdefault(robot.capabilities, []).append(number)
    answers: dict[frozenset[str], tuple[str, ...]] = {}

    def able(needed: frozenset[str]) -> tuple[str, ...]:
        if needed not in answers:
            numbers = sorted(n for caps, members in groups.items() if needed <= caps for n in members)
            answers[needed] = tuple(fleet.robots[n].name for n in numbers)
        return answers[needed]

    return able


# ----------------------------------------------------------------------------------------------
# What the fleet lacks


def impossibilities(problem: AllocationProblem) -> list[str]:
    """Why some jobs (or pairs of jobs that must share robots) cannot be staffed by the fleet:
    a capability no robot has, or fewer able robots than the task's robot number."""
    reasons = []
    for job in problem.jobs.values():
        reason = _short_of(problem.fleet, job.capabilities, job.robots.min, len(job.candidates))
        if reason:
            reasons.append(f"{job.id} ({job.name}) {reason}")
    for first, second in problem.same_robots:
        a, b = problem.jobs[first], problem.jobs[second]
        union = a.capabilities | b.capabilities
        if union in (a.capabilities, b.capabilities):
            continue  # no more than each needs alone
        able = len(problem.having(union))
        reason = _short_of(problem.fleet, union, max(a.robots.min, b.robots.min), able)
        if reason:
            reasons.append(f"{first} ({a.name}) and {second} ({b.name}), done by the same robots, {reason}")
    return reasons


def _short_of(fleet: Fleet, capabilities: frozenset[str], needed: int, able: int) -> str:
    if able >= needed:
        return ""
    missing = sorted(c for c in capabilities if not any(c in r.capabilities for r in fleet.robots))
    if missing:
        return f"needs {', '.join(missing)}: no robot of the fleet has {'it' if len(missing) == 1 else 'them'}"
    needs = ", ".join(sorted(capabilities)) or "no capability"
    return (f"needs {needed} robot{'s' if needed != 1 else ''} with {needs}: the fleet has {able}")


# ----------------------------------------------------------------------------------------------
# The fleet file against the mission


def fleet_problems(mission: MissionStages, fleet: Fleet) -> list[Problem]:
    """Names in the fleet that the mission does not know (a typo would silently change the
    durations or make a robot useless), start places without a place, and task places without
    travel times."""
    domain = mission.domain
    capabilities = set(domain.capabilities) | {c for a in domain.actions for c in a.capabilities}
    actions = {a.name for a in domain.actions}
    problems = []
    for i, robot in enumerate(fleet.robots):
        for c in sorted(robot.capabilities - capabilities):
            problems.append(_unknown(fleet, ("robots", i, "capabilities"), "capability", c, capabilities))
    for name in fleet.durations.actions:
        if name not in actions:
            problems.append(_unknown(fleet, ("durations", "actions", name), "action", name, actions, key=True))
    for name in fleet.durations.capabilities:
        if name not in capabilities:
            problems.append(_unknown(fleet, ("durations", "capabilities", name), "capability", name, capabilities,
                                     key=True))
    places, world_problems = world_places(mission)
    known = set(places) | set(fleet.travel.coordinates) | {p for pair in fleet.travel.times for p in pair}
    for i, robot in enumerate(fleet.robots):
        if robot.start is not None and robot.start not in known:
            problems.append(_unknown(fleet, ("robots", i, "start"), "place", robot.start, known))
    return problems + _stray_table_places(fleet, set(places)) + world_problems


def _stray_table_places(fleet: Fleet, world: set[str]) -> list[Problem]:
    """Places that only the travel table names, where no robot starts, on a single road: no
    trip starts, ends or passes there, so the entry changes no travel time.  Such a place is a
    misspelt one (``WardAA``), whose intended time would otherwise be silently left out."""
    roads: dict[str, set[str]] = {}
    for a, b in fleet.travel.times:
        if a != b:
            roads.setdefault(a, set()).add(b)
            roads.setdefault(b, set()).add(a)
    known = world | set(fleet.travel.coordinates)
    starts = {r.start for r in fleet.robots}
    problems = []
    for name in sorted(roads):
        if name in known or name in starts or len(roads[name]) > 1:
            continue
        (other,) = roads[name]
        row = any(a == name for a, _ in fleet.travel.times)
        near = closest(name, known)
        problems.append(Problem(
            fleet.where(("travel", "times", name) if row else ("travel", "times", other, name), key=True),
            f"unknown place {name!r}: not a world location, not in travel.coordinates and no robot's start, and its "
            f"only road (to {other}) leads nowhere else, so this entry changes no travel time",
            f"Did you mean {near!r}?" if near else "Name a place of the mission, or join it to two places as a "
                                                   "junction of the road network."))
    return problems


def _unknown(fleet: Fleet, path: tuple[str | int, ...], what: str, name: str, known: set[str], *,
             key: bool = False) -> Problem:
    near = closest(name, known)
    plural = {"capability": "capabilities", "place": "places", "action": "actions"}[what]
    hint = f"Did you mean {near!r}?" if near else f"The mission's {plural}: {', '.join(sorted(known)) or 'none'}."
    return Problem(fleet.where(path, key=key), f"unknown {what} {name!r}", hint)
