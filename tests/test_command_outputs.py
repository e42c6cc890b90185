"""The outputs of ``decompose``, ``allocate``, ``export-hddl``, ``compare --plot`` and the ``mutrose`` drop-in
are checked before any work: an output that is an input, two outputs that are one file, an
output that is a folder are refused (exit 2, located at the output), and nothing is written.
A command that writes several files makes them all before writing the first, so a refusal
found late leaves none of them behind."""
from __future__ import annotations

import errno
import fcntl
import json
import os
import resource
import shutil
import subprocess
import sys
import time
from pathlib import Path

import pytest

from conftest import require_reference
from mutrose_cp.cli.program import main
from mutrose_cp.errors import MissionError
from mutrose_cp.output.files import refuse_unsafe_outputs, written_together

ROOT = Path(__file__).resolve().parent.parent
DELIVERY = ROOT / "examples" / "item-delivery"
HOSPITAL = ROOT / "examples" / "hospital-disinfection"


# ----------------------------------------------------------------------------------------------
# the rule


def test_an_input_a_repeated_output_and_a_folder_are_refused(tmp_path: Path):
    source, out = tmp_path / "in.json", tmp_path / "out.json"
    source.write_text("{}")
    link = tmp_path / "link.json"
    link.symlink_to(source)
    with pytest.raises(MissionError, match="would overwrite the input"):
        refuse_unsafe_outputs([out, link], [source])
    with pytest.raises(MissionError, match="are one file") as refused:
        refuse_unsafe_outputs([out, tmp_path / "sub" / ".." / "out.json"], [source])
    assert refused.value.problems[0].where == str(tmp_path / "sub" / ".." / "out.json")
    with pytest.raises(MissionError, match="it is a folder"):
        refuse_unsafe_outputs([tmp_path], [])
    refuse_unsafe_outputs([out, tmp_path / "other.json", None, "-", "-"], [source, None])  # all distinct
    assert sorted(p.name for p in tmp_path.iterdir()) == ["in.json", "link.json"]


# ----------------------------------------------------------------------------------------------
# allocate: output, schedule and chart


@pytest.mark.parametrize("clash", ["schedule", "gantt"])
def test_allocate_refuses_two_outputs_in_one_file(tmp_path: Path, capsys, clash: str):
    out = tmp_path / "out.png"
    extra = ["--schedule", str(out)] if clash == "schedule" else ["--schedule", str(tmp_path / "s.json"),
                                                                   "--gantt", str(out)]
    assert main(["allocate", str(DELIVERY), "--fleet", str(DELIVERY / "fleet.json"), "-o", str(out), "-q",
                 *extra]) == 2
    assert f"error: {out}: the outputs {out} and {out} are one file" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


def test_allocate_refuses_a_folder_before_the_search(tmp_path: Path, capsys):
    (tmp_path / "out.json").mkdir()
    schedule = tmp_path / "schedule.json"
    assert main(["allocate", str(DELIVERY), "--fleet", str(DELIVERY / "fleet.json"), "-o", str(tmp_path / "out.json"),
                 "--schedule", str(schedule), "-q"]) == 2
    assert "out.json: cannot write the output: it is a folder" in capsys.readouterr().err
    assert not schedule.exists()


@pytest.mark.parametrize("clash", ["folder", "input"])
def test_decompose_refuses_an_unsafe_output_before_solving(tmp_path: Path, capsys, monkeypatch, clash: str):
    """A long solve must not end in "cannot write the output": the output is checked first."""
    from mutrose_cp.mission import Mission

    def solve(*_args: object, **_kwargs: object) -> None:
        raise AssertionError("the mission was solved before its output was checked")

    monkeypatch.setattr(Mission, "decompose", solve)
    out = tmp_path / "out.json"
    if clash == "folder":
        out.mkdir()
    else:
        out = HOSPITAL / "configuration" / "configuration.json"
    assert main(["decompose", str(HOSPITAL), "-o", str(out), "-q"]) == 2
    err = capsys.readouterr().err
    assert ("it is a folder" if clash == "folder" else "would overwrite the input") in err


