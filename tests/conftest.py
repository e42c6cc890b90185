"""Shared fixtures: the reference corpus (third-party missions with the original's outputs)."""
from __future__ import annotations

import hashlib
import os
import tempfile
from pathlib import Path
from typing import Iterator

import pytest

ROOT = Path(__file__).resolve().parent.parent

# the tests (and the commands they run) keep the parser cache in a folder of their own, removed
# when the run ends
if "XDG_CACHE_HOME" not in os.environ:
    _cache = tempfile.TemporaryDirectory(prefix="mutrose-cp-test-cache-")
    os.environ["XDG_CACHE_HOME"] = _cache.name
REFERENCE = Path(os.environ.get("MUTROSE_REFERENCE", ROOT.parent / "shared" / "reference"))
if not REFERENCE.is_absolute():
    REFERENCE = (ROOT / REFERENCE).resolve()


def require_reference() -> Path:
    """The corpus path; a missing corpus skips locally and fails on CI."""
    if not REFERENCE.is_dir():
        if os.environ.get("CI") == "true":
            pytest.fail(f"reference corpus not found at {REFERENCE} (set MUTROSE_REFERENCE)")
        pytest.skip(f"reference corpus not found at {REFERENCE}")
    return REFERENCE


def _digests(*roots: Path) -> dict[Path, str]:
    return {path: hashlib.sha256(path.read_bytes()).hexdigest()
            for root in roots if root.is_dir() for path in sorted(root.rglob("*")) if path.is_file()}


@pytest.fixture(scope="session", autouse=True)
def inputs_left_alone() -> Iterator[None]:
    """No test changes the reference corpus or the bundled examples and models: a test that
    edits a mission works on a copy (the corpus files are read-only, which does not stop root)."""
    roots = (REFERENCE, ROOT / "examples", ROOT / "models")
    before = _digests(*roots)
    yield
    after = _digests(*roots)
    changed = sorted(str(p) for p in before.keys() | after.keys() if before.get(p) != after.get(p))
    assert not changed, f"tests changed their inputs: {changed[:5]}"


@pytest.fixture
def reference() -> Path:
    return require_reference()


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    """A copy of the bundled item-delivery mission to change (without its output folder)."""
    import shutil

    folder = tmp_path / "mission"
    shutil.copytree(ROOT / "examples" / "item-delivery", folder, ignore=shutil.ignore_patterns("output"))
    return folder
