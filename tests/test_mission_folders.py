"""Mission folders: a stale copy beside the real file is never read silently, the files used
are named in every summary, and an ambiguous world path is reported."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"



def _stale_copy(folder: Path, sub: str, name: str) -> Path:
    original = next(p for p in (folder / sub).iterdir() if p.is_file())
    copy = folder / sub / name
    shutil.copy(original, copy)
    return original


@pytest.mark.parametrize("sub,option,stale", [("hddl", "--hddl", "delivery-old.hddl"),
                                               ("gm", "--gm", "delivery-gm-old.json")])
def test_two_candidates_are_refused_until_one_is_chosen(mission, capsys, sub, option, stale):
    original = _stale_copy(mission, sub, stale)
    assert main(["check", str(mission)]) == 2
    err = capsys.readouterr().err
    assert f"{mission / sub}: several" in err and original.name in err and stale in err and option in err
    assert main(["check", str(mission), option, original.name]) == 0
    assert original.name in capsys.readouterr().err
    assert main(["check", str(mission), option, "missing.txt"]) == 2
    assert "no " in capsys.readouterr().err


def test_every_summary_names_the_four_files(mission, capsys):
    for command in (["check"], ["count"], ["decompose", "-o", str(mission / "out.json")]):
        assert main([command[0], str(mission), "--json-summary", *command[1:]]) == 0
        out = capsys.readouterr().out
        summary = json.loads(out.splitlines()[0])
        assert set(summary["inputs"]) == {"hddl", "gm", "configuration", "world"}
        assert summary["inputs"]["world"].endswith("knowledge/world_db.xml")


def test_a_world_path_that_names_two_files_is_reported(mission, tmp_path, monkeypatch, capsys):
    cfg = mission / "configuration" / "configuration.json"
    data = json.loads(cfg.read_text())
    relative = data["world_db"]["path"]
    elsewhere = tmp_path / "cwd"
    (elsewhere / relative).parent.mkdir(parents=True)
    shutil.copy(mission / relative, elsewhere / relative)
    monkeypatch.chdir(elsewhere)
    assert main(["check", str(mission)]) == 0
    err = capsys.readouterr().err
    assert f"world_db.path {relative} names two files" in err
    assert f"read {elsewhere / relative}" in err
