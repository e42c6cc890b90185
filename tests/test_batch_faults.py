"""``mutrose-cp batch`` under faults: every rule of its outputs and of its results file, each
broken once on purpose (docs/batch.md, "What a batch refuses" and "The results file").

* outputs: the results file is not the manifest nor an input; no job writes the manifest or the
  results file; no two jobs write one file, whichever option names it or defaults to it; all of
  it found before any job runs;
* the journal: one writer at a time; two batches sharing one results file keep both their
  results; a line cut short
  by a crash does not swallow the next one; a failed append (a full disk) leaves whole lines;
  outputs named in options are not hashed; a job out of memory, stopped by a signal from outside
  or killed at its time limit says so, and leaves no temporary file;
* bad input: a FIFO among the inputs, a NUL byte in a CSV manifest, malformed results lines, an
  unwritable results path, a Ray address that accepts and never answers.

Faults are made on files in temporary folders only: FIFOs (``os.mkfifo``), a full disk
(``RLIMIT_FSIZE``), a file where a folder should be.
"""
from __future__ import annotations

import fcntl
import json
import os
import resource
import signal
import socket
import subprocess
import sys
import threading
import time
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.compare.measure import Measurement

from test_batch import EXAMPLES, batch, job_processes, results, slow_mission, write_manifest

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from generate import generate  # noqa: E402

ITEM = EXAMPLES / "item-delivery"


def _count(mission: Path | str = ITEM, **fields) -> dict:
    return {"command": "count", "inputs": [str(mission)], **fields}


def _started(folder: Path, *args: str) -> subprocess.Popen:
    """A batch started in ``folder``, in a process group of its own (to kill it whole)."""
    return subprocess.Popen([sys.executable, "-m", "mutrose_cp", "batch", *args], cwd=folder, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True, start_new_session=True)


def _wait_for(test, proc: subprocess.Popen, what: str, seconds: float = 120) -> None:
    deadline = time.monotonic() + seconds
    while not test():
        assert proc.poll() is None, (what, proc.communicate())
        assert time.monotonic() < deadline, f"timed out waiting for {what}"
        time.sleep(0.01)


def _lines_in(path: Path) -> int:
    return len(path.read_bytes().splitlines()) if path.exists() else 0


# -- outputs: refused before any job runs ----------------------------------------------------------

def test_the_results_file_is_neither_the_manifest_nor_an_input(tmp_path, mission, capsys):
    manifest = write_manifest(tmp_path / "m.json", [_count(mission)])
    before = manifest.read_bytes()
    world = mission / "knowledge" / "world_db.xml"
    kept = world.read_bytes()
    assert main(["batch", str(manifest), "--results", str(manifest)]) == 2
    assert f"--results {manifest}: the results file would overwrite the input {manifest}, the manifest" \
        in capsys.readouterr().err
    assert main(["batch", str(manifest), "--results", str(world)]) == 2
    assert "the results file would overwrite the input" in capsys.readouterr().err
    assert main(["batch", str(manifest), "--results", "-"]) == 2
    assert "give a file, not -" in capsys.readouterr().err
    assert manifest.read_bytes() == before and world.read_bytes() == kept
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.json", "mission"]


@pytest.mark.parametrize("output,guarded", [("m.json", "the manifest"), ("m.results.jsonl", "the results file")])
def test_no_job_writes_the_manifest_or_the_results_file(tmp_path, capsys, output, guarded):
    manifest = write_manifest(tmp_path / "m.json", [
        {"id": "d", "command": "decompose", "inputs": [str(ITEM)], "output": output}])
    before = manifest.read_bytes()
    assert main(["batch", str(manifest)]) == 2
    assert f"job d writes {guarded} {output}: give it another file" in capsys.readouterr().err
    assert manifest.read_bytes() == before and not (tmp_path / "m.results.jsonl").exists()


def _allocate(mission: Path, output: str, *options: str) -> dict:
    return {"command": "allocate", "inputs": [str(mission)],
            "options": ["--fleet", str(mission / "fleet.json"), "--time-limit", "10", *options], "output": output}


