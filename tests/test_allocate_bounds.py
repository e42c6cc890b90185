"""The allocation's lower bounds and its warm start, on missions small enough to be solved to
optimality: each bound is at most the proven optimum, and the warm start's schedule, list
scheduling improved by local moves, passes the independent checker (``allocation_checker``) as
it is."""
from __future__ import annotations

import json
import shutil
import sys
import time
from pathlib import Path

import pytest

from allocation_checker import check_allocation
from mutrose_cp.allocate import AllocationOptions, Fleet, Objective
from mutrose_cp.allocate.allocation import Allocation
from mutrose_cp.allocate.budget import JOB_STEPS_PER_UNIT, Budget
from mutrose_cp.allocate.improve import evaluate, improve
from mutrose_cp.allocate.load import load_bound
from mutrose_cp.allocate.output import write_decomposition, write_schedule
from mutrose_cp.allocate.problem import build_problem
from mutrose_cp.allocate.schedule import compact, robot_sequences, robot_teams
from mutrose_cp.allocate.warmstart import greedy_plan, least_work_decomposition, warm_start
from mutrose_cp.api import Mission, find_mission_files
from mutrose_cp.cli.program import main

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from allocation import generate  # noqa: E402

ROOT = Path(__file__).resolve().parent.parent
DELIVERY = ROOT / "examples" / "item-delivery"
FLEET = DELIVERY / "fleet.json"


def _variants(tmp_path: Path) -> list[tuple[Path, Path]]:
    """The delivery example with its fleet, without its all-rounder, with a travel table of
    long roads from the dock, and a generated grid of five deliveries for three robots (one of
    each kind)."""
    data = json.loads(FLEET.read_text())
    data["robots"] = [r for r in data["robots"] if r["name"] != "allrounder"]
    fewer = tmp_path / "fewer.json"
    fewer.write_text(json.dumps(data))
    data = json.loads(FLEET.read_text())
    data["travel"]["times"] = {"Dock": {"CentralPharmacy": 70, "SupplyRoom": 90}, "WardB": {"Laboratory": 5}}
    table = tmp_path / "table.json"
    table.write_text(json.dumps(data))
    return [(DELIVERY, FLEET), (DELIVERY, fewer), (DELIVERY, table), generate(5, 3, tmp_path), _relay(tmp_path)]


def _relay(tmp_path: Path) -> tuple[Path, Path]:
    """One delivery between places 1 km apart, for two robots that cannot fetch (no
    manipulation), one at each end: staff load the item at the pharmacy and the robot waiting at
    the ward hands it over (a precedence without an execution constraint), so no robot travels.
    A bound that put the 1 km trip between the two tasks would exceed the optimum."""
    mission = tmp_path / "relay"
    shutil.copytree(DELIVERY, mission, ignore=shutil.ignore_patterns("output", "fleet.json"))
    places = "".join(f"<Location><name>{name}</name><reachable>True</reachable><staffed>True</staffed>"
                     f"<has_drop_box>False</has_drop_box><x>{x}</x><y>0</y></Location>"
                     for name, x in (("Pharmacy", 0), ("Ward", 1000)))
    (mission / "knowledge" / "world_db.xml").write_text(
        f"<world_db>{places}<Delivery><name>D1</name><item>Insulin pens</item><pickup>Pharmacy</pickup>"
        "<destination>Ward</destination><is_collected>False</is_collected><is_delivered>False</is_delivered>"
        "</Delivery></world_db>\n", encoding="utf-8")
    fleet = json.loads(FLEET.read_text())
    fleet["robots"] = [{"name": f"talker-{at}", "capabilities": ["navigation", "communication"], "start": at}
                       for at in ("Pharmacy", "Ward")]
    del fleet["travel"]["coordinates"]
    path = tmp_path / "relay.json"
    path.write_text(json.dumps(fleet))
    return mission, path


