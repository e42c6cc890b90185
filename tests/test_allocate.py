"""``mutrose-cp allocate``: decomposition, robots and schedule chosen together, with travel.

Every schedule returned is verified rule by rule by ``allocation_checker`` (which shares no
code with the model).  The missions are small and the searches finish (OPTIMAL) well within
their limits, so the assertions do not depend on how far a search got; where a test cuts a
search short it accepts either outcome and checks what was reported.
"""
from __future__ import annotations

import json
import re
import shutil
import sys
from pathlib import Path

import pytest

from allocation_checker import AllocationRuleBroken, check_allocation
from mutrose_cp.api import Mission, find_mission_files
from mutrose_cp.cli.program import main

ROOT = Path(__file__).resolve().parent.parent
DELIVERY = ROOT / "examples" / "item-delivery"
HOSPITAL = ROOT / "examples" / "hospital-disinfection"
FLEET = DELIVERY / "fleet.json"


def allocate(tmp_path: Path, mission: Path, fleet: Path, *extra: str, name: str = "run") -> tuple[int, Path, Path]:
    out, schedule = tmp_path / f"{name}.json", tmp_path / f"{name}-schedule.json"
    status = main(["allocate", str(mission), "--fleet", str(fleet), "-o", str(out), "--schedule", str(schedule),
                   "-q", "--time-limit", "20", *extra])
    return status, out, schedule


def checked(tmp_path: Path, mission: Path, fleet: Path, *extra: str, name: str = "run") -> dict:
    status, out, schedule = allocate(tmp_path, mission, fleet, *extra, name=name)
    assert status == 0
    return check_allocation(Mission.load(*find_mission_files(mission)), fleet, schedule, out)


def write_fleet(tmp_path: Path, data: dict, name: str = "fleet.json") -> Path:
    path = tmp_path / name
    path.write_text(json.dumps(data, indent=1))
    return path


# ----------------------------------------------------------------------------------------------
# the example, end to end


def test_example_is_allocated_optimally_and_reproducibly(tmp_path):
    doc = checked(tmp_path, DELIVERY, FLEET)
    assert doc["objective"]["status"] == "OPTIMAL" and doc["objective"]["gap"] == 0
    assert doc["objective"]["kind"] == "makespan" and doc["objective"]["value"] == doc["makespan"]
    assert 0 < doc["objective"]["lp_bound"] <= doc["makespan"]
    assert doc["travel"] > 0  # the robots start at the dock and the ward
    output = json.loads((tmp_path / "run.json").read_text())
    assert len(output["mission_decompositions"]) == 1
    again = checked(tmp_path, DELIVERY, FLEET, name="again")
    assert (tmp_path / "run-schedule.json").read_bytes() == (tmp_path / "again-schedule.json").read_bytes()
    assert (tmp_path / "run.json").read_bytes() == (tmp_path / "again.json").read_bytes()
    assert again == doc


def test_travel_objective_and_weighted_sum(tmp_path):
    makespan = checked(tmp_path, DELIVERY, FLEET, name="makespan")
    travel = checked(tmp_path, DELIVERY, FLEET, "--objective", "travel", name="travel")
    weighted = checked(tmp_path, DELIVERY, FLEET, "--objective", "weighted:1,1", name="weighted")
    assert travel["objective"]["status"] == makespan["objective"]["status"] == "OPTIMAL"
    assert travel["travel"] <= makespan["travel"] and makespan["makespan"] <= travel["makespan"]
    assert weighted["objective"]["value"] == weighted["makespan"] + weighted["travel"]
    if weighted["objective"]["status"] == "OPTIMAL":
        assert weighted["objective"]["value"] <= makespan["makespan"] + makespan["travel"]


def test_fleet_capabilities_drive_the_decomposition(tmp_path):
    """Without a robot that can both pick and talk, delivery 1 (to the staffed WardA, where only
    hand-to-person is valid) cannot be done by one robot fetching it itself (G8: same robot for
    FetchItem and HandOver), so the staff-loading alternative G11 is chosen for it."""
    data = json.loads(FLEET.read_text())
    data["robots"] = [r for r in data["robots"] if r["name"] != "allrounder"]
    doc = checked(tmp_path, DELIVERY, write_fleet(tmp_path, data))
    chosen = {t["decomposition"] for t in doc["tasks"]}
    assert "AT3_1|1" in chosen and "AT1_1|1" not in chosen


