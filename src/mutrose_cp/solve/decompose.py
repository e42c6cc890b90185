"""The decompose job: which valid mission decompositions to hand to the output, and how many
there are.

A :class:`DecompositionRequest` says what the caller wants (the algorithm, the first K, a
uniform sample, the least-cost one, every reason when there is none); :func:`decompose` answers
it with a :class:`DecompositionResult`.  The command line and the API both go through here.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field
from enum import StrEnum
from typing import TYPE_CHECKING, Callable, Iterable

from ..errors import NoDecompositionError
from ..pipeline.stages import MissionStages
from ..model.task_graph import SplitListing
from . import decomposers
from .optimize import CostModel, least_cost

if TYPE_CHECKING:
    from .cpsat import DecompositionSpace

DEFAULT_LIMIT = 1000
SHOWN_REASONS = 3  # reasons named when nothing is valid, unless every reason is asked for
# the optimum needs no listing: a component counted from its conflict definitions is listed for
# the output's space section only up to this many solutions (CP-SAT finds its best one)
OPTIMIZE_LIST_LIMIT = 10_000


class Algorithm(StrEnum):
    CPSAT = "cpsat"
    EXPLORATORY = "exploratory"  # the original's explicit combination, the baseline


@dataclass(frozen=True)
class DecompositionRequest:
    """What to decompose into.  At most one of ``sample`` and ``optimize``; both, a ``limit``
    other than the default and ``explain`` need the CP-SAT decomposer."""

    algorithm: Algorithm = Algorithm.CPSAT
    limit: int | None = DEFAULT_LIMIT  # list the first K (None: all)
    sample: int | None = None  # K decompositions drawn uniformly, with replacement
    seed: int = 0
    optimize: bool = False  # the least-cost decomposition under ``costs``
    costs: CostModel = field(default_factory=CostModel)
    explain: bool = False  # name every reason when nothing is valid (else the first three)

    def __post_init__(self) -> None:
        used = cpsat_options(limit=self.limit, sample=self.sample, optimize=self.optimize, explain=self.explain)
        if self.algorithm == Algorithm.EXPLORATORY and used:
            raise ValueError(f"{', '.join(used)}: only the CP-SAT decomposer offers them")
        if self.sample is not None and (self.optimize or self.limit != DEFAULT_LIMIT):
            raise ValueError("a sample cannot be combined with optimize or limit")


def cpsat_options(*, limit: int | None, sample: int | None, optimize: bool, explain: bool) -> list[str]:
    """The options set, among those only the CP-SAT decomposer offers (the command line names
    them as flags)."""
    return [name for name, used in (("optimize", optimize), ("sample", sample is not None),
                                    ("explain", explain), ("limit", limit != DEFAULT_LIMIT)) if used]


@dataclass
class DecompositionResult:
    """The answer to a request.  ``decompositions`` is consumed once, lazily (listing the first
    thousand of 3^5000 decompositions costs no more than writing them)."""

    algorithm: Algorithm
    decompositions: Iterable[list[int]]  # decomposition vertices in mission order, per decomposition
    total: int  # how many valid mission decompositions exist
    space: DecompositionSpace | None = None  # the CP-SAT decomposer's factored space
    optimum: tuple[list[int], int] | None = None  # with optimize: the decomposition and its cost
    listed: int | None = None  # how many are listed, when that is fewer than ``total``

    def space_section(self, key: Callable[[int], str]) -> dict[str, object] | None:
        """The output's ``space`` section: the count, each component's alternatives (by output
        ``key``) and the optimum; None for the exploratory decomposer."""
        if self.algorithm == Algorithm.EXPLORATORY:
            return None
        components = self.space.component_table(key) if self.space is not None else []
        section: dict[str, object] = {"count": str(self.total), "components": components}
        if self.optimum is not None:
            chosen, cost = self.optimum
            section["optimum"] = {"cost": str(cost), "decomposition": [key(d) for d in chosen]}
        return section


def decompose(mission: MissionStages, request: DecompositionRequest,
              progress: Callable[[int, int], None] | None = None) -> DecompositionResult:
    """Answer ``request`` for ``mission``.  Raises :class:`NoDecompositionError` (with the
    reasons CP-SAT finds) when the mission has tasks but no valid decomposition."""
    if not mission.task_graph.tasks():
        return DecompositionResult(request.algorithm, [], 0)  # no entity of the world matched the queries
    if request.algorithm == Algorithm.EXPLORATORY:
        found = decomposers.exploratory(mission, progress)
        if not found:
            raise NoDecompositionError("no valid mission decomposition")
        return DecompositionResult(request.algorithm, found, len(found))
    space = decomposers.decomposition_space(mission, progress, list_limit=OPTIMIZE_LIST_LIMIT if request.optimize else None)
    if space.count == 0:
        raise _nothing_valid(mission, request.explain)
    return answer(mission, space, request)


def answer(mission: MissionStages, space: DecompositionSpace, request: DecompositionRequest) -> DecompositionResult:
    """``request`` answered over ``space``, which has decompositions: the least-cost one, a
    sample, or the first ones listed (``space`` may be a part of the mission's, such as its
    robust decompositions in an uncertain world)."""
    if request.optimize:
        chosen, cost = least_cost(space, request.costs.decomposition_costs(mission.task_graph))
        return DecompositionResult(request.algorithm, [chosen], space.count, space, optimum=(chosen, cost))
    if request.sample is not None:
        return DecompositionResult(request.algorithm, space.sample(request.sample, request.seed), space.count, space)
    return _listing(space, request.limit)


def _listing(space: DecompositionSpace, limit: int | None) -> DecompositionResult:
    """The first ``limit`` decompositions (all if None), their common part written once where
    the components allow it."""
    total = space.count
    listed = min(total, limit) if limit is not None else total
    split = space.split_listing(limit)
    decompositions: Iterable[list[int]]
    if split is not None:
        prefix, parts = split
        decompositions = SplitListing(prefix, itertools.islice(parts, limit))
    else:
        decompositions = itertools.islice(iter(space), limit)
    return DecompositionResult(Algorithm.CPSAT, decompositions, total, space, listed=listed if listed < total else None)


def _nothing_valid(mission: MissionStages, every_reason: bool) -> NoDecompositionError:
    """The error for a mission without valid decomposition: a conflicting set of labelled
    constraints (CP-SAT assumptions) names what is responsible."""
    from .cpsat import explain

    reasons = explain(decomposers.encoding(mission, explain=True))
    shown = reasons if every_reason else reasons[:SHOWN_REASONS]
    detail = "; ".join(shown) or "the goal model's structure admits no combination"
    more = ("" if every_reason or len(reasons) <= SHOWN_REASONS
            else f" (and {len(reasons) - SHOWN_REASONS} more: --explain lists all)")
    return NoDecompositionError(f"no valid mission decomposition: {detail}{more}", str(mission.goal_model.source))
