"""Local improvement of a list schedule: move tasks between robots while the schedule gets better.

List scheduling (:mod:`.warmstart`) is greedy: it sends a robot across the map for the task that
can end soonest now, and it leaves the last robot to finish with far more than the others.  This
descent fixes both, before the schedule is handed to CP-SAT as its hint:

* a *unit* is a chosen job and the jobs that must share its robot (execution constraints), done
  by one robot; units done by a team stay where they are;
* the moves start from the robots that finish last, the cheapest kind first (:data:`MOVES`):
  a *relocation* takes a unit off a robot and inserts each of its jobs, in order, where it
  adds the least travel to another able robot's sequence, or to its own; a *segment move*
  (or-opt) puts up to ``SEGMENT`` consecutive jobs of a robot elsewhere in its own sequence; a
  *reversal* (2-opt) does a stretch of a robot's sequence backwards; a *swap* exchanges a unit
  of a robot with a unit of another, when each robot can do the other's unit.  The last three
  are evaluated only when they do not lengthen the robot's own work (its jobs and trips),
  since evaluations are what the descent spends;
* every move is evaluated exactly (:func:`evaluate`: each job as early as its predecessors and
  its robots' sequences allow, the trips at each robot's speed) and kept when it lowers the
  objective, or keeps it and lowers the sum of the robots' finishing times, which spreads the
  work and opens the way for the next move.

From a local optimum, a few units moved to random able robots (seeded) start a new descent, and
the best schedule is kept: an iterated local search.  It stops after ``MAX_EVALUATIONS``
schedules, after ``STALL`` kicks in a row that found nothing better, when the objective reaches
a lower bound, or at the end of its budget (:mod:`.budget`), whichever comes first; unless a
clock budget ends it, it is deterministic.  The budget is checked before every evaluation, not
only between moves: on a fleet of thousands of robots one round of moves can try thousands of
schedules, and must not run past the time limit.
"""
from __future__ import annotations

import random
from dataclasses import dataclass, field
from typing import Callable, Iterator, Mapping, Sequence

from .budget import Budget
from .options import Objective
from .problem import AllocationProblem
from .schedule import chosen_predecessors, robot_sequences, robot_teams

MAX_EVALUATIONS = 1_000_000  # schedules evaluated, at most (a budget or STALL ends the search long before)
KICK = 3  # units moved at random to leave a local optimum
STALL = 200  # kicks without a better schedule, at most
SEGMENT = 3  # jobs moved together within a robot's sequence, at most

Sequences = dict[str, list[str]]  # robot -> its jobs in the order it does them


@dataclass(frozen=True)
class Evaluated:
    """A schedule of the sequences: start times, and what the descent compares."""

    start: dict[str, int]
    score: tuple[float, int]  # (objective, sum of the robots' finishing times)


class _Evaluator:
    """Earliest start times of fixed robot sequences (see :func:`evaluate`).  The descent spends
    nearly all its time here, so what does not depend on the sequences is looked up once: each
    job's predecessors, successors, place and duration, and the trips already met."""

    def __init__(self, problem: AllocationProblem, chosen: Sequence[str], objective: Objective) -> None:
        self.problem = problem
        self.objective = objective
        self.robots = problem.robots
        self.before = chosen_predecessors(problem, set(chosen))
        self.chosen = list(chosen)
        self.count = 0
        self.trips: dict[tuple[str, str | None, str | None], int] = {}
        self.after: dict[str, list[str]] = {j: [] for j in self.chosen}
        for j in self.chosen:
            for i in self.before[j]:
                self.after[i].append(j)
        self.location = {j: problem.jobs[j].location for j in self.chosen}
        self.duration = {j: problem.jobs[j].duration for j in self.chosen}

    def __call__(self, sequences: Mapping[str, Sequence[str]]) -> Evaluated | None:
        """The schedule, or None when the sequences contradict the precedences (a cycle)."""
        self.count += 1
        previous, nxt, waiting = self._links(sequences)
        place: dict[tuple[str, str], str | None] = {}  # (job, robot) -> the robot's place after the job
        start: dict[str, int] = {}
        end: dict[str, int] = {}
        ready = [j for j in self.chosen if not waiting[j]]
        travel = 0
        while ready:
            j = ready.pop()
            at = 0
            for i in self.before[j]:
                at = end[i] if end[i] > at else at
            location = self.location[j]
            for robot, p in previous.get(j, ()):
                origin = place[(p, robot)] if p is not None else self.robots[robot].start
                trip = self.trip(robot, origin, location)
                travel += trip
                at = max(at, (end[p] if p is not None else 0) + trip)
                place[(j, robot)] = location or origin
            start[j], end[j] = at, at + self.duration[j]
            for k in self.after[j] + nxt.get(j, []):
                waiting[k] -= 1
                if not waiting[k]:
                    ready.append(k)
        if len(start) < len(self.chosen):
            return None
        finish = [end[s[-1]] for s in sequences.values() if s]
        makespan = max(end.values(), default=0)
        return Evaluated(start, (self.objective.value(makespan, travel), sum(finish)))

    def _links(self, sequences: Mapping[str, Sequence[str]]
               ) -> tuple[dict[str, list[tuple[str, str | None]]], dict[str, list[str]], dict[str, int]]:
        """For each job, its robots with the job each does before it, the jobs its robots do
        next, and how many of its predecessors and robots' previous jobs it waits for."""
        waiting = {j: len(self.before[j]) for j in self.chosen}
        previous: dict[str, list[tuple[str, str | None]]] = {}
        nxt: dict[str, list[str]] = {}
        for robot, sequence in sequences.items():
            p = None
            for j in sequence:
                previous.setdefault(j, []).append((robot, p))
                if p is not None:
                    waiting[j] += 1
                    nxt.setdefault(p, []).append(j)
                p = j
        return previous, nxt, waiting

    def trip(self, robot: str, a: str | None, b: str | None) -> int:
        key = (robot, a, b)
        if key not in self.trips:
            self.trips[key] = self.problem.time(self.robots[robot], a, b)
        return self.trips[key]


