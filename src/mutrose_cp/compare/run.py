"""``mutrose-cp compare``: the decomposers side by side on one mission.

Each decomposer runs as a process of its own (:func:`~mutrose_cp.compare.measure.run_measured`), so the
wall time and peak memory of one cannot leak into another's, and so one can be stopped: the
CP-SAT decomposer, the exploratory one, and with ``original`` a binary of the original tool,
which runs in a temporary mission folder as it expects.  A run that reaches the time limit is
killed and reported as timed out, a run that fails reports its error; neither has a result.

The outputs of the runs that finished are compared, by the reference rules of
:mod:`~mutrose_cp.compare.outputs`, with the first of them (the *reference*).  A space of more
than ``limit`` mission decompositions is not listed: then only the counts are compared.
"""
from __future__ import annotations

import shutil
import sys
import tempfile
from dataclasses import dataclass, field
from pathlib import Path
from typing import Callable

from ..errors import MissionError, Problem
from ..interrupt import phase
from ..io.config import load_configuration
from ..io.decomposition_output import load_decomposition_output
from .measure import Measurement, run_measured
from ..io.mission_files import resolve_config_path
from .outputs import ASPECTS, OutputDiff, OutputView, diff_outputs

FINISHED, TIMED_OUT, FAILED = "finished", "timed out", "failed"
DEFAULT_TIME_LIMIT = 60.0
DEFAULT_LIMIT = 100_000


@dataclass(frozen=True)
class CompareRequest:
    """The mission (its three files, as ``decompose`` takes them) and how to compare."""

    hddl: Path
    gm: Path
    config: Path
    time_limit: float = DEFAULT_TIME_LIMIT  # seconds of wall time per run
    limit: int | None = DEFAULT_LIMIT  # compare the sets up to this many decompositions; None: always
    original: Path | None = None  # an executable of the original tool
    lenient_xml: bool = False
    max_input_mb: int = 256


@dataclass(frozen=True)
class Run:
    """One decomposer's run.  ``count`` is the exact number of valid mission decompositions;
    ``view`` the output compared, None when there is none to compare (the run did not finish,
    found nothing valid, or found more than the request's limit)."""

    decomposer: str  # "cpsat", "exploratory", "original"
    status: str  # FINISHED, TIMED_OUT or FAILED
    seconds: float
    peak_mb: float
    exit_status: int | None
    count: int | None = None
    view: OutputView | None = field(default=None, repr=False)
    error: str = ""  # why it failed
    note: str = ""  # what else to know about a finished run


@dataclass(frozen=True)
class Comparison:
    """A run compared with the reference run.  ``aspects`` maps each aspect to whether the two
    agree, None where it was not compared; ``diff`` holds the differences when the outputs
    themselves were compared, and ``note`` says why they were not."""

    decomposer: str
    reference: str
    aspects: dict[str, bool | None]
    diff: OutputDiff | None = None
    note: str = ""

    @property
    def agree(self) -> bool:
        return all(v is not False for v in self.aspects.values())


@dataclass(frozen=True)
class CompareReport:
    request: CompareRequest
    runs: list[Run]
    comparisons: list[Comparison]

    @property
    def reference(self) -> str | None:
        return self.comparisons[0].reference if self.comparisons else None

    @property
    def agree(self) -> bool:
        """Every run that finished agrees with the others (vacuously, when fewer than two did)."""
        return all(c.agree for c in self.comparisons)

    @property
    def exit_status(self) -> int:
        return 0 if self.agree else 1


# ---------------------------------------------------------------------------------------------
# Running


def _failure(measured: Measurement) -> str:
    """What a failed run said last (stderr, else stdout), or how it ended."""
    for text in (measured.stderr, measured.stdout):
        lines = [line.strip() for line in text.splitlines() if line.strip()]
        if lines:
            return lines[-1].removeprefix("error: ")
    return measured.ending


def _measured_run(decomposer: str, measured: Measurement, *, count: int | None = None,
                  view: OutputView | None = None, error: str = "", note: str = "") -> Run:
    """The run as measured: timed out, failed (with ``error``) or finished."""
    status = TIMED_OUT if measured.timed_out else FAILED if error else FINISHED
    return Run(decomposer, status, measured.seconds, measured.peak_mb, measured.exit_status, count, view, error, note)


def _within(request: CompareRequest, count: int) -> bool:
    return request.limit is None or count <= request.limit


def _input_error(decomposer: str, measured: Measurement) -> MissionError:
    """The decomposer refused the mission (exit status 2): its messages, for the user."""
    return MissionError([Problem("", line) for line in measured.errors] or
                        Problem("", f"the {decomposer} decomposer refused the mission: {_failure(measured)}"))


