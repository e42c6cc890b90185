"""Least-cost mission decompositions: the cost model and the optimisation over the space.

A decomposition's cost is additive: every action it executes costs its own amount (one by
default) and every method it applies may add a cost.  An additive cost splits over the
independent components of the decomposition space, so the optimum is each component's cheapest
solution: read off the listed solutions where a component was listed, a shortest path through
its layers where it was solved block by block (:mod:`.layered`), found by CP-SAT where it was
too large to list.
"""
from __future__ import annotations

import json
from dataclasses import dataclass, field
from typing import TYPE_CHECKING, Mapping

from ..errors import MissionError, NoDecompositionError
from ..model.decomposition_paths import TreeNode
from ..io.text import decode_utf8, read_bytes
from ..model.task_graph import TaskGraph

if TYPE_CHECKING:  # the CP-SAT layer is loaded when a component has to be solved
    from .cpsat import Component, DecompositionSpace

MAX_COST = 10**12  # per action or method: sums over large missions stay far inside 64 bits


def _cost(value: object, where: str) -> int:
    """A cost from the cost file: a whole number (``3`` or ``3.0``), at most ``MAX_COST``."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        raise MissionError(f"expected a whole number as cost, got {json.dumps(value)}", where)
    if not abs(value) <= MAX_COST:  # also infinity (JSON 1e309) and NaN
        raise MissionError(f"cost {value!r} is out of range: costs go from -{MAX_COST} to {MAX_COST}", where)
    if isinstance(value, float) and not value.is_integer():
        raise MissionError(f"expected a whole number as cost, got {value!r}", where)
    return int(value)


@dataclass(frozen=True)
class CostModel:
    """Per-action and per-method costs; an action without a cost costs ``default_action``.
    The default model counts actions."""

    actions: Mapping[str, int] = field(default_factory=dict)
    methods: Mapping[str, int] = field(default_factory=dict)
    default_action: int = 1

    @classmethod
    def read(cls, path: str) -> "CostModel":
        """A JSON cost file ``{"actions": {name: cost}, "methods": {name: cost},
        "default_action": 1}``; every cost a whole number within ``MAX_COST``."""
        text = decode_utf8(read_bytes(path, "cost"), path, "cost file")
        try:
            data = json.loads(text)
        except json.JSONDecodeError as err:
            raise MissionError(f"invalid JSON: {err.msg}", f"{path}:{err.lineno}:{err.colno}") from None
        if not isinstance(data, dict) or not all(isinstance(data.get(k, {}), dict) for k in ("actions", "methods")):
            raise MissionError('expected an object {"actions": {name: cost}, "methods": {name: cost}}', path)
        return cls(
            actions={str(k): _cost(v, f"{path}: actions.{k}") for k, v in data.get("actions", {}).items()},
            methods={str(k): _cost(v, f"{path}: methods.{k}") for k, v in data.get("methods", {}).items()},
            default_action=_cost(data.get("default_action", 1), f"{path}: default_action"),
        )

    def _method_cost(self, node: TreeNode) -> int:
        own = self.methods.get(node.name, 0) if node.kind == "method" else 0
        return own + sum(self._method_cost(c) for c in node.children)

    def decomposition_costs(self, tg: TaskGraph) -> dict[int, int]:
        """The cost of each decomposition vertex of ``tg``."""
        out = {}
        for d in tg.decompositions():
            path = d.decomposition.path
            out[d.index] = (sum(self.actions.get(a.name, self.default_action) for a in path.actions)
                            + self._method_cost(path.tree))
        return out


def least_cost(space: DecompositionSpace, costs: Mapping[int, int]) -> tuple[list[int], int]:
    """A valid mission decomposition of least total cost (decomposition vertices in mission
    order) and its cost.  Ties are broken by the canonical order of a component's solutions
    where the component was listed, by the listing order of its layers where it was not."""
    if space.count == 0:
        raise NoDecompositionError("no valid mission decomposition exists")
    chosen = list(space.fixed)
    for component in space.components:
        chosen += _cheapest(space, component, costs)
    chosen.sort()
    return chosen, sum(costs.get(d, 0) for d in chosen)


def _cheapest(space: DecompositionSpace, component: Component, costs: Mapping[int, int]) -> list[int]:
    """The decomposition vertices of ``component``'s cheapest solution."""
    var_to_dec = space.var_to_dec
    if component.solutions is None and component.layers is not None:
        best_layered, _ = component.layers.least_cost({v: costs.get(var_to_dec[v], 0) for v in component.choice_vars})
        return [var_to_dec[v] for v in best_layered]
    if component.solutions is not None:
        best = min(component.solutions,
                   key=lambda s: (sum(costs.get(var_to_dec[v], 0) for v in s), sorted(s)))
        return [var_to_dec[v] for v in best]
    from .proto import ProtoBuilder  # the CP-SAT layer, loaded when a component needs it
    from .run import INFEASIBLE, OPTIMAL, run_solver

    builder = ProtoBuilder(space.encoding.model)
    for r in component.records:
        builder.post(r)
    for v in component.choice_vars:
        builder.proto.objective.vars.append(builder.var(v))
        builder.proto.objective.coeffs.append(costs.get(var_to_dec[v], 0))
    response = run_solver(builder.proto, accept=(OPTIMAL, INFEASIBLE), what="optimising a component")
    if response.status == INFEASIBLE:  # pragma: no cover - a counted component has solutions
        raise NoDecompositionError("no valid mission decomposition exists")
    return [var_to_dec[v] for v in component.choice_vars if response.solution[builder.var(v)]]

