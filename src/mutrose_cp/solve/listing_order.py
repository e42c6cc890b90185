"""The order in which the exploratory algorithm, like the original, lists mission decompositions.

The exploratory walk (:mod:`.exploratory`) keeps an ordered list of partial decompositions and
visits the mission queue once:

* a task replaces each partial decomposition, in order, by its extensions with each of the
  task's decompositions, in order: the task's choice is less significant than every earlier one;
* an OR operator visits each child with a copy of the list and concatenates the results, child
  by child: the child is more significant than everything chosen before the operator, and what
  the child's own subtree chooses comes after it;
* any other operator visits its children one after the other.

Filtering (preconditions, conflicts, achieve conditions) drops entries without reordering the
others.  So each mission decomposition has a sort key, built by the same walk over its own
choices: a task appends the position of its decomposition, and an OR operator wraps the key
built inside its chosen child as ``(child, key)``.  Two keys first differ at a position that the
same walk built for both, so comparing them as tuples gives the exploratory order.  Sorting the
CP-SAT decomposer's listing by :class:`ExploratoryOrder` gives the original's order for any
space that fits in memory (``tests/test_listing_order.py`` checks it on the corpus and on
generated missions).
"""
from __future__ import annotations

from typing import Iterable

from ..model.task_graph import OperatorVertex, TaskGraph, TaskVertex
from .semantics import mission_queue

Key = tuple[object, ...]


class ExploratoryOrder:
    """Sort keys of mission decompositions (lists of decomposition vertices) of one Task Graph."""

    def __init__(self, tg: TaskGraph) -> None:
        self.tg = tg
        self.queue = mission_queue(tg)
        # the position of each decomposition among its task's, and its task
        self.position: dict[int, int] = {}
        self.task_of: dict[int, int] = {}
        for t in tg.tasks():
            for i, d in enumerate(tg.decompositions_of(t.index)):
                self.position[d.index] = i
                self.task_of[d.index] = t.index
        # the last vertex of each vertex's subtree (vertices are numbered depth first)
        self.end = list(range(len(tg.vertices)))
        for v in reversed(range(len(tg.vertices))):
            parent = tg.vertices[v].parent
            if parent is not None and parent >= 0:
                self.end[parent] = max(self.end[parent], self.end[v])

    def key(self, decomposition: Iterable[int]) -> Key:
        """The sort key of one mission decomposition."""
        if self.tg.unique_branch:
            return tuple(sorted(decomposition))
        chosen = {self.task_of[d]: self.position[d] for d in decomposition}
        walk = _Walk(self, chosen)
        key: Key = ()
        while walk.pos < len(self.queue):
            key = walk.visit(key)
        return key


class _Walk:
    """One decomposition's walk of the mission queue, as :class:`ExploratoryDecomposer` walks
    it (an operator consumes the queue entries that are its children)."""

    def __init__(self, order: ExploratoryOrder, chosen: dict[int, int]) -> None:
        self.order = order
        self.chosen = chosen
        self.active_tasks = sorted(chosen)
        self.pos = 0

    def _front_is_child_of(self, v: int) -> bool:
        queue = self.order.queue
        return self.pos < len(queue) and self.order.tg.vertices[queue[self.pos]].parent == v

    def _holds_choice(self, v: int) -> bool:
        """Whether the decomposition chose something below queue entry ``v``."""
        end = self.order.end[v]
        return any(v <= t <= end for t in self.active_tasks)

    def visit(self, key: Key) -> Key:
        v = self.order.queue[self.pos]
        self.pos += 1
        vertex = self.order.tg.vertices[v]
        if isinstance(vertex, TaskVertex):
            return key + (self.chosen[v],) if v in self.chosen else key
        assert isinstance(vertex, OperatorVertex)
        if vertex.content == "#" and self.order.tg.is_or(v):
            inside: Key | None = None
            child = 0
            while self._front_is_child_of(v):
                entry = self.order.queue[self.pos]
                if inside is None and self._holds_choice(entry):
                    inside = (child, self.visit(key))
                else:
                    self.visit(key)  # another alternative: its entries are consumed, not chosen
                child += 1
            return inside if inside is not None else key
        while self._front_is_child_of(v):
            key = self.visit(key)
        return key
