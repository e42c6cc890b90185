"""Allocation: a mission's decomposition, robots and schedule chosen together, with travel.

``mutrose-cp allocate`` and :meth:`mutrose_cp.mission.Mission.allocate`.  One CP-SAT model,
built on the decomposition model of the embedding API, chooses which valid mission
decomposition is executed, which robots of the fleet execute each of its tasks, in which order
each robot visits the tasks' places, and when everything starts; the LP relaxation, solved by
Clarabel, bounds the objective independently.  The stages are listed in :mod:`.allocation`;
the fleet file is read by :mod:`.fleet` (``docs/formats/fleet.md``), the schedule file written
by :mod:`.output` (``docs/formats/schedule.md``).

The solving stages import OR-Tools' full CP-SAT API (with numpy): :func:`allocate` loads them
when it runs, so reading and checking a fleet stays light.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy_exports import lazy_attributes

if TYPE_CHECKING:
    from .allocation import allocate
    from .fleet import Durations, Fleet, Robot, TravelSpec
    from .options import AllocationOptions, Objective
    from .problem import NoAllocationError

# the public names, each loaded from its module on first use: the command line reads the bounds
# of .options for every command, which must not load the fleet reader and the allocation problem
_EXPORTS = {"Durations": "fleet", "Fleet": "fleet", "Robot": "fleet", "TravelSpec": "fleet",
            "AllocationOptions": "options", "Objective": "options", "NoAllocationError": "problem",
            "allocate": "allocation"}


__getattr__ = lazy_attributes(__name__, _EXPORTS)


__all__ = ["AllocationOptions", "Durations", "Fleet", "NoAllocationError", "Objective", "Robot", "TravelSpec",
           "allocate"]