@pytest.mark.parametrize("objective", ["makespan", "weighted:2,1"])
def test_the_load_bound_is_at_most_the_optimum(tmp_path, objective):
    for mission_dir, fleet_path in _variants(tmp_path):
        mission = Mission.load(*find_mission_files(mission_dir))
        options = AllocationOptions(objective=Objective.parse(objective), time_limit=60)
        allocation = mission.allocate(Fleet.read(fleet_path), options)
        assert allocation.status == "OPTIMAL" and allocation.load is not None
        assert allocation.load.status == "OPTIMAL"
        assert 0 < allocation.load_value <= allocation.objective, (mission_dir, fleet_path)


def test_the_load_bound_counts_the_pool_of_able_robots():
    """The example without travel: the deliveries' work falls on the robots able to do it, so the
    bound is above the whole fleet's average work."""
    mission = Mission.load(*find_mission_files(DELIVERY))
    problem = build_problem(mission.decomposition_model(), Fleet.read(FLEET))
    bound = load_bound(problem, Objective(), Budget(10.0))
    chosen = least_work_decomposition(problem)
    assert chosen is not None and bound.decompositions
    average = sum(problem.jobs[d].duration for d in chosen) / len(problem.fleet.robots)
    assert bound.status == "OPTIMAL" and bound.value is not None and bound.value > average


def test_the_load_bound_counts_the_trip_between_tasks_of_the_same_robot(monkeypatch):
    """In the example the robot that fetches an item also hands it over (an execution
    constraint), so its trip from the supply room to the ward lies on the chain: the bound rises
    above the one of the chains without trips."""
    from mutrose_cp.allocate import load

    mission = Mission.load(*find_mission_files(DELIVERY))
    problem = build_problem(mission.decomposition_model(), Fleet.read(FLEET))
    with_trips = load_bound(problem, Objective(), Budget(10.0))
    monkeypatch.setattr(load, "carry_time", lambda *_: 0)
    without = load_bound(problem, Objective(), Budget(10.0))
    assert with_trips.status == without.status == "OPTIMAL"
    assert with_trips.value is not None and without.value is not None
    assert with_trips.value > without.value


def _one_fetcher(tmp_path: Path, staffed: bool) -> tuple[Path, Path]:
    """Four deliveries in one building (no travel), for one all-rounder, three pickers and a
    talker, with staff so slow to load an item that every robot fetches it itself; the robot
    that fetches an item must also hand it over (an execution constraint).  To a person
    (``staffed``) only the all-rounder can do both, and does all four deliveries one after the
    other (200 s).  Otherwise the world does not say whether anyone is at the ward, so either
    hand-over may be chosen, and into the drop box any picker can do both: the four deliveries
    run side by side (40 s)."""
    mission = tmp_path / f"one-fetcher-{staffed}"
    shutil.copytree(DELIVERY, mission, ignore=shutil.ignore_patterns("output", "fleet.json"))
    places = "".join(f"<Location><name>{name}</name><reachable>True</reachable>{staff}"
                     f"<has_drop_box>{not staffed}</has_drop_box><x>0</x><y>0</y></Location>"
                     for name, staff in (("Pharmacy", ""), ("Ward", "<staffed>True</staffed>" if staffed else "")))
    deliveries = "".join(f"<Delivery><name>D{k}</name><item>Item {k}</item><pickup>Pharmacy</pickup>"
                         "<destination>Ward</destination><is_collected>False</is_collected>"
                         "<is_delivered>False</is_delivered></Delivery>" for k in range(1, 5))
    (mission / "knowledge" / "world_db.xml").write_text(f"<world_db>{places}{deliveries}</world_db>\n")
    fleet = json.loads(FLEET.read_text())
    kinds = {"allrounder": ["manipulation", "communication"], "picker1": ["manipulation"],
             "picker2": ["manipulation"], "picker3": ["manipulation"], "talker": ["communication"]}
    fleet["robots"] = [{"name": name, "capabilities": ["navigation", *caps], "start": "Pharmacy"}
                       for name, caps in kinds.items()]
    fleet["durations"]["actions"]["request-loading"] = 400
    del fleet["travel"]["coordinates"]
    path = tmp_path / f"one-fetcher-{staffed}.json"
    path.write_text(json.dumps(fleet))
    return mission, path


