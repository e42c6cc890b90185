"""The files of a batch job: the ones it reads and the ones it writes.

A batch must know both before any job runs.  What a job *reads* makes its input hash (a rerun
skips a job whose inputs are unchanged); what it *writes* must never be hashed (its output
changes on every run, so the job would never be settled) and must be checked: two jobs writing
one file, a job writing the manifest or the results file, a results file that is one of the
inputs, all destroy something that no rerun can bring back.

Which option names what comes from the parser itself (:func:`.parser.path_options`: every path
option declares its kind with its type), so no option escapes.  What no option names comes from
the commands' own defaults, the one piece of knowledge here: ``decompose`` and ``allocate`` write
where the configuration says without ``-o``; ``allocate`` writes ``schedule.json`` beside its
decomposition without ``--schedule``; ``export-hddl`` writes ``OUT-problem.hddl`` beside the
domain without ``--problem-out``; ``graph`` writes the ``.dot`` text beside a picture when
Graphviz is missing.  A default collides as surely as an explicit path.
"""
from __future__ import annotations

import argparse
import os
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING

from ...errors import MissionError
from ...output.files import STDOUT
from .inputs import refuse_special_input
from .parser import FOLDER, INPUT, path_options

if TYPE_CHECKING:
    from ...model.configuration import Configuration
    from .manifest import Job


@dataclass(frozen=True)
class Written:
    """One file (or folder) a job writes: ``option`` says how the job names it (``-o``,
    ``--schedule``, ``schedule.json beside -o``), ``path`` is relative to the job's folder."""

    option: str
    path: str
    folder: bool = False


@dataclass(frozen=True)
class JobFiles:
    """What one job reads (paths relative to its folder, sorted) and writes; ``unresolved`` is
    why its mission files could not be found (the job will fail on it), or empty."""

    reads: tuple[str, ...]
    writes: tuple[Written, ...]
    unresolved: str = ""


def named_paths(job: Job, args: argparse.Namespace) -> tuple[list[str], list[Written]]:
    """The paths the job names: its positional inputs and the values of its input options, then
    the values of its output options (standard output left out)."""
    reads = list(job.inputs)
    writes: list[Written] = []
    for option in path_options(job.command):
        value = getattr(args, option.dest, None)
        if not isinstance(value, str) or value == STDOUT:
            continue
        if option.kind == INPUT:
            reads.append(value)
        else:
            writes.append(Written(option.flag, value, folder=option.kind == FOLDER))
    return reads, writes


def default_outputs(job: Job, args: argparse.Namespace, configured: str | None) -> list[Written]:
    """The files a command writes without being told where (module docstring): ``configured`` is
    the path the configuration gives (``output.file_path``, as the command resolves it), None if
    unknown."""
    out = getattr(args, "output", None)
    found: list[Written] = []
    if job.command in ("decompose", "allocate") and out is None and not getattr(args, "ihtn", None) and configured:
        found.append(Written("the configuration's output.file_path (no -o)", configured))
        out = configured
    if job.command == "allocate" and getattr(args, "schedule", None) is None and out is not None:
        found.append(Written("schedule.json beside -o", "schedule.json" if out == STDOUT
                             else str(Path(out).with_name("schedule.json"))))
    if job.command == "export-hddl" and out not in (None, STDOUT):
        found += _problem_beside(job, args, Path(out))
    if job.command == "graph" and out not in (None, STDOUT):
        from ...output.render import render_targets

        found += [Written("the .dot text beside -o (no Graphviz)", str(p)) for p in render_targets(out)
                  if str(p) != out]
    return found


def _problem_beside(job: Job, args: argparse.Namespace, out: Path) -> list[Written]:
    """``export-hddl``'s problem file beside its domain, when it has the mission and no
    ``--problem-out``."""
    has_mission = Path(job.inputs[0]).is_dir() or (getattr(args, "gm", None) and getattr(args, "config", None))
    if getattr(args, "problem_out", None) is not None or not has_mission:
        return []
    return [Written("the problem beside -o (no --problem-out)",
                    str(out.with_name(f"{out.stem}-problem{out.suffix or '.hddl'}")))]


