"""The ``mutrose-cp`` commands: one handler per sub-command (``check``, ``decompose``,
``allocate``, ``count``, ``validate``, ``compare``, ``graph``, ``export-hddl``), each given the
parsed arguments and returning the exit status.

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
from typing import TYPE_CHECKING

from ..output.counts import shown_count
from ..errors import MissionError, NoDecompositionError, Problem
from ..interrupt import phase
from ..mission import Mission
from ..pipeline.scenarios import world_scenarios
from ..pipeline.stages import MissionStages
from ..output.files import STDOUT, refuse_unsafe_outputs, staged_outputs
from .flow import (
    expanded,
    load_mission,
    mission_paths,
    read_uncertainty,
    refuse_outputs,
    report_warnings,
    warn_world_as_written,
)
from .process import keep_until_exit
from ..solve.decompose import DEFAULT_LIMIT, Algorithm, DecompositionRequest, DecompositionResult, cpsat_options
from ..solve.optimize import CostModel

if TYPE_CHECKING:
    from ..allocate.fleet import Fleet
    from ..allocate.travel import TravelTimes
    from ..output.uncertainty_section import UncertaintyRecord



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
        if mission.uncertainty_source:
            files["uncertainty"] = mission.uncertainty_source
        data = {**data, "inputs": files}
        line += "\n  read: " + ", ".join(f"{k} {v}" for k, v in files.items())
    if getattr(args, "json_summary", False):
        print(json.dumps(data, sort_keys=True))
    if not getattr(args, "quiet", False):
        print(line, file=sys.stderr)


def cmd_check(args: argparse.Namespace) -> int:
    hddl, gm, cfg, folder = mission_paths(args)
    start = time.perf_counter()
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    read_uncertainty(mission, args.uncertain, args.as_written)
    if mission.expands_per_world:
        world_scenarios(mission)  # more worlds than are expanded: refused here too
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
        from ..allocate.fleet import Fleet

        _check_fleet(mission, Fleet.read(args.fleet))
    if args.properties or args.property:
        _check_properties(args, mission)
    if not args.strict and not args.quiet:
        report_warnings(mission)
    _check_domain(args, mission)
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "check", "valid": True, "task_instances": len(exp.instances),
                    "seconds": round(elapsed, 3)},
             f"ok: {hddl.name}, {gm.name}, {cfg.name} are valid ({len(exp.instances)} task instances"
             + (f", {len(mission.uncertainty.facts)} uncertain facts" if mission.uncertainty is not None else "")
             + f", {elapsed:.2f} s)", mission)
    return 0


def _check_properties(args: argparse.Namespace, mission: Mission) -> None:
    """The properties' syntax, and the names they use against the domain (exit 2 on a problem)."""
    from ..io.properties import given_properties
    from ..pipeline.property_checks import check_properties

    check_properties(given_properties(args.properties, args.property), mission.domain)


def _check_domain(args: argparse.Namespace, mission: Mission) -> None:
    """The domain's warnings (``domain_warnings``); with ``--strict`` every warning of the
    mission is an error instead (exit 2)."""
    from ..pipeline.domain_warnings import domain_warnings

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
    from ..allocate.problem import fleet_problems, mission_travel

    problems = fleet_problems(mission, fleet)
    if problems:
        raise MissionError(problems)
    return mission_travel(mission, fleet)