# two jobs writing one file, named by other options than -o or by none
COLLISIONS = {
    "schedule.json beside -o": (
        lambda m: [_allocate(m, "out/a.json"), _allocate(m, "out/b.json")],
        "job 2 writes out/schedule.json (schedule.json beside -o), as job 1 does (schedule.json beside -o)"),
    "--schedule onto -o": (
        lambda m: [_allocate(m, "out/a.json"), _allocate(m, "out/b.json", "--schedule", "out/a.json")],
        "job 2 writes out/a.json (--schedule), as job 1 does"),
    "--problem-out onto -o": (
        lambda m: [{"command": "decompose", "inputs": [str(m)], "output": "out/x.hddl"},
                   {"command": "export-hddl", "inputs": [str(m)], "options": ["--problem-out", "out/x.hddl"],
                    "output": "out/d.hddl"}],
        "job 2 writes out/x.hddl (--problem-out), as job 1 does"),
    "the configuration's output twice": (
        lambda m: [{"command": "decompose", "inputs": [str(m)], "options": ["--limit", n]} for n in ("1", "2")],
        f"writes {'{m}'}/output/mission.json (the configuration's output.file_path (no -o))"),
    "--ihtn twice": (
        lambda m: [{"command": "decompose", "inputs": [str(m)], "options": ["--ihtn", "ihtn", "--limit", n]}
                   for n in ("1", "2")],
        "job 2 writes into ihtn (--ihtn), as job 1 does (--ihtn)"),
    "-o into another job's --ihtn": (
        lambda m: [{"command": "decompose", "inputs": [str(m)], "options": ["--ihtn", "ihtn"]},
                   {"command": "decompose", "inputs": [str(m)], "output": "ihtn/ihtn_0.json"}],
        "job 2 writes ihtn/ihtn_0.json into ihtn, the folder job 1 writes its files into (--ihtn)"),
    "its own input": (
        lambda m: [{"command": "decompose", "inputs": [str(m)], "options": ["--optimize", "--costs", "costs.json"],
                    "output": "costs.json"}],
        "job 1 writes costs.json, which is its input costs.json"),
}


@pytest.mark.parametrize("case", list(COLLISIONS))
def test_outputs_that_collide_are_refused_whichever_option_names_them(tmp_path, mission, capsys, case):
    jobs, message = COLLISIONS[case]
    (tmp_path / "costs.json").write_text('{"actions": {}}')
    manifest = write_manifest(tmp_path / "m.json", jobs(mission))
    listed = sorted(tmp_path.rglob("*"))
    assert main(["batch", str(manifest)]) == 2
    assert message.replace("{m}", str(mission)) in capsys.readouterr().err
    assert sorted(tmp_path.rglob("*")) == listed  # nothing ran, nothing was written


def test_a_job_that_reads_what_another_writes_runs_when_it_does(tmp_path, mission):
    """``validate`` checks what ``decompose`` wrote: the pair is allowed; run again, both are
    settled (the reader's hash covers the file as it read it); when the writer's inputs change,
    the reader runs again too, though its own line is present."""
    costs = tmp_path / "costs.json"
    costs.write_text('{"actions": {}}')
    manifest = write_manifest(tmp_path / "m.json", [
        {"id": "d", "command": "decompose", "inputs": [str(mission)], "options": ["--optimize", "--costs", "costs.json"],
         "output": "out/d.json"},
        {"id": "v", "command": "validate", "inputs": [str(mission), "out/d.json"]}])
    run = batch(manifest, "--jobs", "1", cwd=tmp_path)
    assert run.returncode == 0, run.stderr
    assert [line["status"] for line in results(tmp_path / "m.results.jsonl")] == ["ok", "ok"]
    again = batch(manifest, "--jobs", "1", cwd=tmp_path)
    assert "0 run" in again.stderr and "2 skipped" in again.stderr, again.stderr
    costs.write_text('{"actions": {}, "methods": {}}')  # read by the writer only
    changed = batch(manifest, "--jobs", "1", cwd=tmp_path)
    assert "2 run" in changed.stderr, changed.stderr
    assert [line["id"] for line in results(tmp_path / "m.results.jsonl")][:2] == ["d", "v"]