def test_teams_fallbacks_and_a_travel_table(tmp_path):
    """Hospital disinfection: RobotNumber ranges ([2,3] teams), FB and Group=False, with travel
    from a table (times at speed 1, both directions) and a robot without a start."""
    mission = Mission.load(*find_mission_files(HOSPITAL))
    rooms = sorted({v.decomposition.instance.location for v in mission.task_graph.decompositions()
                    if isinstance(v.decomposition.instance.location, str)})
    times = {"Base": {room: 10 + 5 * i for i, room in enumerate(rooms)}}
    times.update({a: {b: 7 for b in rooms[i + 1:]} for i, a in enumerate(rooms)})
    capabilities = sorted({c for a in mission.domain.actions for c in a.capabilities})
    fleet = write_fleet(tmp_path, {
        "robots": [{"name": f"d{i}", "capabilities": capabilities, "start": "Base", "speed": 1 + i / 2}
                   for i in range(3)] + [{"name": "free", "capabilities": capabilities}],
        "durations": {"default": 3, "capabilities": {"spraying": 5}},
        "travel": {"times": times}})
    doc = checked(tmp_path, HOSPITAL, fleet)
    assert any(len(t["robots"]) >= 2 for t in doc["tasks"])  # a team task was staffed


def test_no_travel_without_coordinates(tmp_path):
    """A world and fleet without coordinates or a table: travel is not modelled (all 0)."""
    mission = tmp_path / "mission"
    shutil.copytree(DELIVERY, mission, ignore=shutil.ignore_patterns("output"))
    world = mission / "knowledge" / "world_db.xml"
    world.write_text(re.sub(r" ?<[xy]>[^<]*</[xy]>", "", world.read_text()))
    data = json.loads(FLEET.read_text())
    del data["travel"]
    for robot in data["robots"]:
        robot.pop("start")
    doc = checked(tmp_path, mission, write_fleet(tmp_path, data))
    assert doc["travel"] == 0 and doc["objective"]["status"] == "OPTIMAL"


def test_the_api_gives_the_same_schedule(tmp_path, monkeypatch):
    """... and each builds the travel table once: the command line checks the fleet with the
    table it then allocates with."""
    from mutrose_cp.allocate import AllocationOptions, Fleet, problem, travel
    from mutrose_cp.allocate.output import schedule_document

    built: list[set[str]] = []
    original = travel.build_travel

    def build_travel(mission, fleet, needed):
        built.append(set(needed))
        return original(mission, fleet, needed)

    for module in (travel, problem):  # wherever it is called from
        monkeypatch.setattr(module, "build_travel", build_travel)
    checked(tmp_path, DELIVERY, FLEET)
    assert len(built) == 1
    mission = Mission.load(*find_mission_files(DELIVERY))
    allocation = mission.allocate(Fleet.read(FLEET), AllocationOptions(time_limit=20))
    assert allocation.status == "OPTIMAL"
    assert schedule_document(allocation) == json.loads((tmp_path / "run-schedule.json").read_text())
    assert len(built) == 2 and built[0] == built[1]


# ----------------------------------------------------------------------------------------------
# the checker fails on broken schedules (it can fail)


@pytest.mark.parametrize("breakage,rule", [
    (lambda d: d["tasks"][0].update(robots=[]), "robot number"),
    (lambda d: d["robots"][0]["tasks"][0].update(start=d["robots"][0]["tasks"][0]["start"] - 1), "differs"),
    (lambda d: [t.update(start=t["start"] - 5, end=t["end"] - 5) for r in d["robots"] for t in r["tasks"][:1]]
     and [t.update(start=t["start"] - 5, end=t["end"] - 5) for t in d["tasks"]
          if t["decomposition"] in {r["tasks"][0]["decomposition"] for r in d["robots"] if r["tasks"]}],
     "overlap or trip"),
    (lambda d: d.update(travel=d["travel"] - 1), "misreported"),
    (lambda d: d["objective"].update(lp_bound=d["makespan"] + 1), "lp_bound above"),
])
def test_the_checker_catches_broken_schedules(tmp_path, breakage, rule):
    checked(tmp_path, DELIVERY, FLEET)
    path = tmp_path / "run-schedule.json"
    doc = json.loads(path.read_text())
    breakage(doc)
    path.write_text(json.dumps(doc))
    with pytest.raises(AllocationRuleBroken, match=rule):
        check_allocation(Mission.load(*find_mission_files(DELIVERY)), FLEET, path, tmp_path / "run.json")


