"""Output paths as a careless or hostile user gives them: inputs, links, FIFOs, devices, folders,
standard output, umask and modes, a full disk, a closed pipe or stderr, concurrent writers.
Everything happens in a temporary folder; nothing already there is lost, messages name the
user's path."""
from __future__ import annotations

import json
import os
import resource
import stat
import subprocess
import sys
import threading
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.errors import MissionError
from mutrose_cp.output.files import atomic_writer

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"



def _only(folder: Path) -> Path:
    return next(p for p in folder.iterdir() if p.is_file())


def _cli(args: list[str], cwd: Path, preexec=None, stderr=subprocess.PIPE) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mutrose_cp", *args], cwd=cwd, capture_output=False,
                          stdout=subprocess.PIPE, stderr=stderr, text=True, timeout=120, preexec_fn=preexec)


def _no_temporaries(folder: Path) -> None:
    assert sorted(p.name for p in folder.rglob(".*.tmp")) == []


@pytest.mark.parametrize("which", ["gm", "hddl", "configuration", "knowledge"])
def test_an_input_is_never_the_output(mission, capsys, which):
    victim = _only(mission / which)
    before = victim.read_bytes()
    assert main(["decompose", str(mission), "-q", "-o", str(victim)]) == 2
    assert "the output would overwrite the input" in capsys.readouterr().err
    assert victim.read_bytes() == before


def test_a_link_to_an_input_is_refused(mission, tmp_path, capsys):
    link = tmp_path / "out.json"
    link.symlink_to(_only(mission / "gm"))
    assert main(["decompose", str(mission), "-q", "-o", str(link)]) == 2
    assert f"{link}: the output would overwrite the input" in capsys.readouterr().err


def test_the_configurations_output_path_cannot_name_an_input(mission, capsys):
    cfg = _only(mission / "configuration")
    data = json.loads(cfg.read_text())
    data["output"]["file_path"] = f"gm/{_only(mission / 'gm').name}"
    cfg.write_text(json.dumps(data))
    before = _only(mission / "gm").read_bytes()
    assert main(["decompose", str(mission), "-q"]) == 2
    assert "the output would overwrite the input" in capsys.readouterr().err
    assert _only(mission / "gm").read_bytes() == before


def test_check_warns_when_the_output_leaves_the_mission_folder(mission, capsys):
    cfg = _only(mission / "configuration")
    data = json.loads(cfg.read_text())
    data["output"]["file_path"] = "../victim.txt"
    cfg.write_text(json.dumps(data))
    assert main(["check", str(mission)]) == 0
    assert "output.file_path ../victim.txt leaves the mission folder" in capsys.readouterr().err


def test_a_symbolic_link_stays_a_link(mission, tmp_path):
    real = tmp_path / "real.json"
    real.write_text("old")
    link = tmp_path / "link.json"
    link.symlink_to(real)
    assert main(["decompose", str(mission), "-q", "-o", str(link)]) == 0
    assert link.is_symlink() and json.loads(real.read_text())["tasks"]


def test_a_fifo_is_written_through(mission, tmp_path):
    fifo = tmp_path / "pipe"
    os.mkfifo(fifo)
    received: list[bytes] = []
    reader = threading.Thread(target=lambda: received.append(fifo.read_bytes()))
    reader.start()
    assert main(["decompose", str(mission), "-q", "-o", str(fifo)]) == 0
    reader.join(30)
    assert stat.S_ISFIFO(os.stat(fifo).st_mode)
    assert json.loads(received[0])["tasks"]
    _no_temporaries(tmp_path)


@pytest.mark.skipif(os.geteuid() != 0, reason="creating a character device needs root")
def test_a_character_device_is_written_through(mission, tmp_path):
    null = tmp_path / "null"
    os.mknod(null, stat.S_IFCHR | 0o666, os.makedev(1, 3))  # a /dev/null of our own
    assert main(["decompose", str(mission), "-q", "-o", str(null)]) == 0
    assert stat.S_ISCHR(os.stat(null).st_mode)
    _no_temporaries(tmp_path)


def test_a_folder_is_not_an_output(mission, tmp_path, capsys):
    folder = tmp_path / "existing"
    folder.mkdir()
    assert main(["decompose", str(mission), "-q", "-o", str(folder)]) == 2
    err = capsys.readouterr().err
    assert f"error: {folder}: cannot write the output: it is a folder" in err and ".tmp" not in err


