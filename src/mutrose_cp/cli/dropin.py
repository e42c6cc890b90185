"""The ``mutrose`` command: the original decomposer's command line, for the tools that call it.

    mutrose HDDL GM CONFIG [-v | -p | -h]

The VS Code plug-in runs ``mutrose <hddl> ./temp.txt <config> -p`` in its workspace and shows
stdout (the three ``-p`` blocks on success, the messages on failure); the 2D MutRoSe simulator
runs ``mutrose HDDL GM CONFIG`` in its mission folder and reads the file at the configuration's
``output.file_path``.  Both work unchanged (spec ``output.md`` §1, §5, §6):

* the first three arguments are the files, whatever they look like; later ones are options;
* the output goes where the configuration says, relative to the current directory, in its
  format; ``-h`` writes ``./ihtn/ihtn_<n>.json`` instead (at most ``--ihtn-max=N`` files,
  10000 by default: a larger export is refused before anything is written);
* ``-p`` prints the three blocks byte for byte as the original prints them (:mod:`.console`),
  ``-v`` a trace; both together are refused (status 1);
* in every mode stdout also carries what the original's lexers echo of the goal model
  (:mod:`.lexer_echo`), where the original prints it;
* ``-h`` owns ``./ihtn``, as the original: it is emptied and refilled;
* an unknown option is reported as ``Unknown option [x]`` and ignored;
* missing arguments print the original's message (status 1), an unopenable file
  ``I can't open <path>!`` (status 2).

Where the original aborts (invalid input, no valid decomposition) this command prints located
errors on stderr, which the plug-in shows when a command fails (Node's ``Command failed`` and
stderr), and exits with mutrose-cp's status: 2 for invalid input, 3 for a mission without any
valid decomposition.  Warnings and ``Unknown option [x]`` go to stderr too; stdout carries
only what the original prints there (the echo, the ``-p`` blocks) and the ``-v`` trace.

The CP-SAT decomposer lists every valid decomposition (as the original does), sorted into the
original's order (:mod:`.solve.listing_order`); ``MUTROSE_ALGORITHM=exploratory`` in the
environment, or the option ``--algorithm=exploratory``, selects the original's explicit
combination instead.
"""
from __future__ import annotations

import codecs
import io
import os
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import IO, TYPE_CHECKING, Iterable, Mapping, Sequence

from ..interrupt import phase, signal_handlers
from ..io.text import MB, input_limit
from .process import (
    FAILURES,
    Failure,
    command_settings,
    exit_process,
    failure_lines,
    failure_status,
    keep_until_exit,
    prepare_process,
    process_ends_with_command,
    reader_gone,
)
from ..solve.decompose import Algorithm, DecompositionRequest

if TYPE_CHECKING:  # imported when the command runs
    from ..pipeline.constraints import Constraint
    from ..mission import Mission
    from ..model.task_graph import TaskGraph
    from ..output.builder import OutputModel

ALGORITHM_ENV = "MUTROSE_ALGORITHM"
IHTN_FOLDER = Path("ihtn")
MISSING = ("You need to provide a domain file as input.", "You need to provide a Goal Model JSON file as input.",
           "You need to provide a configuration file as input.")
INPUT_LIMIT_MB = 256


@dataclass(frozen=True)
class Invocation:
    """What the command line asks for."""

    files: tuple[str, str, str]  # HDDL, goal model, configuration
    verbose: bool = False  # -v
    pretty: bool = False  # -p
    ihtn: bool = False  # -h
    algorithm: Algorithm = Algorithm.CPSAT
    ihtn_max: int | None = None  # --ihtn-max; None: the export's default (ihtn.DEFAULT_MAX_FILES)


class Usage(Exception):
    """The command line cannot be run: the message and the original's exit status."""

    def __init__(self, message: str, status: int) -> None:
        super().__init__(message)
        self.status = status


def _algorithm(name: str, source: str) -> Algorithm:
    try:
        return Algorithm(name.strip().lower())
    except ValueError:
        raise Usage(f"{source}: unknown decomposer {name!r}: choose cpsat or exploratory", 2) from None


def _ihtn_max(text: str) -> int:
    if not text.isdigit() or int(text) < 1:
        raise Usage(f"--ihtn-max={text}: expected a whole number of files, at least 1", 2)
    return int(text)


