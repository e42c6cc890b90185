"""Allocate a mission to a fleet from Python: the decomposition, the robots and the schedule
chosen together, with travel (what ``mutrose-cp allocate`` does).

    python examples/allocation.py [MISSION_DIR] [FLEET.json]

Defaults: ``examples/item-delivery`` and its ``fleet.json``.  See ``docs/api.md``.
"""
from __future__ import annotations

import sys
from pathlib import Path

from mutrose_cp.allocate import AllocationOptions, Fleet, Objective
from mutrose_cp.api import Mission, find_mission_files

HERE = Path(__file__).resolve().parent


def main(argv: list[str]) -> None:
    folder = Path(argv[0]) if argv else HERE / "item-delivery"
    fleet = Fleet.read(argv[1] if len(argv) > 1 else folder / "fleet.json")
    mission = Mission.load(*find_mission_files(folder))
    allocation = mission.allocate(fleet, AllocationOptions(Objective.parse("makespan"), time_limit=10))
    schedule = allocation.schedule
    print(f"{allocation.status}: makespan {schedule.makespan}, travel {schedule.travel}, "
          f"CP-SAT bound {allocation.cp_bound}, LP bound {allocation.lp_value}, load bound {allocation.load_value}")
    for robot, visits in schedule.routes.items():
        print(f"  {robot}: " + ", ".join(f"{v.job}@{v.location} {v.start}-{v.end}" for v in visits))


if __name__ == "__main__":
    main(sys.argv[1:])
