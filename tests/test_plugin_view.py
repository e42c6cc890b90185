"""What the VS Code plug-in (mutrose-vscode) shows, driven with its own command lines.

The plug-in runs ``mutrose`` through Node's ``child_process.exec``, i.e. ``sh -c`` with its
command string, in the workspace root, with the goal model it edits (a ``.gm`` file):

* ``mutrose <hddl> ./temp.txt <config> -p``: on success it shows stdout in its output panel; on
  failure a pop-up ``Error: ${error}``, which is Node's ``Command failed: <cmd>`` followed by the
  command's **stderr**;
* ``mutrose <hddl> <gm> <config> -h``: then it writes an ``ihtn_N.png`` beside each
  ``ihtn_N.json`` and, on its next run, draws every file of ``./ihtn``.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import require_reference
from mutrose_cp.io.mission_files import find_mission_files
from test_conformance import _cases, _golden_path

ROOT = Path(__file__).resolve().parent.parent
DELIVERY = ROOT / "examples" / "item-delivery"
BIN = Path(sys.executable).parent


def _workspace(tmp_path: Path) -> tuple[Path, str, str, str]:
    """A workspace root holding the mission, the goal model named as the plug-in names it."""
    root = tmp_path / "workspace"
    shutil.copytree(DELIVERY, root)
    gm = next((root / "gm").iterdir())
    gm.rename(gm.with_suffix(".gm"))
    hddl = next((root / "hddl").iterdir()).relative_to(root)
    config = next((root / "configuration").iterdir()).relative_to(root)
    return root, str(hddl), str(gm.with_suffix(".gm").relative_to(root)), str(config)


def _plug_in(command: str, cwd: Path) -> subprocess.CompletedProcess[str]:
    if not (BIN / "mutrose").exists():
        pytest.skip("the mutrose command is not installed beside this Python")
    env = {**os.environ, "PATH": f"{BIN}{os.pathsep}{os.environ.get('PATH', '')}"}
    return subprocess.run(["sh", "-c", command], cwd=cwd, capture_output=True, text=True, timeout=300, env=env)


def test_a_failing_run_names_the_file_line_and_problem_on_stderr(tmp_path: Path):
    root, hddl, gm, config = _workspace(tmp_path)
    domain = root / hddl
    domain.write_text(domain.read_text().replace("(:method", "(:methd", 1))
    shutil.copy(root / gm, root / "temp.txt")
    run = _plug_in(f"mutrose {hddl} ./temp.txt {config} -p", root)
    assert run.returncode != 0
    shown = f"Error: Command failed: mutrose {hddl} ./temp.txt {config} -p\n{run.stderr}"
    assert f"error: {hddl}:" in shown and "methd" in shown  # file, line:col and the problem
    assert run.stdout == ""  # the output panel is not shown on failure; nothing is lost there
    assert "Traceback" not in run.stderr


def test_a_successful_run_prints_the_three_blocks_on_stdout_only(tmp_path: Path):
    root, hddl, gm, config = _workspace(tmp_path)
    shutil.copy(root / gm, root / "temp.txt")
    run = _plug_in(f"mutrose {hddl} ./temp.txt {config} -p", root)
    assert run.returncode == 0, run.stderr
    assert "GENERATED TASK INSTANCES" in run.stdout and "POSSIBLE MISSION DECOMPOSITIONS" in run.stdout
    assert "warning" not in run.stdout and "error" not in run.stdout


def test_a_second_ihtn_run_leaves_only_its_own_files(tmp_path: Path):
    root, hddl, gm, config = _workspace(tmp_path)
    first = _plug_in(f"mutrose {hddl} {gm} {config} -h", root)
    assert first.returncode == 0, first.stderr
    written = sorted(p.name for p in (root / "ihtn").iterdir())
    assert written and all(name.startswith("ihtn_") and name.endswith(".json") for name in written)
    for name in written:  # what the plug-in adds: a picture beside each file, and more
        (root / "ihtn" / name).with_suffix(".png").write_bytes(b"\x89PNG")
    (root / "ihtn" / "notes").mkdir()
    second = _plug_in(f"mutrose {hddl} {gm} {config} -h", root)
    assert second.returncode == 0, second.stderr
    assert sorted(p.name for p in (root / "ihtn").iterdir()) == written


@pytest.mark.parametrize(("mission", "cfg"), _cases("missions"))
def test_the_default_drop_in_writes_the_goldens_byte_for_byte(mission, cfg, tmp_path: Path):
    """With the default (CP-SAT) decomposer, the listing is sorted into the original's order:
    ``mission_decompositions[N]`` is the original's, on food-logistics Delivery too."""
    require_reference()
    folder = tmp_path / mission.name
    shutil.copytree(mission, folder, ignore=shutil.ignore_patterns("output", "ihtn"))
    hddl, gm, _ = find_mission_files(mission, cfg.name)
    run = subprocess.run([sys.executable, "-m", "mutrose_cp.cli.dropin", f"hddl/{hddl.name}", f"gm/{gm.name}",
                          f"configuration/{cfg.name}"], cwd=folder, capture_output=True, text=True, timeout=300,
                         env={k: v for k, v in os.environ.items() if k != "MUTROSE_ALGORITHM"})
    assert run.returncode == 0, run.stderr
    golden = _golden_path(mission, cfg)
    assert (folder / golden.relative_to(mission)).read_bytes() == golden.read_bytes()
