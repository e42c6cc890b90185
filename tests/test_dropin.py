"""The ``mutrose`` drop-in, called exactly as the tools that use the original call it.

* the 2D MutRoSe simulator runs ``mutrose HDDL GM CONFIG`` in the mission folder and reads the
  file at the configuration's ``output.file_path``;
* the VS Code plug-in writes the goal model to ``./temp.txt`` in its workspace, runs
  ``mutrose <hddl> ./temp.txt <config> -p`` there and shows stdout (or, with ``-h``, reads
  ``./ihtn``).

Each run is a separate process in a temporary copy of a reference mission (without its
``output/`` folder), with the relative paths the tools pass.
"""
from __future__ import annotations

import json
import os
import re
import shutil
import subprocess
import sys
import tomllib
from pathlib import Path

import pytest

from mutrose_cp.cli.dropin import ALGORITHM_ENV, MISSING, Invocation, Usage, main, parse
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.solve.decompose import Algorithm

from conftest import ROOT, require_reference
from test_conformance import _cases, _comparator, _golden_path

MISSIONS = _cases("missions")
DELIVERY = ROOT / "examples" / "item-delivery"


def _mutrose(args: list[str], cwd: Path, **env: str) -> subprocess.CompletedProcess:
    """The command as a process, the way a tool starts it (the installed console script runs
    ``mutrose_cp.cli.dropin:entry``, as ``python -m mutrose_cp.cli.dropin`` does)."""
    return subprocess.run([sys.executable, "-m", "mutrose_cp.cli.dropin", *args], cwd=cwd, capture_output=True,
                          text=True, timeout=300, env={**os.environ, **env})


def _copy(mission: Path, tmp_path: Path) -> Path:
    folder = tmp_path / mission.name
    shutil.copytree(mission, folder, ignore=shutil.ignore_patterns("output", "ihtn"))
    return folder


def _relative(mission: Path, cfg: Path) -> tuple[str, str, str]:
    hddl, gm, _ = find_mission_files(mission, cfg.name)
    return f"hddl/{hddl.name}", f"gm/{gm.name}", f"configuration/{cfg.name}"


def _same_output(golden: Path, produced: Path) -> None:
    """JSON outputs agree as the reference comparison says (ids, constraints and mission
    decompositions as sets, every task field); XML outputs byte for byte."""
    assert produced.is_file(), f"no output at {produced}"
    if golden.read_bytes().lstrip().startswith(b"{"):  # some JSON configurations ask for XML output
        compare = _comparator()
        for level in ("structure", "full"):
            results, failures = compare.compare(str(golden), str(produced), level)
            assert all(results), f"{level}: " + "\n".join(failures)
    else:
        assert produced.read_bytes() == golden.read_bytes()


@pytest.mark.parametrize("mission,cfg", MISSIONS)
def test_simulator_invocation(mission, cfg, tmp_path):
    """``mutrose HDDL GM CONFIG`` in the mission folder writes the configuration's output file."""
    require_reference()
    folder = _copy(mission, tmp_path)
    run = _mutrose(list(_relative(mission, cfg)), folder)
    assert run.returncode == 0, run.stdout + run.stderr
    golden = _golden_path(mission, cfg)
    _same_output(golden, folder / golden.relative_to(mission))


@pytest.mark.parametrize("mission,cfg", MISSIONS)
def test_exploratory_drop_in_writes_the_goldens_byte_for_byte(mission, cfg, tmp_path):
    require_reference()
    folder = _copy(mission, tmp_path)
    run = _mutrose(list(_relative(mission, cfg)), folder, **{ALGORITHM_ENV: "exploratory"})
    assert run.returncode == 0, run.stdout + run.stderr
    golden = _golden_path(mission, cfg)
    assert (folder / golden.relative_to(mission)).read_bytes() == golden.read_bytes()


