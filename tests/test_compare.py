"""``mutrose-cp compare``: both decomposers (and a stand-in for the original tool) run as child
processes on real missions, with a time limit, and what they found is compared.

The ``--original`` tests run the real binary of the original tool where it is installed
(``tests/original.py``: skipped when absent), on every reference mission and example and on a
mission it aborts on.  The behaviours a real binary cannot be made to show on demand (a hang, an
edited output, no output) come from a stand-in written into a temporary folder: an executable
script that is called as the original is (``PATH HDDL GM CONFIG`` in a copy of the mission),
refuses files it cannot open as the original does, and writes the corpus's golden output (the
original's own output for that mission) where the configuration says, or an edited copy, or
fails, or hangs.
"""
from __future__ import annotations

import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

import original
from conftest import REFERENCE, require_reference
from mutrose_cp.cli.program import main
from mutrose_cp.interrupt import FAULT_ENV
from mutrose_cp.io.config import load_configuration
from mutrose_cp.io.decomposition_output import load_decomposition_output

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = sorted(p for p in (ROOT / "examples").iterdir() if (p / "configuration").is_dir())
HOSPITAL = ROOT / "examples" / "hospital-disinfection"
SRC = ROOT / "src"


def _compare(capsys, *args: str) -> tuple[int, str, str]:
    code = main(["compare", *args])
    out, err = capsys.readouterr()
    return code, out, err


def _report(capsys, *args: str) -> tuple[int, dict]:
    code, out, _ = _compare(capsys, *args, "--json", "-q")
    return code, json.loads(out)


def _runs(report: dict) -> dict[str, dict]:
    return {r["decomposer"]: r for r in report["runs"]}


def _corpus_runs() -> list[tuple[Path, str]]:
    """Every reference mission with each of its configurations (JSON and XML)."""
    if not REFERENCE.is_dir():
        return []
    return [(m, c.name) for m in sorted((REFERENCE / "missions").iterdir())
            for c in sorted((m / "configuration").glob("*"))]


def _golden_count(mission: Path, config: str) -> int:
    golden = mission / load_configuration(mission / "configuration" / config).output.file_path
    return len(load_decomposition_output(str(golden)).mission_decompositions)


def test_compare_agrees_on_every_example_and_every_reference_mission(capsys):
    require_reference()
    missions = [(e, None) for e in EXAMPLES] + _corpus_runs()
    assert len(missions) >= 13
    for folder, config in missions:
        code, report = _report(capsys, str(folder), *(["--config", config] if config else []))
        runs = _runs(report)
        assert code == 0 and report["agree"], (folder, config, report)
        assert [r["status"] for r in report["runs"]] == ["finished", "finished"]
        assert report["comparisons"][0]["aspects"] == dict.fromkeys(
            ("task ids", "task fields", "constraints", "mission decompositions"), True)
        assert runs["cpsat"]["mission_decompositions"] == runs["exploratory"]["mission_decompositions"]
        if config:  # the original found as many on the corpus
            assert int(runs["cpsat"]["mission_decompositions"]) == _golden_count(folder, config), (folder, config)


def test_the_table_shows_time_memory_count_and_agreement(capsys):
    code, out, err = _compare(capsys, str(HOSPITAL))
    assert code == 0
    header, cpsat, exploratory = out.splitlines()[2:5]
    assert header.split() == ["decomposer", "status", "wall", "time", "peak", "memory", "decompositions", "agrees"]
    for row, name in ((cpsat, "cpsat"), (exploratory, "exploratory")):
        cells = row.split()
        assert cells[0] == name and cells[1] == "finished" and cells[3] == "s" and cells[5] == "MB"
        assert float(cells[2]) >= 0 and float(cells[4]) > 0 and cells[6] == "36"  # 36: see test_examples
    assert cpsat.split()[-1] == "reference" and exploratory.split()[-1] == "yes"
    assert out.splitlines()[-1] == "agree: cpsat, exploratory (36 valid mission decompositions)"
    assert "cpsat: running (time limit 60 s)" in err  # progress, unless -q