# ----------------------------------------------------------------------------------------------
# no feasible allocation: exit 3, naming what is missing


def test_a_missing_capability_is_named(tmp_path, capsys):
    fleet = write_fleet(tmp_path, {"robots": [{"name": "walker", "capabilities": ["navigation"]}]})
    status, out, schedule = allocate(tmp_path, DELIVERY, fleet)
    err = capsys.readouterr().err
    assert status == 3
    assert "no valid mission decomposition can be allocated to this fleet" in err
    assert "needs manipulation: no robot of the fleet has it" in err or "needs communication" in err
    assert not out.exists() and not schedule.exists()


def test_a_missing_robot_number_is_named(tmp_path, capsys):
    """Without UV, a room is disinfected by the spray team (RobotNumber [2,3]): one robot is
    not enough."""
    mission = Mission.load(*find_mission_files(HOSPITAL))
    capabilities = sorted({c for a in mission.domain.actions for c in a.capabilities} - {"uv-irradiation"})
    fleet = write_fleet(tmp_path, {"robots": [{"name": "solo", "capabilities": capabilities}]})
    status, _, _ = allocate(tmp_path, HOSPITAL, fleet)
    err = capsys.readouterr().err
    assert status == 3
    assert "(UVDisinfection) needs uv-irradiation: no robot of the fleet has it" in err
    assert "(TeamDisinfection) needs 2 robots with" in err and "the fleet has 1" in err


# ----------------------------------------------------------------------------------------------
# fleet-file errors: located, all at once, exit 2


@pytest.mark.parametrize("text,expected", [
    ('{"robots": [{"name": "r1", "capabilities": ["navigation"]}],\n "durations": {"defualt": 2}}',
     ":2:16: durations.defualt: unknown key 'defualt'. Did you mean 'default'?"),
    ('{"robots": [{"name": "r1", "capabilities": ["navigation"],\n   "speed": -1}]}',
     ":2:13: robots[0].speed: -1 is out of range"),
    ('{"robots": [{"name": "r1", "capabilities": ["navigation"],\n   "speed": 1e-300}]}',
     ":2:13: robots[0].speed: 1e-300 is out of range: give a number from 0.001 to 1e+06"),
    ('{"robots": [{"name": "r1", "capabilities": []},\n {"name": "r1", "capabilities": []}]}',
     ":2:11: robots[1].name: robot 'r1' is listed twice"),
    ('{"robots": [{"name": "r1", "capabilities": []}], "durations": {"actions": {"navigate": 1.5}}}',
     ":1:88: durations.actions.navigate: expected a whole number, got 1.5"),
    ('{"robots": [{"name": "r1", "capabilities": []}],\n "travel": {"coordinates": {"Dock": [1]}}}',
     ":2:37: travel.coordinates.Dock: expected a point [x, y]"),
    ('{"robots": [}', ":1:13: invalid JSON"),
    ('{"robots": [{"name": "r1", "capabilities": [],\n   "name": "r2"}]}',
     ":2:4: robots[0].name: the key 'name' is given twice"),
    ('{"robots": [{"name": "NaN \\"r1", "capabilities": [],\n   "speed": NaN}]}',
     ":2:13: invalid JSON: NaN is not a JSON number"),
    ('{"robots": []}', ":1:12: robots: expected a non-empty list of robots"),
])
def test_fleet_file_errors_are_located(tmp_path, capsys, text, expected):
    fleet = tmp_path / "fleet.json"
    fleet.write_text(text)
    status, _, _ = allocate(tmp_path, DELIVERY, fleet)
    err = capsys.readouterr().err
    assert status == 2
    assert f"error: {fleet}{expected}" in err
    assert "Traceback" not in err


