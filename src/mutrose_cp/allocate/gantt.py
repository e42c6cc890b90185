"""``--gantt FILE.png|svg``: the schedule as a Gantt chart, one row per robot.

Work is drawn as solid bars labelled with the task, travel as hatched grey bars before them,
so the time a robot spends moving stands apart from the time it spends working.  Matplotlib is
the optional ``bench`` extra; it is imported only here.
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import Any

from ..errors import MissionError
from ..output_file import atomic_writer
from .allocation import Allocation

FORMATS = {".png": "png", ".svg": "svg"}


def gantt_format(path: str | os.PathLike[str]) -> str:
    """The image format of ``path`` from its suffix; a located error for any other suffix."""
    suffix = Path(path).suffix.lower()
    if suffix not in FORMATS:
        raise MissionError(f"the Gantt chart is written as PNG or SVG: name the file .png or .svg, not {suffix or 'without a suffix'}",
                           os.fspath(path))
    return FORMATS[suffix]


def matplotlib_ready() -> None:
    """Fail before any work when matplotlib is missing."""
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise MissionError("--gantt needs matplotlib: pip install 'mutrose-cp[bench]' (or pip install matplotlib)",
                           "--gantt") from None


def _pyplot() -> Any:  # matplotlib.pyplot
    matplotlib_ready()
    import matplotlib

    matplotlib.use("Agg")
    matplotlib.rcParams["svg.hashsalt"] = "mutrose-cp"  # the same ids in every SVG
    import matplotlib.pyplot as plt

    return plt


def write_gantt(allocation: Allocation, path: str | os.PathLike[str]) -> None:
    """Draw the schedule and write it atomically to ``path`` (PNG or SVG, by its suffix)."""
    fmt = gantt_format(path)
    plt = _pyplot()
    schedule, problem = allocation.schedule, allocation.problem
    robots = [r.name for r in problem.fleet.robots]
    colours = plt.get_cmap("tab20")
    tasks = {j: i for i, j in enumerate(schedule.jobs)}
    fig, ax = plt.subplots(figsize=(max(8.0, min(24.0, 0.4 * schedule.makespan ** 0.5 + 8)), 1.0 + 0.55 * len(robots)))
    for row, robot in enumerate(robots):
        for v in schedule.routes[robot]:
            if v.travel:
                ax.barh(row, v.travel, left=v.departure, height=0.5, color="#d9d9d9", hatch="///",
                        edgecolor="#7f7f7f", linewidth=0.5)
            ax.barh(row, max(v.end - v.start, 0.001), left=v.start, height=0.7, color=colours(tasks[v.job] % 20),
                    edgecolor="black", linewidth=0.5)
            ax.text((v.start + v.end) / 2, row, problem.jobs[v.job].task, ha="center", va="center", fontsize=7)
    ax.set_yticks(range(len(robots)), robots)
    ax.invert_yaxis()
    ax.set_xlabel("time")
    ax.set_xlim(0, max(schedule.makespan, 1))
    ax.set_title(f"{allocation.options.objective.name} {allocation.objective} "
                 f"({'optimal' if allocation.status == 'OPTIMAL' else 'best found'}); hatched: travel")
    fig.tight_layout()
    metadata = {"Date": None} if fmt == "svg" else {"Software": None}
    try:
        with atomic_writer(path, "wb") as fh:
            fig.savefig(fh, format=fmt, metadata=metadata, dpi=120)
    finally:
        plt.close(fig)
