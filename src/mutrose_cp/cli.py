"""The ``mutrose-cp`` command line: ``check``, ``decompose`` (and friends).

Bad input ends with located messages on stderr and exit status 2; a mission without any valid
decomposition exits with 3; nothing here prints a Python traceback.
"""
from __future__ import annotations

import argparse
import gc
import json
import os
import signal
import sys
import time
from collections import Counter
from pathlib import Path
from typing import Sequence

from . import __version__
from .batch.command import add_batch_parser
from .errors import MissionError
from .interrupt import Interrupted, phase, signal_handlers
from .io.text import MB, input_limit
from .mission import Mission, find_mission_files, world_file
from .solve.decompose import DEFAULT_LIMIT, Algorithm, DecompositionRequest, DecompositionResult, cpsat_options
from .solve.optimize import CostModel


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
            return
        now = time.monotonic()
        if now - self.last < 0.1 and done < total:
            return
        self.last = now
        of = f"/{total}" if total else ""
        sys.stderr.write(f"\r\033[K{label}: {done}{of}")
        if total and done >= total:
            sys.stderr.write("\n")
        sys.stderr.flush()


def _big(n: int) -> str:
    """A count for a summary line: exact up to 15 digits, else its magnitude."""
    digits = str(n)
    return digits if len(digits) <= 15 else f"{digits[0]}.{digits[1:4]}e{len(digits) - 1} (exact: {len(digits)} digits)"


def _summary(args: argparse.Namespace, data: dict, line: str, mission: Mission | None = None) -> None:
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
    _warn(args, mission)
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "check", "valid": True, "task_instances": len(exp.instances),
                    "seconds": round(elapsed, 3)},
             f"ok: {hddl.name}, {gm.name}, {cfg.name} are valid ({len(exp.instances)} task instances, "
             f"{elapsed:.2f} s)", mission)
    return 0


def cmd_validate(args: argparse.Namespace) -> int:
    """Check an output file against the mission: exit 0 when every listed mission
    decomposition is valid, 1 when some is not (each violation on stdout), 2 on bad input."""
    from .io.decomposition_output import load_decomposition_output
    from .validate import validate

    if len(args.inputs) not in (2, 4):
        raise MissionError("expected HDDL GM CONFIG OUTPUT, or MISSION_DIR OUTPUT")
    *mission_inputs, output_path = args.inputs
    args.inputs = mission_inputs
    hddl, gm, cfg, _folder = _inputs(args)
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    output = load_decomposition_output(output_path)
    report = validate(mission.domain, mission.goal_model, mission.config, mission.initial_state, output)
    for violation in report.violations:
        print(f"{output_path}: {violation}")
    if not args.quiet:
        for note in report.notes:
            print(f"note: {note}", file=sys.stderr)
    bad = sorted({v.decomposition for v in report.violations if v.decomposition is not None})
    file_level = sum(1 for v in report.violations if v.decomposition is None)
    _summary(args, {"command": "validate", "valid": report.valid, "checked": report.checked,
                    "invalid_decompositions": bad, "violations": [str(v) for v in report.violations],
                    "notes": report.notes},
             f"{'valid' if report.valid else 'NOT valid'}: {report.checked - len(bad)} of {report.checked} mission "
             f"decompositions valid" + (f", {file_level} problems in the file" if file_level else "")
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
    from .output import OutputModel, write_output

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
    label = "tasks visited" if args.algorithm == "exploratory" else "components solved"
    progress = _Progress(not args.quiet, f"mission decompositions: {label}")
    with phase("expanding the mission"):
        tg = mission.task_graph
        constraints = mission.constraints
    request = _request(args)
    if not tg.tasks() and not args.quiet:
        print("warning: the mission has no task instances (no entity of the world matched its queries): "
              "nothing to decompose", file=sys.stderr)
    with phase("solving"):
        result = mission.decompose(request, progress)
    decompositions, total = result.decompositions, result.total
    key = {d.index: f"t{i}" for i, d in enumerate(tg.decompositions())}
    section = result.space_section(key.__getitem__)
    note = _note(request, result)
    if args.output:
        out_path = Path(args.output)
    elif folder is not None and not Path(mission.config.output.file_path).is_absolute():
        out_path = folder / mission.config.output.file_path
    else:
        out_path = mission.output_path()
    file_type = args.format or mission.config.output.file_type
    _refuse_inputs_as_output(out_path if not args.ihtn else None, mission, (hddl, gm, cfg))
    model = OutputModel(tg, constraints, decompositions, mission.domain, mission.config, mission.initial_state,
                        space=section)
    if args.ihtn:
        from .ihtn import ihtn_file_count, write_ihtns

        model.decompositions = list(decompositions)
        one = args.ihtn_orderings == "one"
        with phase("counting iHTN files"):
            files = ihtn_file_count(model, one, args.ihtn_max + 1)
        if files > args.ihtn_max:
            how_many = _how_many_ihtn_files(model, one, args.ihtn_max)
            raise MissionError(f"the iHTN export would write {how_many}, over --ihtn-max {args.ihtn_max}; one file "
                               "is written per ordering of each listed decomposition: write the first ordering of "
                               "each with --ihtn-orderings one, list fewer decompositions (--limit K, --optimize), "
                               "or raise --ihtn-max", str(args.ihtn))
        ihtn_progress = _Progress(not args.quiet, "iHTN files written")
        with phase("exporting iHTNs"):
            n_files = write_ihtns(model, Path(args.ihtn), lambda n: ihtn_progress(n, files),
                                  one_per_decomposition=one)
    else:
        n_files = 0
        with phase("writing the output"):
            write_output(model, out_path, file_type)
    elapsed = time.perf_counter() - start
    kinds = Counter(str(c.kind) for c in constraints)
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
             f"{kinds.get('EC', 0)}, {_big(total)} valid mission decompositions{note} -> {where} ({elapsed:.2f} s)", mission)
    return 0


