"""The ``mutrose-cp`` command line: ``check``, ``decompose`` (and friends).

Bad input ends with located messages on stderr and exit status 2; a mission without any valid
decomposition exits with 3; nothing here prints a Python traceback.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import sys
import time
from pathlib import Path
from typing import TYPE_CHECKING, Sequence

from . import __version__
from .batch.command import add_batch_parser
from .counts import shown_count
from .errors import MissionError, Problem
from .ihtn import DEFAULT_MAX_FILES
from .interrupt import phase, signal_handlers
from .io.text import MB, input_limit
from .mission import Mission, find_mission_files, world_file
from .option_types import count_option, input_file, output_file, output_folder, seconds, work_units
from .output_file import STDOUT, refuse_unsafe_outputs, staged_outputs
from .process import (FAILURES, Failure, command_settings, exit_process, failure_lines, failure_problems,
                      failure_status, keep_until_exit, prepare_process, process_ends_with_command, reader_gone)
from .solve.decompose import DEFAULT_LIMIT, Algorithm, DecompositionRequest, DecompositionResult, cpsat_options
from .solve.optimize import CostModel

if TYPE_CHECKING:
    from .allocate.fleet import Fleet
    from .allocate.travel import TravelTimes


def _inputs(args: argparse.Namespace) -> tuple[Path, Path, Path, Path | None]:
    """(hddl, gm, config, mission folder or None) from ``HDDL GM CONFIG`` or ``MISSION_DIR``."""
    files = args.inputs
    if len(files) == 1:
        hddl, gm, cfg = find_mission_files(files[0], getattr(args, "config", None),
                                           hddl_name=getattr(args, "hddl", None), gm_name=getattr(args, "gm", None))
        return hddl, gm, cfg, Path(files[0])
    if len(files) == 3:
        return Path(files[0]), Path(files[1]), Path(files[2]), None
    raise MissionError("expected HDDL GM CONFIG, or a mission folder (hddl/ gm/ configuration/ knowledge/)")


class _Progress:
    """Progress lines on an interactive stderr; silent when redirected or ``--quiet``.

    Called as ``progress(done, total)`` for its own label, or through :meth:`stage` as
    ``(label, done, total)`` by the pipeline."""

    def __init__(self, enabled: bool, label: str = "") -> None:
        self.enabled = enabled and sys.stderr.isatty()
        self.label = label
        self.last = 0.0

    def __call__(self, done: int, total: int) -> None:
        self.stage(self.label, done, total)

    def stage(self, label: str, done: int, total: int) -> None:
        if not self.enabled:
            return  # called once per component or copy: a large mission calls it 50,000 times
        of = f"/{total}" if total else ""
        self.show(f"{label}: {done}{of}", ended=bool(total) and done >= total, now=done >= total)

    def show(self, text: str, *, ended: bool = False, now: bool = False) -> None:
        """Redraw the line as ``text``, at most every 0.1 s unless ``now``; ``ended`` closes it."""
        if not self.enabled:
            return
        moment = time.monotonic()
        if moment - self.last < 0.1 and not now:
            return
        self.last = moment
        sys.stderr.write(f"\r\033[K{text}" + ("\n" if ended else ""))
        sys.stderr.flush()

    def clear(self) -> None:
        if self.enabled:
            sys.stderr.write("\r\033[K")


def _summary(args: argparse.Namespace, data: dict[str, object], line: str, mission: Mission | None = None) -> None:
    """The closing line on stderr (unless ``-q``) and the JSON summary on stdout (with
    ``--json-summary``); both name the four input files the command read."""
    if mission is not None:
        files = {"hddl": mission.domain.source, "gm": mission.goal_model.source,
                 "configuration": str(mission.config_path), "world": str(mission.world_path or "")}
        data = {**data, "inputs": files}
        line += "\n  read: " + ", ".join(f"{k} {v}" for k, v in files.items())
    if getattr(args, "json_summary", False):
        print(json.dumps(data, sort_keys=True))
    if not getattr(args, "quiet", False):
        print(line, file=sys.stderr)


def cmd_check(args: argparse.Namespace) -> int:
    hddl, gm, cfg, folder = _inputs(args)
    start = time.perf_counter()
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    base = (folder if folder is not None else cfg.parent.parent).resolve()
    written = (base / mission.config.output.file_path).resolve()
    if base != written and base not in written.parents:
        mission.warnings.append(f"{cfg}: output.file_path {mission.config.output.file_path} leaves the mission folder: "
                                f"decompose would write {written}")
    # expanding the goal model against the world surfaces the run-time checks too
    exp = mission.expansion
    _ = mission.task_graph
    _ = mission.constraints
    if args.fleet:
        from .allocate.fleet import Fleet

        _check_fleet(mission, Fleet.read(args.fleet))
    if not args.strict:
        _warn(args, mission)
    _check_domain(args, mission)
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "check", "valid": True, "task_instances": len(exp.instances),
                    "seconds": round(elapsed, 3)},
             f"ok: {hddl.name}, {gm.name}, {cfg.name} are valid ({len(exp.instances)} task instances, "
             f"{elapsed:.2f} s)", mission)
    return 0


def _check_domain(args: argparse.Namespace, mission: Mission) -> None:
    """The domain's warnings (``domain_warnings``); with ``--strict`` every warning of the
    mission is an error instead (exit 2)."""
    from .domain_warnings import domain_warnings

    found = domain_warnings(mission.domain, mission.goal_model)
    if args.strict:
        warned = [Problem("", w) for w in (*mission.warnings, *mission.initial_state.warnings)]
        if warned or found:
            raise MissionError([*warned, *found])
    elif not args.quiet:
        for problem in found:
            print(f"warning: {problem}", file=sys.stderr)


def _check_fleet(mission: Mission, fleet: Fleet) -> TravelTimes:
    """The fleet's names against the mission, and travel times to every place the mission's
    tasks are at (``check --fleet``, and before ``allocate`` solves, which then uses them)."""
    from .allocate.problem import fleet_problems, mission_travel

    problems = fleet_problems(mission, fleet)
    if problems:
        raise MissionError(problems)
    return mission_travel(mission, fleet)


def cmd_allocate(args: argparse.Namespace) -> int:
    """Choose the decomposition, the robots and the schedule together; write the schedule, the
    chosen decomposition (and a Gantt chart)."""
    start = time.perf_counter()  # the time limit counts from here: loading the solvers and the fleet is part of it
    from .allocate import AllocationOptions, Fleet, Objective
    from .allocate.output import objective_section, phases_section, summary_line, write_decomposition, write_schedule

    hddl, gm, cfg, folder = _inputs(args)
    objective = Objective.parse(args.objective)
    if args.gantt:
        from .allocate.gantt import gantt_format

        gantt_format(args.gantt)  # and matplotlib, before any work
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    _warn(args, mission)
    fleet = Fleet.read(args.fleet)
    travel = _check_fleet(mission, fleet)
    out_path = Path(args.output) if args.output else _default_output(mission, folder)
    schedule_path = Path(args.schedule) if args.schedule else _default_schedule(out_path)
    _refuse_two_on_stdout(args, out_path, schedule_path)
    _refuse_inputs_as_output((out_path, schedule_path, args.gantt), mission, (hddl, gm, cfg, Path(args.fleet)))
    options = AllocationOptions(objective, args.time_limit, args.workers, args.seed, work_limit=args.work_limit,
                                counted_from=start)
    progress = _AllocationProgress(not args.quiet, objective.name)
    try:
        with phase("allocating"):
            allocation = mission.allocate(fleet, options, progress, travel)
    finally:
        progress.close()
    with phase("writing the output"), staged_outputs((schedule_path, out_path, args.gantt)):
        if args.gantt:  # first: a chart that cannot be drawn leaves nothing written, not even on stdout
            from .allocate.gantt import write_gantt

            write_gantt(allocation, args.gantt)
        write_schedule(allocation, schedule_path)
        write_decomposition(allocation, out_path, args.format or mission.config.output.file_type)
    elapsed = time.perf_counter() - start
    schedule = allocation.schedule
    data = {"command": "allocate", "objective": objective_section(allocation), "makespan": schedule.makespan,
            "travel": schedule.travel, "tasks": len(schedule.jobs),
            "robots_used": sum(1 for v in schedule.routes.values() if v), "schedule": str(schedule_path),
            "output": str(out_path), "gantt": args.gantt, "phases": phases_section(allocation),
            "seconds": round(elapsed, 3)}
    _summary(args, data, f"{summary_line(allocation)} -> {schedule_path}, {out_path}"
             + (f", {args.gantt}" if args.gantt else "") + f" ({elapsed:.2f} s)", mission)
    keep_until_exit(mission, fleet, allocation)  # a fleet of 100,000 robots takes a while to free
    return 0


def _default_schedule(out_path: Path) -> Path:
    """``schedule.json`` beside the decomposition (in the current folder when that goes to
    standard output)."""
    return Path("schedule.json") if os.fspath(out_path) == STDOUT else out_path.with_name("schedule.json")


def _refuse_two_on_stdout(args: argparse.Namespace, out_path: Path, schedule_path: Path) -> None:
    """Standard output takes one document: the decomposition, the schedule or the summary."""
    on_stdout = [name for name, path in (("-o", out_path), ("--schedule", schedule_path)) if os.fspath(path) == STDOUT]
    if getattr(args, "json_summary", False):
        on_stdout.append("--json-summary")
    if len(on_stdout) > 1:
        raise MissionError(f"{' and '.join(on_stdout)} would both print to standard output: send all but one "
                           "to files")


def _default_output(mission: Mission, folder: Path | None) -> Path:
    """Where ``decompose`` would write: the configuration's output path (from the mission
    folder when one was given)."""
    if folder is not None and not Path(mission.config.output.file_path).is_absolute():
        return folder / mission.config.output.file_path
    return mission.output_path()


class _AllocationProgress:
    """The anytime progress line of ``allocate``: the incumbent, the bound and the gap."""

    def __init__(self, enabled: bool, kind: str) -> None:
        self.line = _Progress(enabled)
        self.kind = kind

    def __call__(self, progress: object) -> None:
        from .allocate.search import Progress

        assert isinstance(progress, Progress)
        best = "none yet" if progress.objective is None else f"{progress.objective:g}"
        gap = "" if progress.gap is None else f", gap {100 * progress.gap:.1f}%"
        self.line.show(f"allocating: {self.kind} {best}, bound {progress.bound:g}{gap} ({progress.seconds:.1f} s)")

    def close(self) -> None:
        self.line.clear()


def cmd_validate(args: argparse.Namespace) -> int:
    """Check an output file against the mission: exit 0 when the file's tasks and constraints are
    the mission's and every listed mission decomposition is valid, 1 when not (each violation on
    stdout), 2 on bad input (an unreadable file, or one that is no decomposition output)."""
    from .io.decomposition_output import load_decomposition_output
    from .validate import validate

    if len(args.inputs) not in (2, 4):
        raise MissionError("expected HDDL GM CONFIG OUTPUT, or MISSION_DIR OUTPUT")
    *mission_inputs, output_path = args.inputs
    args.inputs = mission_inputs
    hddl, gm, cfg, _folder = _inputs(args)
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    output = load_decomposition_output(output_path)
    progress = _Progress(not args.quiet, "mission decompositions checked")
    report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state, output,
                      world=mission.knowledge, progress=progress)
    progress.clear()
    for violation in report.violations:
        print(f"{output_path}: {violation}")
    if not args.quiet:
        for note in report.notes:
            print(f"note: {note}", file=sys.stderr)
    bad = sorted({v.decomposition for v in report.violations if v.decomposition is not None})
    file_level = sum(1 for v in report.violations if v.decomposition is None)
    empty = " (the mission has no task instance)" if report.task_instances == 0 and not report.checked else ""
    _summary(args, {"command": "validate", "valid": report.valid, "checked": report.checked,
                    "invalid_decompositions": bad, "violations": [str(v) for v in report.violations],
                    "notes": report.notes, "task_instances": report.task_instances},
             f"{'valid' if report.valid else 'NOT valid'}: {report.checked - len(bad)} of {report.checked} mission "
             f"decompositions valid" + (f", {file_level} problems in the file" if file_level else "") + empty
             + f" ({Path(output_path).name})", mission)
    return 0 if report.valid else 1


def _request(args: argparse.Namespace) -> DecompositionRequest:
    """The decompose options as a library request (their combinations are checked before)."""
    return DecompositionRequest(
        algorithm=Algorithm(args.algorithm),
        limit=None if args.limit == 0 else args.limit,
        sample=args.sample,
        seed=args.seed,
        optimize=args.optimize,
        costs=CostModel.read(args.costs) if args.optimize and args.costs else CostModel(),
        explain=args.explain,
    )


def _note(request: DecompositionRequest, result: DecompositionResult) -> str:
    """What the summary line says about the listed decompositions."""
    if result.optimum is not None:
        return f", optimum cost {result.optimum[1]}"
    if request.sample is not None:
        return f", {request.sample} sampled (seed {request.seed})"
    if result.listed is not None:
        return f", first {result.listed} listed"
    return ""


def cmd_decompose(args: argparse.Namespace) -> int:
    from .output import OutputModel
    from .output_ahead import output_while_solving

    hddl, gm, cfg, folder = _inputs(args)
    start = time.perf_counter()
    if args.algorithm == "exploratory":
        used = ["--" + name for name in cpsat_options(limit=args.limit, sample=args.sample, optimize=args.optimize,
                                                      explain=args.explain)]
        if used:
            raise MissionError(f"{', '.join(used)} {'needs' if len(used) == 1 else 'need'} the CP-SAT decomposer "
                               "(the default): drop --algorithm exploratory")
    if args.output == "-" and args.json_summary:
        raise MissionError("-o - writes the output to standard output: drop --json-summary, which prints there too")
    if args.sample is not None and (args.optimize or args.limit != DEFAULT_LIMIT):
        raise MissionError("--sample lists random decompositions: it cannot be combined with --optimize or --limit")
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    mission.progress = _Progress(not args.quiet).stage
    _warn(args, mission)
    # where and how the output goes is settled, and refused if unsafe, before any work
    out_path = Path(args.output) if args.output else _default_output(mission, folder)
    file_type = _output_format(args, mission)
    if args.json_style == "standard" and file_type != "json":
        raise MissionError(f"--json-style standard applies to JSON output, and this output is {file_type}: "
                           "drop --json-style or write JSON (--format json)")
    _refuse_inputs_as_output((out_path if not args.ihtn else None,), mission, (hddl, gm, cfg, args.costs),
                             folders=(args.ihtn,))
    label = "tasks visited" if args.algorithm == "exploratory" else "components solved"
    progress = _Progress(not args.quiet, f"mission decompositions: {label}")
    with phase("expanding the mission"):
        tg = mission.task_graph
        constraints = mission.constraints
    request = _request(args)
    if not tg.tasks() and not args.quiet:
        print("warning: the mission has no task instances (no entity of the world matched its queries): "
              "nothing to decompose", file=sys.stderr)
    model = OutputModel(tg, constraints, [], mission.domain, mission.config, mission.initial_state)
    if args.ihtn:
        with phase("solving"):
            result = mission.decompose(request, progress)
        from .ihtn import refuse_oversized_export, write_ihtns

        model.decompositions = list(result.decompositions)
        one = args.ihtn_orderings == "one"
        with phase("counting iHTN files"):
            files = refuse_oversized_export(model, one, args.ihtn_max, str(args.ihtn))
        ihtn_progress = _Progress(not args.quiet, "iHTN files written")
        with phase("exporting iHTNs"):
            n_files = write_ihtns(model, Path(args.ihtn), lambda n: ihtn_progress(n, files),
                                  one_per_decomposition=one)
    else:
        n_files = 0
        # the task entries and constraints may be written by a second process while solving
        with output_while_solving(model, out_path, file_type, args.json_style) as finish:
            with phase("solving"):
                result = mission.decompose(request, progress)
            with phase("writing the output"):
                finish(result.decompositions, result.space_section(tg.decomposition_keys.__getitem__))
    keep_until_exit(mission, model, result)
    total, note = result.total, _note(request, result)
    elapsed = time.perf_counter() - start
    kinds = constraints.count_by_kind()
    data = {
        "command": "decompose",
        "algorithm": args.algorithm,
        "task_instances": len(mission.expansion.instances),
        "task_decompositions": len(tg.decompositions()),
        "constraints": {k: kinds.get(k, 0) for k in ("SEQ", "FB", "EC")},
        "mission_decompositions": str(total),
        "output": str(args.ihtn) if args.ihtn else str(out_path),
        "ihtn_files": n_files,
        "seconds": round(elapsed, 3),
    }
    where = f"{n_files} iHTN files in {args.ihtn}" if args.ihtn else str(out_path)
    _summary(args, data,
             f"decomposed: {data['task_instances']} task instances, {data['task_decompositions']} task "
             f"decompositions, constraints SEQ {kinds.get('SEQ', 0)} FB {kinds.get('FB', 0)} EC "
             f"{kinds.get('EC', 0)}, {shown_count(total, digit_count=True)} valid mission decompositions{note} -> "
             f"{where} ({elapsed:.2f} s)", mission)
    return 0


OUTPUT_SUFFIXES = {".json": "json", ".xml": "xml"}


def _output_format(args: argparse.Namespace, mission: Mission) -> str:
    """``--format``; else the suffix of ``-o`` (``x.json`` is JSON), with a warning when the
    configuration asks for the other format; else the configuration's ``output.file_type``."""
    configured = mission.config.output.file_type
    if args.format:
        return str(args.format)
    by_suffix = OUTPUT_SUFFIXES.get(Path(args.output).suffix.lower()) if args.output else None
    if by_suffix is None:
        return configured
    if by_suffix != configured and not args.quiet:
        print(f"warning: {args.output}: writing {by_suffix}, as the suffix says, although {mission.config_path} asks "
              f"for {configured} (output.file_type); --format {configured} follows the configuration",
              file=sys.stderr)
    return by_suffix