@pytest.mark.parametrize("staffed,optimum", [(True, 200), (False, 40)])
def test_the_load_bound_puts_tasks_that_share_a_robot_on_the_robots_able_to_do_both(tmp_path, monkeypatch,
                                                                                      staffed, optimum):
    """Fetching needs a picker, handing over to a person a talker, and one robot must do both:
    the pool of the robots able to do both (the all-rounder) carries the four deliveries, which
    makes the bound the optimum, where fetches and hand-overs pooled apart spread over four
    pickers and two talkers.  A fetch counts there only with a hand-over to a person: into a drop
    box, any picker can do both."""
    from mutrose_cp.allocate import load

    mission_dir, fleet_path = _one_fetcher(tmp_path, staffed)
    mission = Mission.load(*find_mission_files(mission_dir))
    allocation = mission.allocate(Fleet.read(fleet_path), AllocationOptions(time_limit=60))
    assert allocation.status == "OPTIMAL" and allocation.objective == optimum
    assert allocation.load_value == optimum
    problem = build_problem(mission.decomposition_model(), Fleet.read(fleet_path))  # the allocation's holds it
    monkeypatch.setattr(load, "linked_candidates", lambda _problem: {})
    apart = load_bound(problem, Objective(), Budget(10.0))
    assert apart.value is not None and (apart.value < 100 if staffed else apart.value == optimum)


def test_the_warm_start_passes_the_checker(tmp_path):
    for number, (mission_dir, fleet_path) in enumerate(_variants(tmp_path)):
        mission = Mission.load(*find_mission_files(mission_dir))
        problem = build_problem(mission.decomposition_model(), Fleet.read(fleet_path))
        warm = warm_start(problem, load_bound(problem, Objective(), Budget(10.0)).decompositions)
        assert warm is not None
        end = {j: warm.start[j] + problem.jobs[j].duration for j in warm.chosen}
        schedule = compact(problem, warm.chosen, warm.teams, warm.start, end)
        assert dict(schedule.start) == warm.start  # already as early as its sequences allow
        allocation = Allocation(problem, AllocationOptions(), "FEASIBLE", schedule, None, None)
        schedule_path, output_path = tmp_path / f"warm{number}.json", tmp_path / f"warm{number}-mission.json"
        write_schedule(allocation, schedule_path)
        write_decomposition(allocation, output_path, "JSON")
        check_allocation(mission, fleet_path, schedule_path, output_path)


def _generated(tmp_path, deliveries: int, robots: int):
    """A generated mission, its fleet file and its allocation problem."""
    mission_dir, fleet_path = generate(deliveries, robots, tmp_path)
    mission = Mission.load(*find_mission_files(mission_dir))
    return mission, fleet_path, build_problem(mission.decomposition_model(), Fleet.read(fleet_path))


def _listed(tmp_path, deliveries: int, robots: int):
    """A generated mission and fleet, its allocation problem, the load relaxation's balanced
    decomposition and its list schedule."""
    mission, fleet_path, problem = _generated(tmp_path, deliveries, robots)
    chosen = load_bound(problem, Objective(), Budget(10.0)).decompositions[-1]
    plan = greedy_plan(problem, chosen)
    assert plan is not None
    return mission, fleet_path, problem, chosen, plan


def test_the_warm_start_spreads_the_deliveries(tmp_path):
    """Twelve deliveries for six robots: the list schedule of the balanced decomposition ends
    well before the one of the least-work decomposition, which needs the two all-rounders."""
    mission, fleet_path, problem = _generated(tmp_path, 12, 6)
    balanced = load_bound(problem, Objective(), Budget(10.0)).decompositions[-1]
    least = least_work_decomposition(problem)
    assert least is not None
    makespans = []
    for chosen in (balanced, least):
        plan = greedy_plan(problem, chosen)
        assert plan is not None
        makespans.append(max(plan[1][j] + problem.jobs[j].duration for j in chosen))
    assert makespans[0] < makespans[1]


