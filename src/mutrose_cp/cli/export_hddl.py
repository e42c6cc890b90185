"""``mutrose-cp export-hddl``: a MutRoSe domain as standard HDDL, and the mission as a problem.

The domain alone needs only the HDDL file.  Given the mission too (a mission folder, or the
HDDL file with ``--gm`` and ``--config``), a problem file is written beside the domain
(``OUT-problem.hddl``, or ``--problem-out``) when the mission has one
(:mod:`mutrose_cp.output.hddl_problem`); when it has none, the reason is printed and the command still
succeeds, unless ``--problem-out`` asked for the problem explicitly (exit 2).
"""
from __future__ import annotations

import argparse
import sys
from pathlib import Path

from ..errors import MissionError
from ..output.hddl_problem import ProblemNotExpressible, mission_problem
from ..io.hddl import load_domain
from ..io.hddl_writer import HddlExport
from ..mission import Mission
from ..io.mission_files import find_mission_files
from ..output.files import STDOUT, atomic_writer, refuse_unsafe_outputs, staged_outputs
from .flow import warn_world_as_written


def _mission_files(args: argparse.Namespace) -> tuple[Path, tuple[Path, Path] | None]:
    """(HDDL, (goal model, configuration) or None) from the command's input and options."""
    given = Path(args.input)
    if given.is_dir():
        hddl, gm, config = find_mission_files(given, args.config, hddl_name=args.hddl, gm_name=args.gm)
        return hddl, (gm, config)
    if (args.gm is None) != (args.config is None):
        raise MissionError("the problem needs both the goal model and the configuration: give --gm GM and "
                           "--config CONFIG, or neither for the domain alone")
    if args.hddl is not None:
        raise MissionError("--hddl chooses the domain of a mission folder; the domain given here is the file "
                           f"{given}")
    return given, ((Path(args.gm), Path(args.config)) if args.gm is not None else None)


def _problem_path(args: argparse.Namespace) -> Path:
    """``--problem-out``, else ``OUT-problem.hddl`` beside the domain; with the domain on
    standard output (``-o -``) the problem needs a file of its own."""
    if args.problem_out:
        return Path(args.problem_out)
    if args.output == STDOUT:
        raise MissionError("-o - prints the domain; the mission's problem needs a file of its own: give "
                           "--problem-out FILE (or --problem-out - to print it after the domain)")
    out = Path(args.output)
    return out.with_name(f"{out.stem}-problem{out.suffix or '.hddl'}")


def _texts(args: argparse.Namespace, export: HddlExport, mission: Mission | None) -> list[str]:
    """The domain's text, then the problem's when the mission has one: all made before anything
    is written, so that a refused problem (``--problem-out``) leaves no domain file behind."""
    texts = [export.domain_text()]
    if mission is None:
        return texts
    try:
        problem, notes = mission_problem(mission)
    except ProblemNotExpressible as why:
        if args.problem_out:
            raise
        if not args.quiet:
            print(f"note: no problem file: {why}", file=sys.stderr)
        return texts
    export.warnings.extend(notes)
    return [*texts, export.problem_text(problem)]


def export_hddl(args: argparse.Namespace) -> int:
    """Run the command; returns the exit status (errors are raised as :class:`MissionError`)."""
    hddl, mission_files = _mission_files(args)
    if args.problem_out and mission_files is None:
        raise MissionError("--problem-out needs the mission: give --gm GM and --config CONFIG, or a mission folder")
    refuse_unsafe_outputs([args.output], [hddl, *(mission_files or ())])  # before a problem path is made of it
    outputs = [Path(args.output), *([_problem_path(args)] if mission_files else [])]
    refuse_unsafe_outputs(outputs, [hddl, *(mission_files or ())])
    mission = Mission.load(hddl, *mission_files, lenient_xml=args.lenient_xml) if mission_files else None
    if mission is not None:
        refuse_unsafe_outputs(outputs, [mission.world_path])
        if not args.quiet:
            warn_world_as_written(mission)
    export = HddlExport(mission.domain if mission is not None else load_domain(hddl))
    written = []
    texts = _texts(args, export, mission)
    with staged_outputs(outputs[:len(texts)]):  # both files, or neither
        for what, path, text in zip(("domain", "problem"), outputs, texts):
            with atomic_writer(path) as out:
                out.write(text)
            written.append(f"{what} {path}")
    if not args.quiet:
        for warning in export.warnings:
            print(f"warning: {warning}", file=sys.stderr)
        print(f"exported: {', '.join(written)} (standard HDDL)", file=sys.stderr)
    return 0