def test_an_xml_configuration_in_the_three_file_form(capsys, reference):
    mission = reference / "missions" / "room-preparation"
    hddl, = (mission / "hddl").glob("*.hddl")
    gm, = (mission / "gm").glob("*")
    code, report = _report(capsys, str(hddl), str(gm), str(mission / "configuration" / "configuration.xml"))
    assert code == 0 and report["agree"] and report["inputs"]["configuration"].endswith("configuration.xml")


def test_the_table_shows_counts_beyond_15_digits_by_their_magnitude():
    from mutrose_cp.compare.run import FAILED, FINISHED, CompareRequest, CompareReport, Comparison, Run
    from mutrose_cp.compare.report import render_table

    request = CompareRequest(Path("d.hddl"), Path("gm.txt"), Path("c.json"))
    runs = [Run("cpsat", FINISHED, 1.0, 30.0, 0, count=3**50), Run("exploratory", FINISHED, 2.0, 40.0, 0, count=3**50),
            Run("original", FAILED, 0.5, 10.0, 1, error="crashed")]
    agreeing = Comparison("exploratory", "cpsat", {"count": True})
    rows = render_table(CompareReport(request, runs, [agreeing])).splitlines()
    assert [row.split()[-2] for row in rows[2:5]] == ["decompositions", "7.178e23", "7.178e23"]
    assert rows[5].split()[-2:] == ["-", "-"]  # no count, not compared
    assert rows[-1] == "agree: cpsat, exploratory (7.178e23 valid mission decompositions)"
    for count, shown in ((10**15 - 1, "999999999999999"), (10**15, "1.000e15")):  # 15 digits exactly, 16 not
        both = [Run(name, FINISHED, 1.0, 30.0, 0, count=count) for name in ("cpsat", "exploratory")]
        assert render_table(CompareReport(request, both, [agreeing])).splitlines()[-1] == \
            f"agree: cpsat, exploratory ({shown} valid mission decompositions)"


def test_above_the_limit_only_the_counts_are_compared(capsys):
    code, report = _report(capsys, str(HOSPITAL), "--limit", "10")
    comparison, = report["comparisons"]
    assert code == 0 and comparison["agree"]
    assert comparison["aspects"] == {"task ids": None, "task fields": None, "constraints": None,
                                     "mission decompositions": True}
    assert "the sets were not compared (more than --limit 10 mission decompositions" in comparison["note"]
    code, out, _ = _compare(capsys, str(HOSPITAL), "--limit", "10", "-q")
    assert "the sets were not compared" in out


# ---------------------------------------------------------------------------------------------
# the exploratory algorithm timing out on a benchmark world


def test_a_run_over_the_time_limit_is_killed_and_reported_as_timed_out(tmp_path, capsys):
    require_reference()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    try:
        from generate import generate
    finally:
        sys.path.remove(str(ROOT / "benchmarks"))
    # 3^14 = 4,782,969 valid decompositions: the exploratory algorithm combines them one by one
    hddl, gm, cfg = generate("delivery", 14, tmp_path)
    code, out, _ = _compare(capsys, str(hddl), str(gm), str(cfg), "--time-limit", "3", "--limit", "1000", "-q")
    rows = {line.split()[0]: line for line in out.splitlines()[3:5]}
    assert rows["cpsat"].split()[1] == "finished" and rows["cpsat"].split()[6] == "4782969"
    assert rows["exploratory"].split()[1:3] == ["timed", "out"] and rows["exploratory"].split()[7] == "-"
    assert "exploratory: timed out after 3 s (killed; no result)" in out
    assert out.splitlines()[-1] == "nothing to compare: only cpsat finished"
    assert code == 0  # all that finished (one) agree


# ---------------------------------------------------------------------------------------------
# --original, with the real binary