def cmd_graph(args: argparse.Namespace) -> int:
    from .render import render, view_dot

    hddl, gm, cfg, _folder = _inputs(args)
    start = time.perf_counter()
    mission = Mission.load(hddl, gm, cfg, lenient_xml=args.lenient_xml)
    _warn(args, mission)
    result = render(view_dot(mission, args.view, args.index), args.output)
    if result.message:
        print(result.message, file=sys.stderr)
    elapsed = time.perf_counter() - start
    _summary(args, {"command": "graph", "view": args.view, "output": str(result.path), "rendered": result.rendered,
                    "seconds": round(elapsed, 3)},
             f"graph: {args.view} view written to {result.path} ({elapsed:.2f} s)", mission)
    return 0


def _warn(args: argparse.Namespace, mission: Mission) -> None:
    if not getattr(args, "quiet", False):
        for w in (*mission.warnings, *mission.initial_state.warnings):
            print(f"warning: {w}", file=sys.stderr)


def _how_many_ihtn_files(model, one: bool, limit: int) -> str:
    """How many files a refused iHTN export would write, as exactly as a second of work tells."""
    from .ihtn import CountTooCostly, count_orderings, ihtn_file_count

    try:
        return f"{ihtn_file_count(model, one, 10**18, budget=20_000):,} files"
    except CountTooCostly:
        pass
    first = model.decompositions[0]
    members = set(first)
    succ: dict[int, set[int]] = {}
    for c in model.constraints:
        if c.kind in ("SEQ", "FB") and c.first in members and c.second in members:
            succ.setdefault(c.first, set()).add(c.second)
    try:
        alone = count_orderings(list(first), succ, 10**18, budget=500_000)
    except CountTooCostly:
        return f"more than {limit:,} files"
    return f"at least {alone:,} files (the first listed decomposition alone has that many orderings)"


