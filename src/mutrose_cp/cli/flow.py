"""The steps every command that reads a mission takes, in this order: load it and report its
warnings, refuse unsafe outputs before any work, expand it into the Task Graph and its
constraints.  ``mutrose-cp``'s handlers (:mod:`.commands`) and the drop-in ``mutrose``
(:mod:`.dropin`) both go through them, so the two command lines cannot drift apart on what
is warned, refused or computed first."""
from __future__ import annotations

import argparse
import os
import sys
from pathlib import Path
from typing import Sequence

from ..errors import MissionError
from ..interrupt import phase
from ..io.mission_files import find_mission_files
from ..mission import Mission
from ..model.task_graph import TaskGraph
from ..output.files import refuse_unsafe_outputs
from ..pipeline.constraints import Constraints
from ..pipeline.stages import MissionStages
from .process import keep_until_exit

PathArgument = str | os.PathLike[str]


def mission_paths(args: argparse.Namespace) -> tuple[Path, Path, Path, Path | None]:
    """(hddl, gm, config, mission folder or None) from ``HDDL GM CONFIG`` or ``MISSION_DIR``."""
    files = args.inputs
    if len(files) == 1:
        hddl, gm, cfg = find_mission_files(files[0], getattr(args, "config", None),
                                           hddl_name=getattr(args, "hddl", None), gm_name=getattr(args, "gm", None))
        return hddl, gm, cfg, Path(files[0])
    if len(files) == 3:
        return Path(files[0]), Path(files[1]), Path(files[2]), None
    raise MissionError("expected HDDL GM CONFIG, or a mission folder (hddl/ gm/ configuration/ knowledge/)")


def print_warning(warning: str) -> None:
    """A warning, on stderr, where every command prints them."""
    print(f"warning: {warning}", file=sys.stderr)


def load_mission(hddl: PathArgument, gm: PathArgument, cfg: PathArgument, *, lenient_xml: bool,
                 quiet: bool = False, uncertain: PathArgument | None = None, reads_uncertainty: bool = False,
                 as_written: bool = False, world_said_later: bool = False) -> Mission:
    """The mission, with the warnings of loading printed now and those of later stages as they
    are found (none with ``quiet``).  A command that ``reads_uncertainty`` reads the uncertainty
    file ``uncertain`` or the one the configuration names (unless ``as_written``); another says
    that it reads the world as written (unless ``world_said_later``: the caller says which world
    it reads once it knows)."""
    mission = Mission.load(hddl, gm, cfg, lenient_xml=lenient_xml)
    if reads_uncertainty:
        read_uncertainty(mission, uncertain, as_written)
    elif not quiet and not world_said_later:
        warn_world_as_written(mission)
    if not quiet:
        report_warnings(mission)
    keep_until_exit(mission)  # with its stages, freed by the process's end, not one object at a time
    return mission


def warn_world_as_written(mission: Mission) -> None:
    """Say that this command reads the world as written, when the configuration names an
    uncertainty file that it does not read."""
    if mission.configured_uncertainty() is not None:
        print_warning(f"{mission.config.locate('uncertainty')}: this command does not read the uncertainty file "
                      f"{mission.configured_uncertainty()}: the world is read as written")


def read_uncertainty(mission: Mission, uncertain: PathArgument | None, as_written: bool) -> None:
    """Read the uncertainty file ``uncertain``, else the one the configuration names (unless
    ``as_written``), if any."""
    path = uncertain or (None if as_written else mission.configured_uncertainty())
    if path:
        mission.read_uncertainty(path)


def report_warnings(mission: Mission) -> None:
    """The warnings found so far, printed now, and those of later stages as they are found."""
    for warning in (*mission.warnings, *mission.initial_state.warnings):
        print_warning(warning)
    mission.report_warning = print_warning


def refuse_outputs(outputs: Sequence[PathArgument | None], mission: Mission,
                   inputs: Sequence[PathArgument | None], folders: Sequence[PathArgument | None] = ()) -> None:
    """Outputs that are inputs of the mission (the world included) or one another, or folders:
    refused before anything is computed or written (``output.files.refuse_unsafe_outputs``)."""
    uncertainty = mission.uncertainty_source or None
    refuse_unsafe_outputs(outputs, (*inputs, mission.world_path, uncertainty), folders)


def expanded(mission: MissionStages) -> tuple[TaskGraph, Constraints]:
    """The mission's Task Graph and constraints, computed now (the phase an interrupt names)."""
    with phase("expanding the mission"):
        return mission.task_graph, mission.constraints
