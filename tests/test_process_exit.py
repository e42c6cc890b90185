"""How a console-script process ends after a command that kept its objects (``process.py``):
at once, without freeing them, yet with its streams flushed and its exit handlers run."""
from __future__ import annotations

import json
import os
import subprocess
import sys
from pathlib import Path

from mutrose_cp.cli import process
from mutrose_cp.cli.program import main

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"


def test_the_console_script_flushes_its_summary_and_runs_exit_handlers(tmp_path):
    mark, out = tmp_path / "exit-handler-ran", tmp_path / "out.json"
    script = (f"import atexit, sys\n"
              f"atexit.register(lambda: open({str(mark)!r}, 'w').write('ran'))\n"
              f"sys.argv = ['mutrose-cp', 'decompose', {str(EXAMPLE)!r}, '-q', '-o', {str(out)!r}, '--json-summary']\n"
              f"from mutrose_cp.cli.program import entry\n"
              f"entry()\n")
    buffered = {k: v for k, v in os.environ.items() if k != "PYTHONUNBUFFERED"}  # stdout held until flushed
    done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120, env=buffered)
    assert done.returncode == 0, done.stderr
    summary = json.loads(done.stdout)  # written whole, though the process ends without finalizing
    assert summary["command"] == "decompose" and summary["output"] == str(out)
    assert json.loads(out.read_text(encoding="utf-8"))  # the output is complete
    assert mark.read_text() == "ran"  # the batch jobs report their peak memory from such a handler


def test_a_program_that_calls_main_keeps_nothing(tmp_path):
    assert main(["decompose", str(EXAMPLE), "-q", "-o", str(tmp_path / "out.json")]) == 0
    assert process._kept == []  # the mission is freed when the command returns


def test_every_command_that_reads_a_mission_leaves_it_for_the_end_of_the_process(tmp_path):
    """count, verify and explain ended by freeing their mission one object at a time (a third of a
    5000-delivery run); what they made is now kept, and the process ends at once."""
    medication = EXAMPLE.parent / "medication-round"
    for command, example, space in ((["count"], EXAMPLE, "DecompositionSpace"),
                                    (["verify", "--property", "count uses(action pick-item)"], EXAMPLE,
                                     "DecompositionSpace"),
                                    (["explain"], medication, "UncertainSpace")):
        mark = tmp_path / "kept"
        script = (f"import atexit, sys\n"
                  f"from mutrose_cp.cli import process\n"
                  f"atexit.register(lambda: open({str(mark)!r}, 'w').write("
                  f"' '.join(sorted({{type(o).__name__ for o in process._kept}}))))\n"
                  f"sys.argv = ['mutrose-cp', {command[0]!r}, {str(example)!r}, '-q', *{command[1:]!r}]\n"
                  f"from mutrose_cp.cli.program import entry\n"
                  f"entry()\n")
        done = subprocess.run([sys.executable, "-c", script], capture_output=True, text=True, timeout=120)
        assert done.returncode == 0, done.stderr
        kept = mark.read_text().split()
        assert "Mission" in kept and space in kept, (command, kept)
