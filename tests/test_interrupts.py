"""Interrupts (SIGINT, SIGTERM) in every long phase of a command: the process ends with
128 + the signal number and says "interrupted while <phase>", never reports a result from an
unfinished solve, leaves an existing output untouched and no temporary file behind.

The signal is sent by the process itself when the phase named in ``$MUTROSE_CP_FAULT`` starts
(after a delay, so that a solve is under way): the same path as a Ctrl-C or a ``kill``.
"""
from __future__ import annotations

import os
import random
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mutrose_cp.interrupt import FAULT_ENV, Interrupted, signal_handlers
from mutrose_cp.output.files import atomic_writer

from missiongen import Action, GoalNode, Lit, Method, MissionSpec, Room, Task, TaskNode

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"
SENTINEL = "previous output, must survive\n"


FACTS = ("lit", "warm", "loud", "open", "wet", "cold", "dark", "busy", "clean", "full", "hot", "dry", "shut",
         "lent", "sold", "kept")
SWITCHES = 20


def _coupled_mission(folder: Path, switches: int = SWITCHES) -> Path:
    """20 parallel switches (by default), each turning its own half of 16 room facts on, off or leaving them:
    one component of about two million solutions (no switch may turn on a fact that another
    turns off), which takes CP-SAT many seconds to enumerate.  Neither faster way applies: the
    facts each switch touches differ, so what the switches so far have set and cleared takes
    too many values to pass from block to block (``solve/layered.py``), and twenty conflict
    definitions are more than counting from them takes on (``solve/hubs.py``)."""
    actions = [Action("wait-here")]
    tasks = []
    for k in range(switches):
        name = "Switch" + "".join(chr(ord("A") + int(d)) for d in f"{k:02d}")  # letters only: SwitchAA, ...
        touched = random.Random(k).sample(FACTS, len(FACTS) // 2)
        on, off = f"switch-on-{k}", f"switch-off-{k}"
        actions += [Action(on, eff=tuple(Lit(f, "?rm") for f in touched)),
                    Action(off, eff=tuple(Lit(f, "?rm", False) for f in touched))]
        tasks.append(Task(name, (Method(f"m-on-{k}", (), (on,)), Method(f"m-off-{k}", (), (off,)),
                                 Method(f"m-wait-{k}", (), ("wait-here",)))))
    tree = GoalNode(tuple(TaskNode(t.name) for t in tasks), annotation=("flat", "#"))
    MissionSpec(FACTS, ("charged",), tuple(actions), tuple(tasks),
                (Room("Room1", True, tuple((f, None) for f in FACTS), 0),), True, "", tree).write(folder)
    return folder


def _run(args: list[str], fault: str, cwd: Path) -> subprocess.CompletedProcess:
    env = {**os.environ, FAULT_ENV: fault}
    return subprocess.run([sys.executable, "-m", "mutrose_cp", *args], cwd=cwd, env=env, capture_output=True,
                          text=True, timeout=300)


def _leftovers(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.rglob(".*.tmp"))


@pytest.mark.parametrize("sig", ["INT", "TERM"])
@pytest.mark.parametrize("phase,command,delay", [
    ("expanding the mission", "decompose", 0),
    ("solving", "decompose", 0.3),
    ("solving", "count", 0.3),
    ("solving", "count", 1.5),  # deep in the search: the stopped solver must not abort the exit
    ("writing the output", "decompose", 0),
])
def test_interrupted_phase_writes_nothing(tmp_path, sig, phase, command, delay):
    mission = _coupled_mission(tmp_path / "mission") if phase == "solving" else EXAMPLE
    out = tmp_path / "out" / "decomposition.json"
    out.parent.mkdir()
    out.write_text(SENTINEL)
    args = [command, str(mission)] + (["-o", str(out)] if command == "decompose" else [])
    result = _run(args, f"{phase}:{sig}:{delay}", tmp_path)
    assert result.returncode == 128 + signal.Signals["SIG" + sig], result.stderr
    assert f"interrupted while {phase} (SIG{sig})" in result.stderr
    assert "Traceback" not in result.stderr
    assert result.stdout == ""  # in particular no count
    assert out.read_text() == SENTINEL
    assert _leftovers(tmp_path) == []


def test_interrupted_ihtn_export_leaves_no_file(tmp_path):
    target = tmp_path / "ihtn"
    result = _run(["decompose", str(EXAMPLE), "--ihtn", str(target)], "exporting iHTNs:INT", tmp_path)
    assert result.returncode == 130, result.stderr
    assert "interrupted while exporting iHTNs" in result.stderr
    assert not target.exists() or not any(target.iterdir())


def test_interrupt_inside_a_write_removes_the_temporary_file(tmp_path):
    """A signal in the middle of writing (here raised from inside the block) leaves the old file
    and no temporary file."""
    out = tmp_path / "decomposition.json"
    out.write_text(SENTINEL)
    with pytest.raises(Interrupted):
        with atomic_writer(out) as fh:
            fh.write("{" * 100_000)
            raise Interrupted(signal.SIGTERM, "writing the output")
    assert out.read_text() == SENTINEL
    assert _leftovers(tmp_path) == []


@pytest.mark.parametrize("sig", ["INT", "TERM"])
def test_interrupted_while_expanding_the_worlds(tmp_path, sig):
    """Facts the goal model reads: the worlds are expanded while solving; stopped there, nothing
    is written and no count is printed."""
    hospital = EXAMPLE.parent / "hospital-disinfection"
    uncertain = tmp_path / "u.json"
    uncertain.write_text('{"uncertain": [{"entity": "Room101", "attribute": "needs_disinfection", "probability": 0.3}]}')
    out = tmp_path / "plan.json"
    out.write_text(SENTINEL)
    for command in (["decompose", "--most-likely", "-o", str(out)], ["count"]):
        result = _run([command[0], str(hospital), "--uncertain", str(uncertain), *command[1:]], f"solving:{sig}:0",
                      tmp_path)
        assert result.returncode == 128 + signal.Signals["SIG" + sig], result.stderr
        assert "interrupted while solving" in result.stderr and "Traceback" not in result.stderr
        assert result.stdout == "" and out.read_text() == SENTINEL and _leftovers(tmp_path) == []


def test_a_second_signal_while_stopping_is_ignored():
    """Once a command is stopping, a second Ctrl-C or a SIGTERM does not cut its cleaning up
    short: the first signal is the one reported, and the command's handlers ignore the others
    until they are gone (then the previous handlers are back)."""
    before = signal.getsignal(signal.SIGINT)
    with signal_handlers():
        with pytest.raises(Interrupted) as stopped:
            try:
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(5)  # not reached: the handler raises first
            finally:  # the cleaning up, interrupted again
                os.kill(os.getpid(), signal.SIGINT)
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.05)
        assert stopped.value.signum == signal.SIGINT
        assert signal.getsignal(signal.SIGTERM) is signal.SIG_IGN
    assert signal.getsignal(signal.SIGINT) is before
