"""``allocate``'s limits hold whatever the inputs, and bad fleet files are located errors.

* The time limit is shared phase by phase (``allocate/phases.py``): a phase with no time left is
  skipped, one its share ends is cut, and each is reported (``--json-summary`` key ``phases``).
  The tests assert on what is reported, not on how long the test took.
* Fleet files that once crashed the command (a number too large for a float, half of a UTF-16
  pair in a name, a robot without its capabilities) and robot names that matplotlib reads as its
  mathematical notation are located errors with exit 2, or drawn as they are written.

Every file is made in a temporary folder.
"""
from __future__ import annotations

import json
import sys
import time
from pathlib import Path

import pytest

from allocation_checker import check_allocation
from mutrose_cp.allocate import AllocationOptions, Fleet
import mutrose_cp.allocate.output  # noqa: F401  the solvers loaded before any limit counts
from mutrose_cp.allocate.budget import Budget
from mutrose_cp.api import Mission, find_mission_files
from mutrose_cp.cli.program import main

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from allocation import generate  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DELIVERY = ROOT / "examples" / "item-delivery"
FLEET = DELIVERY / "fleet.json"
PHASES = ["problem", "load", "warm", "lp", "model", "search"]


def run(tmp_path: Path, mission: Path, fleet: Path, *extra: str) -> tuple[int, Path, Path]:
    out, schedule = tmp_path / "out.json", tmp_path / "schedule.json"
    status = main(["allocate", str(mission), "--fleet", str(fleet), "-o", str(out), "--schedule", str(schedule), "-q",
                   *extra])
    return status, out, schedule


def write(tmp_path: Path, text: str, name: str = "fleet.json") -> Path:
    path = tmp_path / name
    path.write_text(text, encoding="utf-8")
    return path


# ----------------------------------------------------------------------------------------------
# the time limit, phase by phase


def test_a_large_fleet_reports_every_phase_within_the_limit(tmp_path, capsys):
    """80,000 robots for four deliveries in three seconds, reading the fleet included: the work
    that grows with the fleet (the ways in of every robot, an LP column per kind of robot and
    task, the list schedule) stops with its share, so the phases report no more than the limit between them, some of
    them cut or skipped, and the schedule (the warm start's, or the search's) is a valid one."""
    mission, fleet = generate(4, 80_000, tmp_path)
    status, out, schedule = run(tmp_path, mission, fleet, "--time-limit", "3", "--json-summary")
    captured = capsys.readouterr()
    assert status == 0, captured.err
    summary = json.loads(captured.out)
    phases = summary["phases"]
    assert [p["phase"] for p in phases] == PHASES
    assert all(p["status"] in ("done", "cut", "skipped") for p in phases)
    assert sum(p["seconds"] for p in phases) <= 3.0 + 0.3, phases  # as reported: each phase within its share
    assert any(p["status"] in ("cut", "skipped") for p in phases if p["phase"] != "search"), phases
    assert summary["robots_used"] >= 1 and summary["tasks"] >= 4
    check_allocation(Mission.load(*find_mission_files(mission)), fleet, schedule, out)


def test_a_phase_without_time_left_is_skipped_and_said_so(tmp_path, monkeypatch, capsys):
    """A warm start that leaves less than the search's tenth: the LP bound and the model are
    skipped (the search with them), the warm start's schedule is the result, and the summary
    says which phases were skipped."""
    from mutrose_cp.allocate import phases as phases_module
    from mutrose_cp.allocate import stages

    made: list = []
    real_init, real_warm_start = phases_module.Phases.__init__, stages.warm_start

    def recording_init(self, *args, **kwargs):
        real_init(self, *args, **kwargs)
        made.append(self)

    def slow_warm_start(*args, **kwargs):
        found = real_warm_start(*args, **kwargs)
        phases = made[-1]  # as if it had taken nearly all the time
        time.sleep(max(0.0, phases.started + 0.98 * phases.budget.seconds - time.perf_counter()))
        return found

    monkeypatch.setattr(phases_module.Phases, "__init__", recording_init)
    monkeypatch.setattr(stages, "warm_start", slow_warm_start)
    result = Mission.load(*find_mission_files(DELIVERY)).allocate(Fleet.read(FLEET), AllocationOptions(time_limit=2))
    assert [(p.name, p.status, p.note) for p in result.phases][3:5] == [
        ("lp", "skipped", "no time left"), ("model", "skipped", "no time left")]
    assert result.phases[5].name == "search" and result.phases[5].status == "skipped"
    assert result.status == "FEASIBLE" and result.cp_bound is None  # the warm start's schedule
    status, _, _ = run(tmp_path, DELIVERY, FLEET, "--time-limit", "2", "--json-summary")
    captured = capsys.readouterr()
    summary = json.loads(captured.out)
    assert status == 0 and [p["status"] for p in summary["phases"]][3:] == ["skipped"] * 3


