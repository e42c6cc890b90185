"""Bad mission inputs: every problem is reported, located, with the right exit status.

Each case is one JSON file in ``tests/bad_inputs/``.  It names a valid mission to start from and
the small change that breaks it; the test copies the mission into a temporary folder, applies
the change, runs ``mutrose-cp`` in-process and checks the exit status, that every expected
substring (message *and* location) is on stderr, and that no traceback is printed.

Case keys:

``description``
    what the case breaks (free text).
``base``
    ``hospital-disinfection`` / ``item-delivery`` (``examples/``), or ``reference/<mission>`` (the
    third-party corpus, copied; the case is skipped when the corpus is absent).
``file`` + one of ``replace`` / ``content`` / ``content_file`` / ``truncate`` / ``delete``
    the change, relative to the mission folder.  ``replace`` is ``[old, new]`` or a list of such
    pairs; each ``old`` must occur exactly once.  ``content`` replaces (or creates) the file,
    ``content_file`` copies a file of ``bad_inputs/`` there, ``truncate`` keeps the first N
    characters, ``delete`` removes it.  Several changes go in a ``changes`` list of such objects.
``command`` / ``args`` / ``inputs``
    the sub-command (default ``check``), extra arguments (``{tmp}`` is the temporary folder), and
    ``HDDL GM CONFIG`` paths relative to the mission folder to use instead of the folder.
``expect_exit`` / ``expect``
    the exit status and the substrings that must all be on stderr (timings belong in the
    benchmarks, not here).
``xfail``
    the reason, for a known defect outside the readers (the test is ``xfail(strict=True)``).
"""
from __future__ import annotations

import json
import shutil
from pathlib import Path
from typing import Any

import pytest

from mutrose_cp.cli.program import main

HERE = Path(__file__).resolve().parent
CASES = HERE / "bad_inputs"
EXAMPLES = HERE.parent / "examples"
CHANGE_KEYS = ("replace", "content", "content_file", "truncate", "delete")


def _load_cases() -> list[Any]:
    params = []
    for path in sorted(CASES.glob("*.json")):
        case = json.loads(path.read_text(encoding="utf-8"))
        marks = [pytest.mark.xfail(strict=True, reason=case["xfail"])] if case.get("xfail") else []
        params.append(pytest.param(case, id=path.stem, marks=marks))
    return params


def _base_folder(base: str, request: pytest.FixtureRequest) -> Path:
    if base.startswith("reference/"):
        reference: Path = request.getfixturevalue("reference")  # skips when the corpus is absent
        folder = reference / "missions" / base.removeprefix("reference/")
    else:
        folder = EXAMPLES / base
    assert folder.is_dir(), f"unknown base mission {base}"
    return folder


def _apply(mission: Path, change: dict[str, Any]) -> None:
    target = mission / change["file"]
    kinds = [k for k in CHANGE_KEYS if k in change]
    assert len(kinds) == 1, f"a change needs exactly one of {CHANGE_KEYS}: {change}"
    kind = kinds[0]
    if kind == "delete":
        target.unlink()
    elif kind == "content":
        target.parent.mkdir(parents=True, exist_ok=True)
        target.write_text(change["content"], encoding="utf-8")
    elif kind == "content_file":
        target.parent.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(CASES / change["content_file"], target)
    elif kind == "truncate":
        text = target.read_text(encoding="utf-8")
        target.write_text(text[: change["truncate"]], encoding="utf-8")
    else:
        pairs = change["replace"]
        if pairs and isinstance(pairs[0], str):
            pairs = [pairs]
        text = target.read_text(encoding="utf-8")
        for old, new in pairs:
            assert text.count(old) == 1, f"{change['file']}: {old!r} occurs {text.count(old)} times"
            text = text.replace(old, new)
        target.write_text(text, encoding="utf-8")


def _changes(case: dict[str, Any]) -> list[dict[str, Any]]:
    if "changes" in case:
        return case["changes"]
    if "file" in case:
        return [{k: case[k] for k in ("file", *CHANGE_KEYS) if k in case}]
    return []


def test_enough_cases() -> None:
    cases = [json.loads(p.read_text(encoding="utf-8")) for p in CASES.glob("*.json")]
    assert len(cases) >= 30
    formats = {c["file"].split("/")[0] for case in cases for c in _changes(case)}
    assert {"hddl", "gm", "configuration", "knowledge"} <= formats


@pytest.mark.parametrize("case", _load_cases())
def test_bad_input(case: dict[str, Any], tmp_path: Path, capsys: pytest.CaptureFixture[str],
                   request: pytest.FixtureRequest) -> None:
    mission = tmp_path / "mission"
    shutil.copytree(_base_folder(case["base"], request), mission)
    for change in _changes(case):
        _apply(mission, change)
    inputs = [str(mission / p) for p in case["inputs"]] if "inputs" in case else [str(mission)]
    extra = [a.replace("{tmp}", str(tmp_path)) for a in case.get("args", [])]
    capsys.readouterr()

    code = main([case.get("command", "check"), *inputs, *extra])
    err = capsys.readouterr().err

    assert "Traceback" not in err, err
    assert code == case["expect_exit"], err
    missing = [s for s in case["expect"] if s not in err]
    assert not missing, f"not on stderr: {missing}\n--- stderr ---\n{err}"
    if code != 0:
        assert err.startswith("error: "), err