def test_an_unwritable_results_path_is_found_before_the_first_job(tmp_path, capsys):
    (tmp_path / "afile").write_text("x")
    (tmp_path / "folder").mkdir()
    manifest = write_manifest(tmp_path / "m.json", [
        {"command": "decompose", "inputs": [str(ITEM)], "output": "out/d.json"}])
    assert main(["batch", str(manifest), "--results", str(tmp_path / "afile" / "r.jsonl")]) == 2
    assert f"cannot write the results file: {tmp_path / 'afile'} is a file, not a folder" in capsys.readouterr().err
    assert main(["batch", str(manifest), "--results", str(tmp_path / "folder")]) == 2
    assert "the results file is a folder" in capsys.readouterr().err
    assert not (tmp_path / "out").exists()  # the job never ran


# -- the journal ----------------------------------------------------------------------------------

def test_two_batches_sharing_a_results_file_keep_both_their_results(tmp_path):
    """A runs a quick job, then a slow one; B runs and ends in between, on the same results file.
    Every line of both is in the file at the end, A's jobs first (its manifest order)."""
    slow = slow_mission(tmp_path / "slow")
    for name in ("a", "b"):
        (tmp_path / name).mkdir()
    write_manifest(tmp_path / "a" / "a.json", [_count(id="a1"), _count(slow, id="a2")])
    write_manifest(tmp_path / "b" / "b.json", [_count(EXAMPLES / "hospital-disinfection", id="b1")])
    shared = tmp_path / "shared.jsonl"
    first = _started(tmp_path / "a", "a.json", "--jobs", "1", "--time-limit", "5", "--results", str(shared))
    _wait_for(lambda: _lines_in(shared) == 1, first, "A's first result")
    second = batch("b.json", "--results", str(shared), cwd=tmp_path / "b")
    assert second.returncode == 0, second.stderr
    assert first.wait(timeout=120) == 1, first.communicate()  # a2 timed out
    assert [(line["id"], line["status"]) for line in results(shared)] == [("a1", "ok"), ("a2", "timeout"),
                                                                          ("b1", "ok")]


def test_a_batch_waits_while_another_writer_holds_the_results_file(tmp_path):
    """Another writer holds the lock: the batch waits for it before it reads or appends, then
    goes on."""
    manifest = write_manifest(tmp_path / "m.json", [_count()])
    journal = tmp_path / "m.results.jsonl"
    journal.write_text("")
    with open(journal, "rb") as held:
        fcntl.flock(held, fcntl.LOCK_EX)
        proc = _started(tmp_path, manifest.name)
        time.sleep(3)  # the job alone takes about a second
        assert proc.poll() is None and journal.read_text() == ""
    _, err = proc.communicate(timeout=60)
    assert proc.returncode == 0, err
    assert [line["status"] for line in results(journal)] == ["ok"]


def test_a_line_cut_short_does_not_swallow_the_next_result(tmp_path):
    """A batch killed while writing left half a line: the next batch ends it first, so its own
    first result is a line of its own, even when it is killed in turn before it ends."""
    slow = slow_mission(tmp_path / "slow")
    manifest = write_manifest(tmp_path / "m.json", [_count(id="quick"), _count(slow, id="slow")])
    journal = tmp_path / "m.results.jsonl"
    journal.write_text('{"id": "old", "command": "count", "inputs": ["x"], "opt')  # the crash
    cut = journal.stat().st_size
    proc = _started(tmp_path, "m.json", "--jobs", "1")
    _wait_for(lambda: journal.stat().st_size > cut + 1 and journal.read_bytes().endswith(b"\n"), proc, "a result")
    os.killpg(proc.pid, signal.SIGKILL)  # the batch and its jobs, before it can tidy the file
    proc.wait(timeout=60)
    whole = journal.read_bytes().splitlines()[1:]
    assert [json.loads(line)["id"] for line in whole] == ["quick"]
    rerun = batch(manifest, "--jobs", "1", "--time-limit", "1", cwd=tmp_path)
    assert "1 run" in rerun.stderr and "1 skipped" in rerun.stderr, rerun.stderr
    assert f"{journal}:1: not a result line" in rerun.stderr
    assert [line["id"] for line in results(journal)] == ["quick", "slow"]  # the cut piece is gone


def _file_size_limit(size: int):
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    return limit


