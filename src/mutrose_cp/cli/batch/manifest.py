"""The jobs of a batch: read from a JSON or CSV manifest, or built from a glob (``--each``).

A job names a ``mutrose-cp`` command, its inputs (a mission folder, or ``HDDL GM CONFIG``, plus
whatever else the command takes), its options and its output file.  Every job is checked with the
command line's own parser before any runs, so the manifest accepts exactly the commands and
options the installed ``mutrose-cp`` knows, and a typo fails the whole batch at once with the
job's location instead of failing one job an hour later.

Relative paths in a manifest are relative to the manifest's folder, where the jobs run.
"""
from __future__ import annotations

import argparse
import contextlib
import csv
import glob
import io
import os
import shlex
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterable

from ...errors import MissionError, Problem, closest, located
from ...io.text import decode_utf8, parse_json, read_bytes

FIELDS = ("id", "command", "inputs", "options", "output")
# what every job is run with, when its command has them: its summary is read, not printed
BATCH_FLAGS = ("-q", "--json-summary")


def batch_flags(command: str) -> tuple[str, ...]:
    """The :data:`BATCH_FLAGS` that ``command`` takes (``export-hddl`` prints no summary)."""
    from .parser import known_flags

    flags = known_flags(command)
    return tuple(flag for flag in BATCH_FLAGS if flag in flags) if flags else BATCH_FLAGS


@dataclass(frozen=True)
class Job:
    """One command run of a batch.  ``where`` locates it in its manifest, for messages."""

    id: str
    command: str
    inputs: tuple[str, ...]
    options: tuple[str, ...] = ()
    output: str | None = None
    where: str = ""

    def command_line(self) -> tuple[str, ...]:
        """The arguments after ``mutrose-cp``."""
        output = ("-o", self.output) if self.output is not None else ()
        return (self.command, *self.inputs, *self.options, *output, *batch_flags(self.command))

    def __str__(self) -> str:
        """A short name for messages: the command and the names of its inputs."""
        text = f"{self.command} {' '.join(Path(p).name for p in self.inputs)}"
        return text + (f" -> {self.output}" if self.output else "")


# -- reading a manifest ------------------------------------------------------------------------

def read_manifest(path: str | os.PathLike[str]) -> list[Job]:
    """The jobs of a ``.json`` or ``.csv`` manifest, every problem located (``file: jobs[3].inputs``
    in JSON, ``file:line`` in CSV)."""
    source = os.fspath(path)
    suffix = Path(source).suffix.lower()
    if suffix not in (".json", ".csv"):
        raise MissionError("a manifest is a .json or a .csv file", source)
    text = decode_utf8(read_bytes(source, "manifest"), source, "manifest")
    jobs = _json_jobs(text, source) if suffix == ".json" else _csv_jobs(text, source)
    if not jobs:
        raise MissionError("the manifest lists no job", source)
    return jobs


def _json_jobs(text: str, source: str) -> list[Job]:
    data = parse_json(text, source)
    prefix = "jobs"
    if isinstance(data, dict):
        unknown = [k for k in data if k != "jobs"]
        if unknown or "jobs" not in data:
            raise MissionError(f"expected a list of jobs, or an object with the one key \"jobs\" (found: "
                               f"{', '.join(map(repr, data)) or 'no key'})", source)
        data = data["jobs"]
    else:
        prefix = ""
    if not isinstance(data, list):
        raise MissionError(f"{prefix or 'the manifest'}: expected a list of jobs", source)
    problems: list[Problem] = []
    jobs = []
    for i, entry in enumerate(data):
        where = f"{source}: {prefix}[{i}]"
        if not isinstance(entry, dict):
            problems.append(Problem(where, "expected a job object {\"command\": ..., \"inputs\": [...]}"))
            continue
        job = _job(entry, where, i + 1, problems, _json_list)
        if job is not None:
            jobs.append(job)
    return _checked(jobs, problems)


def _csv_jobs(text: str, source: str) -> list[Job]:
    """A CSV manifest: a header row naming the columns (``command,inputs,options,output,id``), one
    job per row; ``inputs`` and ``options`` are split like a shell line (quote paths with
    spaces)."""
    _refuse_nul(text, source)
    reader = csv.DictReader(io.StringIO(text, newline=""))
    try:
        return _csv_rows(reader, source)
    except csv.Error as err:  # a field over the csv module's size limit, a damaged quote
        raise MissionError(f"invalid CSV: {err}", located(source, reader.line_num)) from None


