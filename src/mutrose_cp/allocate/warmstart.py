"""A first schedule, handed to CP-SAT as a hint: decomposition first, then a greedy allocation.

1. The decomposition: the least total work, found exactly by the decomposer's optimisation
   (``decompose --optimize`` with the fleet's action durations as costs).
2. The allocation: its jobs in an order that respects the precedences, each given the robots
   (among those able) that can be there first, where it must share robots with a job already
   placed, those robots; it starts when its predecessors have ended and its robots arrived.

The hint only guides the search: CP-SAT checks it like any other assignment, and a mission
where the greedy step gets stuck (the first decomposition needs robots that the greedy choice
used up) is simply searched without a hint.
"""
from __future__ import annotations

from dataclasses import dataclass
from graphlib import CycleError, TopologicalSorter

from ..errors import MissionError
from ..solve.decompose import DecompositionRequest
from ..solve.optimize import CostModel
from .model import START, AllocationModel
from .problem import AllocationProblem
from .schedule import chosen_predecessors

Plan = tuple[dict[str, tuple[str, ...]], dict[str, int]]  # teams and start times of the chosen jobs


@dataclass(frozen=True)
class WarmStart:
    """The greedy schedule: the chosen jobs, their teams and start times."""

    chosen: list[str]
    teams: dict[str, tuple[str, ...]]
    start: dict[str, int]

    def route_arcs(self, problem: AllocationProblem) -> set[tuple[str, str]]:
        """The arcs of every robot's route (from ``START`` for its first located job)."""
        arcs: set[tuple[str, str]] = set()
        for robot in problem.fleet.robots:
            route = [j for j in sorted((j for j in self.chosen if robot.name in self.teams[j]),
                                       key=lambda j: (self.start[j], j)) if problem.jobs[j].location is not None]
            arcs |= set(zip([START] + route, route))
        return arcs


def warm_start(problem: AllocationProblem) -> WarmStart | None:
    """The greedy schedule of the least-work decomposition; None when there is none."""
    chosen = least_work_decomposition(problem)
    if chosen is None:
        return None
    plan = greedy_plan(problem, chosen)
    return None if plan is None else WarmStart(chosen, *plan)


def add_hint(am: AllocationModel, warm: WarmStart) -> None:
    """Hint ``warm`` to CP-SAT."""
    _hint(am, warm)


def least_work_decomposition(problem: AllocationProblem) -> list[str] | None:
    """The valid mission decomposition with the least total work (ids, in mission order)."""
    mission = problem.dm.mission
    durations = problem.fleet.durations
    costs = CostModel(actions={a.name: durations.of_action(a.name, a.capabilities) for a in mission.domain.actions})
    try:
        result = mission.decompose(DecompositionRequest(optimize=True, costs=costs))
    except MissionError:
        return None
    if result.optimum is None:
        return None
    tg = mission.task_graph
    ids = [tg.vertices[v].content for v in result.optimum[0]]
    return ids if all(d in problem.jobs for d in ids) else None


def greedy_plan(problem: AllocationProblem, chosen: list[str]) -> Plan | None:
    """Teams and start times for ``chosen`` (see the module docstring), None when stuck."""
    order = _precedence_order(problem, chosen)
    if order is None:
        return None
    robots = {r.name: r for r in problem.fleet.robots}
    free = dict.fromkeys(robots, 0)
    place = {r.name: r.start for r in problem.fleet.robots}
    partners = _partners(problem, set(chosen))
    before = chosen_predecessors(problem, set(chosen))
    teams: dict[str, tuple[str, ...]] = {}
    start: dict[str, int] = {}
    for j in order:
        job = problem.jobs[j]

        def arrival(r: str) -> int:
            return free[r] + problem.time(robots[r], place[r], job.location)

        placed = [teams[p] for p in partners.get(j, []) if p in teams]
        able = [r for r in job.candidates if all(r in problem.jobs[p].candidates for p in partners.get(j, []))]
        team = placed[0] if placed else tuple(sorted(able, key=lambda r: (arrival(r), r))[:job.robots.min])
        if len(team) < job.robots.min or not set(team) <= set(job.candidates) or len(team) > job.robots.max:
            return None
        ready = max([start[i] + problem.jobs[i].duration for i in before[j]] + [arrival(r) for r in team] + [0])
        teams[j], start[j] = team, ready
        for r in team:
            free[r] = ready + job.duration
            place[r] = job.location or place[r]
    return teams, start


def _precedence_order(problem: AllocationProblem, chosen: list[str]) -> list[str] | None:
    before = chosen_predecessors(problem, set(chosen))
    sorter = TopologicalSorter({j: before[j] for j in chosen})
    try:
        sorter.prepare()
    except CycleError:
        return None
    position = {j: i for i, j in enumerate(problem.jobs)}
    order: list[str] = []
    while sorter.is_active():
        ready = sorted(sorter.get_ready(), key=position.__getitem__)
        order += ready
        sorter.done(*ready)
    return order


def _partners(problem: AllocationProblem, chosen: set[str]) -> dict[str, list[str]]:
    out: dict[str, list[str]] = {}
    for a, b in problem.same_robots:
        if a in chosen and b in chosen:
            out.setdefault(a, []).append(b)
            out.setdefault(b, []).append(a)
    return out


def _hint(am: AllocationModel, warm: WarmStart) -> None:
    m, dm, problem = am.model, am.problem.dm, am.problem
    chosen, teams, start = warm.chosen, warm.teams, warm.start
    picked = set(chosen)
    for d, literal in dm.decomposition.items():
        if d in problem.jobs:
            _hint_literal(m, literal, d in picked)
    for (j, r), a in am.assign.items():
        m.add_hint(a, j in picked and r in teams[j])
    for j in chosen:
        m.add_hint(am.start[j], start[j])
        m.add_hint(am.end[j], start[j] + problem.jobs[j].duration)
    used = warm.route_arcs(problem)
    for arcs in am.arcs.values():
        for arc in arcs:
            m.add_hint(arc.literal, (arc.source, arc.target) in used)


def _hint_literal(m: object, literal: object, value: bool) -> None:
    index = literal.index  # type: ignore[attr-defined]
    variable = m.get_bool_var_from_proto_index(index if index >= 0 else -index - 1)  # type: ignore[attr-defined]
    domain = list(m.proto.variables[variable.index].domain)  # type: ignore[attr-defined]
    if domain[0] != domain[-1]:  # constants need no hint
        m.add_hint(variable, value if index >= 0 else not value)  # type: ignore[attr-defined]
