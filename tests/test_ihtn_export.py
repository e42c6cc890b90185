"""iHTN export: counted before anything is written, limited, all or nothing, and it touches no
file of the folder but its own ``ihtn_<n>.json``."""
from __future__ import annotations

import os
import resource
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.output.ihtn import write_ihtns
from mutrose_cp.interrupt import FAULT_ENV, Interrupted
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.output.builder import OutputModel

EXAMPLES = Path(__file__).resolve().parent.parent / "examples"
HOSPITAL = EXAMPLES / "hospital-disinfection"
DELIVERY = EXAMPLES / "item-delivery"


def _files(folder: Path) -> list[str]:
    return sorted(p.name for p in folder.iterdir())


def _staging_left(parent: Path) -> list[str]:
    return sorted(p.name for p in parent.iterdir() if p.name.endswith(".tmp"))


def test_too_many_files_are_refused_before_writing(tmp_path, capsys):
    target = tmp_path / "ihtn"
    assert main(["decompose", str(HOSPITAL), "-q", "--ihtn", str(target)]) == 2
    err = capsys.readouterr().err
    assert "would write at least 17,153,136 files" in err and "--ihtn-max 10000" in err
    assert not target.exists() or _files(target) == []
    assert main(["decompose", str(DELIVERY), "-q", "--ihtn", str(target), "--ihtn-max", "719"]) == 2
    assert "would write 720 files, over --ihtn-max 719" in capsys.readouterr().err
    assert main(["decompose", str(DELIVERY), "-q", "--ihtn", str(target), "--ihtn-max", "720"]) == 0
    assert len(_files(target)) == 720


def test_one_ordering_per_decomposition(tmp_path):
    target = tmp_path / "ihtn"
    assert main(["decompose", str(HOSPITAL), "-q", "--ihtn", str(target), "--ihtn-orderings", "one"]) == 0
    assert _files(target) == sorted(f"ihtn_{n}.json" for n in range(1, 37))


def test_only_numbered_ihtn_files_are_replaced_or_removed(tmp_path):
    target = tmp_path / "ihtn"
    target.mkdir()
    (target / "ihtn_final_approved.json").write_text("keep me")
    (target / "notes.txt").write_text("keep me too")
    (target / "ihtn_999.json").write_text("stale")
    (target / "ihtn_1.json").write_text("old")
    assert main(["decompose", str(DELIVERY), "-q", "--ihtn", str(target), "--optimize"]) == 0
    names = _files(target)
    assert "ihtn_final_approved.json" in names and "notes.txt" in names and "ihtn_999.json" not in names
    assert (target / "ihtn_final_approved.json").read_text() == "keep me"
    assert (target / "ihtn_1.json").read_text() != "old"
    assert _staging_left(tmp_path) == []


def _export(target: Path, cwd: Path, *extra: str, preexec=None, env=None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mutrose_cp", "decompose", str(DELIVERY), "-q", "--ihtn", str(target),
                           *extra], cwd=cwd, capture_output=True, text=True, timeout=300, preexec_fn=preexec,
                          env=env)


def test_disk_full_leaves_the_folder_as_it_was(tmp_path):
    target = tmp_path / "ihtn"
    assert main(["decompose", str(DELIVERY), "-q", "--ihtn", str(target), "--optimize"]) == 0
    before = {p.name: p.read_bytes() for p in target.iterdir()}

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (2048, 2048))

    result = _export(target, tmp_path, "--limit", "2", preexec=small_files)
    assert result.returncode == 2, result.stderr
    assert "File too large" in result.stderr and "Traceback" not in result.stderr
    assert {p.name: p.read_bytes() for p in target.iterdir()} == before
    assert _staging_left(tmp_path) == []


def test_an_interrupted_export_leaves_the_folder_as_it_was(tmp_path):
    target = tmp_path / "ihtn"
    target.mkdir()
    (target / "ihtn_1.json").write_text("previous export")
    result = _export(target, tmp_path, env={**os.environ, FAULT_ENV: "exporting iHTNs:TERM"})
    assert result.returncode == 143, result.stderr
    assert _files(target) == ["ihtn_1.json"] and (target / "ihtn_1.json").read_text() == "previous export"
    assert _staging_left(tmp_path) == []


def test_an_export_interrupted_halfway_leaves_the_folder_as_it_was(tmp_path):
    """The signal arrives after ten files were staged (raised from the progress callback, which
    runs between two files)."""
    mission = Mission.load(*find_mission_files(DELIVERY))
    model = OutputModel(mission.task_graph, mission.constraints, list(mission.decomposition_space()),
                        mission.domain, mission.config, mission.initial_state)
    target = tmp_path / "ihtn"
    target.mkdir()
    (target / "ihtn_1.json").write_text("previous export")

    def progress(n: int) -> None:
        if n == 10:
            raise Interrupted(signal.SIGINT, "exporting iHTNs")

    with pytest.raises(Interrupted):
        write_ihtns(model, target, progress)
    assert _files(target) == ["ihtn_1.json"] and (target / "ihtn_1.json").read_text() == "previous export"
    assert _staging_left(tmp_path) == []


def test_concurrent_exports_leave_one_whole_result(tmp_path):
    target = tmp_path / "ihtn"
    runs = [subprocess.Popen([sys.executable, "-m", "mutrose_cp", "decompose", str(DELIVERY), "-q", "--ihtn",
                              str(target), *extra], cwd=tmp_path, stderr=subprocess.PIPE)
            for extra in (["--limit", "1"], ["--optimize", "--ihtn-orderings", "one"], ["--limit", "1"])]
    assert [r.wait(300) for r in runs] == [0, 0, 0]
    names = _files(target)
    assert names in (sorted(f"ihtn_{n}.json" for n in range(1, 91)), ["ihtn_1.json"])
    assert _staging_left(tmp_path) == []