def test_an_lp_cut_by_its_time_limit_gives_no_bound(tmp_path, monkeypatch, capsys):
    """An LP given no time at all (not even skipped for it) is cut while it is being built."""
    from mutrose_cp.allocate import phases, stages

    monkeypatch.setattr(stages, "LP_SHARE", 0.0)
    monkeypatch.setattr(phases, "MIN_PHASE", 0.0)
    mission = tmp_path / "mission"
    shutil.copytree(DELIVERY, mission, ignore=shutil.ignore_patterns("output"))
    out, schedule = tmp_path / "run.json", tmp_path / "schedule.json"
    assert main(["allocate", str(mission), "--fleet", str(FLEET), "-o", str(out), "--schedule", str(schedule),
                 "--time-limit", "20"]) == 0
    doc = check_allocation(Mission.load(*find_mission_files(mission)), FLEET, schedule, out)
    assert doc["objective"]["lp_bound"] is None and doc["objective"]["lp_status"] == "MaxTime"
    assert doc["objective"]["load_bound"] is not None
    assert "LP not solved (MaxTime)" in capsys.readouterr().err


def _check_plan(tmp_path: Path, mission: Mission, fleet_path: Path, problem, chosen, teams, start, name: str) -> None:
    """The schedule of ``teams`` / ``start`` passes the checker, and no job can start earlier."""
    end = {j: start[j] + problem.jobs[j].duration for j in chosen}
    schedule = compact(problem, chosen, teams, start, end)
    assert dict(schedule.start) == dict(start)
    allocation = Allocation(problem, AllocationOptions(), "FEASIBLE", schedule, None, None)
    write_schedule(allocation, tmp_path / f"{name}.json")
    write_decomposition(allocation, tmp_path / f"{name}-mission.json", "JSON")
    check_allocation(mission, fleet_path, tmp_path / f"{name}.json", tmp_path / f"{name}-mission.json")


def test_local_moves_shorten_the_list_schedule(tmp_path):
    """Twelve deliveries for six robots: moving deliveries off the robot that finishes last
    ends well before the list schedule, the schedule passes the checker, and the same seed gives
    the same schedule (the search stops on its own budget, not on the clock)."""
    mission, fleet_path, problem, chosen, plan = _listed(tmp_path, 12, 6)
    listed = max(plan[1][j] + problem.jobs[j].duration for j in chosen)
    teams, start, value = improve(problem, chosen, *plan, Objective(), Budget(600.0, 2.0))
    assert value == max(start[j] + problem.jobs[j].duration for j in chosen) < 0.9 * listed
    _check_plan(tmp_path, mission, fleet_path, problem, chosen, teams, start, "improved")
    evaluated = evaluate(problem, chosen, robot_sequences(problem, chosen, teams, start))
    assert evaluated is not None and evaluated.start == start
    assert improve(problem, chosen, *plan, Objective(), Budget(600.0, 2.0)) == (teams, start, value)


def test_orders_against_the_precedences_are_no_schedule(tmp_path):
    """A robot that hands an item over before fetching it: the evaluator finds the cycle."""
    mission, fleet_path, problem = _generated(tmp_path, 2, 3)
    first, second = problem.same_robots[0]
    chosen = [first, second]
    robot = next(r for r in problem.jobs[first].candidates if r in problem.jobs[second].candidates)
    assert evaluate(problem, chosen, {robot: [second, first]}) is None
    forward = evaluate(problem, chosen, {robot: [first, second]})
    assert forward is not None and forward.start[second] >= forward.start[first] + problem.jobs[first].duration