def run_ours(request: CompareRequest, decomposer: str, work: Path) -> Run:
    """Run ``mutrose-cp decompose`` with one algorithm, listing every decomposition up to the
    limit.  An input error (exit status 2) is the mission's, not the decomposer's: raised."""
    out = work / f"{decomposer}.json"
    command = [sys.executable, "-m", "mutrose_cp", "decompose", str(request.hddl), str(request.gm),
               str(request.config), "-q", "--json-summary", "-o", str(out), "--format", "json",
               "--max-input-mb", str(request.max_input_mb), "--algorithm", decomposer,
               "--as-written"]  # both decomposers read the world as written: the exploratory one knows no uncertainty
    if decomposer == "cpsat":
        command += ["--limit", str(request.limit or 0)]
    if request.lenient_xml:
        command.append("--lenient-xml")
    measured = run_measured(command, Path.cwd(), request.time_limit)
    if measured.timed_out:
        return _measured_run(decomposer, measured)
    if measured.exit_status == 2:
        raise _input_error(decomposer, measured)
    if measured.exit_status == 3:
        return _measured_run(decomposer, measured, count=0, note="no valid mission decomposition")
    summary = measured.summary
    if measured.exit_status != 0 or summary is None or "mission_decompositions" not in summary:
        return _measured_run(decomposer, measured, error=_failure(measured))
    count = int(summary["mission_decompositions"])
    view = OutputView.of(load_decomposition_output(str(out))) if _within(request, count) else None
    out.unlink(missing_ok=True)
    return _measured_run(decomposer, measured, count=count, view=view)


def _copy_inside(source: Path, folder: Path, relative: str, key: str) -> None:
    target = (folder / relative).resolve()
    if folder.resolve() not in target.parents:
        raise MissionError(f"{key} {relative} leaves the mission folder: the original, run in a copy of it, "
                           "could not find it there", str(source))
    target.parent.mkdir(parents=True, exist_ok=True)
    shutil.copyfile(source, target)


def original_mission(request: CompareRequest, folder: Path) -> tuple[list[str], Path]:
    """A mission folder for the original: copies of the domain, goal model and configuration in
    ``hddl/``, ``gm/`` and ``configuration/``, and of the world where the configuration names it
    (the original reads it relative to the folder it runs in).  Returns the three arguments and
    the output file the original will write (the configuration's ``output.file_path``)."""
    config = load_configuration(request.config, lenient=request.lenient_xml)
    arguments = []
    for sub, path in (("hddl", request.hddl), ("gm", request.gm), ("configuration", request.config)):
        (folder / sub).mkdir(parents=True, exist_ok=True)
        shutil.copyfile(path, folder / sub / path.name)
        arguments.append(f"{sub}/{path.name}")
    if not Path(config.world_db.path).is_absolute():
        world = resolve_config_path(config.world_db.path, request.config)
        _copy_inside(world, folder, config.world_db.path, "world_db.path")
    output = Path(config.output.file_path)
    if not output.is_absolute():
        output = folder / output
        output.parent.mkdir(parents=True, exist_ok=True)  # the original expects the folder to exist
    return arguments, output


def run_original(request: CompareRequest, work: Path) -> Run:
    """Run the original tool as ``ORIGINAL HDDL GM CONFIG`` in a copy of the mission and read the
    output file its configuration names."""
    assert request.original is not None
    folder = work / "original"
    arguments, output = original_mission(request, folder)
    measured = run_measured([str(request.original), *arguments], folder, request.time_limit)
    if measured.timed_out:
        return _measured_run("original", measured)
    if measured.exit_status != 0:
        return _measured_run("original", measured, error=_failure(measured))
    if not output.is_file():
        return _measured_run("original", measured, error=f"it wrote no output file at {output}")
    try:
        written = load_decomposition_output(str(output))
    except MissionError as err:
        return _measured_run("original", measured, error=f"its output cannot be read: {err}")
    count = len(written.mission_decompositions)
    return _measured_run("original", measured, count=count,
                         view=OutputView.of(written) if _within(request, count) else None)


# ---------------------------------------------------------------------------------------------
# Comparing


def compare_runs(reference: Run, run: Run, limit: int | None) -> Comparison:
    """``run`` against ``reference``: the whole outputs when both were read, else the counts."""
    if reference.view is not None and run.view is not None:
        diff = diff_outputs(reference.view, run.view)
        return Comparison(run.decomposer, reference.decomposer, {a: diff.agrees(a) for a in ASPECTS}, diff)
    aspects: dict[str, bool | None] = dict.fromkeys(ASPECTS)
    aspects["mission decompositions"] = reference.count == run.count
    above = [r.decomposer for r in (reference, run) if r.count and not (limit is None or r.count <= limit)]
    why = (f"more than --limit {limit} mission decompositions ({', '.join(above)})" if above
           else "no valid mission decomposition, so no output file")
    return Comparison(run.decomposer, reference.decomposer, aspects,
                      note=f"the sets were not compared ({why}): only the counts")


def compare(request: CompareRequest, progress: Callable[[str], None] | None = None) -> CompareReport:
    """Run the decomposers one after the other and compare what they found."""
    say = progress or (lambda _message: None)
    runs: list[Run] = []
    with tempfile.TemporaryDirectory(prefix="mutrose-cp-compare-") as tmp:
        for decomposer in ("cpsat", "exploratory", *(("original",) if request.original else ())):
            say(f"{decomposer}: running (time limit {request.time_limit:g} s)")
            with phase(f"running {decomposer}"):  # named by an interrupt's message
                run = run_original(request, Path(tmp)) if decomposer == "original" else \
                    run_ours(request, decomposer, Path(tmp))
            say(f"{decomposer}: {run.status} in {run.seconds:.2f} s, {run.peak_mb:.1f} MB")
            runs.append(run)
    finished = [r for r in runs if r.status == FINISHED]
    comparisons = [compare_runs(finished[0], r, request.limit) for r in finished[1:]]
    return CompareReport(request, runs, comparisons)
