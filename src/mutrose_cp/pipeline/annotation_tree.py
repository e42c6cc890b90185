"""The runtime annotation tree (RAT, spec ``semantics.md`` §4).

Its nodes are the operators of the goals' runtime annotations (``;``, ``#``, ``FALLBACK``),
means-end nodes for single-child goals, and goal/task leaves.  Expanded ``forAll`` goals become
a parallel "dummy" node over one copy per iterated element.  The tree is built by
:mod:`mutrose_cp.pipeline.expansion` in the same walk that creates the task instances; the Task Graph is
built from it.
"""
from __future__ import annotations

from dataclasses import KW_ONLY, dataclass, field
from enum import StrEnum
from typing import Iterator, Mapping

from ..model import Binding


class RatKind(StrEnum):
    OPERATOR = "operator"  # ;, # or FALLBACK of a goal's runtime annotation
    MEANSEND = "meansend"  # a goal refined by a single child
    GOAL = "goal"  # a goal leaf: a query goal, which selects but adds no task
    TASK = "task"  # a task instance leaf


OPERATOR, MEANSEND, GOAL, TASK = RatKind.OPERATOR, RatKind.MEANSEND, RatKind.GOAL, RatKind.TASK


@dataclass(slots=True)
class RatNode:
    kind: RatKind
    content: str  # ";", "#", "FALLBACK", a goal id, or a task instance id
    related_goal: str | None = None  # the goal this node belongs to; "" for a forAll dummy node
    children: list["RatNode"] = field(default_factory=list)
    _: KW_ONLY
    group: bool = True
    divisible: bool = True
    or_decomposition: bool = False
    var_maps: Mapping[str, Binding] = field(default_factory=dict)
    is_forall_dummy: bool = False
    inner: bool = False  # an operator nested inside its goal's annotation (not the goal's top node)

    def walk(self) -> Iterator["RatNode"]:
        """Pre-order traversal."""
        yield self
        for c in self.children:
            yield from c.walk()

    def render(self) -> str:
        """The annotation as an expression, e.g. ``(G2;((AT1_1;AT2_1)#AT3_1))`` (for humans)."""
        if self.kind in (TASK, GOAL):
            return self.content
        if self.kind == MEANSEND:
            return "".join(c.render() for c in self.children)
        sep = "," if self.content == "FALLBACK" else self.content
        inner = sep.join(c.render() for c in self.children)
        return f"FALLBACK({inner})" if self.content == "FALLBACK" else f"({inner})"
