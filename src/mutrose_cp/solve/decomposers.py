"""The decomposers as functions of a mission's stages: the exploratory algorithm, the boolean
model, and the space of valid decompositions solved component by component.

:class:`mutrose_cp.mission.Mission` offers each as a method; the solvers that need another
(the decompose job, the embedding, the allocator's warm start) call these directly.  Each
imports its solver when first called: the CP-SAT layer takes a while to import, and a small
mission needs none of it.
"""
from __future__ import annotations

from typing import TYPE_CHECKING, Callable

from ..pipeline.recursion import deep
from ..pipeline.stages import MissionStages

if TYPE_CHECKING:
    from .cpsat import DecompositionSpace
    from .encoding import Encoding


@deep
def exploratory(stages: MissionStages, progress: Callable[[int, int], None] | None = None) -> list[list[int]]:
    """Valid mission decompositions by the original's explicit combination."""
    from .exploratory import ExploratoryDecomposer  # deferred: start-up time

    return ExploratoryDecomposer(stages.task_graph, stages.constraints, stages.domain, stages.goal_model,
                                 stages.config, stages.initial_state, progress).run()


@deep
def encoding(stages: MissionStages, explain: bool = False) -> Encoding:
    """The boolean model of the valid mission decompositions (see ``solve/encoding.py``)."""
    from .encoding import Encoder  # deferred: start-up time

    return Encoder(stages.task_graph, stages.constraints, stages.domain, stages.goal_model, stages.config,
                   stages.initial_state, explain).encode()


@deep
def decomposition_space(stages: MissionStages, progress: Callable[[int, int], None] | None = None,
                        keep: bool = True, list_limit: int | None = None) -> DecompositionSpace:
    """The valid mission decompositions as a product of independently solved components
    (``list_limit``: see ``solve.cpsat.solve_component``)."""
    from .cpsat import ENUMERATION_CAP, build_space  # deferred: start-up time

    return build_space(encoding(stages), keep=keep, progress=progress,
                       list_limit=ENUMERATION_CAP if list_limit is None else list_limit)