def _refuse_inputs_as_output(out_path: Path | None, mission: Mission, inputs: tuple[Path, ...]) -> None:
    """An output that is one of the mission's inputs (the same file, after links, by device and
    inode) would destroy it: refuse before anything is computed or written."""
    if out_path is None or str(out_path) == "-":
        return
    try:
        target = os.stat(out_path)
    except OSError:
        return  # a new file cannot be an input
    world = mission.world_path
    for path in (*inputs, *([world] if world is not None else [])):
        try:
            st = os.stat(path)
        except OSError:
            continue
        if (st.st_dev, st.st_ino) == (target.st_dev, target.st_ino):
            raise MissionError(f"the output would overwrite the input {path}: choose another output file",
                               str(out_path))


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
             f"counted: {_big(total)} valid mission decompositions in {len(space.components)} independent components "
             f"({elapsed:.2f} s)", mission)
    sys.stderr.flush()
    print(total)  # the bare count is the last line of stdout
    # like decompose: a mission whose tasks admit no valid combination is an error (status 3)
    return 3 if total == 0 and mission.task_graph.tasks() else 0


MAX_COUNT = 2**62  # beyond any listing that fits on a disk; CP-SAT's limits are 64-bit


def _count_option(minimum: int):
    """An argparse type: an integer from ``minimum`` to ``MAX_COUNT`` (a usage error, exit 2,
    otherwise)."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if not minimum <= value <= MAX_COUNT:
            raise argparse.ArgumentTypeError(f"{text} is out of range: give a number from {minimum} to {MAX_COUNT}")
        return value
    return parse


def build_parser() -> argparse.ArgumentParser:
    parser = argparse.ArgumentParser(
        prog="mutrose-cp",
        description="Decompose MutRoSe multi-robot missions (goal model + HDDL + configuration + world).",
    )
    parser.add_argument("--version", action="version", version=f"mutrose-cp {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")

    def common(p: argparse.ArgumentParser) -> None:
        p.add_argument("inputs", nargs="+", metavar="INPUT",
                       help="HDDL GM CONFIG, or one mission folder with hddl/ gm/ configuration/ knowledge/")
        p.add_argument("--config", help="in a mission folder with several configurations, the one to use")
        p.add_argument("--hddl", help="in a mission folder with several HDDL files, the one to use")
        p.add_argument("--gm", help="in a mission folder with several goal models, the one to use")
        p.add_argument("--lenient-xml", action="store_true",
                       help="read XML whose repair changes which records exist or how they nest, as the original "
                            "does (with warnings) instead of refusing it")
        p.add_argument("--world", metavar="FILE",
                       help="read the world knowledge from FILE instead of the configuration's world_db.path")
        p.add_argument("--max-input-mb", type=_count_option(1), default=256, metavar="MB",
                       help="refuse input files larger than this (default 256)")
        p.add_argument("-q", "--quiet", action="store_true", help="no progress and no summary on stderr")
        p.add_argument("--json-summary", action="store_true", help="print a machine-readable summary on stdout")

    p = sub.add_parser("check", help="validate the mission inputs and report every problem found")
    common(p)
    p.set_defaults(func=cmd_check)

    p = sub.add_parser("decompose", help="decompose the mission and write the output file")
    common(p)
    p.add_argument("-o", "--output", help="output file (overrides the configuration's output.file_path)")
    p.add_argument("--format", choices=("json", "xml"), help="output format (default: the configuration's)")
    p.add_argument("--algorithm", choices=("cpsat", "exploratory"), default="cpsat",
                   help="cpsat (default): solver-backed, factored; exploratory: the original's explicit combination")
    p.add_argument("--limit", type=_count_option(0), default=DEFAULT_LIMIT, metavar="K",
                   help="cpsat: list the first K mission decompositions (0 = all; default 1000)")
    p.add_argument("--sample", type=_count_option(1), metavar="K", help="cpsat: list K decompositions drawn uniformly at random")
    p.add_argument("--seed", type=_count_option(0), default=0, help="random seed for --sample (default 0)")
    p.add_argument("--optimize", action="store_true",
                   help="cpsat: output the decomposition of least cost (fewest actions, or --costs)")
    p.add_argument("--costs", metavar="FILE", help='JSON cost file {"actions": {...}, "methods": {...}}')
    p.add_argument("--explain", action="store_true",
                   help="cpsat: when no decomposition exists, name the conflicting goals, tasks and facts")
    p.add_argument("--ihtn", metavar="DIR", help="write one iHTN file per ordering of each valid decomposition "
                                                 "into DIR instead of the output file")
    p.add_argument("--ihtn-orderings", choices=("all", "one"), default="all",
                   help="--ihtn: every ordering of each decomposition (default), or only the first consistent one")
    p.add_argument("--ihtn-max", type=_count_option(1), default=10_000, metavar="N",
                   help="--ihtn: refuse (exit 2) an export of more than N files (default 10000)")
    p.set_defaults(func=cmd_decompose)

    p = sub.add_parser("count", help="print the exact number of valid mission decompositions")
    common(p)
    p.set_defaults(func=cmd_count)

    p = sub.add_parser("validate", help="check an output file (ours or the original's) against the mission")
    common(p)
    p.set_defaults(func=cmd_validate)
    p.usage = "mutrose-cp validate [-h] [--config CONFIG] [-q] [--json-summary] (HDDL GM CONFIG | MISSION_DIR) OUTPUT"

    p = sub.add_parser("graph", help="draw the expanded goal model, the Task Graph or one decomposition")
    common(p)
    p.add_argument("--view", choices=("goal-model", "task-graph", "decomposition"), default="task-graph")
    p.add_argument("--index", type=int, default=0, help="decomposition view: which valid decomposition (0-based)")
    p.add_argument("-o", "--output", required=True, help="FILE.svg, FILE.png (needs graphviz) or FILE.dot")
    p.set_defaults(func=cmd_graph)

    add_batch_parser(sub)
    return parser


def entry() -> None:
    """The console script (and ``python -m mutrose_cp``): run the command and exit with its
    status.  After an interrupt everything is cleaned up already, and the process ends at once:
    a CP-SAT search stopped midway can leave native state whose teardown at interpreter exit
    aborts the process (status 134 instead of 130)."""
    code = main()
    if code in (128 + signal.SIGINT, 128 + signal.SIGTERM):
        for stream in (sys.stdout, sys.stderr):
            try:
                stream.flush()
            except (OSError, ValueError):
                pass
        os._exit(code)
    sys.exit(code)


def main(argv: Sequence[str] | None = None) -> int:
    # The pipeline allocates millions of small acyclic objects (vertices, edges, literals);
    # Python's cyclic collector then rescans them over and over, which cost up to 3x the
    # run time on large missions.  A command is short-lived: the collector is paused meanwhile.
    collecting = gc.isenabled()
    gc.disable()
    # exact counts are big integers (3^10000 has 4772 digits, over Python's default limit for
    # converting an int to text); the limit is restored for an embedding program
    digits = sys.get_int_max_str_digits()
    sys.set_int_max_str_digits(0)
    try:
        return _main(argv)
    finally:
        sys.set_int_max_str_digits(digits)
        if collecting:
            gc.enable()


def _usable_stderr() -> None:
    """Started with stderr closed, messages go nowhere rather than failing the command."""
    try:
        os.fstat(2)
    except OSError:
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115 - lives as long as the process
        return
    if sys.stderr is None:
        sys.stderr = open(os.devnull, "w")  # noqa: SIM115


def _main(argv: Sequence[str] | None) -> int:
    _usable_stderr()
    if hasattr(signal, "SIGXFSZ"):
        # over a file-size limit, a write fails with EFBIG (a located error) instead of the
        # signal killing the process
        signal.signal(signal.SIGXFSZ, signal.SIG_IGN)
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
    except (Interrupted, MissionError, RecursionError, OSError) as err:
        return _report(err)


def _report(err: Interrupted | MissionError | RecursionError | OSError) -> int:
    """Print why a command stopped (never a traceback) and return its exit status."""
    match err:
        case Interrupted(during=during):
            print(f"interrupted{' while ' + during if during else ''} ({err}): no output was written", file=sys.stderr)
            return err.exit_code
        case MissionError(problems=problems):
            for problem in problems:
                print(f"error: {problem}", file=sys.stderr)
            if len(problems) > 1:
                print(f"{len(problems)} problems found", file=sys.stderr)
            return err.exit_code
        case RecursionError():
            print("error: the mission is nested too deeply to process", file=sys.stderr)
            return 2
        case OSError():
            print(f"error: {err.filename or ''}: {err.strerror or err}", file=sys.stderr)
            return 2