def evaluate(problem: AllocationProblem, chosen: Sequence[str], sequences: Mapping[str, Sequence[str]],
             objective: Objective = Objective()) -> Evaluated | None:
    """Each chosen job as early as its predecessors and its robots allow, every robot doing its
    jobs in the order of ``sequences`` and travelling from its last place at its speed; None when
    the orders and the precedences form a cycle."""
    return _Evaluator(problem, chosen, objective)(sequences)


@dataclass(frozen=True)
class Improved:
    """The best schedule the descent found, and whether its budget ended it (``cut``) rather
    than a local optimum it could not leave, the lower bound or its own limits."""

    teams: dict[str, tuple[str, ...]]
    start: dict[str, int]
    value: float
    cut: bool = False


def improve(problem: AllocationProblem, chosen: Sequence[str], teams: Mapping[str, tuple[str, ...]],
            start: Mapping[str, int], objective: Objective, budget: Budget, seed: int = 0,
            floor: float | None = None) -> tuple[dict[str, tuple[str, ...]], dict[str, int], float]:
    """The descent of the module docstring from the schedule ``teams`` / ``start`` of
    ``chosen``, restarted from random kicks (``seed``) while the budget lasts and the objective
    is above ``floor`` (a lower bound: nothing better exists); returns the teams, start times
    and objective of the best schedule found."""
    found = improve_schedule(problem, chosen, teams, start, objective, budget, seed, floor)
    return found.teams, found.start, found.value


def improve_schedule(problem: AllocationProblem, chosen: Sequence[str], teams: Mapping[str, tuple[str, ...]],
                     start: Mapping[str, int], objective: Objective, budget: Budget, seed: int = 0,
                     floor: float | None = None) -> Improved:
    """:func:`improve`, saying whether the budget cut it (the allocation reports it)."""
    running = budget.running()
    evaluator = _Evaluator(problem, chosen, objective)
    # the busy robots only: an evaluation then costs the jobs, not the fleet (idle robots are
    # reached through the moves, problem.first_idle)
    sequences = {r: s for r, s in robot_sequences(problem, chosen, teams, start).items() if s}
    first = evaluator(sequences)
    if first is None:  # the start times contradict the precedences: not a schedule to improve
        return Improved(dict(teams), dict(start), float("inf"))
    units = _units(problem, chosen, teams)
    stall = 0  # kicks since the last improvement

    def left() -> bool:
        return evaluator.count < MAX_EVALUATIONS and stall < STALL and running(evaluator.count * len(chosen))

    sequences, best = _descend(problem, evaluator, sequences, first, units, left)
    rng = random.Random(seed)
    while units and left() and (floor is None or best.score[0] > floor):
        stall += 1
        kicked = _kick(problem, sequences, units, rng)
        moved = evaluator(kicked)
        if moved is None:
            continue
        trial, result = _descend(problem, evaluator, kicked, moved, units, left)
        if result.score < best.score:
            sequences, best, stall = trial, result, 0
    cut = not running(evaluator.count * len(chosen)) and (floor is None or best.score[0] > floor)
    return Improved(robot_teams(sequences, chosen), best.start, best.score[0], cut)