def cmd_allocate(args: argparse.Namespace) -> int:
    """Choose the decomposition, the robots and the schedule together; write the schedule, the
    chosen decomposition (and a Gantt chart)."""
    start = time.perf_counter()  # the time limit counts from here: loading the solvers and the fleet is part of it
    from ..allocate import AllocationOptions, Fleet, Objective
    from ..allocate.output import objective_section, phases_section, summary_line, write_decomposition, write_schedule

    hddl, gm, cfg, folder = mission_paths(args)
    objective = Objective.parse(args.objective)
    if args.gantt:
        from ..allocate.gantt import gantt_format

        gantt_format(args.gantt)  # and matplotlib, before any work
    mission = load_mission(hddl, gm, cfg, lenient_xml=args.lenient_xml, quiet=args.quiet)
    fleet = Fleet.read(args.fleet)
    travel = _check_fleet(mission, fleet)
    out_path = Path(args.output) if args.output else _default_output(mission, folder)
    schedule_path = Path(args.schedule) if args.schedule else _default_schedule(out_path)
    _refuse_two_on_stdout(args, out_path, schedule_path)
    refuse_outputs((out_path, schedule_path, args.gantt), mission, (hddl, gm, cfg, Path(args.fleet)))
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
            from ..allocate.gantt import write_gantt

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
        from ..allocate.search import Progress

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
    from ..io.decomposition_output import load_decomposition_output
    from ..validate import validate
    from ..validate.listed import output_world

    if len(args.inputs) not in (2, 4):
        raise MissionError("expected HDDL GM CONFIG OUTPUT, or MISSION_DIR OUTPUT")
    *mission_inputs, output_path = args.inputs
    args.inputs = mission_inputs
    hddl, gm, cfg, _folder = mission_paths(args)
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    output = load_decomposition_output(output_path)
    world = output_world(mission, output)  # expanded in one world of uncertain facts the goal model reads
    if output.assumed_world and not args.quiet:
        print(f"note: checked in the world the output was expanded in: "
              f"{', '.join(f'{e}.{a} = {v}' for e, a, v in output.assumed_world)}", file=sys.stderr)
    elif not args.quiet:
        warn_world_as_written(mission)
    progress = _Progress(not args.quiet, "mission decompositions checked")
    report = validate(world.domain, world.goal_model, world.config, world.initial_state, output,
                      world=world.knowledge, progress=progress)
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
    from ..output.builder import OutputModel
    from ..output.ahead import output_while_solving

    hddl, gm, cfg, folder = mission_paths(args)
    start = time.perf_counter()
    _refuse_decompose_options(args)
    mission = load_mission(hddl, gm, cfg, lenient_xml=args.lenient_xml, quiet=args.quiet, uncertain=args.uncertain,
                           reads_uncertainty=True, as_written=args.as_written)
    _refuse_uncertainty_options(args, mission)
    mission.progress = _Progress(not args.quiet).stage
    # where and how the output goes is settled, and refused if unsafe, before any work
    out_path = Path(args.output) if args.output else _default_output(mission, folder)
    file_type, format_warning = _output_format(args, mission)
    if mission.expands_per_world and file_type == "xml" and not args.ihtn:
        raise MissionError("the goal model reads uncertain facts, so the output is the mission expanded in one world, "
                           "which only the JSON output's uncertainty section can name: write JSON (--format json)")
    if args.json_style == "standard" and file_type != "json":
        raise MissionError(f"--json-style standard applies to JSON output, and this output is {file_type}: "
                           "drop --json-style or write JSON (--format json)")
    refuse_outputs((out_path if not args.ihtn else None,), mission, (hddl, gm, cfg, args.costs),
                             folders=(args.ihtn,))
    if format_warning and not args.quiet:  # said once the output is accepted, never before a refusal
        print(format_warning, file=sys.stderr)
    label = "tasks visited" if args.algorithm == "exploratory" else "components solved"
    progress = _Progress(not args.quiet, f"mission decompositions: {label}")
    request = _request(args)
    solved: tuple[DecompositionResult, "UncertaintyRecord | None"] | None = None
    written: MissionStages = mission
    if mission.expands_per_world:
        # the goal model reads uncertain facts: the output is the expansion of one world, known
        # once the decompositions are chosen
        with phase("solving"):
            solved, written = _solve_uncertain(args, mission, request)
    tg, constraints = expanded(written)
    if not tg.tasks() and not args.quiet:
        print("warning: the mission has no task instances (no entity of the world matched its queries): "
              "nothing to decompose", file=sys.stderr)
    model = OutputModel(tg, constraints, [], written.domain, written.config, written.initial_state)

    def solve() -> tuple[DecompositionResult, "UncertaintyRecord | None"]:
        return solved if solved is not None else _solve(args, mission, request, progress)
    if args.ihtn:
        with phase("solving"):
            result, record = solve()
        from ..output.ihtn import refuse_oversized_export, write_ihtns

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
                result, record = solve()
            with phase("writing the output"):
                listed = result.decompositions if record is None else record.listed(result.decompositions)
                model.uncertainty = None if record is None else record.section
                finish(listed, result.space_section(tg.decomposition_keys.__getitem__))
    keep_until_exit(mission, model, result)
    total, note = result.total, _note(request, result)
    elapsed = time.perf_counter() - start
    kinds = constraints.count_by_kind()
    data = {
        "command": "decompose",
        "algorithm": args.algorithm,
        "task_instances": len(written.expansion.instances),
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


def _refuse_decompose_options(args: argparse.Namespace) -> None:
    """The options of decompose that cannot go together, refused before anything is read."""
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
    if args.most_likely and (args.sample is not None or args.optimize):
        raise MissionError("--most-likely chooses one decomposition: it cannot be combined with --sample or --optimize")


def _refuse_uncertainty_options(args: argparse.Namespace, mission: Mission) -> None:
    """The options that need an uncertainty file, and the decomposer that does not read one."""
    if mission.uncertainty is None and (args.robust or args.most_likely):
        raise MissionError(f"--{'robust' if args.robust else 'most-likely'} chooses among decompositions under uncertain "
                           "facts: give --uncertain FILE, or name one in the configuration (docs/formats/uncertainty.md)")
    if mission.uncertainty is not None and args.algorithm == "exploratory":
        raise MissionError("uncertain facts are decided by the CP-SAT decomposer (the default): drop --algorithm "
                           "exploratory, or the uncertainty file")
    if mission.uncertainty is not None and args.explain:
        raise MissionError("--explain says why a known world has no decomposition; with uncertain facts, "
                           "mutrose-cp explain says which facts to sense, and count --possible how many are valid "
                           "for some value: drop --explain, or the uncertainty file (--as-written)")
    if mission.expands_per_world and args.ihtn:
        raise MissionError("the goal model reads uncertain facts, so the decompositions are of the mission expanded "
                           "in one world, which iHTN files cannot name: write the JSON output, whose uncertainty "
                           "section names it")


def _solve(args: argparse.Namespace, mission: Mission, request: DecompositionRequest,
           progress: "_Progress") -> tuple[DecompositionResult, "UncertaintyRecord | None"]:
    """The decompositions the request asks for, and with uncertain facts what each assumes."""
    if mission.uncertainty is None:
        return mission.decompose(request, progress), None
    return _solve_uncertain(args, mission, request)[0]


def _solve_uncertain(args: argparse.Namespace, mission: Mission, request: DecompositionRequest
                     ) -> tuple[tuple[DecompositionResult, "UncertaintyRecord"], MissionStages]:
    """The decompositions the request asks for under the uncertain facts, what each assumes, and
    the mission whose task ids they are in: the world they were chosen in when the goal model
    reads uncertain facts (``solve/scenarios.py``), else the mission."""
    from ..output.uncertainty_section import UncertaintyRecord
    from ..solve.decompose import answer
    from ..solve.scenarios import ExpandedSpace, decided_space

    uncertain = decided_space(mission)
    worlds = uncertain if isinstance(uncertain, ExpandedSpace) else None
    # the decompositions of several worlds cannot be listed in one output: the robust ones can
    space = None if worlds is not None and args.most_likely else uncertain.space(robust=args.robust)
    if (space.count if space is not None else uncertain.count(robust=False)) == 0:
        raise NoDecompositionError("no mission decomposition is valid " + (
            "whatever the uncertain facts are (count --possible counts those valid for some value; explain says "
            "which facts to sense)" if args.robust else "for any value of the uncertain facts"),
            str(mission.goal_model.source))
    if args.most_likely:
        costs = CostModel.read(args.costs) if args.costs else CostModel()
        table = (worlds.content_costs(costs.decomposition_costs) if worlds is not None
                 else costs.decomposition_costs(mission.task_graph))
        chosen, _probability = uncertain.most_likely(table)  # for worlds, chooses the frame written
        total = space.count if space is not None else uncertain.count(robust=False)
        result = DecompositionResult(Algorithm.CPSAT, [chosen], total, space)
    else:
        assert space is not None
        result = answer(worlds.output_stages if worlds is not None else mission, space, request)
    return (result, UncertaintyRecord(uncertain)), worlds.output_stages if worlds is not None else mission


def _output_format(args: argparse.Namespace, mission: Mission) -> tuple[str, str]:
    """``--format``; else the suffix of ``-o`` (``x.json`` is JSON), with a warning to give when
    the configuration asks for the other format; else the configuration's ``output.file_type``."""
    configured = mission.config.output.file_type
    if args.format:
        return str(args.format), ""
    by_suffix = OUTPUT_SUFFIXES.get(Path(args.output).suffix.lower()) if args.output else None
    if by_suffix is None:
        return configured, ""
    if by_suffix == configured:
        return by_suffix, ""
    return by_suffix, (f"warning: {args.output}: writing {by_suffix}, as the suffix says, although "
                       f"{mission.config_path} asks for {configured} (output.file_type); --format {configured} "
                       "follows the configuration")


def cmd_graph(args: argparse.Namespace) -> int:
    from ..output.render import render, render_targets, view_dot

    if args.from_output and args.view != "decomposition":
        raise MissionError("--from-output draws a decomposition: give it with --view decomposition")
    hddl, gm, cfg, _folder = mission_paths(args)
    start = time.perf_counter()
    mission = load_mission(hddl, gm, cfg, lenient_xml=args.lenient_xml, quiet=args.quiet, world_said_later=True)
    refuse_outputs(render_targets(args.output), mission, (hddl, gm, cfg, *([args.from_output] if args.from_output else [])))
    chosen = None
    drawn: MissionStages = mission
    if args.from_output:
        from ..validate.listed import listed_decomposition

        drawn, chosen = listed_decomposition(mission, args.from_output, args.index)
    if drawn is not mission and not args.quiet:
        print(f"note: drawn in the world {args.from_output} was expanded in", file=sys.stderr)
    elif not args.quiet:
        warn_world_as_written(mission)
    result = render(view_dot(drawn, args.view, args.index, chosen=chosen, source=args.from_output or ""), args.output)
    if result.message:
        print(result.message, file=sys.stderr)
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "graph", "view": args.view, "output": str(result.path), "rendered": result.rendered,
                    "seconds": round(elapsed, 3)},
             f"graph: {args.view} view written to {result.path} ({elapsed:.2f} s)", mission)
    return 0