def _units_backwards(problem, chosen, teams, start) -> tuple[dict, dict]:
    """The schedule with the robot that finishes last doing its units (a job and those that
    must share its robot) in the reverse order, each unit's jobs still in order: a route a
    reordering should shorten."""
    from mutrose_cp.allocate.improve import _units

    sequences = robot_sequences(problem, chosen, teams, start)
    last = max((r for r in sequences if sequences[r]),
               key=lambda r: start[sequences[r][-1]] + problem.jobs[sequences[r][-1]].duration)
    unit = {j: n for n, u in enumerate(_units(problem, chosen, teams)) for j in u}
    order = list(dict.fromkeys(unit[j] for j in sequences[last]))
    sequences[last] = [j for u in reversed(order) for j in sequences[last] if unit[j] == u]
    evaluated = evaluate(problem, chosen, sequences)
    assert evaluated is not None
    return robot_teams(sequences, chosen), evaluated.start


@pytest.mark.parametrize("move", ["_segment_moves", "_reversals", "_swaps"])
def test_each_move_shortens_a_schedule_alone(tmp_path, monkeypatch, move):
    """Each kind of move beyond relocation, alone and without kicks, shortens a schedule that
    relocations have left: the reordering moves one whose last robot does its deliveries
    backwards, the swaps the relocations' own local optimum (every robot busy, so no unit can
    simply move); the result passes the checker and is the same on every run."""
    from mutrose_cp.allocate import improve as local

    mission, fleet_path, problem, chosen, plan = _listed(tmp_path, 10, 4)
    monkeypatch.setattr(local, "STALL", 1)  # one descent
    monkeypatch.setattr(local, "KICK", 0)
    monkeypatch.setattr(local, "MOVES", (local._relocations,))
    teams, start, value = improve(problem, chosen, *plan, Objective(), Budget(600.0, 2.0))
    if move != "_swaps":
        teams, start = _units_backwards(problem, chosen, teams, start)
        value = max(start[j] + problem.jobs[j].duration for j in chosen)
    monkeypatch.setattr(local, "MOVES", (getattr(local, move),))
    better = improve(problem, chosen, teams, start, Objective(), Budget(600.0, 2.0))
    assert better[2] < value
    _check_plan(tmp_path, mission, fleet_path, problem, chosen, *better[:2], move)
    assert improve(problem, chosen, teams, start, Objective(), Budget(600.0, 2.0)) == better


def test_a_work_limit_gives_the_same_schedule_on_a_slower_machine(tmp_path, monkeypatch):
    """``--work-limit``: a search cut by its budget (twelve deliveries for six robots, not
    proven in one unit) writes the same bytes when the clock runs a thousand times faster (a
    machine that much slower), and every CP-SAT run of it is limited by deterministic time only;
    a clock budget would end each phase at once."""
    from mutrose_cp.allocate import search as search_module
    from mutrose_cp.solve import run

    limits = []

    def recording(solve):
        def wrapper(proto, **kwargs):
            parameters = kwargs.get("parameters")  # none: solved to the end
            if parameters is not None:
                limits.append((parameters.max_time_in_seconds, parameters.max_deterministic_time))
            return solve(proto, **kwargs)
        return wrapper

    monkeypatch.setattr(run, "run_solver", recording(run.run_solver))
    monkeypatch.setattr(search_module, "run_solver", recording(search_module.run_solver))
    mission_dir, fleet_path = generate(12, 6, tmp_path)
    real = time.perf_counter
    files = []
    for name in ("machine", "slower machine"):
        if name == "slower machine":
            monkeypatch.setattr(time, "perf_counter", lambda: real() * 1000)
        out, schedule = tmp_path / f"{name}.json", tmp_path / f"{name} schedule.json"
        assert main(["allocate", str(mission_dir), "--fleet", str(fleet_path), "-o", str(out),
                     "--schedule", str(schedule), "-q", "--work-limit", "1"]) == 0
        monkeypatch.setattr(time, "perf_counter", real)
        doc = check_allocation(Mission.load(*find_mission_files(mission_dir)), fleet_path, schedule, out)
        assert doc["objective"]["status"] == "FEASIBLE"  # cut by the budget, not finished
        files.append((schedule.read_bytes(), out.read_bytes()))
    assert files[0] == files[1]
    assert all(seconds == float("inf") for seconds, _ in limits)  # CP-SAT never reads the clock
    # the load relaxation's two halves of a tenth, and the search's three quarters, per run
    assert [work for _, work in limits if work != float("inf")] == [0.05, 0.05, 0.75] * 2


