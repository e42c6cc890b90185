"""The original C++ decomposer as a test oracle, found by path (``MUTROSE_ORIGINAL``, default
``../shared/original/MutroseMissionDecomposer``) and skipped when absent.

It is always run under a time limit, with no standard input (it waits for ENTER on some
inputs), in a temporary copy of the mission folder (it writes where the configuration says).
"""
from __future__ import annotations

import json
import os
import shutil
import subprocess
import tempfile
from dataclasses import dataclass
from pathlib import Path

import pytest

import numericgen

ROOT = Path(__file__).resolve().parents[1]
ORIGINAL = Path(os.environ.get("MUTROSE_ORIGINAL", ROOT.parent / "shared" / "original" / "MutroseMissionDecomposer"))


def available() -> bool:
    return ORIGINAL.is_file() and os.access(ORIGINAL, os.X_OK)


def require() -> Path:
    if not available():
        pytest.skip(f"the original decomposer is not at {ORIGINAL} (set MUTROSE_ORIGINAL)")
    return ORIGINAL


@dataclass(frozen=True)
class OriginalRun:
    status: int
    stdout: str
    output: dict | None  # the JSON output file, when it wrote one

    def valid_decompositions(self) -> set[frozenset[str]]:
        """The valid mission decompositions as sets of decomposition ids (``AT1_1|2``)."""
        return set() if self.output is None else numericgen.valid_decompositions(self.output)

    def actions(self) -> dict[str, list[str]]:
        """Decomposition id -> its action names."""
        return {} if self.output is None else numericgen.decomposition_actions(self.output)


def run(folder: Path, hddl: Path, gm: Path, config: Path, timeout: float = 20.0) -> OriginalRun:
    """Run the original on a copy of ``folder`` (the three files given inside it); the
    configuration's output is read from ``output/mission.json`` (the generator's)."""
    binary = require()
    with tempfile.TemporaryDirectory(prefix="mutrose-original-") as tmp:
        work = Path(tmp) / "mission"
        shutil.copytree(folder, work)
        (work / "output").mkdir(exist_ok=True)
        rel = [str(Path(p).resolve().relative_to(Path(folder).resolve())) for p in (hddl, gm, config)]
        done = subprocess.run([str(binary), *rel], cwd=work, stdin=subprocess.DEVNULL, capture_output=True,
                              text=True, timeout=timeout, errors="replace")
        out = work / "output" / "mission.json"
        output = json.loads(out.read_text()) if done.returncode == 0 and out.is_file() else None
        return OriginalRun(done.returncode, done.stdout, output)