def test_the_shares_are_of_the_time_left_when_the_allocation_starts(monkeypatch):
    """A limit that counts from the start of the command shares what reading the inputs left;
    a phase that would get less than a few milliseconds is skipped; a work budget has fixed
    shares and no clock."""
    from mutrose_cp.allocate import phases as phases_module
    from mutrose_cp.allocate.phases import Phases

    now = [100.0]
    monkeypatch.setattr(phases_module.time, "perf_counter", lambda: now[0])
    phases = Phases(Budget(10.0), started=96.0)  # reading took 4 of the 10 s
    assert phases.total == 6.0
    assert phases.share(0.25, keep=0.1) == Budget(1.5)
    now[0] = 105.0  # 1 s left
    assert phases.share(0.25, keep=0.1).seconds == pytest.approx(0.4) and phases.share(0.25, keep=0.2) is None
    now[0] = 106.0
    assert phases.share(1.0) is None
    work = Phases(Budget(10.0, 4.0), started=0.0)
    assert work.share(0.25, keep=0.9) == Budget(2.5, 1.0)


def test_a_computation_past_its_deadline_is_stopped():
    """What cannot be interrupted in this process (Clarabel's setup) runs in a child that the
    deadline ends; a result, and an exception, come back from it."""
    from mutrose_cp.allocate.timed import run_within

    assert run_within(lambda: time.sleep(30), 0.2) == (False, None)
    assert run_within(lambda: ("Solved", 1.5), 10.0) == (True, ("Solved", 1.5))
    with pytest.raises(ZeroDivisionError):
        run_within(lambda: 1 / 0, 10.0)


def test_many_junctions_in_the_road_network(tmp_path):
    """A travel table of 3,000 junctions (a grid of roads), every robot starting at one: the
    quickest trips are found from the places the schedule uses, not between every two
    junctions, and match the roads (checked by the checker's own reading of the table)."""
    mission, fleet = generate(3, 30, tmp_path)
    data = json.loads(fleet.read_text())
    side = 60
    junctions = [f"J{i}" for i in range(side * 50)]
    times: dict[str, dict[str, int]] = {}
    for i, name in enumerate(junctions):
        if (i + 1) % side:
            times.setdefault(name, {})[junctions[i + 1]] = 5
        if i + side < len(junctions):
            times.setdefault(name, {})[junctions[i + side]] = 7
    world = (mission / "knowledge" / "world_db.xml").read_text()
    places = sorted(set(part.split("</name>")[0] for part in world.split("<Location><name>")[1:]))
    for k, place in enumerate(places):
        times[place] = {junctions[(37 * k) % len(junctions)]: 3, junctions[(91 * k + 5) % len(junctions)]: 4}
    data["travel"] = {"times": times}
    for k, robot in enumerate(data["robots"]):
        robot["start"] = junctions[(53 * k) % len(junctions)]
    fleet.write_text(json.dumps(data))
    status, out, schedule = run(tmp_path, mission, fleet, "--time-limit", "5")
    assert status == 0
    check_allocation(Mission.load(*find_mission_files(mission)), fleet, schedule, out)


# ----------------------------------------------------------------------------------------------
# fleet files that crashed the command: located errors, exit 2, on check --fleet and allocate


def _refused(tmp_path: Path, capsys, fleet: Path, *expected: str) -> None:
    for command in (["check", str(DELIVERY), "--fleet", str(fleet), "-q"],
                    ["allocate", str(DELIVERY), "--fleet", str(fleet), "-q", "-o", str(tmp_path / "out.json")]):
        assert main(command) == 2
        err = capsys.readouterr().err
        assert "Traceback" not in err
        for text in expected:
            assert text in err, err
    assert not (tmp_path / "out.json").exists()


@pytest.mark.parametrize("number,shown", [("1" + "0" * 400, "10000000... (401 digits)"),
                                          ("-" + "9" * 5000, "-9999999... (5000 digits)")])
def test_an_integer_too_large_for_a_float_is_out_of_range(tmp_path, capsys, number, shown):
    fleet = write(tmp_path, '{"robots": [{"name": "r1", "capabilities": ["navigation"],\n'
                            f'   "speed": {number}}}], "durations": {{"default": {number}}}}}')
    _refused(tmp_path, capsys, fleet, f"{fleet}:2:13: robots[0].speed: {shown} is out of range",
             f"durations.default: {shown} is out of range: give a number from 0 to 1e+06")
    with pytest.raises(Exception, match="is out of range"):  # the API reads it alike
        Fleet.read(fleet)