def test_an_append_that_fails_leaves_whole_lines_only(tmp_path):
    """The disk fills (``RLIMIT_FSIZE``) in the middle of a result line: the batch stops with a
    located error, and the file holds its earlier whole lines, byte for byte."""
    write_manifest(tmp_path / "m.json", [_count(EXAMPLES / "hospital-disinfection")])
    earlier = write_manifest(tmp_path / "e.json", [_count(id=f"e{i}", options=["--max-input-mb", str(i)])
                                                   for i in range(1, 6)])
    journal = tmp_path / "m.results.jsonl"
    assert batch(earlier, "--results", str(journal), cwd=tmp_path).returncode == 0
    before = journal.read_bytes()
    run = subprocess.run([sys.executable, "-m", "mutrose_cp", "batch", "m.json"], cwd=tmp_path, capture_output=True,
                         text=True, timeout=120, preexec_fn=_file_size_limit(len(before) + 100))
    assert run.returncode == 2, run.stderr
    assert f"error: {journal.name}: cannot write the results file: File too large" in run.stderr, run.stderr
    assert "Traceback" not in run.stderr
    assert journal.read_bytes() == before


CUT_BACK = """
import dataclasses
import sys
from pathlib import Path
from mutrose_cp.cli.batch.journal import ResultsFile
from mutrose_cp.errors import MissionError

journal = ResultsFile(Path(sys.argv[1]))
journal.open()
line = next(iter(journal.lines.values()))
try:
    journal.record(dataclasses.replace(line, input_hash="sha256:new"))
except MissionError as err:
    print(err)
print(Path(sys.argv[1]).read_bytes() == Path(sys.argv[2]).read_bytes())  # before the batch ends
"""


def test_a_failed_append_is_cut_back_at_once(tmp_path):
    """Between the failed append and the end of the batch, the file already ends with its last
    whole line: a batch appending meanwhile, or a crash, finds no piece of a line."""
    earlier = write_manifest(tmp_path / "e.json", [_count()])
    journal = tmp_path / "r.jsonl"
    assert batch(earlier, "--results", str(journal), cwd=tmp_path).returncode == 0
    copy = tmp_path / "copy.jsonl"
    copy.write_bytes(journal.read_bytes())
    run = subprocess.run([sys.executable, "-c", CUT_BACK, str(journal), str(copy)], capture_output=True, text=True,
                         timeout=60, preexec_fn=_file_size_limit(journal.stat().st_size + 100))
    assert run.stdout.splitlines() == [f"{journal}: cannot write the results file: File too large; the jobs that "
                                       "finished before are recorded", "True"], run.stdout + run.stderr


def test_outputs_named_in_options_are_not_hashed(tmp_path):
    """``--schedule`` names an output: a rerun finds the job settled (one line, one id), though
    the file it wrote is new."""
    manifest = write_manifest(tmp_path / "m.json", [{**_allocate(ITEM, "out/a.json", "--schedule", "out/s.json"),
                                                     "id": "x"}])
    first = batch(manifest, cwd=tmp_path)
    assert first.returncode == 0, first.stderr
    assert (tmp_path / "out" / "s.json").is_file()
    again = batch(manifest, cwd=tmp_path)
    assert "0 run" in again.stderr and "1 skipped" in again.stderr, again.stderr
    assert [line["id"] for line in results(tmp_path / "m.results.jsonl")] == ["x"]


def test_repeated_job_ids_are_refused_where_they_are(tmp_path, capsys):
    write_manifest(tmp_path / "m.json", [_count(id="a"), _count(EXAMPLES / "hospital-disinfection", id="a")])
    assert main(["batch", str(tmp_path / "m.json")]) == 2
    assert f"{tmp_path / 'm.json'}: jobs[1]: job id 'a' is also the id of the job at {tmp_path / 'm.json'}: jobs[0]" \
        in capsys.readouterr().err
    (tmp_path / "m.csv").write_text(f"id,command,inputs\n7,count,{ITEM}\n7,check,{ITEM}\n")
    assert main(["batch", str(tmp_path / "m.csv")]) == 2
    assert f"{tmp_path / 'm.csv'}:3: job id '7' is also the id of the job at {tmp_path / 'm.csv'}:2" \
        in capsys.readouterr().err
    assert not list(tmp_path.glob("*.jsonl"))


# -- statuses --------------------------------------------------------------------------------------

def _address_space(megabytes: int):
    def limit() -> None:
        resource.setrlimit(resource.RLIMIT_AS, (megabytes << 20, megabytes << 20))
    return limit