def parse(argv: Sequence[str], environ: Mapping[str, str] = os.environ, out: IO[str] | None = None) -> Invocation:
    """The invocation, read as the original reads it.  Unknown options are reported on ``out``
    (stderr by default) and ignored; :class:`Usage` is raised for missing files and for ``-v`` with ``-p``."""
    files, options = list(argv[:3]), list(argv[3:])
    flags = {"-v": False, "-p": False, "-h": False}
    unknown: list[str] = []
    algorithm = _algorithm(environ[ALGORITHM_ENV], ALGORITHM_ENV) if environ.get(ALGORITHM_ENV) else Algorithm.CPSAT
    ihtn_max: int | None = None
    for opt in options:
        if opt in flags:
            flags[opt] = True
        elif opt.startswith("--algorithm="):
            algorithm = _algorithm(opt.partition("=")[2], "--algorithm")
        elif opt.startswith("--ihtn-max="):
            ihtn_max = _ihtn_max(opt.partition("=")[2])
        else:
            unknown.append(opt)
    if unknown:
        print("\n" + "".join(f"Unknown option [{opt}]\n" for opt in unknown), file=out or sys.stderr)
    if flags["-v"] and flags["-p"]:
        raise Usage("Options -v and -p cannot be used together!", 1)
    if len(files) < 3:
        raise Usage(MISSING[len(files)], 1)
    return Invocation((files[0], files[1], files[2]), flags["-v"], flags["-p"], flags["-h"], algorithm, ihtn_max)


def _openable(files: Sequence[str]) -> None:
    """The original opens the three files first: the first that cannot be opened is named.
    They are opened without waiting (a FIFO without a writer would block the open); a file that
    opens but is not a regular file is refused, located, when it is read."""
    for path in files:
        try:
            os.close(os.open(path, os.O_RDONLY | os.O_NONBLOCK))
        except OSError:
            raise Usage(f"I can't open {path}!", 2) from None


def run(inv: Invocation, out: IO[str] | None = None) -> int:
    """Decompose as the original does: the output file (or iHTN files) and, on ``out``, what the
    original prints there: its lexers' echo (in every mode) around the ``-p`` blocks or the
    ``-v`` trace."""
    from .flow import expanded
    from ..output.lexer_echo import LexerEcho
    from ..output.builder import OutputModel

    out = out if out is not None else sys.stdout
    mission = _load(inv)
    tg, constraints = expanded(mission)
    echo = LexerEcho.of(mission.goal_model, mission.expansion.rat)
    echo.print_head(out)  # the full stdio buffers the original wrote while reading the goal model
    if inv.verbose or inv.pretty:
        _print_mission(inv, mission, out)
    with phase("solving"):
        result = mission.decompose(_every_decomposition(inv.algorithm))
    decompositions = _in_original_order(inv.algorithm, tg, result.decompositions)
    # listed in memory only when read more than once (the prints, the iHTN counting); the output
    # file alone streams them
    if inv.verbose or inv.pretty or inv.ihtn:
        listed = list(decompositions)
        if inv.verbose or inv.pretty:
            _print_decompositions(inv, tg, constraints, listed, out)
        decompositions = listed
    model = OutputModel(tg, constraints, decompositions, mission.domain, mission.config, mission.initial_state)
    _write(inv, mission, model)
    echo.print_tail(out)  # what the original's stdio buffer held at exit
    keep_until_exit(mission, model, result)
    return 0


def _print_mission(inv: Invocation, mission: Mission, out: IO[str]) -> None:
    """What is printed before solving: ``-p``'s first two blocks, or ``-v``'s stages up to the
    Task Graph."""
    from ..output import console

    if inv.verbose:
        _trace_mission(mission, out)
    else:
        console.print_task_instances(mission.task_graph, out)
        console.print_constraints(mission.task_graph, mission.constraints, out)


def _print_decompositions(inv: Invocation, tg: TaskGraph, constraints: Sequence[Constraint],
                          decompositions: Sequence[Sequence[int]], out: IO[str]) -> None:
    """What is printed after solving: ``-p``'s last block, or ``-v``'s constraints and valid
    mission decompositions."""
    from ..output import console

    if inv.verbose:
        console.print_constraints(tg, constraints, out)
        console.print_trace_decompositions(tg, decompositions, out)
    else:
        console.print_mission_decompositions(tg, decompositions, out)


def _load(inv: Invocation) -> Mission:
    """The mission, its warnings on stderr, its output checked against its inputs (the shared
    steps of :mod:`.flow`, imported when the command runs: a usage error never loads them)."""
    from .flow import load_mission, refuse_outputs

    hddl, gm, cfg = inv.files
    mission = load_mission(hddl, gm, cfg, lenient_xml=True)  # the original repairs XML silently
    # the original would overwrite an input named as its output: refused, before any work
    refuse_outputs((None if inv.ihtn else mission.output_path(),), mission, inv.files)
    return mission