def test_work_and_time_limits_are_checked(tmp_path, capsys):
    from mutrose_cp.errors import MissionError

    out = tmp_path / "run.json"
    for extra, message in ((["--work-limit", "1", "--time-limit", "5"], "not allowed with argument"),
                           (["--work-limit", "nan"], "nan is not a positive number of units of work"),
                           (["--work-limit", "0"], "0 is not a positive number of units of work")):
        assert main(["allocate", str(DELIVERY), "--fleet", str(FLEET), "-o", str(out), *extra]) == 2
        err = capsys.readouterr().err
        assert message in err and "Traceback" not in err and not out.exists()
    for bad in (0, -1.0, float("inf"), float("nan"), True):
        with pytest.raises(MissionError, match="not a limit"):
            AllocationOptions(work_limit=bad)


def test_a_budget_shares_work_in_fixed_parts_and_time_in_what_is_left(monkeypatch):
    from mutrose_cp.allocate import budget as budget_module

    monkeypatch.setattr(budget_module.time, "perf_counter", lambda: 100.0)  # a clock that stands still
    clock, work = Budget(10.0), Budget(10.0, 4.0)
    assert work.part(0.25) == Budget(2.5, 1.0) and work.rest(96.0, 0.5) == work.part(0.5)  # no clock in work
    assert clock.rest(96.0, 0.5) == Budget(6.0) and clock.rest(80.0) == Budget(0.0)  # what is left, at least 0
    assert work.job_steps() == 4 * JOB_STEPS_PER_UNIT and clock.job_steps() is None
    steps = work.running()
    assert steps(4 * JOB_STEPS_PER_UNIT - 1) and not steps(4 * JOB_STEPS_PER_UNIT)
    from mutrose_cp.solve.native import cmh

    for budget, workers in ((clock, 1), (work, 2)):
        parameters = cmh.SatParameters()
        budget.limit(parameters, workers)
        assert (parameters.max_time_in_seconds, parameters.max_deterministic_time,
                parameters.interleave_search) == ((10.0, float("inf"), False) if budget is clock else
                                                  (float("inf"), 4.0, True))


def test_a_search_without_any_schedule_reports_the_warm_start(tmp_path, monkeypatch):
    """A short limit can end CP-SAT in its presolve, before it has taken the hint: the warm
    start's schedule, which is complete, is reported (FEASIBLE, no bound from the search), and
    without a warm start nothing is (exit 4)."""
    from mutrose_cp.allocate import stages
    from mutrose_cp.solve.run import IncompleteSolveError

    def unfinished(*_args, **_kwargs):
        raise IncompleteSolveError("CP-SAT did not finish the allocation (UNKNOWN)")

    monkeypatch.setattr(stages, "search", unfinished)
    mission = Mission.load(*find_mission_files(DELIVERY))
    result = mission.allocate(Fleet.read(FLEET), AllocationOptions(time_limit=20))
    assert result.status == "FEASIBLE" and result.cp_bound is None and result.gap is None
    assert result.objective >= result.load_value
    write_schedule(result, tmp_path / "schedule.json")
    write_decomposition(result, tmp_path / "mission.json", "JSON")
    check_allocation(mission, FLEET, tmp_path / "schedule.json", tmp_path / "mission.json")
    with pytest.raises(IncompleteSolveError):
        mission.allocate(Fleet.read(FLEET), AllocationOptions(time_limit=20, warm_start=False))