def test_out_of_memory_under_an_inherited_address_space_limit_is_memory(tmp_path):
    """No ``--memory-mb``: the batch runs under ``ulimit -v``, which its jobs inherit.  The
    job's MemoryError surfaces from a C extension as a SystemError traceback, exit 1: still
    ``memory``, so that a rerun with more memory runs it again."""
    hddl, gm, cfg = generate("delivery", 12, tmp_path / "gen")
    manifest = write_manifest(tmp_path / "m.json", [
        {"command": "decompose", "inputs": [str(hddl), str(gm), str(cfg)], "options": ["--algorithm", "exploratory"],
         "output": "out/big.json"}])
    run = subprocess.run([sys.executable, "-m", "mutrose_cp", "batch", str(manifest)], cwd=tmp_path,
                         capture_output=True, text=True, timeout=300, preexec_fn=_address_space(700))
    assert run.returncode == 1, run.stderr
    [line] = results(tmp_path / "m.results.jsonl")
    assert line["status"] == "memory", line
    assert "ran out of memory under the limit of" in line["problems"][0]
    assert not (tmp_path / "out" / "big.json").exists() and not list(tmp_path.rglob(".*.tmp"))


@pytest.mark.parametrize("exit_status,stderr,limit", [
    (-signal.SIGABRT, "terminate called after throwing an instance of 'std::bad_alloc'\n  what():  std::bad_alloc\n",
     (0, False)),
    (1, "Traceback (most recent call last):\n  ...\nMemoryError\n...\nSystemError: error return without exception "
        "set\n", (0, False)),
    (-signal.SIGSEGV, "", (700, True)),  # under ulimit -v: a stack or a mapping that could not grow
    (2, "error: cannot map the file: [Errno 12] Cannot allocate memory\n", (100, False)),
    (-signal.SIGSEGV, "", (700, False)),  # a crash: under RLIMIT_DATA the peak would be near the limit
])
def test_a_native_report_of_memory_is_memory(exit_status, stderr, limit):
    from mutrose_cp.cli.batch.statuses import CRASHED, MEMORY, MemoryLimit, classify

    run = Measurement(exit_status=exit_status, seconds=1.0, peak_mb=20.0, stdout="", stderr=stderr)
    expected = CRASHED if limit == (700, False) else MEMORY
    assert classify(run, MemoryLimit(*limit)) == expected


def test_a_job_stopped_from_outside_is_interrupted_and_runs_again(tmp_path):
    slow = slow_mission(tmp_path / "slow")
    manifest = write_manifest(tmp_path / "m.json", [_count(slow, id="slow")])
    proc = _started(tmp_path, "m.json")
    _wait_for(lambda: bool(job_processes(tmp_path)), proc, "the job")
    time.sleep(0.5)
    for pid in job_processes(tmp_path):
        os.kill(pid, signal.SIGTERM)
    proc.communicate(timeout=60)
    [line] = results(tmp_path / "m.results.jsonl")
    assert line["status"] == "interrupted", line
    rerun = batch(manifest, "--time-limit", "1", cwd=tmp_path)
    assert "1 run" in rerun.stderr, rerun.stderr  # not settled
    assert [line["status"] for line in results(tmp_path / "m.results.jsonl")] == ["timeout"]


def test_a_job_killed_at_its_time_limit_leaves_no_temporary_file(tmp_path):
    """The job is frozen (SIGSTOP) while its output's temporary file exists, so that the time
    limit kills it there: the batch removes the file the job could not."""
    hddl, gm, cfg = generate("delivery", 11, tmp_path / "gen")
    manifest = write_manifest(tmp_path / "m.json", [
        {"command": "decompose", "inputs": [str(hddl), str(gm), str(cfg)], "options": ["--algorithm", "exploratory"],
         "output": "out/big.json"}])
    proc = _started(tmp_path, manifest.name, "--time-limit", "20")  # time to reach the writing on a slow machine
    out = tmp_path / "out"
    _wait_for(lambda: out.is_dir() and any(p.name.endswith(".tmp") for p in out.iterdir()), proc, "the temporary file",
              seconds=60)
    for pid in job_processes(tmp_path):
        os.killpg(pid, signal.SIGSTOP)
    assert proc.wait(timeout=60) == 1, proc.communicate()
    [line] = results(tmp_path / "m.results.jsonl")
    assert line["status"] == "timeout"
    assert any(p.startswith("removed the temporary file out/.big.json.") for p in line["problems"]), line
    assert not list(out.iterdir())


