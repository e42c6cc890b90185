"""The output rules, for every file option of every command, found in the parser.

Every option that names a file declares its kind with its argparse type (``option_types``:
``output_file``, ``output_folder``, ``input_file``).  The tests below walk the parser, so a new
option cannot escape them:

* every string-valued option is a path of a declared kind, or is listed here as text;
* every output option refuses an input of its command (the world file, which no option names)
  before any work, exit 2, located at the output, and leaves the input as it was;
* every output file option refuses an empty path and a path ending with ``/``;
* a FIFO that nobody reads, as an output, fails at once (no wait), and so does a FIFO input of
  the ``mutrose`` drop-in;
* a command that writes several files replaces all of them or none.
"""
from __future__ import annotations

import argparse
import json
import os
import shutil
import signal
import subprocess
import sys
from pathlib import Path

import pytest

from mutrose_cp.cli.parser import build_parser
from mutrose_cp.cli.program import main
from mutrose_cp.cli.option_types import PATH_TYPES, input_file, output_file, output_folder

ROOT = Path(__file__).resolve().parent.parent
DELIVERY = ROOT / "examples" / "item-delivery"

# string options that are not paths: what they name is explained beside each
TEXT_OPTIONS = {
    ("allocate", "--objective"),  # makespan | travel | weighted:A,B
    ("compare", "--original"),  # a program, found on PATH
    ("batch", "--ray"),  # a Ray address
    ("batch", "--each"),  # a glob pattern
    ("batch", "--output"),  # a pattern of output paths, {name} filled per job (each job checks its own)
}


def _subcommands(parser: argparse.ArgumentParser) -> dict[str, argparse.ArgumentParser]:
    for action in parser._actions:  # argparse keeps its subparsers here
        if isinstance(action, argparse._SubParsersAction):
            return dict(action.choices)
    return {}


def _string_options(parser: argparse.ArgumentParser) -> list[argparse.Action]:
    """Options that take one string (not flags, counts, numbers or choices)."""
    return [a for a in parser._actions
            if a.option_strings and isinstance(a, argparse._StoreAction) and a.choices is None
            and (a.type is None or a.type in PATH_TYPES) and a.nargs in (None, "?")]


def _options(kind) -> list[tuple[str, str]]:
    out = []
    for command, sub in _subcommands(build_parser()).items():
        for action in _string_options(sub):
            if action.type is kind:
                out.append((command, action.option_strings[-1]))
    return out


# path options not typed yet (none: a new one fails the test until it is typed or listed here)
UNTYPED: set[tuple[str, str]] = set()


def test_every_path_option_declares_its_kind():
    unclassified = {(command, action.option_strings[-1])
                    for command, sub in _subcommands(build_parser()).items()
                    for action in _string_options(sub)
                    if action.type is None and (command, action.option_strings[-1]) not in TEXT_OPTIONS}
    assert unclassified == UNTYPED, "give these options a path type (option_types) or list them as text"
    assert len(_options(output_file)) >= 8 and _options(output_folder) and _options(input_file)


@pytest.fixture()
def mission(tmp_path: Path) -> Path:
    folder = tmp_path / "mission"
    shutil.copytree(DELIVERY, folder)
    return folder


def _world_named(mission: Path, name: str) -> Path:
    """Rename the mission's world file to ``knowledge/NAME`` (the configuration follows)."""
    config = next((mission / "configuration").glob("*.json"))
    data = json.loads(config.read_text())
    world = mission / data["world_db"]["path"]
    renamed = world.with_name(name)
    world.rename(renamed)
    data["world_db"]["path"] = str(renamed.relative_to(mission))
    config.write_text(json.dumps(data))
    return renamed


def _batch_of(mission: Path) -> list[str]:
    """A batch of one job on the mission: its manifest beside the mission."""
    manifest = mission.parent / "m.json"
    manifest.write_text(json.dumps([{"command": "count", "inputs": [str(mission)]}]))
    return ["batch", "-q", str(manifest)]