def cmd_graph(args: argparse.Namespace) -> int:
    from .render import render, render_targets, view_dot

    hddl, gm, cfg, _folder = _inputs(args)
    start = time.perf_counter()
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    _warn(args, mission)
    _refuse_inputs_as_output(render_targets(args.output), mission, (hddl, gm, cfg))
    result = render(view_dot(mission, args.view, args.index), args.output)
    if result.message:
        print(result.message, file=sys.stderr)
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "graph", "view": args.view, "output": str(result.path), "rendered": result.rendered,
                    "seconds": round(elapsed, 3)},
             f"graph: {args.view} view written to {result.path} ({elapsed:.2f} s)", mission)
    return 0


def _warn(args: argparse.Namespace, mission: Mission) -> None:
    """The warnings of loading now, and those of later stages as they are found."""
    if not getattr(args, "quiet", False):
        for w in (*mission.warnings, *mission.initial_state.warnings):
            print(f"warning: {w}", file=sys.stderr)
        mission.report_warning = _print_warning


def _print_warning(warning: str) -> None:
    print(f"warning: {warning}", file=sys.stderr)


def _refuse_inputs_as_output(outputs: Sequence[Path | str | None], mission: Mission,
                             inputs: tuple[Path | str | None, ...], folders: Sequence[Path | str | None] = ()) -> None:
    """Outputs that are inputs of the mission (the world included) or one another, or folders:
    refused before anything is computed or written (``output_file.refuse_unsafe_outputs``)."""
    refuse_unsafe_outputs(outputs, (*inputs, mission.world_path), folders)


