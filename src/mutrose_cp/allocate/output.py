"""What an allocation writes: the schedule file, the chosen decomposition, the summary.

* The schedule (``docs/formats/schedule.md``): per robot its route (each task with the trip
  before it), per task its robots, and what is proven about the objective.  It holds no clock
  time, so the same inputs and a search that finished give the same bytes.
* The chosen decomposition in the original output format (``output.py``), listed as the only
  mission decomposition: a tool that executes ``mission_decompositions[0]`` executes the
  allocated one.
"""
from __future__ import annotations

import json
import os
from typing import Any

from ..output.builder import OutputModel
from ..output.formats import write_output
from ..output.files import atomic_writer
from .allocation import Allocation
from .phases import CUT, SKIPPED

PHASE_NAMES = {"problem": "problem", "load": "load bound", "warm": "warm start", "lp": "LP bound", "model": "model",
               "search": "search"}

SCHEDULE_FORMAT = "mutrose-cp schedule 1"


def _number(value: float | None) -> float | int | None:
    """A bound or gap as written: whole numbers as integers, others to 6 decimals."""
    if value is None:
        return None
    rounded = round(value, 6)
    return int(rounded) if float(rounded).is_integer() else rounded


def objective_section(allocation: Allocation) -> dict[str, Any]:
    return {
        "kind": allocation.options.objective.name,
        "value": allocation.objective,
        "status": allocation.status,
        "bound": _number(allocation.cp_bound),
        "gap": _number(allocation.gap),
        "lp_bound": _number(allocation.lp_value),
        "lp_gap": _number(allocation.lp_gap),
        "lp_status": allocation.lp.status if allocation.lp is not None else None,
        "load_bound": _number(allocation.load_value),
        "load_gap": _number(allocation.load_gap),
        "restricted": allocation.restricted,
    }


def schedule_document(allocation: Allocation) -> dict[str, Any]:
    """The schedule file's content (see ``docs/formats/schedule.md``)."""
    problem, schedule = allocation.problem, allocation.schedule
    tg = problem.dm.mission.task_graph
    key = {d.content: f"t{i}" for i, d in enumerate(tg.decompositions())}
    robots = []
    for robot in problem.fleet.robots:
        visits = []
        for v in schedule.routes[robot.name]:
            job = problem.jobs[v.job]
            entry: dict[str, Any] = {"decomposition": v.job, "key": key[v.job], "task": job.task, "name": job.name,
                                     "location": v.location, "start": v.start, "end": v.end}
            if v.travel:
                entry["travel"] = {"from": v.origin, "departure": v.departure, "time": v.travel}
            visits.append(entry)
        robots.append({"name": robot.name, "start": robot.start, "tasks": visits})
    tasks = [{"decomposition": j, "key": key[j], "task": problem.jobs[j].task, "name": problem.jobs[j].name,
              "actions": list(problem.jobs[j].actions), "location": problem.jobs[j].location,
              "start": schedule.start[j], "end": schedule.end[j], "robots": list(schedule.teams[j])}
             for j in schedule.jobs]
    return {"format": SCHEDULE_FORMAT, "objective": objective_section(allocation), "makespan": schedule.makespan,
            "travel": schedule.travel, "robots": robots, "tasks": tasks}


def phases_section(allocation: Allocation) -> list[dict[str, Any]]:
    """The phases of the run as ``--json-summary`` lists them: each with its status (done, cut,
    skipped or off), its seconds and, when there is more to say, why.  Not in the schedule file,
    which holds no clock time."""
    return [{"phase": p.name, "status": p.status, "seconds": round(p.seconds, 3), **({"note": p.note} if p.note else {})}
            for p in allocation.phases]


def write_schedule(allocation: Allocation, path: str | os.PathLike[str]) -> None:
    """Write the schedule file atomically."""
    text = json.dumps(schedule_document(allocation), indent=2, ensure_ascii=False) + "\n"
    with atomic_writer(path) as fh:
        fh.write(text)


def write_decomposition(allocation: Allocation, path: str | os.PathLike[str], file_type: str) -> None:
    """Write the chosen decomposition as the only mission decomposition of an output file."""
    mission = allocation.problem.dm.mission
    tg = mission.task_graph
    index = {d.content: d.index for d in tg.decompositions()}
    chosen = [index[j] for j in allocation.schedule.jobs]
    model = OutputModel(tg, mission.constraints, [chosen], mission.domain, mission.config, mission.initial_state)
    write_output(model, path, file_type)


def summary_line(allocation: Allocation) -> str:
    """``allocated: makespan 136 (optimal), travel 214, 6 tasks on 3 robots, LP bound 74.9``."""
    schedule = allocation.schedule
    busy = sum(1 for visits in schedule.routes.values() if visits)
    kind = allocation.options.objective.name
    limit = "time limit" if allocation.options.work_limit is None else "work limit"
    if allocation.status == "OPTIMAL":
        proof = "optimal"
    elif allocation.restricted:
        proof = f"best found at the {limit}, search restricted to near robots and places"
    elif allocation.cp_bound is None:
        proof = f"the warm start: the search had no schedule yet at the {limit}"
    else:
        proof = f"best found at the {limit}, bound {allocation.cp_bound:g}, gap {_percent(allocation.gap)}"
    value = f"{kind} {allocation.objective} ({proof})"
    if kind != "makespan":
        value += f", makespan {schedule.makespan}"
    if kind != "travel":
        value += f", travel {schedule.travel}"
    return (f"allocated: {value}, {len(schedule.jobs)} tasks on {busy} of {len(schedule.routes)} robots"
            f"{_bounds(allocation)}{_short_phases(allocation)}")


def _short_phases(allocation: Allocation) -> str:
    """``; cut by the limit: LP bound; skipped: search (no time left)``: the phases that did not
    run to their end (a search cut by the limit is said so above), so that a fleet too large for
    the limit says so."""
    cut = [PHASE_NAMES.get(p.name, p.name) for p in allocation.phases if p.status == CUT and p.name != "search"]
    skipped = [f"{PHASE_NAMES.get(p.name, p.name)} ({p.note})" for p in allocation.phases if p.status == SKIPPED]
    return (f"; cut by the limit: {', '.join(cut)}" if cut else "") + (f"; skipped: {', '.join(skipped)}" if skipped else "")


def _bounds(allocation: Allocation) -> str:
    """``, LP bound 74.9 (gap 45.0%), load bound 70 (gap 48.5%)``; an LP stopped at its time
    limit is said to be so."""
    out = ""
    if allocation.lp_value is not None:
        out += f", LP bound {allocation.lp_value:.1f} (gap {_percent(allocation.lp_gap)})"
    elif allocation.lp is not None:
        out += f", LP not solved ({allocation.lp.status})"
    if allocation.load_value is not None:
        out += f", load bound {allocation.load_value:g} (gap {_percent(allocation.load_gap)})"
    return out


def _percent(gap: float | None) -> str:
    return "unknown" if gap is None else f"{100 * gap:.1f}%"