def test_every_fleet_problem_is_reported_at_once(tmp_path, capsys):
    fleet = write_fleet(tmp_path, {"robots": [{"name": "", "capabilities": "navigation", "speed": "fast"}],
                                   "travel": {"metric": "taxicab"}})
    assert main(["check", str(DELIVERY), "--fleet", str(fleet), "-q"]) == 2
    err = capsys.readouterr().err
    assert "robots[0].name" in err and "robots[0].capabilities" in err and "robots[0].speed" in err
    assert "travel.metric: unknown metric 'taxicab'" in err and "4 problems found" in err


def test_check_names_fleet_names_the_mission_does_not_know(tmp_path, capsys):
    data = json.loads(FLEET.read_text())
    data["robots"][0]["capabilities"].append("manipulaton")
    data["robots"][1]["start"] = "Dok"
    data["durations"]["actions"]["pick-itme"] = 3
    fleet = write_fleet(tmp_path, data)
    assert main(["check", str(DELIVERY), "--fleet", str(fleet), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{fleet}:5:20: unknown capability 'manipulaton'. Did you mean 'manipulation'?" in err
    assert "unknown place 'Dok'. Did you mean 'Dock'?" in err
    assert "unknown action 'pick-itme'. Did you mean 'pick-item'?" in err
    assert main(["check", str(DELIVERY), "--fleet", str(FLEET), "-q"]) == 0


def test_a_misspelt_place_of_the_travel_table_is_named(tmp_path, capsys):
    """A place only the table names, where no robot starts, on a single road, changes no time:
    a misspelt place, whose intended entry would silently be left out.  A junction (two roads)
    is a place of the road network."""
    data = json.loads(FLEET.read_text())
    data["travel"]["times"] = {"Dock": {"WardAA": 4}}
    fleet = write_fleet(tmp_path, data)
    assert main(["check", str(DELIVERY), "--fleet", str(fleet), "-q"]) == 2
    err = capsys.readouterr().err
    line = next(i for i, text in enumerate(fleet.read_text().splitlines(), 1) if '"WardAA"' in text)
    column = fleet.read_text().splitlines()[line - 1].index('"WardAA"') + 1
    assert f"{fleet}:{line}:{column}: unknown place 'WardAA': not a world location" in err
    assert "Did you mean 'WardA'?" in err
    data["travel"]["times"] = {"Dock": {"Junction": 4}, "Junction": {"WardA": 3}}
    assert main(["check", str(DELIVERY), "--fleet", str(write_fleet(tmp_path, data)), "-q"]) == 0


def test_a_task_place_without_coordinates_is_located_in_the_world(mission, tmp_path, capsys):
    world = mission / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace(" <x>30</x> <y>40</y>", "", 1))  # WardB
    fleet = write_fleet(tmp_path, {"robots": [{"name": "r", "capabilities": ["navigation", "manipulation",
                                                                               "communication"], "start": "WardA"}]})
    assert main(["check", str(mission), "--fleet", str(fleet), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{world}:" in err and "place WardB has no coordinates and no travel time to" in err


def test_bad_world_coordinates_are_located(mission, tmp_path, capsys):
    world = mission / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace("<x>30</x>", "<x>east</x>", 1))
    assert main(["check", str(mission), "--fleet", str(FLEET), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{world}:" in err and "location SupplyRoom: x must be a number, got 'east'" in err
    world.write_text(world.read_text().replace("<x>east</x>", "<x>1e300</x>", 1))  # trip times of 300 digits
    assert main(["allocate", str(mission), "--fleet", str(FLEET), "-q", "-o", str(tmp_path / "o.json")]) == 2
    err = capsys.readouterr().err
    assert f"{world}:20: location SupplyRoom: x 1e300 is out of range: give a number from -1e+09 to 1e+09" in err


def test_bad_options_are_usage_errors(tmp_path, capsys):
    status, out, _ = allocate(tmp_path, DELIVERY, FLEET, "--objective", "fastest")
    assert status == 2 and "unknown objective 'fastest'" in capsys.readouterr().err and not out.exists()
    status, _, _ = allocate(tmp_path, DELIVERY, FLEET, "--gantt", str(tmp_path / "chart.pdf"))
    err = capsys.readouterr().err
    assert status == 2 and "--gantt: cannot tell the chart's format from" in err and "name a .png or .svg file" in err



@pytest.mark.parametrize("option,value,message", [
    ("--seed", str(2**40), "--seed: 1099511627776 is out of range: give a number from 0 to 2147483647"),
    ("--workers", "100000", "--workers: 100000 is out of range: give a number from 1 to 256"),
])
def test_solver_options_beyond_cp_sat_are_usage_errors(tmp_path, capsys, option, value, message):
    """CP-SAT takes a 32-bit seed (a larger one was a TypeError inside it) and fails at once with
    tens of thousands of threads (which read as a timeout)."""
    status, out, _ = allocate(tmp_path, DELIVERY, FLEET, option, value)
    err = capsys.readouterr().err
    assert status == 2 and message in err and "Traceback" not in err and not out.exists()
    from mutrose_cp.allocate import AllocationOptions
    from mutrose_cp.errors import MissionError

    with pytest.raises(MissionError, match="out of range"):
        AllocationOptions(**{option.lstrip("-"): int(value)})


# ----------------------------------------------------------------------------------------------
# the Gantt chart


@pytest.mark.parametrize("suffix", [".png", ".svg"])
def test_gantt_chart(tmp_path, suffix):
    pytest.importorskip("matplotlib")
    chart = tmp_path / f"chart{suffix}"
    status, _, _ = allocate(tmp_path, DELIVERY, FLEET, "--gantt", str(chart))
    assert status == 0
    head = chart.read_bytes()[:200]
    assert head.startswith(b"\x89PNG") if suffix == ".png" else b"<svg" in head or b"<?xml" in head
    again = tmp_path / f"again{suffix}"
    assert allocate(tmp_path, DELIVERY, FLEET, "--gantt", str(again), name="again")[0] == 0
    assert again.read_bytes() == chart.read_bytes()  # no date, no version, fixed ids


def test_gantt_without_matplotlib_is_refused_before_the_search(tmp_path, capsys, monkeypatch):
    monkeypatch.setitem(sys.modules, "matplotlib", None)  # as if not installed
    status, out, schedule = allocate(tmp_path, DELIVERY, FLEET, "--gantt", str(tmp_path / "chart.png"))
    assert status == 2 and "--gantt needs matplotlib, which is not installed" in capsys.readouterr().err
    assert not out.exists() and not schedule.exists()


def test_the_example_script_runs(capsys):
    import runpy
    import sys

    argv = sys.argv
    sys.argv = [str(ROOT / "examples" / "allocation.py")]
    try:
        runpy.run_path(str(ROOT / "examples" / "allocation.py"), run_name="__main__")
    finally:
        sys.argv = argv
    out = capsys.readouterr().out
    assert out.startswith("OPTIMAL: makespan 136, travel 214") and "picker:" in out


@pytest.mark.parametrize("phase", ["allocating", "writing the output"])
def test_an_interrupt_writes_nothing(tmp_path, phase):
    import os
    import subprocess
    import sys

    from mutrose_cp.interrupt import FAULT_ENV

    out, schedule, chart = tmp_path / "out.json", tmp_path / "schedule.json", tmp_path / "chart.svg"
    run = subprocess.run([sys.executable, "-m", "mutrose_cp", "allocate", str(DELIVERY), "--fleet", str(FLEET),
                          "-o", str(out), "--schedule", str(schedule), "--gantt", str(chart)],
                         env={**os.environ, FAULT_ENV: f"{phase}:INT"}, capture_output=True, text=True, timeout=120)
    assert run.returncode == 130, run.stderr
    assert f"interrupted while {phase}" in run.stderr and "Traceback" not in run.stderr
    assert sorted(p.name for p in tmp_path.iterdir()) == []
