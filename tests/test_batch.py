"""``mutrose-cp batch`` on the local pool: manifests (JSON, CSV, ``--each``), every command on
main as a job, per-job time and memory limits, the results file and resuming after an interrupt.

The Ray engine and the byte-for-byte comparison of the engines are in ``test_batch_ray.py``.
"""
from __future__ import annotations

import io
import json
import signal
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mutrose_cp.cli.batch.report import Progress
from mutrose_cp.cli.program import main

from conftest import ROOT
from test_interrupts import _coupled_mission

sys.path.insert(0, str(ROOT / "benchmarks"))
from generate import generate  # noqa: E402

EXAMPLES = ROOT / "examples"


def slow_mission(folder: Path) -> Path:
    """A mission whose ``count`` takes CP-SAT many seconds: a job to stop midway."""
    return _coupled_mission(folder)


def batch(*args: str, cwd: Path, env: dict | None = None) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-m", "mutrose_cp", "batch", *map(str, args)], cwd=cwd,
                          capture_output=True, text=True, timeout=300, env=env)


def results(path: Path) -> list[dict]:
    return [json.loads(line) for line in path.read_text().splitlines()]


def write_manifest(path: Path, jobs: list[dict]) -> Path:
    path.write_text(json.dumps({"jobs": jobs}, indent=1))
    return path


# -- every command on main as a job; the results file ------------------------------------------

def test_every_command_runs_as_a_job_and_each_line_is_a_result(tmp_path):
    item, hospital = EXAMPLES / "item-delivery", EXAMPLES / "hospital-disinfection"
    manifest = write_manifest(tmp_path / "m.json", [
        {"id": "d", "command": "decompose", "inputs": [str(item)], "options": ["--optimize"], "output": "out/d.json"},
        {"id": "c", "command": "count", "inputs": [str(hospital)]},
        {"id": "k", "command": "check", "inputs": [str(item)]},
        {"id": "v", "command": "validate", "inputs": [str(item), "out/d.json"]},
        {"id": "bad", "command": "count", "inputs": [str(tmp_path / "no-such-mission")]},
    ])
    run = batch(manifest, "--jobs", "1", cwd=tmp_path)  # one at a time: validate reads what decompose wrote
    assert run.returncode == 1, run.stderr  # one job failed
    lines = results(tmp_path / "m.results.jsonl")
    assert [line["id"] for line in lines] == ["d", "c", "k", "v", "bad"]
    assert list(lines[0]) == ["id", "command", "inputs", "options", "output", "input_hash", "status", "exit_code",
                              "seconds", "peak_mb", "time_limit", "memory_mb", "summary", "problems"]
    by_id = {line["id"]: line for line in lines}
    assert by_id["d"]["status"] == "ok" and by_id["d"]["summary"]["mission_decompositions"] == "8"
    assert json.loads((tmp_path / "out" / "d.json").read_text())  # the job's own output file
    assert by_id["c"]["summary"]["mission_decompositions"] == "36"
    assert by_id["k"]["summary"]["valid"] is True
    assert by_id["v"]["status"] == "ok" and by_id["v"]["summary"]["checked"] == 1
    assert by_id["bad"]["status"] == "invalid-input" and by_id["bad"]["exit_code"] == 2
    assert "is not a directory" in by_id["bad"]["problems"][0]
    assert all(line["peak_mb"] > 0 and line["seconds"] > 0 for line in lines)
    assert "invalid-input" in run.stderr and "bad: count no-such-mission" in run.stderr  # the summary table