def _descend(problem: AllocationProblem, evaluator: _Evaluator, sequences: Sequences, best: Evaluated,
             units: list[list[str]], left: Callable[[], bool]) -> tuple[Sequences, Evaluated]:
    """Better moves while there are some and the budget lasts."""
    while left():
        found = _better_move(problem, evaluator, sequences, units, best, left)
        if found is None:
            break
        sequences, best = found
    return sequences, best


def _kick(problem: AllocationProblem, sequences: Sequences, units: list[list[str]], rng: random.Random) -> Sequences:
    """``KICK`` random units moved to random able robots: a way out of a local optimum."""
    out = sequences
    for unit in rng.sample(units, min(KICK, len(units))):
        source = next(r for r, s in out.items() if unit[0] in s)
        able = problem.having(frozenset().union(*(problem.jobs[j].capabilities for j in unit)))
        order = {j: i for r in out for i, j in enumerate(out[r])}
        out = _relocate(problem, out, sorted(unit, key=order.__getitem__), source, rng.choice(able))
    return out


def _units(problem: AllocationProblem, chosen: Sequence[str], teams: Mapping[str, tuple[str, ...]]) -> list[list[str]]:
    """The chosen jobs done by one robot, grouped with those that must share it, in a fixed
    order; a group with a team job is left out."""
    group = {j: j for j in chosen}

    def root(j: str) -> str:
        while group[j] != j:
            j = group[j]
        return j

    for a, b in problem.same_robots:
        if a in group and b in group:
            group[root(a)] = root(b)
    members: dict[str, list[str]] = {}
    for j in chosen:
        members.setdefault(root(j), []).append(j)
    return [jobs for jobs in members.values() if all(len(teams[j]) == 1 for j in jobs)]


def _better_move(problem: AllocationProblem, evaluator: _Evaluator, sequences: Sequences, units: list[list[str]],
                 best: Evaluated, left: Callable[[], bool]) -> tuple[Sequences, Evaluated] | None:
    """The first move that scores better than ``best``: each kind of :data:`MOVES` in turn, off
    the robots that finish last first; None also when the budget (``left``) ends first."""
    end = {j: best.start[j] + problem.jobs[j].duration for j in best.start}
    order = sorted((r for r in sequences if sequences[r]), key=lambda r: (-end[sequences[r][-1]], r))
    around = _Around(problem, sequences, units, best, end, evaluator.trip)
    for move in MOVES:
        for robot in order:
            for moved in move(around, robot):
                result = evaluator(moved)
                if result is not None and result.score < best.score:
                    return moved, result
                if not left():
                    return None
    return None


@dataclass(frozen=True)
class _Around:
    """A schedule the moves start from: its sequences, units and end times."""

    problem: AllocationProblem
    sequences: Sequences
    units: list[list[str]]
    best: Evaluated
    end: dict[str, int]
    trip: Callable[[str, str | None, str | None], int]  # (robot, from, to) -> seconds
    current: dict[str, int] = field(default_factory=dict)  # each robot's work now (see no_longer)

    def units_of(self, robot: str) -> list[list[str]]:
        """``robot``'s units, the longest first, each in the order of its start times."""
        mine = [u for u in self.units if u[0] in self.sequences[robot]]
        mine.sort(key=lambda u: -sum(self.problem.jobs[j].duration for j in u))
        return [sorted(u, key=lambda j: (self.best.start[j], j)) for u in mine]

    def able(self, robot: str, unit: list[str]) -> bool:
        return all(robot in self.problem.able(j) for j in unit)

    def finish(self, robot: str) -> int:
        sequence = self.sequences.get(robot)
        return self.end[sequence[-1]] if sequence else 0

    def work(self, robot: str, sequence: Sequence[str]) -> int:
        """What ``robot`` spends on ``sequence`` without waiting: its jobs and its trips."""
        jobs = self.problem.jobs
        here = self.problem.robots[robot].start
        total = 0
        for j in sequence:
            total += jobs[j].duration + self.trip(robot, here, jobs[j].location)
            here = jobs[j].location or here
        return total

    def no_longer(self, robot: str, sequence: Sequence[str]) -> bool:
        """Whether ``robot`` spends no more on ``sequence`` than on its sequence now: the moves
        beyond relocation are evaluated only then, as the evaluations are what the search spends."""
        if robot not in self.current:
            self.current[robot] = self.work(robot, self.sequences[robot])
        return self.work(robot, sequence) <= self.current[robot]