def test_a_parent_that_is_a_file(mission, tmp_path, capsys):
    (tmp_path / "afile").write_text("")
    target = tmp_path / "afile" / "out.json"
    assert main(["decompose", str(mission), "-q", "-o", str(target)]) == 2
    err = capsys.readouterr().err
    assert f"error: {target}: cannot write the output: " in err and ".tmp" not in err


def test_dash_is_standard_output(mission, tmp_path):
    result = _cli(["decompose", str(mission), "-q", "-o", "-"], tmp_path)
    assert result.returncode == 0, result.stderr
    assert json.loads(result.stdout)["mission_decompositions"]
    assert sorted(tmp_path.iterdir()) == [mission]


def test_new_files_follow_the_umask_and_replaced_files_keep_their_mode(mission, tmp_path):
    new = tmp_path / "new.json"
    result = _cli(["decompose", str(mission), "-q", "-o", str(new)], tmp_path, preexec=lambda: os.umask(0o027))
    assert result.returncode == 0, result.stderr
    assert stat.S_IMODE(os.stat(new).st_mode) == 0o640
    new.chmod(0o600)
    assert main(["decompose", str(mission), "-q", "-o", str(new)]) == 0
    assert stat.S_IMODE(os.stat(new).st_mode) == 0o600


def test_disk_full_keeps_the_old_output(mission, tmp_path):
    out = tmp_path / "out.json"
    out.write_text("previous")

    def small_files() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (4096, 4096))

    result = _cli(["decompose", str(mission), "-q", "-o", str(out)], tmp_path, preexec=small_files)
    assert result.returncode == 2
    assert f"error: {out}: cannot write the output: File too large" in result.stderr
    assert out.read_text() == "previous"
    _no_temporaries(tmp_path)


def test_closed_stderr(mission, tmp_path):
    out = tmp_path / "out.json"
    result = subprocess.run([sys.executable, "-m", "mutrose_cp", "decompose", str(mission), "-o", str(out)],
                            cwd=tmp_path, stdout=subprocess.PIPE, stderr=subprocess.DEVNULL, text=True, timeout=120,
                            preexec_fn=lambda: os.close(2))
    assert result.returncode == 0
    assert json.loads(out.read_text())["tasks"]


def test_a_closed_pipe_on_standard_output(monkeypatch):
    read_end, write_end = os.pipe()
    os.close(read_end)
    stream = os.fdopen(write_end, "w")
    monkeypatch.setattr(sys, "stdout", stream)
    with pytest.raises(MissionError) as info:
        with atomic_writer("-") as fh:
            fh.write("x" * 1_000_000)
    assert str(info.value) == "standard output: cannot write the output: the reader closed the pipe"


def test_concurrent_writers_leave_one_whole_output(mission, tmp_path):
    out = tmp_path / "out.json"
    procs = [subprocess.Popen([sys.executable, "-m", "mutrose_cp", "decompose", str(mission), "-q", "-o", str(out),
                               *extra], cwd=tmp_path, stderr=subprocess.PIPE)
             for extra in ([], ["--format", "xml"], [], ["--format", "xml"])]
    assert [p.wait(120) for p in procs] == [0, 0, 0, 0]
    text = out.read_text()
    assert text.startswith("<?xml") or json.loads(text)["tasks"]  # one writer's whole file
    _no_temporaries(tmp_path)


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_folder(mission, tmp_path, capsys):
    folder = tmp_path / "locked"
    folder.mkdir()
    folder.chmod(0o555)
    try:
        target = folder / "out.json"
        assert main(["decompose", str(mission), "-q", "-o", str(target)]) == 2
        err = capsys.readouterr().err
        assert f"error: {target}: cannot write the output: Permission denied" in err
        assert list(folder.iterdir()) == []
    finally:
        folder.chmod(0o755)


def test_binary_mode_replaces_the_file_with_the_bytes_written(tmp_path):
    out = tmp_path / "picture.bin"
    out.write_bytes(b"old")
    with atomic_writer(out, "wb") as fh:
        fh.write(b"\x00\r\n")
    assert out.read_bytes() == b"\x00\r\n"
    _no_temporaries(tmp_path)