def _golden_counts(golden: dict) -> dict[str, int]:
    """Constraints of a golden output by kind (a fallback is written as EC without flags)."""
    constraints = golden["constraints"] or []
    return {"sequential": sum(c["type"] == "SEQ" for c in constraints),
            "execution": sum(c["type"] == "EC" and "group" in c for c in constraints),
            "fallback": sum(c["type"] == "EC" and "group" not in c for c in constraints)}


def _blocks(stdout: str) -> dict[str, str]:
    """The ``-p`` blocks by title, in the order printed."""
    found = re.findall(r"^-+ ([A-Z ]+) -+\n(.*?)^-+$", stdout, re.M | re.S)
    return {title: body for title, body in found}


def _json_golden(case) -> bool:
    mission, cfg = case.values
    return mission is None or _golden_path(mission, cfg).read_bytes().lstrip().startswith(b"{")


TASK_ID = re.compile(r"^Task \[\S+\] With ID \[(\S+)\] ", re.M)


@pytest.mark.parametrize("mission,cfg", [c for c in MISSIONS if _json_golden(c)])
def test_plug_in_invocation_prints_the_three_blocks(mission, cfg, tmp_path):
    """``mutrose <hddl> ./temp.txt <config> -p`` in the workspace: the three blocks hold the
    golden output's task decompositions, constraint counts and mission decompositions (their
    exact bytes are checked in test_console_exact.py), and the output file is written."""
    require_reference()
    workspace = _copy(mission, tmp_path)
    hddl, gm, config = _relative(mission, cfg)
    shutil.copy(workspace / gm, workspace / "temp.txt")
    run = _mutrose([hddl, "./temp.txt", config, "-p"], workspace)
    assert run.returncode == 0, run.stdout + run.stderr
    blocks = _blocks(run.stdout)
    assert list(blocks) == ["GENERATED TASK INSTANCES", "MISSION CONSTRAINTS", "POSSIBLE MISSION DECOMPOSITIONS"]
    golden_path = _golden_path(mission, cfg)
    golden = json.loads(golden_path.read_text())
    ids = {t["id"] for t in golden["tasks"].values()}
    assert set(TASK_ID.findall(blocks["GENERATED TASK INSTANCES"])) == ids
    counts = dict(re.findall(r"^Number of (\w+)(?: Mission)? [Cc]onstraints: (\d+)$", blocks["MISSION CONSTRAINTS"], re.M))
    assert {k.lower(): int(v) for k, v in counts.items()} == _golden_counts(golden)
    missions = re.findall(r"^@+ MISSION (\d+) @+\n(.*?)^@+$", blocks["POSSIBLE MISSION DECOMPOSITIONS"], re.M | re.S)
    assert [int(n) for n, _ in missions] == list(range(1, len(missions) + 1))
    printed = [TASK_ID.findall(body) for _, body in missions]
    key = {k: t["id"] for k, t in golden["tasks"].items()}
    assert printed == [[key[t] for t in md] for md in golden["mission_decompositions"]]  # the original's order
    _same_output(golden_path, workspace / golden_path.relative_to(mission))


@pytest.mark.parametrize("mission,cfg", [c for c in _cases("ihtn") if c.values[1] is None or c.values[1].suffix == ".json"])
def test_plug_in_ihtn_invocation(mission, cfg, tmp_path):
    """``-h`` writes ``./ihtn/ihtn_<n>.json``, numbered as the original numbers them, and no
    output file."""
    require_reference()
    workspace = _copy(mission, tmp_path)
    (workspace / "ihtn").mkdir()
    (workspace / "ihtn" / "ihtn_99.json").write_text("{}")  # from an earlier, larger export
    run = _mutrose([*_relative(mission, cfg), "-h"], workspace)
    assert run.returncode == 0, run.stdout + run.stderr
    suffix = cfg.stem.removeprefix("configuration")
    golden_dir = mission / "ihtn" / suffix if suffix else mission / "ihtn"
    expected = sorted(p.name for p in golden_dir.glob("ihtn_*.json"))
    assert sorted(p.name for p in (workspace / "ihtn").iterdir()) == expected
    for name in expected:
        assert json.loads((workspace / "ihtn" / name).read_text()) == json.loads((golden_dir / name).read_text()), name
    assert not (workspace / "output").exists()


