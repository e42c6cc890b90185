"""``mutrose … -p`` prints on stdout, byte for byte, what the original prints there.

The corpus holds the original's ``-p`` stdout for every reference mission
(``console/<mission>/<configuration>.p.stdout``, its exit status in ``.p.exit``; its stderr was
empty), recorded as the VS Code plug-in runs it: inside the mission folder, the goal model
written to ``./temp.txt``, ``mutrose <hddl> ./temp.txt <config> -p``.  Each is compared with the
drop-in run the same way, in a temporary copy of the mission, with either decomposer and with
each configuration of that name (JSON and XML print the same).  ``console/errors`` holds two
broken copies of lab-samples-logistics with the original's stdout, stderr and status; there the
drop-in prints located errors on stderr instead (docs/deviations.md, the drop-in section).
"""
from __future__ import annotations

import os
import re
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import REFERENCE, require_reference
from mutrose_cp.io.mission_files import find_mission_files

CONSOLE = REFERENCE / "console"
DROP_IN = (sys.executable, "-m", "mutrose_cp.cli.dropin")  # what the installed ``mutrose`` script runs
SUFFIX = ".p.stdout"


def run_as_plug_in(folder: Path, hddl: str, gm: str, config: str, command: tuple[str, ...] = DROP_IN,
                   algorithm: str | None = None, timeout: float = 300) -> subprocess.CompletedProcess[bytes]:
    """``<command> <hddl> ./temp.txt <config> -p`` in ``folder``, as the plug-in runs it: the goal
    model (``gm``, relative to ``folder``) copied to ``./temp.txt``, no standard input, stdout and
    stderr as bytes.  ``algorithm`` sets ``MUTROSE_ALGORITHM`` (unset: the default decomposer)."""
    shutil.copy(folder / gm, folder / "temp.txt")
    env = {k: v for k, v in os.environ.items() if k != "MUTROSE_ALGORITHM"}
    if algorithm is not None:
        env["MUTROSE_ALGORITHM"] = algorithm
    return subprocess.run([*command, hddl, "./temp.txt", config, "-p"], cwd=folder, stdin=subprocess.DEVNULL,
                          capture_output=True, timeout=timeout, env=env)


def mission_copy(mission: Path, tmp_path: Path) -> Path:
    """A copy of ``mission`` to run in, without the outputs the original wrote."""
    folder = tmp_path / mission.name
    shutil.copytree(mission, folder, ignore=shutil.ignore_patterns("output", "ihtn"))
    return folder


def relative_files(folder: Path, config_name: str | None = None) -> tuple[str, str, str]:
    """The mission's HDDL, goal model and configuration, relative to its folder, as the plug-in's
    settings name them."""
    return tuple(str(p.relative_to(folder)) for p in find_mission_files(folder, config_name))  # type: ignore[return-value]


def _recorded() -> list[Path]:
    return sorted(p for p in CONSOLE.glob(f"*/*{SUFFIX}") if p.parent.name != "errors")


def _configurations(recorded: Path) -> list[Path]:
    """The mission's configurations the recorded output is named after (``configuration.p.stdout``:
    ``configuration.json`` and ``configuration.xml``)."""
    stem = recorded.name.removesuffix(SUFFIX)
    folder = REFERENCE / "missions" / recorded.parent.name / "configuration"
    return sorted(p for p in folder.glob(f"{stem}.*") if p.suffix in (".json", ".xml"))


def _cases() -> list:
    if not CONSOLE.is_dir():
        return [pytest.param(None, None, id="corpus-missing")]
    return [pytest.param(recorded, cfg, id=f"{recorded.parent.name}/{cfg.name}")
            for recorded in _recorded() for cfg in _configurations(recorded)]


def _error_cases() -> list:
    if not (CONSOLE / "errors").is_dir():
        return [pytest.param(None, id="corpus-missing")]
    return [pytest.param(case, id=case.name) for case in sorted((CONSOLE / "errors").iterdir()) if case.is_dir()]


def test_every_recorded_output_is_compared():
    require_reference()
    recorded = _recorded()
    assert len(recorded) >= 8
    assert all(_configurations(r) for r in recorded), [r.name for r in recorded if not _configurations(r)]


@pytest.mark.parametrize("algorithm", ["cpsat", "exploratory"])
@pytest.mark.parametrize(("recorded", "cfg"), _cases())
def test_the_plug_in_call_prints_the_originals_stdout_byte_for_byte(recorded, cfg, algorithm, tmp_path):
    require_reference()
    mission = cfg.parent.parent
    folder = mission_copy(mission, tmp_path)
    run = run_as_plug_in(folder, *relative_files(folder, cfg.name), algorithm=algorithm)
    expected_status = int(recorded.with_name(recorded.name.removesuffix(SUFFIX) + ".p.exit").read_text())
    assert run.returncode == expected_status, run.stderr.decode()
    assert run.stdout == recorded.read_bytes()
    assert b"error" not in run.stderr  # warnings only, on stderr where the plug-in does not look


def _originals_location(case: Path) -> tuple[str, str]:
    """What the original's message names: (the file and line of a parse error) or (the task and
    the undeclared predicate of a failed check)."""
    said = b"".join((case.parent / f"{case.name}.p.{kind}").read_bytes() for kind in ("stdout", "stderr")).decode()
    parse = re.search(r"in file (\S+) in line \x1b\[1m(\d+)", said)
    if parse:
        return parse[1], parse[2]
    check = re.search(r'Task (\S+) has the predicate "([^"]+)"', said)
    assert check, said
    return check[1], check[2]


@pytest.mark.parametrize("case", _error_cases())
def test_a_broken_mission_fails_with_the_originals_finding_on_stderr(case, tmp_path):
    """stdout stays empty (the original prints a parse error there, status 255, and a failed
    check on stderr through an assertion, status 134); stderr names what the original names,
    located (``error: file:line:col: …``); the status is 2, mutrose-cp's for invalid input."""
    require_reference()
    folder = mission_copy(case, tmp_path)
    run = run_as_plug_in(folder, *relative_files(folder))
    assert int((case.parent / f"{case.name}.p.exit").read_text()) != 0
    assert (run.returncode, run.stdout) == (2, b"")
    shown = run.stderr.decode()
    first, second = _originals_location(case)
    if second.isdigit():  # a parse error: same file, same line
        assert re.search(rf"^error: {re.escape(first)}:{second}:\d+: syntax error", shown, re.M), shown
    else:  # a failed check: same task, same predicate
        assert re.search(rf"^error: \S+:\d+:\d+: .*'{re.escape(second)}'.*'{re.escape(first)}'", shown, re.M), shown
    assert "Traceback" not in shown
