"""The head of the JSON output written by a second process while solving (``output_ahead.py``):
the same bytes as writing the whole document in one process, on every reference mission and a
stamped world; a failure in the child (no semantic mapping, a full disk) reported by the parent
as when it writes the head itself; an interrupt while solving kills the child and leaves the old
output and no temporary file; and no child is left running or unreaped."""
from __future__ import annotations

import dataclasses
import os
import resource
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mutrose_cp.errors import MissionError
from mutrose_cp.interrupt import FAULT_ENV
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.output.builder import OutputModel
from mutrose_cp.output.formats import write_output
from mutrose_cp.output import ahead as output_ahead
from mutrose_cp.output.ahead import AHEAD_MIN_DECOMPOSITIONS, output_while_solving
from mutrose_cp.solve.decompose import DecompositionRequest

from conftest import ROOT, require_reference

sys.path.insert(0, str(ROOT / "benchmarks"))
from generate import generate  # noqa: E402

pytestmark = pytest.mark.skipif(not hasattr(os, "fork") or len(os.sched_getaffinity(0)) < 2,
                                reason="the head is written ahead only with fork and two cores")
SENTINEL = "previous output, must survive\n"
ROOMS = AHEAD_MIN_DECOMPOSITIONS // 19 + 1  # vital signs: 19 decompositions a room


def _no_child_left() -> None:
    with pytest.raises(ChildProcessError):
        os.waitpid(-1, os.WNOHANG)


def _written_both_ways(mission: Mission, folder: Path) -> tuple[bytes, bytes]:
    tg = mission.task_graph
    result = mission.decompose(DecompositionRequest())
    section = result.space_section(tg.decomposition_keys.__getitem__)
    alone = folder / "alone.json"
    write_output(OutputModel(tg, mission.constraints, result.decompositions, mission.domain, mission.config,
                             mission.initial_state, space=section), alone, "json")
    ahead = folder / "ahead.json"
    model = OutputModel(tg, mission.constraints, [], mission.domain, mission.config, mission.initial_state)
    with output_while_solving(model, ahead, "json", minimum=0) as finish:
        result = mission.decompose(DecompositionRequest())  # its listing is read once
        finish(result.decompositions, result.space_section(tg.decomposition_keys.__getitem__))
    _no_child_left()
    return alone.read_bytes(), ahead.read_bytes()