def _refuse_nul(text: str, source: str) -> None:
    """A NUL byte, located: no path or argument can hold one (a binary file given as the
    manifest, or a damaged one)."""
    at = text.find("\0")
    if at >= 0:
        line = text.count("\n", 0, at) + 1
        column = at - (text.rfind("\n", 0, at) + 1) + 1
        raise MissionError("the manifest holds a NUL byte, which no path or argument can hold (is it a binary file?)",
                           located(source, line, column))


def _csv_rows(reader: csv.DictReader[str], source: str) -> list[Job]:
    header = reader.fieldnames or []
    problems = [Problem(located(source, 1), f"unknown column {name!r}" + _suggest(name))
                for name in header if name not in FIELDS]
    if problems:
        raise MissionError(problems)
    jobs: list[Job] = []
    for row in reader:
        where = located(source, reader.line_num)
        if None in row:  # more cells than header columns
            problems.append(Problem(where, f"{len(header) + len(row[None])} cells, the header names {len(header)}"))
            continue
        fields = {k: v for k, v in row.items() if v not in (None, "")}
        if not fields:
            continue  # an empty line
        job = _job(fields, where, len(jobs) + 1, problems, _csv_list)
        if job is not None:
            jobs.append(job)
    return _checked(jobs, problems)


def _checked(jobs: list[Job], problems: list[Problem]) -> list[Job]:
    """The jobs of a manifest, once no two share an id; every problem found raised together."""
    _refuse_repeated_ids(jobs, problems)
    if problems:
        raise MissionError(problems)
    return jobs


def _refuse_repeated_ids(jobs: list[Job], problems: list[Problem]) -> None:
    """Two jobs with one id: the results file, the messages and the summary name a job by its
    id, so one would pass for the other."""
    first: dict[str, Job] = {}
    for job in jobs:
        if job.id in first:
            problems.append(Problem(job.where, f"job id {job.id!r} is also the id of the job at "
                                               f"{first[job.id].where}: give each job its own id"))
        first.setdefault(job.id, job)


def _suggest(name: str) -> str:
    near = closest(name, FIELDS, 0.6)
    return f" (did you mean {near!r}?)" if near else f"; the fields are {', '.join(FIELDS)}"


def _json_list(value: Any, key: str, where: str, problems: list[Problem]) -> tuple[str, ...] | None:
    if isinstance(value, str) and key == "inputs":
        return (value,)
    if isinstance(value, list) and all(isinstance(v, str) for v in value):
        return tuple(value)
    problems.append(Problem(f"{where}.{key}", "expected a list of strings"))
    return None


def _csv_list(value: Any, key: str, where: str, problems: list[Problem]) -> tuple[str, ...] | None:
    try:
        return tuple(shlex.split(value))
    except ValueError as exc:
        problems.append(Problem(where, f"column {key}: {exc} (quote a path with spaces as \"a b\")"))
        return None


ListReader = Callable[[Any, str, str, list[Problem]], "tuple[str, ...] | None"]


def _job(fields: dict[str, Any], where: str, number: int, problems: list[Problem], as_list: ListReader) -> Job | None:
    """One job from its fields (a JSON object or a CSV row), its problems added to ``problems``."""
    before = len(problems)
    problems.extend(Problem(f"{where}.{key}", f"unknown field {key!r}" + _suggest(key))
                    for key in fields if key not in FIELDS)
    command = fields.get("command")
    if not isinstance(command, str) or not command:
        problems.append(Problem(where, "the job names no command (\"command\": \"decompose\", \"count\", ...)"))
    inputs = as_list(fields["inputs"], "inputs", where, problems) if "inputs" in fields else ()
    if inputs == ():
        problems.append(Problem(where, "the job names no inputs (a mission folder, or HDDL GM CONFIG)"))
    options = as_list(fields["options"], "options", where, problems) if "options" in fields else ()
    output, ident = fields.get("output"), fields.get("id", str(number))
    if output is not None and (not isinstance(output, str) or not output):
        problems.append(Problem(where, "output: expected a file name"))
    if not isinstance(ident, (str, int)) or isinstance(ident, bool):
        problems.append(Problem(where, "id: expected a name or a number"))
    if len(problems) == before:
        _refuse_nul_fields(where, {"command": [command], "inputs": inputs, "options": options,
                                   "output": [output], "id": [ident]}, problems)
    if len(problems) > before or not isinstance(command, str) or inputs is None or options is None:
        return None
    return Job(str(ident), command, inputs, options, output, where)


