"""The steps every command that reads a mission takes, in this order: load it and report its
warnings, refuse unsafe outputs before any work, expand it into the Task Graph and its
constraints.  ``mutrose-cp``'s handlers (:mod:`.commands`) and the drop-in ``mutrose``
(:mod:`.dropin`) both go through them, so the two command lines cannot drift apart on what
is warned, refused or computed first."""
from __future__ import annotations

import os
import sys
from typing import Sequence

from ..interrupt import phase
from ..mission import Mission
from ..model.task_graph import TaskGraph
from ..output.files import refuse_unsafe_outputs
from ..pipeline.constraints import Constraints

PathArgument = str | os.PathLike[str]


def print_warning(warning: str) -> None:
    """A warning, on stderr, where every command prints them."""
    print(f"warning: {warning}", file=sys.stderr)


def load_mission(hddl: PathArgument, gm: PathArgument, cfg: PathArgument, *, lenient_xml: bool,
                 quiet: bool = False) -> Mission:
    """The mission, with the warnings of loading printed now and those of later stages as they
    are found (none with ``quiet``)."""
    mission = Mission.load(hddl, gm, cfg, lenient_xml=lenient_xml)
    if not quiet:
        report_warnings(mission)
    return mission


def report_warnings(mission: Mission) -> None:
    """The warnings found so far, printed now, and those of later stages as they are found."""
    for warning in (*mission.warnings, *mission.initial_state.warnings):
        print_warning(warning)
    mission.report_warning = print_warning


def refuse_outputs(outputs: Sequence[PathArgument | None], mission: Mission,
                   inputs: Sequence[PathArgument | None], folders: Sequence[PathArgument | None] = ()) -> None:
    """Outputs that are inputs of the mission (the world included) or one another, or folders:
    refused before anything is computed or written (``output.files.refuse_unsafe_outputs``)."""
    refuse_unsafe_outputs(outputs, (*inputs, mission.world_path), folders)


def expanded(mission: Mission) -> tuple[TaskGraph, Constraints]:
    """The mission's Task Graph and constraints, computed now (the phase an interrupt names)."""
    with phase("expanding the mission"):
        return mission.task_graph, mission.constraints