def test_a_float_beyond_the_largest_is_out_of_range(tmp_path, capsys):
    fleet = write(tmp_path, '{"robots": [{"name": "r1", "capabilities": [], "speed": 1e400}]}')
    _refused(tmp_path, capsys, fleet, f"{fleet}:1:57: robots[0].speed: a number beyond 1.8e+308 is out of range")


def test_half_of_a_utf16_pair_in_a_name_is_refused(tmp_path, capsys):
    """JSON's ``\\ud800`` alone decodes to no character: a robot name, a capability or a key
    holding one is refused where it is (it would fail the solver's names and the schedule)."""
    fleet = write(tmp_path, '{"robots": [{"name": "\\ud800", "capabilities": ["navigation"]},\n'
                            ' {"name": "r2", "capabilities": ["nav\\udfffigation"]}],\n'
                            ' "durations": {"actions": {"\\ud83d": 3}}}')
    _refused(tmp_path, capsys, fleet,
             f"{fleet}:1:22: robots[0].name: the string '\\ud800' holds a lone surrogate (\\ud800)",
             f"{fleet}:2:34: robots[1].capabilities[0]: the string 'nav\\udfffigation' holds a lone surrogate",
             f"{fleet}:3:28: durations.actions.\\ud83d: the key '\\ud83d' holds a lone surrogate")
    pair = write(tmp_path, '{"robots": [{"name": "\\ud83d\\ude00", "capabilities": []}]}', "pair.json")
    assert Fleet.read(pair).robots[0].name == "\N{GRINNING FACE}"  # a whole pair is a character
    with pytest.raises(Exception, match="holds a lone surrogate"):  # a program's text may hold one as it is
        Fleet.parse('{"robots": [{"name": "a\ud800", "capabilities": []}]}')


def test_a_robot_without_capabilities_is_refused(tmp_path, capsys):
    """The fleet format requires the key (``[]`` for a robot that can do nothing)."""
    fleet = write(tmp_path, '{"robots": [{"name": "r1", "capabilities": ["navigation"]},\n'
                            '  {"name": "r2", "start": "Dock"}]}')
    _refused(tmp_path, capsys, fleet, f'{fleet}:2:3: robots[1]: missing key "capabilities"')
    assert Fleet.read(write(tmp_path, '{"robots": [{"name": "r", "capabilities": []}]}', "none.json"))


# ----------------------------------------------------------------------------------------------
# the Gantt chart: names as they are written, and nothing written when it fails


TEX_NAMES = ["$x^", "a$b", "$x^$", "$\\frac{1}{$"]


def test_robot_names_are_drawn_as_written(tmp_path):
    """Names with dollar signs are text: matplotlib would read ``$x^$`` as its mathematical
    notation, fail on it and lose the chart after the search."""
    pytest.importorskip("matplotlib")
    data = json.loads(FLEET.read_text())
    data["robots"] += [{"name": name, "capabilities": ["navigation"]} for name in TEX_NAMES]
    fleet = write(tmp_path, json.dumps(data))
    chart = tmp_path / "chart.svg"
    status, out, schedule = run(tmp_path, DELIVERY, fleet, "--gantt", str(chart), "--time-limit", "20")
    assert status == 0 and out.exists() and schedule.exists()
    svg = chart.read_text(encoding="utf-8")
    for name in TEX_NAMES:  # each label is one text, its characters as written (the SVG names it)
        assert f"<!-- {name} -->" in svg, name


def test_a_chart_that_fails_leaves_nothing_written(tmp_path, monkeypatch, capsys):
    """The chart is drawn before the schedule is written, so a chart that cannot be drawn
    leaves no file, and nothing on standard output either (``--schedule -``)."""
    pytest.importorskip("matplotlib")
    from mutrose_cp.allocate import gantt
    from mutrose_cp.errors import MissionError

    def failing(*_args, **_kwargs):
        raise MissionError("cannot draw the chart", "chart.png")

    monkeypatch.setattr(gantt, "save_chart", failing)
    out = tmp_path / "out.json"
    status = main(["allocate", str(DELIVERY), "--fleet", str(FLEET), "-o", str(out), "--schedule", "-",
                   "--gantt", str(tmp_path / "chart.png"), "--time-limit", "20", "-q"])
    captured = capsys.readouterr()
    assert status == 2 and "cannot draw the chart" in captured.err
    assert captured.out == "" and sorted(p.name for p in tmp_path.iterdir()) == []