def cmd_count(args: argparse.Namespace) -> int:
    hddl, gm, cfg, _folder = mission_paths(args)
    start = time.perf_counter()
    mission = load_mission(hddl, gm, cfg, lenient_xml=args.lenient_xml, quiet=args.quiet, uncertain=args.uncertain,
                           reads_uncertainty=True, as_written=args.as_written)
    if not mission.expands_per_world:
        with phase("expanding the mission"):
            _ = mission.constraints
    if mission.uncertainty is not None:
        return _count_uncertain(args, mission, start)
    if args.robust or args.possible:
        raise MissionError(f"--{'robust' if args.robust else 'possible'} counts decompositions under uncertain facts: "
                           "give --uncertain FILE, or name one in the configuration (docs/formats/uncertainty.md)")
    with phase("solving"):
        space = mission.decomposition_space(_Progress(not args.quiet, "components solved"), keep=False)
        total = space.count
    keep_until_exit(space)
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "count", "mission_decompositions": str(total), "components": len(space.components),
                    "seconds": round(elapsed, 3)},
             f"counted: {shown_count(total, digit_count=True)} valid mission decompositions in "
             f"{len(space.components)} independent components ({elapsed:.2f} s)", mission)
    sys.stderr.flush()
    print(total)  # the bare count is the last line of stdout
    # like decompose: a mission whose tasks admit no valid combination is an error (status 3)
    return 3 if total == 0 and mission.task_graph.tasks() else 0