# the smallest command line of each command that writes files, on the mission folder
BASE = {
    "batch": _batch_of,
    "decompose": lambda m: ["decompose", str(m), "-q"],
    "allocate": lambda m: ["allocate", str(m), "--fleet", str(m / "fleet.json"), "-q", "--time-limit", "10"],
    "graph": lambda m: ["graph", str(m), "-q"],
    "export-hddl": lambda m: ["export-hddl", str(m), "-q"],
    "compare": lambda m: ["compare", str(m), "-q"],
    "verify": lambda m: ["verify", str(m), "--property", "count uses(decomposition AT1_1|1)", "-q"],
}
# options the command needs, unless the test gives them
REQUIRED = {"graph": ("--output", "graph.dot"), "export-hddl": ("--output", "out.hddl")}
# the suffix the option's file must have (a chart's names its format; graph writes .dot as is)
SUFFIX = {"--gantt": ".svg", "--plot": ".svg", ("graph", "-o"): ".dot"}


@pytest.mark.parametrize(("command", "option"), _options(output_file) + _options(output_folder))
def test_every_output_option_refuses_an_input(mission: Path, capsys, command: str, option: str):
    """The world file is an input of every command here that no option names: each output
    option pointed at it is refused before any work, and nothing is written."""
    if command not in BASE:
        pytest.fail(f"{command} {option}: add the command's smallest command line to BASE")
    suffix = SUFFIX.get((command, option), SUFFIX.get(option, ".xml"))
    world = _world_named(mission, "world" + suffix)
    before = world.read_bytes()
    target = world.parent if option in ("--ihtn", "--witness-dir") else world  # a folder that holds an input
    argv = BASE[command](mission) + [option, str(target)]
    required = REQUIRED.get(command)
    if required is not None and required[0] != option:
        argv += [required[0], str(mission.parent / required[1])]
    listed = sorted(str(p) for p in mission.parent.rglob("*"))
    status = main(argv)
    err = capsys.readouterr().err
    assert status == 2, err
    assert "would overwrite the input" in err or "holds the input" in err, err
    assert str(target) in err
    assert world.read_bytes() == before
    assert sorted(str(p) for p in mission.parent.rglob("*")) == listed  # nothing written


@pytest.mark.parametrize(("command", "option"), _options(output_file))
@pytest.mark.parametrize("value", ["", "out/"])
def test_every_output_file_option_refuses_a_path_that_names_no_file(mission: Path, capsys, command, option, value):
    argv = BASE[command](mission) + [option, value]
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert option in err and ("empty" in err or "ends with /" in err), err


def test_an_output_beside_a_file_where_a_folder_should_be(mission: Path, capsys):
    (mission.parent / "afile").write_text("x")
    assert main(["decompose", str(mission), "-q", "-o", str(mission.parent / "afile" / "out.json")]) == 2
    assert "is a file, not a folder" in capsys.readouterr().err


def test_ihtn_folder_that_is_a_file(mission: Path, capsys):
    (mission.parent / "afile").write_text("x")
    assert main(["decompose", str(mission), "-q", "--ihtn", str(mission.parent / "afile")]) == 2
    assert "cannot write the output files: it is a file; give a folder" in capsys.readouterr().err


def test_costs_file_as_the_output_is_refused(mission: Path, capsys):
    costs = mission.parent / "costs.json"
    costs.write_text('{"actions": {}}')
    assert main(["decompose", str(mission), "-q", "--optimize", "--costs", str(costs), "-o", str(costs)]) == 2
    assert "would overwrite the input" in capsys.readouterr().err
    assert costs.read_text() == '{"actions": {}}'


def test_graph_dot_fallback_onto_an_input_is_refused(mission: Path, capsys, monkeypatch):
    """Without Graphviz the picture's DOT text goes beside it: -o gm/NAME.png would write
    gm/NAME.dot, which is the goal model here."""
    gm = next((mission / "gm").iterdir())
    renamed = gm.with_suffix(".dot")
    gm.rename(renamed)
    monkeypatch.setenv("PATH", str(Path(sys.executable).parent))  # no dot there
    before = renamed.read_bytes()
    assert main(["graph", str(mission), "-q", "-o", str(renamed.with_suffix(".png"))]) == 2
    assert "would overwrite the input" in capsys.readouterr().err
    assert renamed.read_bytes() == before