def test_a_csv_manifest_runs_its_rows(tmp_path):
    (tmp_path / "m.csv").write_text(f'command,inputs,options,output\ncount,"{EXAMPLES / "item-delivery"}",,\n'
                                    f'decompose,{EXAMPLES / "hospital-disinfection"},--limit 2,out/h.json\n')
    run = batch("m.csv", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    lines = results(tmp_path / "m.results.jsonl")
    assert [(line["command"], line["options"], line["status"]) for line in lines] == [
        ("count", [], "ok"), ("decompose", ["--limit", "2"], "ok")]
    assert len(json.loads((tmp_path / "out" / "h.json").read_text())["mission_decompositions"]) == 2


def test_each_world_with_one_mission(tmp_path):
    """``--each GLOB --mission DIR COMMAND``: the mission once per world (``--world``)."""
    for n in (2, 3):
        generate("delivery", n, tmp_path / "gen")
    mission = tmp_path / "mission"
    hddl, gm, cfg = generate("delivery", 1, tmp_path / "base")
    for sub, src in (("hddl", hddl), ("gm", gm), ("configuration", cfg)):
        (mission / sub).mkdir(parents=True)
        (mission / sub / src.name).write_bytes(src.read_bytes())
    run = batch("--each", "gen/delivery-*.xml", "--mission", "mission", "--output", "out/{name}.json",
                "decompose", "--limit", "0", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    lines = results(tmp_path / "batch.results.jsonl")
    assert [line["options"] for line in lines] == [["--world", f"gen/delivery-{n}.xml", "--limit", "0"] for n in (2, 3)]
    assert [line["summary"]["mission_decompositions"] for line in lines] == ["9", "27"]  # 3^n
    assert [len(json.loads((tmp_path / "out" / f"delivery-{n}.json").read_text())["mission_decompositions"])
            for n in (2, 3)] == [9, 27]


def test_each_mission_folder(tmp_path):
    run = batch("--each", str(EXAMPLES / "*"), "check", cwd=tmp_path)
    folders = sorted(p.name for p in EXAMPLES.iterdir() if p.is_dir())
    lines = results(tmp_path / "batch.results.jsonl")
    assert [Path(line["inputs"][0]).name for line in lines] == folders
    assert run.returncode == 0, run.stderr
    assert all(line["summary"]["valid"] for line in lines)


# -- limits ----------------------------------------------------------------------------------------

def test_time_and_memory_limits_stop_one_job_and_the_batch_goes_on(tmp_path):
    slow = _coupled_mission(tmp_path / "slow")  # CP-SAT enumerates ~2 million solutions: many seconds
    hddl, gm, cfg = generate("delivery", 12, tmp_path / "gen")  # the exploratory lists 3^12 decompositions
    manifest = write_manifest(tmp_path / "m.json", [
        {"id": "slow", "command": "count", "inputs": [str(slow)]},
        {"id": "big", "command": "decompose", "inputs": [str(hddl), str(gm), str(cfg)],
         "options": ["--algorithm", "exploratory"], "output": "out/big.json"},
        # under the same limits: a mission whose inputs are read without reserving the input limit
        {"id": "fine", "command": "decompose", "inputs": [str(EXAMPLES / "item-delivery")], "output": "out/ok.json"},
    ])
    run = batch(manifest, "--time-limit", "4", "--memory-mb", "100", cwd=tmp_path)
    assert run.returncode == 1, run.stderr
    status = {line["id"]: line for line in results(tmp_path / "m.results.jsonl")}
    assert status["slow"]["status"] == "timeout" and status["slow"]["exit_code"] is None
    assert status["slow"]["problems"] == ["stopped at the time limit of 4 s"]
    assert status["big"]["status"] == "memory", status["big"]
    assert status["fine"]["status"] == "ok", status["fine"]
    assert not (tmp_path / "out" / "big.json").exists()
    assert not list(tmp_path.rglob(".*.tmp"))
    assert not _processes_reading(slow)  # the timed-out job's process group was killed


def _processes_reading(path: Path) -> list[int]:
    """The processes whose command line names ``path``."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and str(path) in (proc / "cmdline").read_bytes().decode(errors="replace"):
                found.append(int(proc.name))
        except OSError:
            continue
    return found


# -- resuming ---------------------------------------------------------------------------------------

def test_a_rerun_skips_settled_jobs_and_reruns_changed_inputs(tmp_path):
    mission = tmp_path / "mission"
    mission.mkdir()
    for sub in ("hddl", "gm", "configuration", "knowledge"):
        (mission / sub).mkdir()
        for f in (EXAMPLES / "item-delivery" / sub).iterdir():
            (mission / sub / f.name).write_bytes(f.read_bytes())
    manifest = write_manifest(tmp_path / "m.json", [
        {"id": "a", "command": "count", "inputs": ["mission"]},
        {"id": "b", "command": "check", "inputs": [str(EXAMPLES / "hospital-disinfection")]},
    ])
    assert batch(manifest, cwd=tmp_path).returncode == 0
    first = results(tmp_path / "m.results.jsonl")
    again = batch(manifest, cwd=tmp_path)
    assert "0 run" in again.stderr and "2 skipped" in again.stderr
    assert results(tmp_path / "m.results.jsonl") == first  # nothing ran: the very same lines
    world = next((mission / "knowledge").iterdir())
    world.write_text(world.read_text().replace("</world_db>", "<!-- changed -->\n</world_db>"))
    changed = batch(manifest, cwd=tmp_path)
    assert "1 run" in changed.stderr and "1 skipped" in changed.stderr, changed.stderr
    after = results(tmp_path / "m.results.jsonl")
    assert after[1] == first[1] and after[0]["input_hash"] != first[0]["input_hash"]


def test_a_timed_out_job_runs_again_under_a_higher_limit(tmp_path):
    manifest = write_manifest(tmp_path / "m.json", [{"command": "count", "inputs": [str(EXAMPLES / "item-delivery")]}])
    assert batch(manifest, "--time-limit", "0.05", cwd=tmp_path).returncode == 1
    assert results(tmp_path / "m.results.jsonl")[0]["status"] == "timeout"
    assert "0 run" in batch(manifest, "--time-limit", "0.05", cwd=tmp_path).stderr  # same limit: settled
    assert batch(manifest, "--time-limit", "100", cwd=tmp_path).returncode == 0
    assert [line["status"] for line in results(tmp_path / "m.results.jsonl")] == ["ok"]


def test_an_interrupted_batch_records_the_finished_jobs_only_and_resumes(tmp_path):
    """SIGINT while the fourth of five jobs runs (one at a time): three lines, no line and no
    output for the running one; the rerun runs the last two only."""
    slow = _coupled_mission(tmp_path / "slow")
    quick = [{"id": f"q{i}", "command": "decompose", "inputs": [str(EXAMPLES / "item-delivery")],
              "options": ["--limit", str(i)], "output": f"out/q{i}.json"} for i in (1, 2, 3)]
    manifest = write_manifest(tmp_path / "m.json", [
        *quick, {"id": "slow", "command": "decompose", "inputs": [str(slow)], "output": "out/slow.json"},
        {"id": "last", "command": "count", "inputs": [str(EXAMPLES / "item-delivery")]}])
    journal = tmp_path / "m.results.jsonl"
    proc = subprocess.Popen([sys.executable, "-m", "mutrose_cp", "batch", "m.json", "--jobs", "1"], cwd=tmp_path,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 120
    while not (journal.exists() and len(journal.read_text().splitlines()) == 3):
        assert proc.poll() is None and time.monotonic() < deadline, proc.communicate()
        time.sleep(0.05)
    time.sleep(0.3)  # the slow job is under way
    proc.send_signal(signal.SIGINT)
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 130, err
    assert "interrupted (SIGINT): 2 jobs not finished" in err and "Traceback" not in err
    assert [line["id"] for line in results(journal)] == ["q1", "q2", "q3"]
    assert not (tmp_path / "out" / "slow.json").exists() and not list(tmp_path.rglob(".*.tmp"))
    assert not _processes_reading(slow)
    done = results(journal)
    # the rerun: the slow job under a time limit this time, so that it ends
    rerun = batch(manifest, "--jobs", "1", "--time-limit", "3", cwd=tmp_path)
    assert "2 run" in rerun.stderr and "3 skipped" in rerun.stderr, rerun.stderr
    lines = results(journal)
    assert lines[:3] == done  # untouched: not run again
    assert [(line["id"], line["status"]) for line in lines[3:]] == [("slow", "timeout"), ("last", "ok")]


# -- bad manifests and usage: located errors, exit 2, nothing runs ------------------------------

@pytest.mark.parametrize("jobs,message", [
    ([{"command": "decompse", "inputs": ["x"]}], "m.json: jobs[0]: job 1: mutrose-cp decompse: argument COMMAND: "
                                                  "invalid choice: 'decompse'"),
    ([{"command": "count", "inputs": ["x"], "options": ["--limt", "3"]}],
     "m.json: jobs[0]: job 1: mutrose-cp count: unrecognized arguments: --limt 3"),
    ([{"command": "count", "inputs": ["x"], "outptu": "y"}], "m.json: jobs[0].outptu: unknown field 'outptu' "
                                                              "(did you mean 'output'?)"),
    ([{"command": "count", "inputs": ["x"], "output": "y.json"}], "count writes no output file"),
    ([{"command": "decompose", "inputs": ["x"], "options": ["-o", "y.json"]}], "give it as the job's output"),
    ([{"command": "decompose", "inputs": ["x"], "output": "y.json"},
      {"command": "decompose", "inputs": ["z"], "output": "./y.json"}], "job 2 writes ./y.json, as job 1 does"),
    ([{"command": "count", "inputs": "x"}, {"command": "count", "inputs": ["x"]}], "job 2 repeats job 1"),
    ([{"command": "batch", "inputs": ["other.json"]}], "a batch job cannot be a batch"),
    ([{"command": "count"}], "m.json: jobs[0]: the job names no inputs"),
    ([{"command": "count", "inputs": [1]}], "m.json: jobs[0].inputs: expected a list of strings"),
])
def test_manifest_problems_are_located(tmp_path, capsys, jobs, message):
    write_manifest(tmp_path / "m.json", jobs)
    assert main(["batch", str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err
    assert message in err, err
    assert not (tmp_path / "m.results.jsonl").exists()


@pytest.mark.parametrize("value,message", [
    ("inf", "inf is not a positive number of seconds"),
    ("nan", "nan is not a positive number of seconds"),
    ("-5", "-5 is not a positive number of seconds"),
    ("1e8", "1e8 is out of range: give at most 10000000 seconds"),
    ("soon", "expected a number of seconds, got 'soon'"),
])
def test_time_limit_is_checked_as_the_other_commands_check_it(tmp_path, capsys, value, message):
    write_manifest(tmp_path / "m.json", [{"command": "count", "inputs": [str(EXAMPLES / "item-delivery")]}])
    assert main(["batch", "--time-limit", value, str(tmp_path / "m.json")]) == 2
    err = capsys.readouterr().err
    assert f"argument --time-limit: {message}" in err and "Traceback" not in err, err
    assert not (tmp_path / "m.results.jsonl").exists()


def test_time_limit_after_the_manifest_is_checked_too(tmp_path):
    write_manifest(tmp_path / "m.json", [{"command": "count", "inputs": [str(EXAMPLES / "item-delivery")]}])
    run = batch("m.json", "--time-limit", "inf", cwd=tmp_path)
    assert run.returncode == 2
    assert "argument --time-limit: inf is not a positive number of seconds" in run.stderr, run.stderr
    assert "Traceback" not in run.stderr and not (tmp_path / "m.results.jsonl").exists()


def test_json_syntax_and_csv_problems_are_located(tmp_path, capsys):
    (tmp_path / "m.json").write_text('{"jobs": [\n  {"command": "count",, }\n]}')
    assert main(["batch", str(tmp_path / "m.json")]) == 2
    assert f"{tmp_path / 'm.json'}:2:23" in capsys.readouterr().err
    (tmp_path / "m.csv").write_text('command,inputs,optoins\ncount,x,\n')
    assert main(["batch", str(tmp_path / "m.csv")]) == 2
    assert f"{tmp_path / 'm.csv'}:1: unknown column 'optoins' (did you mean 'options'?)" in capsys.readouterr().err
    (tmp_path / "m.csv").write_text('command,inputs\ncount,x\ncount,"""a b"\n')  # the cell is: "a b
    assert main(["batch", str(tmp_path / "m.csv")]) == 2
    assert f"{tmp_path / 'm.csv'}:3: column inputs: No closing quotation" in capsys.readouterr().err


def test_each_needs_matches(tmp_path, capsys):
    assert main(["batch", "--each", str(tmp_path / "nothing-*"), "count"]) == 2
    assert "no mission folder matches" in capsys.readouterr().err


def test_ray_without_ray_installed_says_how_to_install_it(tmp_path):
    write_manifest(tmp_path / "m.json", [{"command": "count", "inputs": [str(EXAMPLES / "item-delivery")]}])
    code = ("import sys; sys.modules['ray'] = None; from mutrose_cp.cli.program import main; "
            "sys.exit(main(['batch', 'm.json', '--ray']))")
    run = subprocess.run([sys.executable, "-c", code], cwd=tmp_path, capture_output=True, text=True, timeout=60)
    assert run.returncode == 2
    assert "Ray is not installed: install it with  pip install 'mutrose-cp[ray]'" in run.stderr
    assert not (tmp_path / "m.results.jsonl").exists()


# -- the progress bar ---------------------------------------------------------------------------------

class _Terminal(io.StringIO):
    def isatty(self) -> bool:
        return True


def test_progress_bar_counts_jobs_and_failures_on_a_terminal_only():
    screen = _Terminal()
    bar = Progress(total=4, skipped=1, enabled=True, stream=screen)
    bar.finished("ok")
    bar.last = 0.0
    bar.finished("timeout")
    assert "] 3/4 jobs, 1 not ok, about " in screen.getvalue().rsplit("\r", 1)[-1]
    bar.finished("ok")
    assert screen.getvalue().endswith("] 4/4 jobs, 1 not ok\n")
    redirected = io.StringIO()
    Progress(total=2, skipped=0, enabled=True, stream=redirected).finished("ok")
    assert redirected.getvalue() == ""


def test_the_dissertation_experiment_is_one_valid_manifest(tmp_path, reference):
    """``ladder_manifest.py dissertation``: both algorithms on every configuration of the
    scalability folders, every job accepted by the command line's parser."""
    from ladder_manifest import main as write_manifest_of

    from mutrose_cp.cli.batch.manifest import check_jobs, read_manifest

    assert write_manifest_of(["dissertation", str(tmp_path)]) == 0
    jobs = read_manifest(tmp_path / "dissertation.json")
    from run import DISSERTATION

    configurations = sum(1 for folder, template, _gm, sizes in DISSERTATION.values() for i in range(len(sizes))
                         if (reference / folder / "configuration" / template.format(i=i)).exists())
    assert configurations == 34  # Table 5.2: 8 delivery, 13 pickup and 13 vital-signs worlds
    assert len(jobs) == 2 * configurations
    assert len(check_jobs(jobs, tmp_path)) == len(jobs)
    assert {job.options[-1] for job in jobs} == {"exploratory", "--lenient-xml"}


def job_processes(folder: Path) -> list[int]:
    """The job processes (``mutrose_cp.cli.batch.child``) running in ``folder`` (for the tests of interrupted and killed batches)."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            if (proc.name.isdigit() and b"mutrose_cp.cli.batch.child" in (proc / "cmdline").read_bytes()
                    and (proc / "cwd").resolve() == folder.resolve()):
                found.append(int(proc.name))
        except OSError:
            continue
    return found
