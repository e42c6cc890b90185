"""An independent checker of ``mutrose-cp allocate``'s outputs.

It shares no code with the allocation package: it reads the schedule file, the decomposition
output and the fleet file as plain JSON, computes durations and travel times itself (the world's
``x``/``y`` fields, the fleet's coordinates and travel table, shortest paths with networkx), and
checks every rule of the allocation against the mission's task graph and constraints:

* the decomposition written is one valid mission decomposition (the project's output
  validator, itself independent of the solvers), and the schedule's tasks are exactly it;
* each task's robots: as many as its robot number, each with every capability its actions need;
* its duration is the sum of its actions' (the fleet's rules: action, else capability, else
  default);
* execution constraints: the same single robot (Group=False) or the same team (Divisible=False);
* precedences: SEQ and FB, also through tasks that are not executed (the constraint list is
  transitively reduced);
* per robot: one thing at a time, and before each task the trip from where the robot is (its
  start, then its last task's place) takes the travel time at its speed;
* the routes and the tasks agree; makespan and travel are what the routes say; the objective is
  not below any bound reported, and a proven optimum has no gap.
"""
from __future__ import annotations

import json
import math
from pathlib import Path

import networkx as nx

from mutrose_cp.io.decomposition_output import load_decomposition_output
from mutrose_cp.mission import Mission
from mutrose_cp.validate import validate


class AllocationRuleBroken(AssertionError):
    pass


def _fail(rule: str, detail: object) -> None:
    raise AllocationRuleBroken(f"{rule}: {detail}")


def check_allocation(mission: Mission, fleet_path: Path, schedule_path: Path, output_path: Path) -> dict:
    """Check every rule (see the module docstring); returns the schedule document."""
    fleet = json.loads(Path(fleet_path).read_text())
    doc = json.loads(Path(schedule_path).read_text())
    tg = mission.task_graph
    decompositions = {v.content: v for v in tg.decompositions()}
    chosen = [t["decomposition"] for t in doc["tasks"]]
    _check_decomposition(mission, output_path, chosen, tg)
    robots = {r["name"]: r for r in fleet["robots"]}
    tasks = {t["decomposition"]: t for t in doc["tasks"]}
    for d, task in tasks.items():
        _check_task(mission, fleet, robots, decompositions[d], task)
    _check_constraints(mission, tasks)
    travel = _travel_times(mission, fleet)
    total = 0
    for robot in doc["robots"]:
        total += _check_route(robots[robot["name"]], robot["tasks"], tasks, travel)
    for d, task in tasks.items():
        on = sorted(r["name"] for r in doc["robots"] if any(v["decomposition"] == d for v in r["tasks"]))
        if on != sorted(task["robots"]):
            _fail("routes and tasks disagree", (d, on, task["robots"]))
    makespan = max((t["end"] for t in doc["tasks"]), default=0)
    if doc["makespan"] != makespan or doc["travel"] != total:
        _fail("makespan or travel misreported", (doc["makespan"], makespan, doc["travel"], total))
    _check_objective(doc["objective"], makespan, total)
    return doc


def _check_decomposition(mission: Mission, output_path: Path, chosen: list[str], tg) -> None:
    output = load_decomposition_output(str(output_path))
    report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state, output)
    if not report.valid or report.checked != 1:
        _fail("the decomposition written is not one valid mission decomposition", report.violations)
    keys = {f"t{i}": v.content for i, v in enumerate(tg.decompositions())}
    listed = [keys[k] for k in output.mission_decompositions[0]]
    if sorted(listed) != sorted(chosen):
        _fail("the schedule's tasks are not the decomposition written", (listed, chosen))


def _duration(fleet: dict, action) -> int:
    table = fleet.get("durations", {})
    if action.name in table.get("actions", {}):
        return table["actions"][action.name]
    by_capability = [table.get("capabilities", {})[c] for c in action.capabilities
                     if c in table.get("capabilities", {})]
    return max(by_capability) if by_capability else table.get("default", 1)


def _check_task(mission: Mission, fleet: dict, robots: dict, vertex, task: dict) -> None:
    dec = vertex.decomposition
    actions = [mission.domain.action_by_name[a.name] for a in dec.path.actions]
    team = task["robots"]
    number = dec.instance.robot_number
    if len(set(team)) != len(team) or not number.min <= len(team) <= number.max:
        _fail("robot number", (task["decomposition"], team, number))
    needed = {c for a in actions for c in a.capabilities}
    for r in team:
        if not needed <= set(robots[r]["capabilities"]):
            _fail("capabilities", (task["decomposition"], r, needed))
    if task["end"] - task["start"] != sum(_duration(fleet, a) for a in actions):
        _fail("duration", task)