def _in_original_order(algorithm: Algorithm, tg: TaskGraph, decompositions: Iterable[list[int]]) -> Iterable[list[int]]:
    """The valid mission decompositions in the original's order, whichever decomposer listed
    them: ``mission_decompositions[N]``, ``MISSION N`` and ``ihtn_N.json`` are the original's
    (solve/listing_order.py)."""
    if algorithm == Algorithm.EXPLORATORY:
        return decompositions
    from ..solve.listing_order import ExploratoryOrder

    with phase("ordering the decompositions"):
        return sorted(decompositions, key=ExploratoryOrder(tg).key)


def _write(inv: Invocation, mission: Mission, model: OutputModel) -> None:
    """The configuration's output file, or the iHTN files with ``-h``."""
    from ..output.formats import write_output

    if inv.ihtn:
        _write_ihtns(model, inv.ihtn_max)
    else:
        with phase("writing the output"):
            write_output(model, mission.output_path(), mission.config.output.file_type)


def _every_decomposition(algorithm: Algorithm) -> DecompositionRequest:
    """Every valid mission decomposition, as the original lists them (the exploratory
    decomposer always lists all; CP-SAT is told to)."""
    if algorithm == Algorithm.EXPLORATORY:
        return DecompositionRequest(algorithm=algorithm)
    return DecompositionRequest(algorithm=algorithm, limit=None)


def _trace_mission(mission: Mission, out: IO[str]) -> None:
    """``-v``: the inputs and every stage up to the Task Graph."""
    from ..output import console

    files = {"domain": mission.domain.source, "goal model": mission.goal_model.source,
             "configuration": str(mission.config_path), "world": str(mission.world_path or "")}
    console.print_inputs(mission.domain, files, out)
    console.print_expansion(mission.expansion.rat.render(), mission.expansion.instances, out)
    console.print_decomposition_paths(mission.task_graph, out)
    console.print_world_state(mission.initial_state, out)
    console.print_task_graph(mission.task_graph, out)


def _write_ihtns(model: OutputModel, maximum: int | None) -> None:
    """``-h``: every ordering of every valid decomposition as ``./ihtn/ihtn_<n>.json``, at most
    ``maximum`` files (the export's default when None).  Imported here: only ``-h`` uses it."""
    from ..output.ihtn import DEFAULT_MAX_FILES, refuse_oversized_export, write_ihtns

    with phase("counting iHTN files"):
        refuse_oversized_export(model, False, maximum or DEFAULT_MAX_FILES, str(IHTN_FOLDER), "raise the bound with --ihtn-max=N "
                                "(-h writes every ordering of every valid decomposition), or use mutrose-cp "
                                f"decompose --ihtn {IHTN_FOLDER} --ihtn-orderings one")
    with phase("exporting iHTNs"):
        write_ihtns(model, IHTN_FOLDER, owned=True)


def _report(err: Failure) -> int:
    """Why the command stopped, on stderr, and the exit status.  The plug-in runs the command
    through Node's ``exec`` and shows ``Command failed: <cmd>`` followed by its stderr when it
    fails: what is printed there is what the user sees."""
    for line in failure_lines(err):
        print(line, file=sys.stderr)
    return failure_status(err)


def main(argv: Sequence[str] | None = None) -> int:
    """Run ``mutrose`` with ``argv`` (without the program name) and return its exit status."""
    with command_settings():
        prepare_process()
        utf8_stdout()
        try:
            return _command(sys.argv[1:] if argv is None else list(argv))
        except BrokenPipeError:
            return reader_gone()


def utf8_stdout() -> None:
    """Write stdout in UTF-8 whatever the locale or ``PYTHONIOENCODING`` say: the original writes
    the bytes of its inputs (UTF-8 goal models, world files read as UTF-8) as they are, and the
    plug-in decodes stdout as UTF-8.  Undecodable bytes of file names (held as surrogate
    escapes) are written back as they were."""
    out = sys.stdout
    if isinstance(out, io.TextIOWrapper) and (codecs.lookup(out.encoding).name != "utf-8"
                                              or out.errors != "surrogateescape"):
        out.reconfigure(encoding="utf-8", errors="surrogateescape")


def _command(argv: list[str]) -> int:
    try:
        inv = parse(argv)
        _openable(inv.files)
    except Usage as usage:
        print(usage, file=sys.stderr)
        return usage.status
    try:
        with signal_handlers(), input_limit(INPUT_LIMIT_MB * MB):
            return run(inv)
    except BrokenPipeError:
        raise
    except FAILURES as err:
        return _report(err)


def entry() -> None:
    """The ``mutrose`` console script."""
    process_ends_with_command()
    exit_process(main())


if __name__ == "__main__":
    entry()