def test_export_hddl_paths_that_name_no_file(mission: Path, capsys):
    for value in (".", str(mission)):
        assert main(["export-hddl", str(mission), "-q", "-o", value]) == 2
        assert "it is a folder" in capsys.readouterr().err
    assert main(["export-hddl", str(mission), "-q", "-o", "-"]) == 2
    assert "needs a file of its own" in capsys.readouterr().err
    assert not list(Path.cwd().glob("--problem*"))


@pytest.mark.parametrize("extra", [["-o", "-", "--json-summary"], ["-o", "-", "--schedule", "-"]])
def test_allocate_prints_one_document_on_standard_output(mission: Path, capsys, extra):
    argv = ["allocate", str(mission), "--fleet", str(mission / "fleet.json"), "-q", *extra]
    assert main(argv) == 2
    assert "would both print to standard output" in capsys.readouterr().err


def test_a_fifo_nobody_reads_fails_at_once(mission: Path, capsys):
    fifo = mission.parent / "out.json"
    os.mkfifo(fifo)
    proc = subprocess.run([sys.executable, "-m", "mutrose_cp", "decompose", str(mission), "-q", "-o", str(fifo)],
                          capture_output=True, text=True, timeout=60)
    assert proc.returncode == 2 and "no process is reading this FIFO" in proc.stderr
    assert "Traceback" not in proc.stderr


def test_dropin_does_not_wait_on_a_fifo_input(mission: Path):
    fifo = mission.parent / "domain.hddl"
    os.mkfifo(fifo)
    gm = next((mission / "gm").iterdir())
    config = next((mission / "configuration").iterdir())
    proc = subprocess.Popen([sys.executable, "-c", "from mutrose_cp.cli.dropin import entry; entry()",
                             str(fifo), str(gm), str(config)], cwd=mission, stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        out, err = proc.communicate(timeout=60)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGKILL)
        pytest.fail("mutrose waited on a FIFO input")
    assert proc.returncode == 2 and "not a regular file" in out + err and "Traceback" not in out + err


def test_allocate_replaces_all_its_files_or_none(mission: Path, capsys):
    """The chart is the last file written: when it fails (a FIFO nobody reads), the new schedule
    and decomposition written before it are dropped and the old ones stay."""
    pytest.importorskip("matplotlib")
    out, schedule, chart = (mission.parent / n for n in ("allocated.json", "schedule.json", "chart.png"))
    out.write_text("old decomposition")
    schedule.write_text("old schedule")
    os.mkfifo(chart)
    status = main(["allocate", str(mission), "--fleet", str(mission / "fleet.json"), "-q", "--time-limit", "10",
                   "-o", str(out), "--schedule", str(schedule), "--gantt", str(chart)])
    assert status == 2 and "no process is reading this FIFO" in capsys.readouterr().err
    assert out.read_text() == "old decomposition" and schedule.read_text() == "old schedule"
    assert not list(mission.parent.glob(".*.tmp"))
    os.unlink(chart)
    assert main(["allocate", str(mission), "--fleet", str(mission / "fleet.json"), "-q", "--time-limit", "10",
                 "-o", str(out), "--schedule", str(schedule), "--gantt", str(chart)]) == 0
    assert out.read_text() != "old decomposition" and schedule.read_text() != "old schedule" and chart.is_file()


def _files_up_to(size: int):
    def limit() -> None:
        import resource

        resource.setrlimit(resource.RLIMIT_FSIZE, (size, size))
    return limit


def test_allocate_on_a_full_disk_keeps_every_old_file(mission: Path):
    """The schedule (a few kB) fits under the file-size limit, the decomposition does not: the
    new schedule is dropped with it, and both old files stay."""
    out, schedule = mission.parent / "allocated.json", mission.parent / "schedule.json"
    out.write_text("old decomposition")
    schedule.write_text("old schedule")
    run = subprocess.run([sys.executable, "-m", "mutrose_cp", "allocate", str(mission), "--fleet",
                          str(mission / "fleet.json"), "-q", "--time-limit", "10", "-o", str(out),
                          "--schedule", str(schedule)], capture_output=True, text=True, timeout=120,
                         preexec_fn=_files_up_to(8000))
    assert run.returncode == 2, run.stderr
    assert f"error: {out}: cannot write the output: File too large" in run.stderr
    assert out.read_text() == "old decomposition" and schedule.read_text() == "old schedule"
    assert not list(mission.parent.glob(".*.tmp"))