@pytest.mark.parametrize("folder, config", [(e, None) for e in EXAMPLES] + _corpus_runs(),
                         ids=lambda v: v.name if isinstance(v, Path) else (v or ""))
def test_the_real_original_agrees_on_every_example_and_reference_mission(capsys, folder, config):
    binary = original.require()
    code, report = _report(capsys, str(folder), *(["--config", config] if config else []), "--original", str(binary))
    runs = _runs(report)
    assert code == 0 and report["agree"], report
    assert runs["original"]["status"] == "finished" and runs["original"]["exit_status"] == 0
    assert runs["original"]["mission_decompositions"] == runs["cpsat"]["mission_decompositions"]


def test_the_real_original_aborting_is_reported_with_its_message(tmp_path, capsys, reference):
    """A forAll whose achieve condition the original checks for the last room only
    (docs/deviations.md, 1): it aborts where both decomposers find the valid decomposition."""
    binary = original.require()
    sys.path.insert(0, str(ROOT / "benchmarks"))
    from generate import generate

    hddl, gm, cfg = generate("vital-signs", 2, tmp_path / "vital-signs")
    code, out, _ = _compare(capsys, str(hddl), str(gm), str(cfg), "--original", str(binary), "-q")
    assert "original: failed: " in out and "No decomposition satisfied achieve condition of goal G7" in out
    assert code == 0  # cpsat and exploratory, the runs that finished, agree


# ---------------------------------------------------------------------------------------------
# --original, with a stand-in for the original tool

STAND_IN = '''#!{python}
"""A stand-in for the original MutRoSe decomposer, behaviour {behaviour!r}."""
import json, os, sys, time
hddl, gm, config = sys.argv[1:4]
for path in (hddl, gm, config, {world!r}):
    if not os.path.exists(path):
        print(f"I can't open {{path}}!")
        sys.exit(2)
golden = open({golden!r}, encoding="utf-8").read()
behaviour = {behaviour!r}
if behaviour == "hang":
    import subprocess
    helper = subprocess.Popen(["sleep", "60"])
    open({pids!r}, "w").write(f"{{os.getpid()}} {{helper.pid}}")
    time.sleep(60)
if behaviour == "abort":
    print("NO VALID DECOMPOSITIONS FOR TASK AT1_1: PrepareRoom")
    sys.stdout.flush()
    os.abort()
if behaviour == "differ":  # one task of the first decomposition decomposed another way
    doc = json.loads(golden)
    ids = {{key: task["id"] for key, task in doc["tasks"].items()}}
    first = doc["mission_decompositions"][0]
    for i, key in enumerate(first):
        others = [k for k in ids if k not in first and ids[k].split("|")[0] == ids[key].split("|")[0]]
        if others:
            first[i] = others[0]
            break
    golden = json.dumps(doc)
if behaviour != "no output":
    open({output!r}, "w", encoding="utf-8").write(golden)
'''


def _stand_in(tmp_path: Path, mission: Path, behaviour: str, config: str = "configuration.json") -> Path:
    cfg = load_configuration(mission / "configuration" / config)
    script = tmp_path / "bin" / "MutroseMissionDecomposer"
    script.parent.mkdir(exist_ok=True)
    script.write_text(STAND_IN.format(python=sys.executable, behaviour=behaviour, world=cfg.world_db.path,
                                      golden=str(mission / cfg.output.file_path), output=cfg.output.file_path,
                                      pids=str(tmp_path / "pids")), encoding="utf-8")
    script.chmod(0o755)
    return script


def test_the_original_agreeing(tmp_path, capsys, reference):
    mission = reference / "missions" / "vital-signs-monitoring"
    code, report = _report(capsys, str(mission), "--original", str(_stand_in(tmp_path, mission, "golden")))
    runs = _runs(report)
    assert code == 0 and report["agree"]
    assert runs["original"]["status"] == "finished" and runs["original"]["exit_status"] == 0
    assert runs["original"]["mission_decompositions"] == runs["cpsat"]["mission_decompositions"]
    assert [c["decomposer"] for c in report["comparisons"]] == ["exploratory", "original"]