def test_the_package_installs_the_mutrose_command():
    scripts = tomllib.loads((ROOT / "pyproject.toml").read_text())["project"]["scripts"]
    assert scripts["mutrose"] == "mutrose_cp.cli.dropin:entry"
    installed = Path(sys.executable).parent / "mutrose"
    if installed.exists():  # an installed package (CI): the script itself answers
        run = subprocess.run([str(installed)], capture_output=True, text=True, timeout=60)
        assert (run.returncode, run.stdout, run.stderr) == (1, "", MISSING[0] + "\n")


# -- the command line, in process ----------------------------------------------------------------


def test_unknown_options_are_reported_and_ignored(capsys):
    inv = parse(["d.hddl", "gm.txt", "c.json", "-x", "-p", "--quiet"], {})
    assert inv == Invocation(("d.hddl", "gm.txt", "c.json"), pretty=True)
    assert capsys.readouterr().err == "\nUnknown option [-x]\nUnknown option [--quiet]\n\n"


@pytest.mark.parametrize("argv,message,status", [
    ([], MISSING[0], 1),
    (["d.hddl"], MISSING[1], 1),
    (["d.hddl", "gm.txt"], MISSING[2], 1),
    (["d.hddl", "gm.txt", "c.json", "-v", "-p"], "Options -v and -p cannot be used together!", 1),
    (["d.hddl", "gm.txt", "c.json", "--algorithm=fast"], "--algorithm: unknown decomposer 'fast': choose cpsat or "
                                                         "exploratory", 2),
    (["d.hddl", "gm.txt", "c.json", "--ihtn-max=0"], "--ihtn-max=0: expected a whole number of files, at least 1", 2),
])
def test_usage_errors_have_the_original_messages_and_statuses(argv, message, status, capsys):
    assert main(argv) == status
    captured = capsys.readouterr()  # on stderr, which the plug-in shows when the command fails
    assert captured.err.strip() == message and captured.out == ""


def test_the_decomposer_is_chosen_by_environment_or_option():
    files = ["d.hddl", "gm.txt", "c.json"]
    assert parse(files, {}).algorithm == Algorithm.CPSAT
    assert parse(files, {ALGORITHM_ENV: "exploratory"}).algorithm == Algorithm.EXPLORATORY
    assert parse([*files, "--algorithm=exploratory"], {ALGORITHM_ENV: "cpsat"}).algorithm == Algorithm.EXPLORATORY
    with pytest.raises(Usage, match="MUTROSE_ALGORITHM"):
        parse(files, {ALGORITHM_ENV: "quantum"})


def test_an_unopenable_file_is_named_as_the_original_names_it(tmp_path, capsys, monkeypatch):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "d.hddl").write_text("")
    assert main(["d.hddl", "missing.txt", "c.json", "-p"]) == 2
    assert capsys.readouterr().err == "I can't open missing.txt!\n"


def test_bad_input_gives_located_errors_on_stderr_without_traceback(mission, capsys, monkeypatch):
    monkeypatch.chdir(mission)
    hddl = next((mission / "hddl").glob("*.hddl"))
    hddl.write_text(hddl.read_text().replace("(:method", "(:methd", 1))
    hddl_arg, gm, cfg = (str(p.relative_to(mission)) for p in find_mission_files(mission))
    assert main([hddl_arg, gm, cfg]) == 2
    captured = capsys.readouterr()
    out = captured.err
    assert captured.out == ""
    assert re.search(rf"^error: {re.escape(hddl_arg)}:\d+:\d+: ", out, re.M), out
    assert "Traceback" not in out and not (mission / "output").exists()


