"""One mission decomposition read from an output file (``decompose``'s, the original's, or a
witness that ``verify`` wrote), as the mission's Task Graph vertices, so that it can be drawn.

The file's task keys are mapped to decomposition ids (``AT1_2|1``) and those to the mission's
task decompositions; the result must be one of the mission's valid decompositions, or the file
was written for another mission (or by hand) and drawing it would show something that cannot
run.  Every refusal names the file and the place in it (exit status 2)."""
from __future__ import annotations

from ..errors import MissionError, Problem
from ..io.decomposition_output import DecompositionOutput, load_decomposition_output
from ..pipeline.scenarios import world_with
from ..pipeline.stages import MissionStages
from ..solve import decomposers


def output_world(mission: MissionStages, output: DecompositionOutput) -> MissionStages:
    """``mission`` in the world ``output`` says its tasks were expanded in (its uncertainty
    section's ``world``, written when the goal model reads uncertain facts), else ``mission``."""
    if not output.assumed_world:
        return mission
    return world_with(mission, {(e, a): v for e, a, v in output.assumed_world},
                      f"{output.source}: mission_decomposition_uncertainty.world")


def listed_decomposition(mission: MissionStages, path: str, index: int = 0) -> tuple[MissionStages, list[int]]:
    """The decomposition vertices of mission decomposition ``index`` (0-based) listed in ``path``,
    and the mission they are of: ``mission``, or ``mission`` in the world the file says its
    tasks were expanded in (docs/formats/output.md, ``mission_decomposition_uncertainty``)."""
    output = load_decomposition_output(path)
    mission = output_world(mission, output)
    listed = output.mission_decompositions
    if not -len(listed) <= index < len(listed):
        raise MissionError(Problem(path, f"mission_decompositions: no decomposition {index}: the file lists "
                                         f"{len(listed)}"))
    where = f"mission_decompositions[{index % len(listed)}]"
    by_id = {v.decomposition.id: v.index for v in mission.task_graph.decompositions() if v.decomposition is not None}
    chosen = []
    for key in listed[index]:
        task = output.tasks.get(key)
        if task is None:
            raise MissionError(Problem(path, f"{where}: task {key} is not in the file's tasks"))
        if task.id not in by_id:
            raise MissionError(Problem(path, f"{where}: {key} is task decomposition {task.id}, which this mission "
                                             "does not have (was the file written for another mission?)"))
        chosen.append(by_id[task.id])
    if not decomposers.decomposition_space(mission).contains(chosen):
        raise MissionError(Problem(path, f"{where}: not a valid decomposition of this mission "
                                         "(mutrose-cp validate tells why)"))
    return mission, sorted(chosen)
