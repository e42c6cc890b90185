"""What ``compare`` shows: a table for the terminal, a JSON object for scripts, a bar chart.

The table has one row per decomposer (status, wall time, peak memory, number of valid mission
decompositions, whether it agrees with the reference run), then the runs that did not finish
and, for each run that disagrees, its first differences in task ids.  The chart needs
matplotlib (the ``bench`` extra, :mod:`mutrose_cp.output.charts`).
"""
from __future__ import annotations

from typing import Any, Sequence

from ..output.charts import chart_format, figure, save_chart
from .run import FINISHED, TIMED_OUT, CompareReport, Comparison, Run
from ..output.counts import shown_count
from .outputs import nearest

SHOWN = 5  # differences of each kind in the table
LISTED = 40  # differences of each kind in the JSON object


def _agrees(report: CompareReport, run: Run) -> str:
    if run.decomposer == report.reference:
        return "reference"
    for c in report.comparisons:
        if c.decomposer == run.decomposer:
            return "yes" if c.agree else "NO"
    return "-"


def _rows(report: CompareReport) -> list[tuple[str, ...]]:
    return [(r.decomposer, r.status, f"{r.seconds:.2f} s", f"{r.peak_mb:.1f} MB", shown_count(r.count),
             _agrees(report, r)) for r in report.runs]


def _aligned(header: Sequence[str], rows: Sequence[Sequence[str]]) -> list[str]:
    """Text columns left-aligned, number columns (time, memory, count) right-aligned."""
    widths = [max(len(row[i]) for row in (header, *rows)) for i in range(len(header))]
    right = {2, 3, 4}
    return ["  ".join(cell.rjust(w) if i in right else cell.ljust(w)
                      for i, (cell, w) in enumerate(zip(row, widths))).rstrip() for row in (header, *rows)]


def _unfinished(report: CompareReport) -> list[str]:
    lines = []
    for r in report.runs:
        if r.status == TIMED_OUT:
            lines.append(f"{r.decomposer}: timed out after {report.request.time_limit:g} s (killed; no result)")
        elif r.status != FINISHED:
            lines.append(f"{r.decomposer}: failed: {r.error}")
        elif r.note:
            lines.append(f"{r.decomposer}: {r.note}")
    return lines


def _some(items: Sequence[str], total: int | None = None) -> str:
    more = (total if total is not None else len(items)) - min(len(items), SHOWN)
    return "; ".join(items[:SHOWN]) + (f"; and {more} more" if more > 0 else "")


def _decomposition_lines(c: Comparison) -> list[str]:
    """The first decompositions found by one side only, each with how the nearest one of the
    other side differs from it, task by task (``-AT2_1|2 +AT2_1|1``)."""
    assert c.diff is not None
    lines = []
    for label, mine, theirs, other in ((c.reference, c.diff.missing_decompositions, c.diff.unexpected_decompositions,
                                        c.decomposer),
                                       (c.decomposer, c.diff.unexpected_decompositions, c.diff.missing_decompositions,
                                        c.reference)):
        if mine:
            lines.append(f"    {len(mine)} only in {label}{', the first:' if len(mine) > SHOWN else ':'}")
        for ids in mine[:SHOWN]:
            near = nearest(ids, theirs)
            change = " ".join([*(f"-{i}" for i in near[0]), *(f"+{i}" for i in near[1])]) if near else ""
            lines.append(f"      {' '.join(ids)}" + (f"  (nearest in {other}: {change})" if near else ""))
    return lines


def _difference_lines(c: Comparison) -> list[str]:
    lines = [f"{c.decomposer} differs from {c.reference}:"]
    if c.diff is None:
        return [*lines, f"  mission decompositions: {c.note}, and they differ"]
    d = c.diff
    for aspect, only_reference, only_run in (("task ids", d.missing_ids, d.unexpected_ids),
                                             ("constraints", d.missing_constraints, d.unexpected_constraints)):
        if only_reference:
            lines.append(f"  {aspect} only in {c.reference}: {_some(only_reference)}")
        if only_run:
            lines.append(f"  {aspect} only in {c.decomposer}: {_some(only_run)}")
    if d.changed_fields:
        lines.append(f"  task fields ({c.reference} vs {c.decomposer}): {_some(d.changed_fields)}")
    if not c.diff.agrees("mission decompositions"):
        lines += ["  mission decompositions:", *_decomposition_lines(c)]
    return lines