def _check_constraints(mission: Mission, tasks: dict) -> None:
    tg = mission.task_graph
    order = nx.DiGraph()
    for c in mission.constraints:
        first, second = tg.vertices[c.first].content, tg.vertices[c.second].content
        if c.kind in ("SEQ", "FB"):
            order.add_edge(first, second)
        elif c.kind == "EC" and first in tasks and second in tasks:
            a, b = tasks[first]["robots"], tasks[second]["robots"]
            if not c.group and not (len(a) == 1 and a == b):
                _fail("execution constraint: the same robot", (first, a, second, b))
            if c.group and not c.divisible and sorted(a) != sorted(b):
                _fail("execution constraint: the same team", (first, a, second, b))
    for first in tasks:
        if first not in order:
            continue
        for second in nx.descendants(order, first):
            if second in tasks and tasks[first]["end"] > tasks[second]["start"]:
                _fail("precedence", (first, tasks[first]["end"], second, tasks[second]["start"]))


def _travel_times(mission: Mission, fleet: dict):
    """``(a, b) -> time at speed 1``: the world's coordinates, the fleet's own, its table and
    shortest paths."""
    points = {}
    knowledge = mission.knowledge
    for kind in mission.config.location_types:
        for record in knowledge.records_of(kind):
            x, y = record.findtext("x"), record.findtext("y")
            if x is not None and y is not None:
                points[knowledge.record_id(record)] = (float(x), float(y))
    travel = fleet.get("travel", {})
    points.update({k: tuple(v) for k, v in travel.get("coordinates", {}).items()})
    metric = travel.get("metric", "euclidean")
    graph = nx.DiGraph()
    for a, pa in points.items():
        for b, pb in points.items():
            if a != b:
                dx, dy = pa[0] - pb[0], pa[1] - pb[1]
                graph.add_edge(a, b, weight=abs(dx) + abs(dy) if metric == "manhattan" else math.hypot(dx, dy))
    for a, row in travel.get("times", {}).items():
        for b, t in row.items():
            graph.add_edge(a, b, weight=t)
            if a not in travel["times"].get(b, {}):  # both directions, unless the reverse is given
                graph.add_edge(b, a, weight=t)
    modelled = bool(points) or bool(travel.get("times"))
    lengths: dict[str, dict[str, float]] = {}  # from each place asked about (a road network can be large)

    def time(robot: dict, a: str | None, b: str | None) -> int:
        if not modelled or a is None or b is None or a == b:
            return 0
        if a not in lengths:
            lengths[a] = nx.single_source_dijkstra_path_length(graph, a)
        return math.ceil(lengths[a][b] / robot.get("speed", 1.0) - 1e-9)

    return time


def _check_route(robot: dict, visits: list[dict], tasks: dict, travel) -> int:
    """One thing at a time, each trip long enough; returns the robot's travel."""
    place, free, total = robot.get("start"), 0, 0
    for v in visits:
        task = tasks[v["decomposition"]]
        if (v["start"], v["end"]) != (task["start"], task["end"]) or v["location"] != task["location"]:
            _fail("route entry differs from its task", (robot["name"], v, task))
        trip = travel(robot, place, v["location"])
        reported = v.get("travel", {}).get("time", 0)
        if reported != trip:
            _fail("travel time", (robot["name"], v["decomposition"], place, v["location"], reported, trip))
        if v["start"] < free + trip:
            _fail("overlap or trip too short", (robot["name"], v["decomposition"], free, trip, v["start"]))
        if trip and (v["travel"]["departure"] < free or v["travel"]["from"] != place):
            _fail("trip leaves before the previous task ends", (robot["name"], v))
        total += trip
        free = v["end"]
        place = v["location"] or place
    return total


def _check_objective(objective: dict, makespan: int, travel: int) -> None:
    kind = objective["kind"]
    if kind == "makespan":
        value = makespan
    elif kind == "travel":
        value = travel
    else:
        a, b = (int(w) for w in kind.removeprefix("weighted:").split(","))
        value = a * makespan + b * travel
    if objective["value"] != value:
        _fail("objective value", (objective, value))
    for bound in ("bound", "lp_bound", "load_bound"):
        if objective[bound] is not None and objective[bound] > value + 1e-6:
            _fail(f"{bound} above the objective", (objective, value))
    if objective["status"] == "OPTIMAL" and objective["gap"] != 0:
        _fail("an optimum with a gap", objective)
    if objective["status"] not in ("OPTIMAL", "FEASIBLE"):
        _fail("status", objective)
