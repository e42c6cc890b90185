"""Input encodings: a UTF-8 byte-order mark is accepted in every input format, and bytes that
are not UTF-8 are reported at ``file:line:col``."""
from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"


def _copy(tmp_path: Path) -> Path:
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    return folder


def _file(folder: Path, sub: str) -> Path:
    return next(p for p in (folder / sub).iterdir() if p.is_file())


@pytest.mark.parametrize("sub", ["hddl", "gm", "configuration", "knowledge"])
def test_byte_order_mark_is_accepted(tmp_path, sub, capsys):
    folder = _copy(tmp_path)
    path = _file(folder, sub)
    path.write_bytes(b"\xef\xbb\xbf" + path.read_bytes())
    assert main(["check", str(folder)]) == 0, capsys.readouterr().err


@pytest.mark.parametrize("sub,what", [("hddl", "HDDL domain"), ("gm", "goal model"), ("configuration", "configuration")])
def test_non_utf8_byte_is_located(tmp_path, sub, what, capsys):
    folder = _copy(tmp_path)
    path = _file(folder, sub)
    lines = path.read_bytes().split(b"\n")
    lines[2] = lines[2] + b" \xe9"  # after the third line's text
    path.write_bytes(b"\n".join(lines))
    assert main(["check", str(folder)]) == 2
    err = capsys.readouterr().err
    column = len(lines[2].decode("utf-8", errors="replace"))
    assert f"{path}:3:{column}: the {what} is not UTF-8 text: byte 0xe9" in err
    assert "Traceback" not in err