# -- what a job reads ----------------------------------------------------------------------------

class FileFinder:
    """The files of the jobs of one batch, found as each command finds them.  A configuration
    read by many jobs is parsed once.  Paths are relative to the jobs' folder, which must be the
    current folder while the finder runs."""

    def __init__(self) -> None:
        self._configs: dict[tuple[str, int, int, bool], Configuration | MissionError] = {}

    def job_files(self, job: Job, args: argparse.Namespace) -> JobFiles:
        """What ``job`` reads and writes.  An input that is a FIFO or a device is a located error,
        raised before anything reads it; a mission whose files cannot be found is left to the job,
        which reports it (the reason stands in for the files in its hash)."""
        named, writes = named_paths(job, args)
        # a file that is not there yet counts too: another job may write it, or the job fails on it
        reads = {a for a in named if not os.path.isdir(a)}
        for name in sorted(reads):
            refuse_special_input(name)
        lenient = getattr(args, "lenient_xml", False)
        try:
            mission = mission_inputs(job, args)
        except (MissionError, OSError) as err:
            return JobFiles(tuple(sorted(reads)), tuple(writes), str(err))
        for path in mission:
            refuse_special_input(str(path))
        reads |= {str(p) for p in mission}
        if not mission:
            return JobFiles(tuple(sorted(reads)), tuple(writes + default_outputs(job, args, None)))
        try:
            world = self.world(mission[2], getattr(args, "world", None), lenient)
        except (MissionError, OSError) as err:
            return JobFiles(tuple(sorted(reads)), tuple(writes), str(err))
        refuse_special_input(str(world))
        configured = self.configured_output(job, mission[2], lenient)
        return JobFiles(tuple(sorted(reads | {str(world)})), tuple(writes + default_outputs(job, args, configured)))

    def world(self, config: Path, given: str | None, lenient: bool) -> Path:
        """The world file a job reads: ``--world``, else the one its configuration names, as the
        command resolves it from here."""
        from ...io.mission_files import resolve_config_path

        if given is not None:
            return Path(given)
        return resolve_config_path(self.configuration(config, lenient).world_db.path, config)

    def configuration(self, config: Path, lenient: bool) -> Configuration:
        """The configuration at ``config``, read once per version of the file."""
        from ...io.config import load_configuration

        try:
            st = os.stat(config)
        except OSError:  # the reader says what is wrong with it
            return load_configuration(config, lenient=lenient)
        key = (os.path.realpath(config), st.st_size, st.st_mtime_ns, lenient)
        if key not in self._configs:
            try:
                self._configs[key] = load_configuration(config, lenient=lenient)
            except MissionError as err:
                self._configs[key] = err
        found = self._configs[key]
        if isinstance(found, MissionError):
            raise found
        return found

    def configured_output(self, job: Job, config: Path, lenient: bool) -> str | None:
        """Where the configuration sends the output (``output.file_path``), as the command
        resolves it: from the mission folder when the job names one, else from the jobs' folder."""
        try:
            relative = self.configuration(config, lenient).output.file_path
        except (MissionError, OSError):
            return None
        folder = Path(job.inputs[0])
        if folder.is_dir() and not Path(relative).is_absolute():
            return str(folder / relative)
        return relative


def mission_inputs(job: Job, args: argparse.Namespace) -> tuple[Path, ...]:
    """The HDDL, goal model and configuration a job reads, found as the command finds them
    (``find_mission_files`` in a mission folder, with ``--config``, ``--hddl``, ``--gm``); empty
    for a job whose inputs are not a mission."""
    from ...io.mission_files import find_mission_files

    first = Path(job.inputs[0])
    if first.is_dir():
        return find_mission_files(first, getattr(args, "config", None), hddl_name=getattr(args, "hddl", None),
                                  gm_name=getattr(args, "gm", None))
    if len(job.inputs) >= 3:
        return tuple(Path(p) for p in job.inputs[:3])
    return ()