def cmd_count(args: argparse.Namespace) -> int:
    hddl, gm, cfg, _folder = _inputs(args)
    start = time.perf_counter()
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    _warn(args, mission)
    with phase("expanding the mission"):
        _ = mission.constraints
    with phase("solving"):
        space = mission.decomposition_space(_Progress(not args.quiet, "components solved"), keep=False)
        total = space.count
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "count", "mission_decompositions": str(total), "components": len(space.components),
                    "seconds": round(elapsed, 3)},
             f"counted: {shown_count(total, digit_count=True)} valid mission decompositions in "
             f"{len(space.components)} independent components ({elapsed:.2f} s)", mission)
    sys.stderr.flush()
    print(total)  # the bare count is the last line of stdout
    # like decompose: a mission whose tasks admit no valid combination is an error (status 3)
    return 3 if total == 0 and mission.task_graph.tasks() else 0


def cmd_compare(args: argparse.Namespace) -> int:
    """Run the decomposers on the mission and compare them (``compare.py``); the report as a
    table, or as JSON with ``--json``.  Exit 0 when all that finished agree, 1 when not."""
    from .compare import CompareRequest, compare
    from .compare_report import plot_format, render_table, report_json, write_plot

    hddl, gm, cfg, _folder = _inputs(args)
    if args.plot:
        plot_format(args.plot)  # before anything runs
        world = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml).world_path
        refuse_unsafe_outputs((args.plot,), (hddl, gm, cfg, world))
    original = None
    if args.original:
        found = shutil.which(args.original)
        if found is None:
            raise MissionError("--original: not an executable file (the original tool, run as PATH HDDL GM CONFIG)",
                               args.original)
        original = Path(found).resolve()
    request = CompareRequest(hddl, gm, cfg, time_limit=args.time_limit, limit=args.limit or None, original=original,
                             lenient_xml=args.lenient_xml, max_input_mb=args.max_input_mb)
    report = compare(request, None if args.quiet else lambda message: print(message, file=sys.stderr))
    if args.plot:
        write_plot(report, args.plot)
    print(json.dumps(report_json(report), sort_keys=True) if args.json else render_table(report))
    return report.exit_status