# ----------------------------------------------------------------------------------------------
# export-hddl: domain and problem


def test_export_refuses_the_problem_over_the_domain(tmp_path: Path, capsys):
    folder = require_reference() / "missions" / "lab-samples-logistics"
    out = tmp_path / "d.hddl"
    assert main(["export-hddl", str(folder), "-o", str(out), "--problem-out", str(out), "-q"]) == 2
    assert "are one file" in capsys.readouterr().err
    assert not out.exists()


def test_a_refused_problem_writes_no_domain(tmp_path: Path, capsys):
    out = tmp_path / "d.hddl"
    assert main(["export-hddl", str(HOSPITAL), "-o", str(out), "--problem-out", str(tmp_path / "p.hddl")]) == 2
    assert "error: the mission's tasks are not one total order" in capsys.readouterr().err
    assert list(tmp_path.iterdir()) == []


# ----------------------------------------------------------------------------------------------
# compare --plot


def test_compare_refuses_a_plot_over_an_input_before_running(tmp_path: Path, capsys):
    mission = tmp_path / "mission"
    shutil.copytree(HOSPITAL, mission)
    chart = mission / "knowledge" / "chart.png"
    chart.symlink_to(mission / "gm" / "hospital-disinfection-gm.json")
    before = (mission / "gm" / "hospital-disinfection-gm.json").read_bytes()
    hddl, gm, cfg = (next((mission / d).iterdir()) for d in ("hddl", "gm", "configuration"))
    assert main(["compare", str(hddl), str(gm), str(cfg), "--plot", str(chart), "-q"]) == 2
    err = capsys.readouterr().err
    assert "would overwrite the input" in err and "running" not in err
    assert gm.read_bytes() == before


# ----------------------------------------------------------------------------------------------
# the mutrose drop-in: the configuration's output path


def test_dropin_never_writes_its_output_over_an_input(tmp_path: Path):
    mission = tmp_path / "mission"
    shutil.copytree(HOSPITAL, mission)
    config = json.loads((mission / "configuration" / "configuration.json").read_text())
    config["output"]["file_path"] = "knowledge/world_db.xml"
    (mission / "configuration" / "configuration.json").write_text(json.dumps(config))
    world = (mission / "knowledge" / "world_db.xml").read_bytes()
    run = subprocess.run([sys.executable, "-m", "mutrose_cp.cli.dropin", "hddl/hospital-disinfection.hddl",
                          "gm/hospital-disinfection-gm.json", "configuration/configuration.json"],
                         cwd=mission, capture_output=True, text=True, timeout=120, env=dict(os.environ))
    assert run.returncode == 2
    assert "knowledge/world_db.xml: the output would overwrite the input" in run.stderr
    assert (mission / "knowledge" / "world_db.xml").read_bytes() == world


# ----------------------------------------------------------------------------------------------
# iHTN files (decompose --ihtn, mutrose -h): a full disk, a file where the folder goes


def _small_files() -> None:
    resource.setrlimit(resource.RLIMIT_FSIZE, (200, 200))


def test_a_full_disk_leaves_no_ihtn_folder_and_names_it(tmp_path: Path):
    run = subprocess.run([sys.executable, "-m", "mutrose_cp", "decompose", str(DELIVERY), "--ihtn", "ihtn",
                          "--ihtn-orderings", "one", "-q"], cwd=tmp_path, capture_output=True, text=True,
                         timeout=120, preexec_fn=_small_files)
    assert run.returncode == 2
    assert "error: ihtn: cannot write the output: File too large" in run.stderr
    assert list(tmp_path.iterdir()) == []


def test_a_file_where_the_ihtn_folder_goes_is_refused(tmp_path: Path, capsys):
    (tmp_path / "ihtn").write_text("notes\n")
    assert main(["decompose", str(DELIVERY), "--ihtn", str(tmp_path / "ihtn"), "-q"]) == 2
    assert f"error: {tmp_path / 'ihtn'}: cannot write the output files: it is a file; give a folder" in \
        capsys.readouterr().err
    assert (tmp_path / "ihtn").read_text() == "notes\n"


