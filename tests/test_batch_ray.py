"""Same results everywhere: every job of a batch writes the same bytes whether it runs alone, in the
local pool or on Ray (a local cluster of 2 CPUs, started by ``batch --ray`` inside the test).

The manifest: every configuration of the reference missions, and the quick benchmark ladder of
the delivery family as ``benchmarks/ladder_manifest.py`` writes it.  The Ray run is interrupted
once a few jobs are done and run again: it finishes the rest only.  The test is marked ``ray``
and bounded by a timeout: CI installs the ``ray`` extra and runs it (about a minute on 2 cores,
10 s of which start the Ray cluster).
"""
from __future__ import annotations

import json
import os
import signal
import socket
import subprocess
import sys
import time
from pathlib import Path

import pytest

from mutrose_cp.cli.batch.manifest import read_manifest

from conftest import ROOT, require_reference
from test_batch import job_processes

sys.path.insert(0, str(ROOT / "benchmarks"))
from ladder_manifest import ladder_jobs  # noqa: E402
from run import QUICK_LADDER  # noqa: E402


def _ray_or_skip() -> None:
    try:
        import ray  # noqa: F401
    except ImportError:
        if os.environ.get("CI") == "true":
            pytest.fail("ray is not installed: CI installs the ray extra (pip install -e '.[test,ray]')")
        pytest.skip("ray is not installed (pip install 'mutrose-cp[ray]')")


def _reference_jobs(reference: Path) -> list[dict]:
    jobs = []
    for mission in sorted((reference / "missions").iterdir()):
        for cfg in sorted((mission / "configuration").iterdir()):
            jobs.append({"id": f"{mission.name}/{cfg.name}", "command": "decompose", "inputs": [str(mission)],
                         "options": ["--config", cfg.name], "output": f"out/{mission.name}-{cfg.name}.out"})
    return jobs


def _batch(folder: Path, *options: str) -> subprocess.CompletedProcess:
    run = subprocess.run([sys.executable, "-m", "mutrose_cp", "batch", "m.json", *options], cwd=folder,
                         capture_output=True, text=True, timeout=480)
    assert "Traceback" not in run.stderr, run.stderr
    return run


def _outputs(folder: Path) -> dict[str, bytes]:
    return {p.name: p.read_bytes() for p in sorted((folder / "out").iterdir())}


def _settled(folder: Path) -> list[tuple]:
    """Per job: its status, exit status and what its summary says apart from time and paths."""
    lines = [json.loads(line) for line in (folder / "m.results.jsonl").read_text().splitlines()]
    return [(line["id"], line["status"], line["exit_code"], line["input_hash"],
             {k: v for k, v in (line["summary"] or {}).items() if k not in ("seconds", "inputs")}) for line in lines]


@pytest.mark.ray
@pytest.mark.timeout(600)
def test_alone_local_pool_and_ray_write_the_same_bytes(tmp_path):
    _ray_or_skip()
    reference = require_reference()
    gen = tmp_path / "gen"
    gen.mkdir()
    ladder = ladder_jobs("delivery", QUICK_LADDER, gen)
    for job in ladder:  # the generated missions are shared by the three runs: absolute paths
        job["inputs"] = [str((gen / p).resolve()) for p in job["inputs"]]
    manifest = json.dumps({"jobs": _reference_jobs(reference) + ladder})
    folders = {name: tmp_path / name for name in ("alone", "pool", "ray")}
    for folder in folders.values():
        folder.mkdir()
        (folder / "m.json").write_text(manifest)

    for job in read_manifest(folders["alone"] / "m.json"):  # each job alone, as a user runs it
        subprocess.run([sys.executable, "-m", "mutrose_cp", *job.command_line()], cwd=folders["alone"],
                       capture_output=True, timeout=300)
    pool = _batch(folders["pool"], "--jobs", "2")
    assert pool.returncode in (0, 1), pool.stderr  # 1: a reference mission without a valid decomposition
    # on Ray: interrupted once some jobs are done, then run again to finish
    journal = folders["ray"] / "m.results.jsonl"
    first = subprocess.Popen([sys.executable, "-m", "mutrose_cp", "batch", "m.json", "--ray", "--jobs", "2"],
                             cwd=folders["ray"], stdout=subprocess.DEVNULL, stderr=subprocess.PIPE, text=True)
    deadline = time.monotonic() + 300
    while not (journal.exists() and len(journal.read_text().splitlines()) >= 3):
        assert first.poll() is None and time.monotonic() < deadline, first.communicate()
        time.sleep(0.05)
    first.send_signal(signal.SIGINT)
    _, err = first.communicate(timeout=120)
    assert first.returncode == 130 and "interrupted (SIGINT)" in err and "Traceback" not in err, err
    done = len(journal.read_text().splitlines())
    assert 3 <= done < len(ladder) + len(_reference_jobs(reference))
    deadline = time.monotonic() + 10  # the cancelled jobs' processes get their SIGKILL
    while job_processes(folders["ray"]):
        assert time.monotonic() < deadline, "a job of the interrupted batch is still running"
        time.sleep(0.05)
    ray = _batch(folders["ray"], "--ray", "--jobs", "2")
    assert ray.returncode == pool.returncode, ray.stderr
    assert f"{done} skipped" in ray.stderr and "Ray (a local cluster, 2 CPUs)" in ray.stderr, ray.stderr

    alone = _outputs(folders["alone"])
    assert len(alone) == sum(1 for line in _settled(folders["pool"]) if line[1] == "ok")  # one file per job done
    assert "delivery-100-cpsat-optimize.json" in alone and "room-preparation-configuration.xml.out" in alone
    assert _outputs(folders["pool"]) == alone
    assert _outputs(folders["ray"]) == alone
    assert _settled(folders["ray"]) == _settled(folders["pool"])
    statuses = {line[0]: line[1] for line in _settled(folders["pool"])}
    assert all(statuses[job["id"]] == "ok" for job in ladder)


@pytest.mark.ray
def test_an_address_where_no_cluster_answers_is_refused_at_once(tmp_path):
    _ray_or_skip()
    with socket.socket() as free:  # a port nothing listens on
        free.bind(("127.0.0.1", 0))
        port = free.getsockname()[1]
    (tmp_path / "m.json").write_text(json.dumps([{"command": "count", "inputs": [str(ROOT / "examples" / "item-delivery")]}]))
    run = _batch(tmp_path, "--ray", f"127.0.0.1:{port}")
    assert run.returncode == 2
    assert f"error: --ray: nothing answers at 127.0.0.1:{port}" in run.stderr
    assert not (tmp_path / "m.results.jsonl").exists()
