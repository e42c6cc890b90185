"""Start-up stays lean: the commands import neither the data-science stack OR-Tools' high-level
API pulls in, nor the libraries that only some commands need.  (Checked by the modules loaded,
not by time: timings belong in the benchmarks.)"""
from __future__ import annotations

import json
import subprocess
import sys
from pathlib import Path

import pytest

from conftest import require_reference

ROOT = Path(__file__).resolve().parent.parent
HEAVY = ("pandas", "numpy", "networkx", "clarabel", "matplotlib", "graphviz", "scipy")

PROBE = """
import json, sys
from mutrose_cp.cli.program import main
status = main(sys.argv[1:])
print(json.dumps([status, sorted({m.split('.')[0] for m in sys.modules})]))
"""


def _loaded(args: list[str], cwd: Path) -> tuple[int, set[str]]:
    run = subprocess.run([sys.executable, "-c", PROBE, *args], cwd=cwd, capture_output=True, text=True,
                         timeout=300)
    status, modules = json.loads(run.stdout.strip().splitlines()[-1])
    return status, set(modules)


@pytest.mark.parametrize("command", [["decompose"], ["count"], ["check"], ["decompose", "--algorithm", "exploratory"],
                                     ["compare"], ["export-hddl"]])
def test_commands_on_a_reference_mission_load_no_heavy_module(tmp_path, command):
    mission = require_reference() / "missions" / "room-preparation"
    out = {"decompose": ["-o", str(tmp_path / "out.json")], "export-hddl": ["-o", str(tmp_path / "out.hddl")]}.get(
        command[0], [])
    status, modules = _loaded([*command, str(mission), "-q", *out], tmp_path)
    assert status in (0, 3)
    assert not modules & set(HEAVY), sorted(modules & set(HEAVY))
    assert "ortools" not in modules  # its components are tiny: enumerated without CP-SAT


def test_a_component_too_large_to_enumerate_loads_only_the_lean_cp_sat_helper(tmp_path):
    from test_interrupts import _coupled_mission

    # ten switches: a component the faster ways cannot take on either, of thousands of solutions
    mission = _coupled_mission(tmp_path / "coupled", switches=10)
    status, modules = _loaded(["count", str(mission), "-q"], tmp_path)
    assert status == 0
    assert "ortools" in modules and not modules & set(HEAVY)


def test_validate_loads_networkx_only_when_it_runs(tmp_path):
    example = ROOT / "examples" / "item-delivery"
    out = tmp_path / "out.json"
    status, modules = _loaded(["decompose", str(example), "-q", "-o", str(out)], tmp_path)
    assert status == 0 and "networkx" not in modules
    status, modules = _loaded(["validate", str(example), str(out), "-q"], tmp_path)
    assert status == 0 and "networkx" in modules and "pandas" not in modules