# -- bad input: located errors, never a traceback, never a hang -----------------------------------

@pytest.mark.parametrize("where", ["--world", "hddl"])
def test_a_fifo_input_is_refused_without_waiting(tmp_path, mission, where):
    fifo = tmp_path / "input.fifo"
    os.mkfifo(fifo)
    if where == "--world":
        job = {"command": "count", "inputs": [str(mission)], "options": ["--world", str(fifo)]}
    else:
        job = {"command": "count", "inputs": [str(fifo), str(next((mission / "gm").iterdir())),
                                              str(next((mission / "configuration").iterdir()))]}
    write_manifest(tmp_path / "m.json", [job])
    try:
        run = subprocess.run([sys.executable, "-m", "mutrose_cp", "batch", "m.json"], cwd=tmp_path,
                             capture_output=True, text=True, timeout=60)
    except subprocess.TimeoutExpired:
        pytest.fail("the batch waited on a FIFO input")
    assert run.returncode == 2 and "Traceback" not in run.stderr, run.stderr
    assert f"error: m.json: jobs[0]: job 1: {fifo}: the input is a FIFO (named pipe), not a regular file" \
        in run.stderr, run.stderr


def test_a_nul_byte_in_a_csv_manifest_is_located(tmp_path, capsys):
    (tmp_path / "m.csv").write_bytes(b"command,inputs\ncount,ab\0c\n")
    assert main(["batch", str(tmp_path / "m.csv")]) == 2
    assert f"error: {tmp_path / 'm.csv'}:2:9: the manifest holds a NUL byte" in capsys.readouterr().err


MALFORMED = {
    "input_hash a list": lambda line: {**line, "input_hash": [line["input_hash"]]},
    "an unknown status": lambda line: {**line, "status": "fine"},
    "seconds too large for a float": lambda line: {**line, "seconds": "HUGE"},
    "a list, not an object": lambda line: [line],
    "nested too deeply": lambda line: "DEEP",
}


@pytest.mark.parametrize("case", list(MALFORMED))
def test_a_malformed_results_line_is_reported_and_its_job_runs_again(tmp_path, case):
    manifest = write_manifest(tmp_path / "m.json", [_count()])
    journal = tmp_path / "m.results.jsonl"
    assert batch(manifest, cwd=tmp_path).returncode == 0
    text = json.dumps(MALFORMED[case](results(journal)[0]))
    text = text.replace('"HUGE"', "1" + "0" * 400).replace('"DEEP"', "[" * 100_000 + "]" * 100_000)
    journal.write_text(text + "\n")
    run = batch(manifest, cwd=tmp_path)
    assert run.returncode == 0 and "Traceback" not in run.stderr, run.stderr
    assert f"warning: {journal}:1: not a result line (" in run.stderr and "1 run" in run.stderr, run.stderr
    assert results(journal)[0]["status"] == "ok"  # the new result first; the malformed line is kept after it


@pytest.mark.ray
def test_ctrl_c_stops_a_batch_joining_a_cluster_that_never_answers(tmp_path):
    """An address that accepts connections and never answers: Ray waits 30 s for it, in native
    code; Ctrl-C stops the batch at once all the same."""
    pytest.importorskip("ray")
    listener = socket.create_server(("", 0))  # every address: Ray may reach it by the machine's own
    port = listener.getsockname()[1]
    accepted: list[socket.socket] = []

    def accept() -> None:
        while True:
            try:
                accepted.append(listener.accept()[0])
            except OSError:
                return

    threading.Thread(target=accept, daemon=True).start()
    write_manifest(tmp_path / "m.json", [_count()])
    proc = _started(tmp_path, "m.json", "--ray", f"127.0.0.1:{port}")
    try:
        # the batch's own check connects once, then Ray: once Ray has connected, it is waiting
        _wait_for(lambda: len(accepted) >= 2, proc, "Ray's connection", seconds=60)
        time.sleep(0.5)
        stopped = time.monotonic()
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=60)
        assert time.monotonic() - stopped < 5, "Ctrl-C waited for Ray"
        assert proc.returncode == 130 and "interrupted (SIGINT)" in err and "Traceback" not in err, err
    finally:
        listener.close()
        for conn in accepted:
            conn.close()
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