def _refuse_nul_fields(where: str, values: dict[str, Any], problems: list[Problem]) -> None:
    """A NUL character in a field (``"\\u0000"`` in JSON): no path or argument can hold one, and
    the job could not even be started."""
    for key, items in values.items():
        if any(isinstance(v, str) and "\0" in v for v in items or ()):
            problems.append(Problem(f"{where}.{key}", "holds a NUL character, which no path or argument can hold"))


# -- the glob form -----------------------------------------------------------------------------

def jobs_from_glob(pattern: str, command: str, options: Iterable[str], *, mission: str | None = None,
                   output: str | None = None) -> list[Job]:
    """``--each GLOB [--mission DIR] [--output PATTERN] COMMAND OPTIONS``: one job per match.

    Without ``mission`` the folders matched are mission folders, each a job's input.  With it,
    the files matched are world files: every job runs the one mission on its own world
    (``--world``).  What is not of the kind looked for (a README beside the missions) is left
    out.  ``output`` is a pattern where ``{name}`` is the match's name without its suffix."""
    wanted = "world file" if mission is not None else "mission folder"
    matches = [Path(m) for m in sorted(glob.glob(pattern, recursive=True))
               if (os.path.isfile(m) if mission is not None else os.path.isdir(m))]
    if not matches:
        hint = "" if mission is not None else " (to run one mission on many world files, add --mission DIR)"
        raise MissionError(f"no {wanted} matches {pattern!r}{hint}", "--each")
    jobs = []
    for i, path in enumerate(matches, start=1):
        match = str(path)
        try:
            out = None if output is None else output.format(name=path.stem if path.is_file() else path.name)
        except (KeyError, IndexError, ValueError) as exc:
            raise MissionError(f"--output {output}: {exc!r}: the one field is {{name}}", "--output") from None
        inputs = (match,) if mission is None else (mission,)
        world = () if mission is None else ("--world", match)
        jobs.append(Job(str(i), command, inputs, (*world, *options), out, f"--each {match}"))
    return jobs


# -- checking the jobs against the command line -------------------------------------------------

def check_jobs(jobs: list[Job], base: Path) -> list[argparse.Namespace]:
    """Parse every job's command line with the ``mutrose-cp`` parser; the parsed arguments of each,
    or every problem at once (an unknown command or option, an output given twice).  What the
    jobs write is checked once their files are known (:mod:`.safety`); ``base`` is the jobs'
    folder."""
    from .parser import mutrose_parser

    parser = mutrose_parser()
    problems: list[Problem] = []
    parsed = []
    for job in jobs:
        parsed.append(_check_job(parser, job, problems))
    if problems:
        raise MissionError(problems)
    return parsed  # type: ignore[return-value]  # no None is left without a problem


def _check_job(parser: argparse.ArgumentParser, job: Job, problems: list[Problem]) -> argparse.Namespace | None:
    """The job's command line parsed, or its problem added to ``problems``.  The job's output
    goes first (``COMMAND -o OUTPUT INPUTS OPTIONS``), so that a command whose ``-o`` is required
    parses, and a ``-o`` among the options, which would come later and win, shows."""
    from .parser import path_options

    where = f"{job.where}: job {job.id}"
    if job.command == "batch":
        problems.append(Problem(where, "a batch job cannot be a batch: list its jobs in this manifest"))
        return None
    options = path_options(job.command)  # none for a command the parser does not know: it says so below
    takes_output = any(option.dest == "output" for option in options)
    if job.output is not None and options and not takes_output:
        problems.append(Problem(where, f"{job.command} writes no output file: drop the job's output"))
        return None
    if job.output == "-":
        problems.append(Problem(where, "output -: a job's standard output carries its summary; give a file name"))
        return None
    output = ["-o", job.output] if job.output is not None and takes_output else []
    args, error = _parse(parser, [job.command, *output, *job.inputs, *job.options, *batch_flags(job.command)])
    if args is None:
        problems.append(Problem(where, f"mutrose-cp {job.command}: {error}"))
        return None
    if takes_output and args.output != job.output:
        problems.append(Problem(where, "the options name an output (-o): give it as the job's output"))
        return None
    return args


def _parse(parser: argparse.ArgumentParser, argv: list[str]) -> tuple[argparse.Namespace | None, str]:
    """``parser.parse_args(argv)`` with its usage error as text instead of a message and an exit."""
    err = io.StringIO()
    try:
        with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
            return parser.parse_args(argv), ""
    except SystemExit:
        lines = err.getvalue().strip().splitlines()
        return None, lines[-1].split("error: ", 1)[-1] if lines else "the options ask for help (-h): drop it"