def test_an_oversized_ihtn_export_is_refused_before_writing(tmp_path, capsys, monkeypatch):
    folder = _copy(DELIVERY, tmp_path)
    monkeypatch.chdir(folder)
    files = [str(p.relative_to(folder)) for p in find_mission_files(folder)]
    assert main([*files, "-h", "--ihtn-max=719"]) == 2
    out = capsys.readouterr().err
    assert "error: ihtn: the iHTN export would write 720 files, over --ihtn-max 719" in out
    assert "raise the bound with --ihtn-max=N" in out and "--limit" not in out  # only what mutrose takes
    assert not (folder / "ihtn").exists() or not any((folder / "ihtn").iterdir())
    assert main([*files, "-h", "--ihtn-max=720"]) == 0
    assert len(list((folder / "ihtn").glob("ihtn_*.json"))) == 720


def test_verbose_trace_shows_every_stage(tmp_path, capsys, monkeypatch):
    mission = require_reference() / "missions" / "room-preparation"
    folder = _copy(mission, tmp_path)
    monkeypatch.chdir(folder)
    cfg = folder / "configuration" / "configuration.json"
    assert main([*_relative(mission, cfg), "-v"]) == 0
    out = capsys.readouterr().out
    sections = re.findall(r"^==== ([a-z]+(?: [a-z]+)*)", out, re.M)
    assert sections == ["inputs", "runtime annotation", "task instances", "decomposition paths",
                        "initial world state", "task graph", "valid mission decompositions"]
    assert "(G2;(((AT1_1;(G8;AT2_1))#AT3_1)#((AT1_2;(G8;AT2_2))#AT3_2)))" in out
    assert "AT3_1: FurnitureMoving (?rm = RoomA) at location [RoomA], robots 2..4" in out
    assert "Number of Sequential Mission Constraints: 8" in out  # the -p block's wording
    assert (folder / "output" / "task_output.json").is_file()


PROBE = """
import json, sys, io, contextlib
from mutrose_cp.cli.dropin import main
with contextlib.redirect_stdout(io.StringIO()):
    status = main(sys.argv[1:])
print(json.dumps([status, sorted(m for m in sys.modules if m.startswith(("mutrose_cp", "ortools", "numpy")))]))
"""


@pytest.mark.parametrize("option", ["-p", "-h"])
def test_the_plug_in_calls_load_only_what_they_use(option, tmp_path):
    """``-p`` prints and writes the output file: it loads neither the iHTN export nor the other
    commands (mutrose-cp's own command line) nor CP-SAT for a mission of tiny components;
    ``-h`` loads the export."""
    mission = require_reference() / "missions" / "room-preparation"
    folder = _copy(mission, tmp_path)
    run = subprocess.run([sys.executable, "-c", PROBE, *_relative(mission, mission / "configuration" / "configuration.json"),
                          option], cwd=folder, capture_output=True, text=True, timeout=300)
    status, modules = json.loads(run.stdout.strip().splitlines()[-1])
    assert status == 0, run.stderr
    assert ("mutrose_cp.output.ihtn" in modules) == (option == "-h")
    assert not {"mutrose_cp.cli.program", "ortools", "numpy"} & set(modules)
    assert "mutrose_cp.output.lexer_echo" in modules and ("mutrose_cp.output.console" in modules) == (option == "-p")


def test_a_closed_stdout_ends_with_a_message_not_a_traceback(tmp_path):
    """``mutrose … -p | head -1``: the reader goes away while the blocks are printed."""
    mission = require_reference() / "missions" / "lab-samples-logistics"
    folder = _copy(mission, tmp_path)
    read_end, write_end = os.pipe()
    os.close(read_end)  # every write to stdout now fails with EPIPE
    try:
        run = subprocess.run([sys.executable, "-m", "mutrose_cp.cli.dropin",
                              *_relative(mission, mission / "configuration" / "configuration.json"), "-p"],
                             cwd=folder, stdout=write_end, stderr=subprocess.PIPE, text=True, timeout=300)
    finally:
        os.close(write_end)
    assert run.returncode == 2
    assert run.stderr.strip() == "error: standard output: the reader closed the pipe; the output was not written"