def test_the_original_with_an_xml_output(tmp_path, capsys, reference):
    mission = reference / "missions" / "room-preparation"
    script = _stand_in(tmp_path, mission, "golden", "configuration.xml")
    code, report = _report(capsys, str(mission), "--config", "configuration.xml", "--original", str(script))
    assert code == 0 and report["agree"] and _runs(report)["original"]["status"] == "finished"


def test_the_original_disagreeing_is_detected_and_shown_by_task_id(tmp_path, capsys, reference):
    mission = reference / "missions" / "vital-signs-monitoring"
    script = _stand_in(tmp_path, mission, "differ")
    code, report = _report(capsys, str(mission), "--original", str(script))
    assert code == 1 and not report["agree"]
    exploratory, original = report["comparisons"]
    assert exploratory["agree"] and not original["agree"]
    assert original["aspects"] == {"task ids": True, "task fields": True, "constraints": True,
                                   "mission decompositions": False}
    differences, = original["differences"]
    assert differences["only_in_reference_count"] == 1 and differences["only_in_run_count"] == 1
    assert all("|" in task for task in differences["only_in_run"][0])  # ids, never t-keys
    code, out, _ = _compare(capsys, str(mission), "--original", str(script), "-q")
    assert code == 1
    assert "original differs from cpsat:" in out and "    1 only in cpsat:" in out and "    1 only in original:" in out
    assert "(nearest in original: -AT2_1_1|1 +AT2_1_1|2)" in out  # the task where they part, by id
    assert out.splitlines()[-1] == "DISAGREE: original differs from cpsat"


def test_a_failing_original_reports_its_error(tmp_path, capsys, reference):
    mission = reference / "missions" / "room-preparation"
    code, out, _ = _compare(capsys, str(mission), "--original", str(_stand_in(tmp_path, mission, "abort")), "-q")
    assert "original: failed: NO VALID DECOMPOSITIONS FOR TASK AT1_1: PrepareRoom" in out
    assert code == 0  # cpsat and exploratory, the runs that finished, agree
    code, report = _report(capsys, str(mission), "--original", str(_stand_in(tmp_path, mission, "no output")))
    original = _runs(report)["original"]
    assert original["status"] == "failed" and original["error"].startswith("it wrote no output file at ")


def test_a_hanging_original_is_killed_with_its_helpers(tmp_path, capsys, reference):
    mission = reference / "missions" / "room-preparation"
    script = _stand_in(tmp_path, mission, "hang")
    code, report = _report(capsys, str(mission), "--original", str(script), "--time-limit", "2")
    original = _runs(report)["original"]
    assert code == 0 and original["status"] == "timed out" and original["exit_status"] is None
    for pid in map(int, (tmp_path / "pids").read_text().split()):
        assert not _alive(pid)


def _alive(pid: int) -> bool:
    """Running, not a zombie waiting for a parent that does not reap it."""
    deadline = time.monotonic() + 5
    while time.monotonic() < deadline:
        try:
            state = Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
        except OSError:
            return False
        if state == "Z":
            return False
        time.sleep(0.05)
    return True


def test_an_interrupted_compare_leaves_no_run_behind(tmp_path, reference):
    mission = reference / "missions" / "room-preparation"
    script = _stand_in(tmp_path, mission, "hang")
    proc = subprocess.Popen([sys.executable, "-m", "mutrose_cp", "compare", str(mission), "--original", str(script),
                             "-q"], cwd=tmp_path, env={**os.environ, "PYTHONPATH": str(SRC)},
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    pids = tmp_path / "pids"
    deadline = time.monotonic() + 60
    while not pids.exists() and time.monotonic() < deadline:
        time.sleep(0.05)
    time.sleep(0.1)
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=30)
    assert proc.returncode == 130 and "interrupted" in err and "Traceback" not in err
    for pid in map(int, pids.read_text().split()):
        assert not _alive(pid)


