"""Malformed world XML from the command line: a repair that changes which records exist is an
error (exit 2, located) unless --lenient-xml, which reads it as the original does, with a
warning."""
from __future__ import annotations

import shutil

from mutrose_cp.cli.program import main

from conftest import require_reference


def _room_preparation(tmp_path):
    folder = tmp_path / "room-preparation"
    shutil.copytree(require_reference() / "missions" / "room-preparation", folder)
    return folder, folder / "knowledge" / "World_db.xml"


def test_a_deleted_end_tag_is_refused_then_read_leniently(tmp_path, capsys):
    folder, world = _room_preparation(tmp_path)
    text = world.read_text()
    world.write_text(text.replace("</Room>", "", 1))
    assert main(["count", str(folder)]) == 2
    err = capsys.readouterr().err
    assert f"error: {world}:" in err and "<Room> (line" in err and "is never closed" in err
    assert "--lenient-xml" in err
    assert main(["count", str(folder), "--lenient-xml"]) == 0
    captured = capsys.readouterr()
    assert "warning: " in captured.err and "is never closed" in captured.err


def test_a_stray_end_tag_is_refused(tmp_path, capsys):
    folder, world = _room_preparation(tmp_path)
    text = world.read_text()
    world.write_text(text.replace("</Room>", "</Room></Room>", 1))
    assert main(["check", str(folder)]) == 2
    assert "closes the root element <world_db> early" in capsys.readouterr().err


def test_the_shipped_tag_typo_is_a_warning(tmp_path, capsys):
    folder, _world = _room_preparation(tmp_path)
    assert main(["check", str(folder), "--config", "configuration.xml"]) == 0
    assert "</location_type> closes <location_types> (line 15); read as </location_types>" in capsys.readouterr().err