def test_every_reference_mission(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    reference = require_reference()
    configurations = sorted((reference / "missions").glob("*/configuration/*.json"))
    for cfg in configurations:
        monkeypatch.chdir(cfg.parent.parent)
        alone, ahead = _written_both_ways(Mission.load(*find_mission_files(cfg.parent.parent, cfg.name)), tmp_path)
        assert ahead == alone, cfg
    assert len(configurations) >= 7


def test_a_stamped_world(tmp_path: Path) -> None:
    require_reference()
    alone, ahead = _written_both_ways(Mission.load(*generate("vital-signs", 30, tmp_path)), tmp_path)
    assert ahead == alone


def test_a_failure_of_the_child_is_raised_by_the_parent(tmp_path: Path) -> None:
    """No semantic mapping for a printed predicate: the child cannot write the head, and the
    parent raises its error (not a result), removes the temporary file and keeps the old one."""
    require_reference()
    mission = Mission.load(*generate("vital-signs", 6, tmp_path))
    config = dataclasses.replace(mission.config, semantic_mapping=tuple(
        m for m in mission.config.semantic_mapping if m.pred != "available"))
    out = tmp_path / "out" / "decomposition.json"
    out.parent.mkdir()
    out.write_text(SENTINEL)
    model = OutputModel(mission.task_graph, mission.constraints, [], mission.domain, config, mission.initial_state)
    with pytest.raises(MissionError, match="No Semantic Mapping exists for predicate \\[available Patient1\\]"):
        with output_while_solving(model, out, "json", minimum=0) as finish:
            finish([], None)
    _no_child_left()
    assert out.read_text() == SENTINEL
    assert [p.name for p in out.parent.iterdir()] == ["decomposition.json"]


def _large_mission(folder: Path) -> tuple[Path, Path, Path]:
    """Vital signs with enough rooms for the head to be written ahead by default."""
    return generate("vital-signs", ROOMS, folder)


def _cli(args: list[str], cwd: Path, env: dict[str, str] | None = None, preexec=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mutrose_cp", *args], cwd=cwd, capture_output=True, text=True,
                          timeout=300, env={**os.environ, **(env or {})}, preexec_fn=preexec)


def _running_writers(out: Path) -> list[str]:
    """Processes still running with ``out`` on their command line (a forked child keeps its
    parent's)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and str(out).encode() in (proc / "cmdline").read_bytes():
                found.append(proc.name)
        except OSError:
            continue
    return found


def test_the_command_line_writes_ahead_with_the_same_bytes(tmp_path: Path) -> None:
    require_reference()
    mission = _large_mission(tmp_path)
    ahead = tmp_path / "ahead.json"
    result = _cli(["decompose", *map(str, mission), "-q", "-o", str(ahead), "--limit", "2"], tmp_path)
    assert result.returncode == 0, result.stderr
    m = Mission.load(*mission)
    assert len(m.task_graph.decompositions()) >= AHEAD_MIN_DECOMPOSITIONS  # so it was written ahead
    res = m.decompose(DecompositionRequest(limit=2))
    alone = tmp_path / "alone.json"
    write_output(OutputModel(m.task_graph, m.constraints, res.decompositions, m.domain, m.config, m.initial_state,
                             space=res.space_section(m.task_graph.decomposition_keys.__getitem__)), alone, "json")
    assert ahead.read_bytes() == alone.read_bytes()


@pytest.mark.parametrize("sig", ["INT", "TERM"])
def test_an_interrupt_while_solving_stops_the_writer(tmp_path: Path, sig: str) -> None:
    require_reference()
    mission = _large_mission(tmp_path)
    out = tmp_path / "out" / "decomposition.json"
    out.parent.mkdir()
    out.write_text(SENTINEL)
    result = _cli(["decompose", *map(str, mission), "-o", str(out)], tmp_path, {FAULT_ENV: f"solving:{sig}"})
    assert result.returncode == 128 + signal.Signals["SIG" + sig], result.stderr
    assert f"interrupted while solving (SIG{sig})" in result.stderr
    assert "Traceback" not in result.stderr
    time.sleep(0.5)  # a writer left running would still be writing
    assert _running_writers(out) == []
    assert out.read_text() == SENTINEL
    assert [p.name for p in out.parent.iterdir()] == ["decomposition.json"]


def test_a_full_disk_in_the_writer_keeps_the_old_output(tmp_path: Path) -> None:
    require_reference()
    mission = _large_mission(tmp_path)
    out = tmp_path / "out" / "decomposition.json"
    out.parent.mkdir()
    out.write_text(SENTINEL)

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (1 << 20, 1 << 20))

    result = _cli(["decompose", *map(str, mission), "-q", "-o", str(out)], tmp_path, preexec=small_files)
    assert result.returncode == 2, result.stderr
    assert f"error: {out}: cannot write the output: File too large" in result.stderr
    assert "Traceback" not in result.stderr
    assert out.read_text() == SENTINEL
    assert [p.name for p in out.parent.iterdir()] == ["decomposition.json"]


STUCK_WRITER = """
import os, sys
from mutrose_cp.mission import Mission
from mutrose_cp.output.builder import OutputModel
from mutrose_cp.output.ahead import output_while_solving
fifo, *mission = sys.argv[1:]
reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # never read: the writer blocks once the pipe is full
m = Mission.load(*mission)
model = OutputModel(m.task_graph, m.constraints, [], m.domain, m.config, m.initial_state)
try:
    with output_while_solving(model, fifo, "json", minimum=0) as finish:
        raise KeyboardInterrupt  # the solve stops
except KeyboardInterrupt:
    pass
try:
    os.waitpid(-1, os.WNOHANG)
except ChildProcessError:
    print("no child left")
"""


def test_leaving_early_kills_a_blocked_writer(tmp_path: Path) -> None:
    """The output is a FIFO that nobody reads: the child blocks on its first full pipe.  The
    solve stops; leaving the block must kill the child, not wait for it."""
    require_reference()
    mission = generate("vital-signs", 30, tmp_path)
    fifo = tmp_path / "out.fifo"
    os.mkfifo(fifo)
    result = subprocess.run([sys.executable, "-c", STUCK_WRITER, str(fifo), *map(str, mission)], cwd=tmp_path,
                            capture_output=True, text=True, timeout=120)
    assert result.returncode == 0, result.stderr
    assert result.stdout == "no child left\n"


def test_the_largest_missions_write_their_head_in_one_process(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """Above ``AHEAD_MAX_DECOMPOSITIONS`` the memory a child copies matters more: no fork."""
    require_reference()
    mission = Mission.load(*generate("vital-signs", 6, tmp_path))
    assert len(mission.task_graph.decompositions()) > 10
    monkeypatch.setattr(output_ahead, "AHEAD_MAX_DECOMPOSITIONS", 10)

    def no_fork() -> int:
        raise AssertionError("forked")

    monkeypatch.setattr(os, "fork", no_fork)
    alone, ahead = _written_both_ways(mission, tmp_path)
    assert ahead == alone


def test_a_memory_limited_run_writes_its_head_in_one_process(tmp_path: Path) -> None:
    """``batch --memory-mb`` limits each process: a second one could take the run past it."""
    require_reference()
    mission = _large_mission(tmp_path)
    out = tmp_path / "out.json"
    script = ("import os, resource, sys\n"
              "resource.setrlimit(resource.RLIMIT_DATA, (8 << 30, 8 << 30))\n"
              "def no_fork(): raise AssertionError('forked')\n"
              "os.fork = no_fork\n"
              "from mutrose_cp.cli.program import main\n"
              "sys.exit(main(sys.argv[1:]))\n")
    result = subprocess.run([sys.executable, "-c", script, "decompose", *map(str, mission), "-q", "-o", str(out)],
                            cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert result.returncode == 0, result.stderr
    assert out.stat().st_size > 0