def _relocations(around: _Around, robot: str) -> Iterator[Sequences]:
    """Each unit of ``robot`` to its own sequence again (reinserted) or to another able robot's,
    the robots that finish first first (of the idle ones, the first of each kind)."""
    robots = list(around.sequences) + around.problem.first_idle(around.sequences)
    targets = sorted(robots, key=lambda r: (r != robot, around.finish(r), r))
    for unit in around.units_of(robot):
        for target in targets:
            if around.able(target, unit):
                yield _relocate(around.problem, around.sequences, unit, robot, target)


def _swaps(around: _Around, robot: str) -> Iterator[Sequences]:
    """Each unit of ``robot`` exchanged with a unit of another robot when each robot can do
    the other's: what a relocation cannot do when every other robot is as busy."""
    others = sorted((r for r in around.sequences if r != robot), key=lambda r: (around.finish(r), r))
    for unit in around.units_of(robot):
        for other in others:
            if not around.able(other, unit):
                continue
            for theirs in around.units_of(other):
                if around.able(robot, theirs):
                    there = _relocate(around.problem, around.sequences, unit, robot, other)
                    swapped = _relocate(around.problem, there, theirs, other, robot)
                    if around.no_longer(robot, swapped[robot]):
                        yield swapped


def _segment_moves(around: _Around, robot: str) -> Iterator[Sequences]:
    """Or-opt on ``robot``'s own sequence: up to ``SEGMENT`` consecutive jobs moved, in order,
    to every other position of it (the exact evaluation judges the waits as well as the
    trips, which a least-travel insertion does not)."""
    sequence = around.sequences[robot]
    for length in range(1, SEGMENT + 1):
        for i in range(len(sequence) - length + 1):
            rest = sequence[:i] + sequence[i + length:]
            for at in range(len(rest) + 1):
                moved = rest[:at] + sequence[i:i + length] + rest[at:]
                if at != i and around.no_longer(robot, moved):
                    yield {**around.sequences, robot: moved}


def _reversals(around: _Around, robot: str) -> Iterator[Sequences]:
    """2-opt on ``robot``'s own sequence: each stretch of it done backwards, which uncrosses
    its route (the evaluator rejects a reversal against a precedence)."""
    sequence = around.sequences[robot]
    for i in range(len(sequence) - 1):
        for k in range(i + 2, len(sequence) + 1):
            reversed_ = sequence[:i] + sequence[i:k][::-1] + sequence[k:]
            if around.no_longer(robot, reversed_):
                yield {**around.sequences, robot: reversed_}


Move = Callable[[_Around, str], Iterator[Sequences]]
MOVES: tuple[Move, ...] = (_relocations, _segment_moves, _reversals, _swaps)  # cheapest first


def _relocate(problem: AllocationProblem, sequences: Sequences, unit: list[str], source: str, target: str) -> Sequences:
    """``sequences`` with ``unit`` taken off ``source`` and each of its jobs inserted, in order,
    where it adds the least travel to ``target``'s sequence."""
    out = dict(sequences)  # the other robots' lists are shared, not copied: a fleet can be large
    out[source] = [j for j in out[source] if j not in unit]
    robot = problem.robots[target]
    sequence = out[target] = list(out.get(target, ()))
    earliest = 0
    for j in unit:
        place = problem.jobs[j].location
        best_at, best_cost = len(sequence), None
        before = _place_before(problem, sequence, earliest, robot.start)
        for at in range(earliest, len(sequence) + 1):
            if at > earliest:  # where the robot is before the at-th job: carried along
                before = problem.jobs[sequence[at - 1]].location or before
            after = problem.jobs[sequence[at]].location if at < len(sequence) else None
            cost = problem.time(robot, before, place) + problem.time(robot, place, after or place) - (
                problem.time(robot, before, after) if after else 0)
            if best_cost is None or cost < best_cost:
                best_at, best_cost = at, cost
        sequence.insert(best_at, j)
        earliest = best_at + 1
    return out


def _place_before(problem: AllocationProblem, sequence: list[str], at: int, origin: str | None) -> str | None:
    """Where a robot is before the ``at``-th job of its sequence."""
    for j in reversed(sequence[:at]):
        if problem.jobs[j].location is not None:
            return problem.jobs[j].location
    return origin