def _count_uncertain(args: argparse.Namespace, mission: Mission, start: float) -> int:
    """``count`` with uncertain facts: the decompositions valid for some value of them (or, with
    ``--robust``, whatever their values); the summary gives both."""
    from ..solve.scenarios import ExpandedSpace, decided_space
    from .uncertain import worlds_line

    with phase("solving"):
        space = decided_space(mission)
        robust, possible = space.bounds(robust=True), space.bounds(robust=False)
    keep_until_exit(space)
    low, high = robust if args.robust else possible
    elapsed = time.perf_counter() - start
    facts = len(mission.uncertainty.facts) if mission.uncertainty is not None else 0

    def shown(bounds: tuple[int, int]) -> str:
        low, high = bounds
        return shown_count(low, digit_count=True) if low == high else \
            f"between {shown_count(low, digit_count=True)} and {shown_count(high, digit_count=True)}"
    line = (f"counted: {shown(possible)} mission decompositions valid for some value of the {facts} uncertain facts, "
            f"{shown(robust)} of them whatever their values ({elapsed:.2f} s)")
    for c in space.components:
        if c.bounds is not None:
            line += f"\n  bounds, not exact counts: {c.unlisted}"
    if isinstance(space, ExpandedSpace):
        line += "\n" + worlds_line(space)
    _summary(args, {"command": "count", "mission_decompositions": str(low) if low == high else f"{low}..{high}",
                    "exact": low == high, "robust": [str(n) for n in robust], "possible": [str(n) for n in possible],
                    "uncertain_facts": facts, "components": len(space.components), "seconds": round(elapsed, 3),
                    **({"worlds": len(space.worlds)} if isinstance(space, ExpandedSpace) else {})},
             line, mission)
    sys.stderr.flush()
    print(low if low == high else f"{low}..{high}")  # the bare count, or its bounds, is the last line
    # no robust decomposition is an answer; none valid for any value of the facts is status 3,
    # unless the mission has no task (in any world it is expanded in: not the one as written)
    has_tasks = any(w.space is not None for w in space.worlds) if isinstance(space, ExpandedSpace) \
        else bool(mission.task_graph.tasks())
    return 3 if possible[1] == 0 and has_tasks else 0