def build_parser() -> argparse.ArgumentParser:
    from .allocate.options import MAX_SEED, MAX_WORKERS

    parser = argparse.ArgumentParser(
        prog="mutrose-cp",
        description="Decompose MutRoSe multi-robot missions (goal model + HDDL + configuration + world).",
    )
    parser.add_argument("--version", action="version", version=f"mutrose-cp {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def reading(p: argparse.ArgumentParser) -> None:
        """How the inputs are read: XML repair and the size bound."""
        p.add_argument("--lenient-xml", action="store_true",
                       help="read XML whose repair changes which records exist or how they nest, as the original "
                            "does (with warnings) instead of refusing it")
        p.add_argument("--max-input-mb", type=count_option(1), default=256, metavar="MB",
                       help="refuse input files larger than this (default 256)")

    def mission_inputs(p: argparse.ArgumentParser) -> None:
        """Which mission: its three files, or its folder and the files to pick there."""
        p.add_argument("inputs", nargs="+", metavar="INPUT",
                       help="HDDL GM CONFIG, or one mission folder with hddl/ gm/ configuration/ knowledge/")
        p.add_argument("--config", type=input_file, help="in a mission folder with several configurations, the one to use")
        p.add_argument("--hddl", type=input_file, help="in a mission folder with several HDDL files, the one to use")
        p.add_argument("--gm", type=input_file, help="in a mission folder with several goal models, the one to use")

    def common(p: argparse.ArgumentParser) -> None:
        mission_inputs(p)
        reading(p)
        p.add_argument("--world", metavar="FILE", type=input_file,
                       help="read the world knowledge from FILE instead of the configuration's world_db.path")
        p.add_argument("-q", "--quiet", action="store_true", help="no progress and no summary on stderr")
        p.add_argument("--json-summary", action="store_true", help="print a machine-readable summary on stdout")

    p = sub.add_parser("check", help="validate the mission inputs and report every problem found")
    common(p)
    p.add_argument("--strict", action="store_true", help="treat every warning as an error (exit 2)")
    p.add_argument("--fleet", metavar="FLEET.json", type=input_file, help="also check a fleet file against the mission")
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("decompose", help="decompose the mission and write the output file")
    common(p)
    p.add_argument("-o", "--output", type=output_file,
                   help="output file (overrides the configuration's output.file_path)")
    p.add_argument("--format", choices=("json", "xml"),
                   help="output format (default: the suffix of -o, .json or .xml, else the configuration's)")
    p.add_argument("--json-style", choices=("boost", "standard"), default="boost",
                   help="boost (default): the original's JSON, which its readers expect; standard: valid UTF-8 "
                        "JSON with [] and {} for empty lists, numbers as numbers")
    p.add_argument("--algorithm", choices=("cpsat", "exploratory"), default="cpsat",
                   help="cpsat (default): solver-backed, factored; exploratory: the original's explicit combination")
    p.add_argument("--limit", type=count_option(0), default=DEFAULT_LIMIT, metavar="K",
                   help="cpsat: list the first K mission decompositions (0 = all; default 1000)")
    p.add_argument("--sample", type=count_option(1), metavar="K", help="cpsat: list K decompositions drawn uniformly at random")
    p.add_argument("--seed", type=count_option(0), default=0, help="random seed for --sample (default 0)")
    p.add_argument("--optimize", action="store_true",
                   help="cpsat: output the decomposition of least cost (fewest actions, or --costs)")
    p.add_argument("--costs", metavar="FILE", type=input_file, help='JSON cost file {"actions": {...}, "methods": {...}}')
    p.add_argument("--explain", action="store_true",
                   help="cpsat: when no decomposition exists, name the conflicting goals, tasks and facts")
    p.add_argument("--ihtn", metavar="DIR", type=output_folder,
                   help="write one iHTN file per ordering of each valid decomposition "
                                                 "into DIR instead of the output file")
    p.add_argument("--ihtn-orderings", choices=("all", "one"), default="all",
                   help="--ihtn: every ordering of each decomposition (default), or only the first consistent one")
    p.add_argument("--ihtn-max", type=count_option(1), default=DEFAULT_MAX_FILES, metavar="N",
                   help="--ihtn: refuse (exit 2) an export of more than N files (default 10000)")
    p.set_defaults(func=cmd_decompose)

    p = sub.add_parser("allocate", help="choose the decomposition, the robots and the schedule together")
    common(p)
    p.add_argument("--fleet", required=True, metavar="FLEET.json", type=input_file,
                   help="the robots, durations and travel (JSON)")
    p.add_argument("-o", "--output", type=output_file, help="the chosen decomposition, in the output format (default: the "
                                          "configuration's output.file_path)")
    p.add_argument("--format", choices=("json", "xml"), help="format of -o (default: the configuration's)")
    p.add_argument("--schedule", metavar="FILE", type=output_file, help="the schedule (default: schedule.json beside -o)")
    p.add_argument("--gantt", metavar="FILE.png|svg", type=output_file, help="also draw the schedule (needs matplotlib)")
    p.add_argument("--objective", default="makespan", metavar="makespan|travel|weighted:A,B",
                   help="minimise the makespan (default), the total travel, or A * makespan + B * travel")
    limit = p.add_mutually_exclusive_group()
    limit.add_argument("--time-limit", type=seconds, default=10.0, metavar="S",
                       help="stop the search after S seconds with the best schedule found (default 10)")
    limit.add_argument("--work-limit", type=work_units, metavar="W",
                       help="stop after W units of deterministic work instead (about a second each): the same "
                            "schedule on every machine, with any --workers")
    p.add_argument("--workers", type=count_option(1, MAX_WORKERS), default=1, metavar="N",
                   help="CP-SAT search threads (default 1: the same schedule on every finished run)")
    p.add_argument("--seed", type=count_option(0, MAX_SEED), default=0, help="CP-SAT random seed (default 0)")
    p.set_defaults(func=cmd_allocate)

    p = sub.add_parser("count", help="print the exact number of valid mission decompositions")
    common(p)
    p.set_defaults(func=cmd_count)

    p = sub.add_parser("validate", help="check an output file (ours or the original's) against the mission")
    common(p)
    p.set_defaults(func=cmd_validate)
    p.usage = "mutrose-cp validate [-h] [--config CONFIG] [-q] [--json-summary] (HDDL GM CONFIG | MISSION_DIR) OUTPUT"

    from .compare import DEFAULT_LIMIT as COMPARE_LIMIT, DEFAULT_TIME_LIMIT

    p = sub.add_parser("compare", help="run both decomposers (and the original tool) on the mission, each in its "
                                       "own process, and compare time, memory and results")
    mission_inputs(p)
    reading(p)  # passed on to the decomposers
    p.add_argument("--time-limit", type=seconds, default=DEFAULT_TIME_LIMIT, metavar="S",
                   help=f"wall-time limit of each run in seconds (default {DEFAULT_TIME_LIMIT:g}); a run over it "
                        "is killed")
    p.add_argument("--limit", type=count_option(0), default=COMPARE_LIMIT, metavar="K",
                   help="compare the sets of decompositions up to K of them, else only their counts "
                        f"(default {COMPARE_LIMIT}; 0 = always)")
    p.add_argument("--original", metavar="PATH",
                   help="also run this binary of the original tool (as PATH HDDL GM CONFIG, in a copy of the mission)")
    p.add_argument("--json", action="store_true", help="print the report as one JSON object instead of a table")
    p.add_argument("--plot", metavar="FILE", type=output_file, help="bar chart of time and memory: FILE.png, .svg or .pdf (needs matplotlib)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines on stderr")
    p.set_defaults(func=cmd_compare)

    p = sub.add_parser("graph", help="draw the expanded goal model, the Task Graph or one decomposition")
    common(p)
    p.add_argument("--view", choices=("goal-model", "task-graph", "decomposition"), default="task-graph")
    p.add_argument("--index", type=int, default=0, help="decomposition view: which valid decomposition (0-based)")
    p.add_argument("-o", "--output", required=True, type=output_file,
                   help="FILE.svg, FILE.png (needs graphviz) or FILE.dot")
    p.set_defaults(func=cmd_graph)

    p = sub.add_parser("export-hddl", help="write the domain (and the mission's problem) as standard HDDL")
    p.add_argument("input", metavar="INPUT", help="the HDDL domain, or a mission folder")
    p.add_argument("-o", "--output", required=True, metavar="OUT.hddl", type=output_file,
                   help="the standard HDDL domain to write")
    p.add_argument("--gm", type=input_file,
                   help="the goal model (with --config: also write the problem); in a folder, which one")
    p.add_argument("--config", type=input_file, help="the configuration (with --gm); in a mission folder, which one")
    p.add_argument("--hddl", type=input_file, help="in a mission folder with several HDDL files, the one to use")
    p.add_argument("--problem-out", metavar="FILE", type=output_file, help="the problem file (default OUT-problem.hddl); exit 2 "
                                                         "when the mission has no problem form")
    reading(p)
    p.add_argument("-q", "--quiet", action="store_true", help="no warnings and no summary on stderr")
    p.set_defaults(func=cmd_export_hddl)

    add_batch_parser(sub)
    return parser


def cmd_export_hddl(args: argparse.Namespace) -> int:
    from .hddl_export import export_hddl

    return export_hddl(args)


def entry() -> None:
    """The console script (and ``python -m mutrose_cp``): run the command and exit with its
    status."""
    process_ends_with_command()
    exit_process(main())


def main(argv: Sequence[str] | None = None) -> int:
    with command_settings():
        try:
            return _main(argv)
        except BrokenPipeError:  # telling why failed too: stderr is the closed pipe (2>&1 | head)
            return reader_gone()


def _main(argv: Sequence[str] | None) -> int:
    prepare_process()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # usage errors (status 2), --help and --version (status 0)
        return int(exit_.code or 0)
    if not getattr(args, "command", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        with signal_handlers(), input_limit(args.max_input_mb * MB), world_file(getattr(args, "world", None)):
            status: int = args.func(args)
            return status
    except FAILURES as err:
        status = _report(err)
        if getattr(args, "json_summary", False):
            print(json.dumps({"command": args.command, "ok": False, "status": status, "problems": _problems(err)},
                             sort_keys=True))
        return status


def _problems(err: Failure) -> list[dict[str, str | int | None]]:
    """Why a command failed, as the records ``--json-summary`` lists."""
    return [p.record() for p in failure_problems(err)]


def _report(err: Failure) -> int:
    """Print why a command stopped (never a traceback) and return its exit status."""
    lines = failure_lines(err)
    for line in lines:
        print(line, file=sys.stderr)
    if isinstance(err, MissionError) and len(lines) > 1:
        print(f"{len(lines)} problems found", file=sys.stderr)
    return failure_status(err)
