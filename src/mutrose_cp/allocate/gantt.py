"""``--gantt FILE.png|svg``: the schedule as a Gantt chart, one row per robot.

Work is drawn as solid bars labelled with the task, travel as hatched grey bars before them,
so the time a robot spends moving stands apart from the time it spends working.  Matplotlib is
the optional ``bench`` extra (:mod:`mutrose_cp.output.charts`).

Robot and task names are the fleet's and the mission's, any text: they are drawn as they are
written, never read as matplotlib's mathematical notation (``$x^`` would fail the drawing, and
``a$b$`` turn into other text) nor handed to TeX, whatever the user's matplotlib settings.
"""
from __future__ import annotations

import os

from ..output.charts import chart_format, figure, save_chart
from .allocation import Allocation

FORMATS = ("png", "svg")
OPTION = "--gantt"
ALL_ROBOTS = 60  # robots: a larger fleet's idle robots are left out of the chart
MAX_ROWS = 800  # rows drawn at most (matplotlib refuses an image over 65,536 pixels high)


def gantt_format(path: str | os.PathLike[str]) -> str:
    """The image format of ``path`` from its suffix, matplotlib checked: before any work."""
    return chart_format(path, OPTION, FORMATS)


def write_gantt(allocation: Allocation, path: str | os.PathLike[str]) -> None:
    """Draw the schedule and write it atomically to ``path`` (PNG or SVG, by its suffix)."""
    import matplotlib

    fmt = gantt_format(path)
    with matplotlib.rc_context({"text.usetex": False}):  # a user's matplotlibrc may turn TeX on
        _draw(allocation, path, fmt)


def _draw(allocation: Allocation, path: str | os.PathLike[str], fmt: str) -> None:
    import matplotlib

    schedule, problem = allocation.schedule, allocation.problem
    robots, left_out = _rows(allocation)
    colours = matplotlib.colormaps["tab20"]
    tasks = {j: i for i, j in enumerate(schedule.jobs)}
    chart = figure(figsize=(max(8.0, min(24.0, 0.4 * schedule.makespan ** 0.5 + 8)), 1.0 + 0.55 * len(robots)))
    ax = chart.subplots()
    for row, robot in enumerate(robots):
        for v in schedule.routes[robot]:
            if v.travel:
                ax.barh(row, v.travel, left=v.departure, height=0.5, color="#d9d9d9", hatch="///",
                        edgecolor="#7f7f7f", linewidth=0.5)
            ax.barh(row, max(v.end - v.start, 0.001), left=v.start, height=0.7, color=colours(tasks[v.job] % 20),
                    edgecolor="black", linewidth=0.5)
            ax.text((v.start + v.end) / 2, row, problem.jobs[v.job].task, ha="center", va="center", fontsize=7,
                    parse_math=False)
    ax.set_yticks(range(len(robots)), robots, parse_math=False)
    ax.invert_yaxis()
    ax.set_xlabel("time")
    ax.set_xlim(0, max(schedule.makespan, 1))
    ax.set_title(f"{allocation.options.objective.name} {allocation.objective} "
                 f"({'optimal' if allocation.status == 'OPTIMAL' else 'best found'}); hatched: travel{left_out}",
                 parse_math=False)
    chart.tight_layout()
    save_chart(chart, path, fmt, dpi=120)


def _rows(allocation: Allocation) -> tuple[list[str], str]:
    """The robots drawn, one row each, and what the title says of those left out: every robot
    of a small fleet; of a large one, the robots with tasks, at most :data:`MAX_ROWS`."""
    names = [r.name for r in allocation.problem.fleet.robots]
    if len(names) <= ALL_ROBOTS:
        return names, ""
    busy = [r for r in names if allocation.schedule.routes[r]]
    shown = busy[:MAX_ROWS]
    more = f", the first {len(shown)} of them shown" if len(shown) < len(busy) else ""
    return shown, f"; {len(names) - len(busy)} idle robots of {len(names)} not shown{more}"