def _verdict(report: CompareReport) -> str:
    finished = [r.decomposer for r in report.runs if r.status == FINISHED]
    if len(finished) < 2:
        return f"nothing to compare: only {finished[0]} finished" if finished else "nothing to compare: no run finished"
    if not report.agree:
        differing = [c.decomposer for c in report.comparisons if not c.agree]
        return f"DISAGREE: {', '.join(differing)} {'differs' if len(differing) == 1 else 'differ'} from {report.reference}"
    counts = shown_count(next(r.count for r in report.runs if r.status == FINISHED))
    return f"agree: {', '.join(finished)} ({counts} valid mission decompositions)"


def render_table(report: CompareReport) -> str:
    """The report as text for the terminal."""
    request = report.request
    lines = [f"mission: {request.hddl}, {request.gm}, {request.config}", ""]
    lines += _aligned(("decomposer", "status", "wall time", "peak memory", "decompositions", "agrees"), _rows(report))
    notes = _unfinished(report) + [f"{c.decomposer}: {c.note}" for c in report.comparisons if c.note and c.agree]
    if notes:
        lines += ["", *notes]
    for c in report.comparisons:
        if not c.agree:
            lines += ["", *_difference_lines(c)]
    lines += ["", _verdict(report)]
    return "\n".join(lines)


# ---------------------------------------------------------------------------------------------
# JSON


def _run_json(run: Run) -> dict[str, Any]:
    return {"decomposer": run.decomposer, "status": run.status, "exit_status": run.exit_status,
            "seconds": round(run.seconds, 3), "peak_mb": round(run.peak_mb, 1),
            "mission_decompositions": None if run.count is None else str(run.count),
            "error": run.error or None, "note": run.note or None}


def _differences_json(c: Comparison) -> list[dict[str, Any]]:
    if c.diff is None:
        return []
    d = c.diff
    kinds = (("task ids", d.missing_ids, d.unexpected_ids),
             ("constraints", d.missing_constraints, d.unexpected_constraints),
             ("mission decompositions", d.missing_decompositions, d.unexpected_decompositions))
    out: list[dict[str, Any]] = [
        {"aspect": aspect, "only_in_reference": [list(x) if isinstance(x, tuple) else x for x in mine[:LISTED]],
         "only_in_reference_count": len(mine),
         "only_in_run": [list(x) if isinstance(x, tuple) else x for x in theirs[:LISTED]],
         "only_in_run_count": len(theirs)}
        for aspect, mine, theirs in kinds if mine or theirs]
    if d.changed_fields:
        out.append({"aspect": "task fields", "changed": list(d.changed_fields[:LISTED]),
                    "changed_count": len(d.changed_fields)})
    return out


def report_json(report: CompareReport) -> dict[str, Any]:
    """The report as one JSON object (see docs/cli.md, ``compare``)."""
    request = report.request
    return {
        "command": "compare",
        "inputs": {"hddl": str(request.hddl), "gm": str(request.gm), "configuration": str(request.config)},
        "time_limit_s": request.time_limit,
        "limit": request.limit or 0,
        "runs": [_run_json(r) for r in report.runs],
        "reference": report.reference,
        "comparisons": [{"decomposer": c.decomposer, "reference": c.reference, "agree": c.agree,
                         "aspects": c.aspects, "note": c.note or None, "differences": _differences_json(c)}
                        for c in report.comparisons],
        "agree": report.agree,
    }


# ---------------------------------------------------------------------------------------------
# Bar chart


def plot_format(path: str) -> str:
    """The chart's format from the file suffix; checked, with matplotlib's presence, before any
    decomposer runs."""
    return chart_format(path, "--plot")


def write_plot(report: CompareReport, path: str) -> None:
    """Two bar charts side by side, wall time and peak memory per decomposer; a run that timed
    out or failed is hatched and labelled so.  Written atomically; the same report gives the same
    bytes (no creation date in SVG or PDF)."""
    fmt = plot_format(path)
    names = [r.decomposer for r in report.runs]
    chart = figure(figsize=(8, 3.6), layout="constrained")
    chart.suptitle(f"{report.request.config.name}: {_verdict(report)}", fontsize=9)
    for axes, values, title, unit in zip(chart.subplots(1, 2), ([r.seconds for r in report.runs],
                                                                 [r.peak_mb for r in report.runs]),
                                         ("wall time (s)", "peak memory (MB)"), ("s", "MB")):
        bars = axes.bar(names, values, color=["#4c72b0" if r.status == FINISHED else "#bbbbbb" for r in report.runs])
        for bar, run in zip(bars, report.runs):
            if run.status != FINISHED:
                bar.set_hatch("//")
        axes.bar_label(bars, labels=[f"{v:.2f} {unit}" if r.status == FINISHED else r.status
                                     for v, r in zip(values, report.runs)], fontsize=8)
        axes.set_title(title)
        axes.margins(y=0.15)
    save_chart(chart, path, fmt)