# ----------------------------------------------------------------------------------------------
# how both front ends tell a failure


@pytest.mark.parametrize("front_end", ["mutrose-cp", "mutrose"])
def test_both_front_ends_tell_a_failure_alike(capsys, front_end: str):
    from mutrose_cp.cli import program as cli, dropin

    report = cli._report if front_end == "mutrose-cp" else dropin._report
    assert report(OSError(errno.EFBIG, "File too large")) == 2  # a write error without a file name
    assert report(OSError(errno.ENOENT, "No such file or directory", "gm.json")) == 2
    assert report(MissionError("unknown goal", "gm.json: goal G3")) == 2
    printed = capsys.readouterr().err.splitlines()  # both on stderr
    assert printed == ["error: File too large", "error: gm.json: No such file or directory",
                       "error: gm.json: goal G3: unknown goal"]


# ----------------------------------------------------------------------------------------------
# concurrent runs: a set of files written in turn


def test_the_folders_of_a_set_of_outputs_are_locked_while_it_is_written(tmp_path: Path):
    outputs = [tmp_path / "a" / "x.json", tmp_path / "b" / "y.json", None, "-"]
    with written_together(outputs):
        for folder in ("a", "b"):
            fd = os.open(tmp_path / folder, os.O_RDONLY)
            try:
                with pytest.raises(BlockingIOError):
                    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)
            finally:
                os.close(fd)
    fd = os.open(tmp_path / "a", os.O_RDONLY)
    fcntl.flock(fd, fcntl.LOCK_EX | fcntl.LOCK_NB)  # released
    os.close(fd)
    assert sorted(p.name for p in tmp_path.rglob("*")) == ["a", "b"]  # nothing left behind


def _blocked_on_a_lock(pid: int) -> bool:
    """Whether process ``pid`` waits for a lock (``/proc/locks`` marks waiters with ``->``)."""
    return any(line.split()[1] == "->" and line.split()[5] == str(pid)
               for line in Path("/proc/locks").read_text().splitlines() if len(line.split()) > 5)


@pytest.mark.skipif(not Path("/proc/locks").exists(), reason="needs Linux's /proc/locks")
def test_export_waits_for_a_run_writing_the_same_files(tmp_path: Path):
    """Another run holds the folder (as export-hddl and allocate do while writing their set):
    this run writes its files only once that one is done, so the two never mix."""
    folder = tmp_path / "out"
    folder.mkdir()
    other = os.open(folder, os.O_RDONLY)
    fcntl.flock(other, fcntl.LOCK_EX)
    run = subprocess.Popen([sys.executable, "-m", "mutrose_cp", "export-hddl", str(HOSPITAL), "-o",
                            str(folder / "d.hddl"), "-q"], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        while run.poll() is None and not _blocked_on_a_lock(run.pid):
            time.sleep(0.02)
        waited = run.poll() is None and not (folder / "d.hddl").exists()
    finally:
        os.close(other)
    _, err = run.communicate(timeout=120)
    assert waited, "the run wrote while another held the folder"
    assert run.returncode == 0, err
    assert (folder / "d.hddl").is_file()


@pytest.mark.parametrize("command", [["mutrose_cp", "decompose", str(HOSPITAL), "-o", "-"],
                                     ["mutrose_cp.cli.dropin", "hddl/hospital-disinfection.hddl",
                                      "gm/hospital-disinfection-gm.json", "configuration/configuration.json", "-p"]])
def test_stdout_and_stderr_on_one_closed_pipe(tmp_path: Path, command: list[str]):
    """``… 2>&1 | head``: the message about the closed pipe cannot be told either; the command
    still ends with status 2, not with a traceback (status 1)."""
    mission = tmp_path / "mission"
    shutil.copytree(HOSPITAL, mission)
    read_end, write_end = os.pipe()
    os.close(read_end)
    try:
        run = subprocess.run([sys.executable, "-m", *command], cwd=mission, stdin=subprocess.DEVNULL,
                             stdout=write_end, stderr=write_end, timeout=120)
    finally:
        os.close(write_end)
    assert run.returncode == 2