@pytest.mark.parametrize("sig", ["INT", "TERM"])
def test_an_interrupt_names_the_run_and_leaves_no_temporary_folder(tmp_path, sig):
    env = {**os.environ, "PYTHONPATH": str(SRC), "TMPDIR": str(tmp_path), FAULT_ENV: f"running exploratory:{sig}"}
    proc = subprocess.run([sys.executable, "-m", "mutrose_cp", "compare", str(HOSPITAL), "-q"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 128 + signal.Signals["SIG" + sig]
    assert f"interrupted while running exploratory (SIG{sig})" in proc.stderr and proc.stdout == ""
    assert list(tmp_path.iterdir()) == []


# ---------------------------------------------------------------------------------------------
# plots and bad input


def test_plot_writes_a_bar_chart(tmp_path, capsys):
    pytest.importorskip("matplotlib")  # in the test extra
    chart = tmp_path / "compare.svg"
    code, _, _ = _compare(capsys, str(HOSPITAL), "--plot", str(chart), "-q")
    svg = chart.read_text(encoding="utf-8")
    assert code == 0 and "<svg" in svg and "wall time (s)" in svg and "peak memory (MB)" in svg


def test_the_same_report_gives_the_same_chart(tmp_path):
    pytest.importorskip("matplotlib")
    from mutrose_cp.compare.run import CompareRequest, compare
    from mutrose_cp.compare.report import write_plot

    report = compare(CompareRequest(*_files(HOSPITAL)))
    for name in ("a.svg", "b.svg", "c.png", "d.png"):
        write_plot(report, str(tmp_path / name))
    assert (tmp_path / "a.svg").read_bytes() == (tmp_path / "b.svg").read_bytes()
    assert (tmp_path / "c.png").read_bytes() == (tmp_path / "d.png").read_bytes()
    assert (tmp_path / "c.png").read_bytes().startswith(b"\x89PNG")


def _files(folder: Path) -> tuple[Path, Path, Path]:
    from mutrose_cp.io.mission_files import find_mission_files

    return find_mission_files(folder)


def test_plot_without_matplotlib_is_a_clear_error(monkeypatch, tmp_path, capsys):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed
    code, out, err = _compare(capsys, str(HOSPITAL), "--plot", str(tmp_path / "c.png"))
    assert code == 2 and out == ""
    assert "--plot needs matplotlib, which is not installed: pip install 'mutrose-cp[bench]'" in err
    assert "running" not in err  # refused before anything ran


@pytest.mark.parametrize("args,message", [
    (["--plot", "chart.txt"], "cannot tell the chart's format from 'chart.txt'"),
    (["--original", "/nonexistent/MutroseMissionDecomposer"], "--original: not an executable file"),
    (["--time-limit", "0"], "0 is not a positive number of seconds"),
    (["--time-limit", "1e8"], "1e8 is out of range: give at most 10000000 seconds"),
    (["--time-limit", "soon"], "expected a number of seconds, got 'soon'"),
])
def test_bad_options_exit_2(capsys, args, message):
    code, out, err = _compare(capsys, str(HOSPITAL), *args)
    assert code == 2 and message in err and "Traceback" not in err


def test_a_broken_mission_is_an_input_error_with_its_location(mission, capsys):
    hddl, = (mission / "hddl").glob("*.hddl")
    hddl.write_text(hddl.read_text(encoding="utf-8").replace("(:action", "(:acton", 1), encoding="utf-8")
    code, out, err = _compare(capsys, str(mission))
    assert code == 2 and out == ""
    assert f"error: {hddl}:" in err and "Traceback" not in err
    assert "exploratory: running" not in err  # the first run's input error ends the command
