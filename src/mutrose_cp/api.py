"""Embedding API: the whole space of valid mission decompositions as ONE CP-SAT model.

``Mission.decomposition_space()`` splits the boolean model into independent components and
solves each one on its own, which is the fast way to count or list decompositions.  An
application that *optimises over* the decompositions (a task allocator, a scheduler, a cost
model) needs the opposite: a single ``cp_model.CpModel`` that already contains every rule of a
valid decomposition, to which it adds its own variables and constraints (robots assigned to
decompositions, start times, no-overlap, an objective) so that CP-SAT chooses the decomposition
*together with* the allocation.  :class:`DecompositionModel` is that model plus typed maps from
the mission's names (decomposition ids, task instance ids, OR goals) to CP-SAT literals::

    from mutrose_cp.api import Mission, DecompositionModel
    from ortools.sat.python import cp_model

    mission = Mission.load(hddl, gm, config)
    dm = mission.decomposition_model()          # == DecompositionModel.build(mission)
    x = dm.decomposition["AT1_1|1"]             # a CP-SAT literal
    dm.model.Add(...)                            # your variables and constraints
    solver = cp_model.CpSolver()
    solver.Solve(dm.model)
    print(dm.solution(solver))                   # ["AT1_1|1", "AT2_1|2", ...]

See ``docs/api.md`` and ``examples/allocation.py`` (robot allocation and scheduling).
"""
from __future__ import annotations

from .mission import Mission
from .io.mission_files import find_mission_files
from .solve.embedding import ConstraintInfo, CpLiteral, DecompositionInfo, DecompositionModel

__all__ = ["Mission", "DecompositionModel", "DecompositionInfo", "ConstraintInfo", "CpLiteral",
           "find_mission_files"]