def cmd_compare(args: argparse.Namespace) -> int:
    """Run the decomposers on the mission and compare them (``compare.py``); the report as a
    table, or as JSON with ``--json``.  Exit 0 when all that finished agree, 1 when not."""
    from ..compare.run import CompareRequest, compare
    from ..compare.report import plot_format, render_table, report_json, write_plot

    hddl, gm, cfg, _folder = mission_paths(args)
    if args.plot:
        plot_format(args.plot)  # before anything runs
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml) if args.plot or not args.quiet else None
    if args.plot:
        assert mission is not None
        refuse_unsafe_outputs((args.plot,), (hddl, gm, cfg, mission.world_path))
    original = None
    if args.original:
        found = shutil.which(args.original)
        if found is None:
            raise MissionError("--original: not an executable file (the original tool, run as PATH HDDL GM CONFIG)",
                               args.original)
        original = Path(found).resolve()
    if mission is not None and not args.quiet:
        warn_world_as_written(mission)
    request = CompareRequest(hddl, gm, cfg, time_limit=args.time_limit, limit=args.limit or None, original=original,
                             lenient_xml=args.lenient_xml, max_input_mb=args.max_input_mb)
    report = compare(request, None if args.quiet else lambda message: print(message, file=sys.stderr))
    if args.plot:
        write_plot(report, args.plot)
    print(json.dumps(report_json(report), sort_keys=True) if args.json else render_table(report))
    return report.exit_status


def cmd_export_hddl(args: argparse.Namespace) -> int:
    from .export_hddl import export_hddl

    return export_hddl(args)
