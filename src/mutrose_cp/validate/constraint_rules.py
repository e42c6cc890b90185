"""The constraints a mission's goal model implies (semantics.md §6), to check an output's list.

The constraint tree is the minimal Task Graph's operators (:func:`.task_graph.minimal_tree`).
Each operator combines its consecutive children (``;``: SEQ, ``FALLBACK``: FB) or every two of
them (``#``: parallel), a child being a task or the list of its subtree.  A subtree's list takes
part through its end points:

* a SEQ node runs from the tasks its left child ends with (the second task of a SEQ, both of a
  FB or parallel pair) to those its right child starts with (the first of a SEQ or FB, both of a
  parallel pair);
* a FB node from every task of its left child's list but the first of a FB pair, to every task of
  its right child's list but the second of a FB pair;
* a subtree whose list is empty (one task under an operator kept for its achieve condition)
  joins none of its siblings.

Parallel pairs order nothing, except where a context dependency says a decomposition enables a
task to its right (a SEQ from that decomposition).  Each pair of tasks becomes one constraint
between every two of their decompositions; execution constraints come from the Task Graph.  Then
a SEQ implied by a SEQ followed by a SEQ or FB, and a FB implied by two FBs, are left out (the
original's trimming, computed once on the whole list, §6.4).
"""
from __future__ import annotations

from dataclasses import dataclass, field

from .task_graph import Graph, TreeNode

Decomposition = tuple[str, int]  # (instance id, number)


@dataclass(frozen=True)
class Expected:
    """The constraints between decompositions: ordered SEQ and FB pairs, and execution
    constraints (unordered pairs) with their flags."""

    ordered: dict[tuple[Decomposition, Decomposition], str]  # (first, second) -> "SEQ" | "FB"
    execution: dict[frozenset[Decomposition], tuple[bool, bool]]


@dataclass
class _Summary:
    """A subtree's constraint list: its SEQ/FB pairs and which tasks stand where in its pairs."""

    pairs: dict[tuple[int, int], str] = field(default_factory=dict)
    seq1: set[int] = field(default_factory=set)
    seq2: set[int] = field(default_factory=set)
    fb1: set[int] = field(default_factory=set)
    fb2: set[int] = field(default_factory=set)
    par: set[int] = field(default_factory=set)

    def ends(self) -> set[int]:
        return self.seq1 | self.seq2 | self.fb1 | self.fb2 | self.par

    def add(self, kind: str, a: int, b: int) -> None:
        if (a, b) in self.pairs:
            return
        self.pairs[(a, b)] = kind
        first, second = (self.seq1, self.seq2) if kind == "SEQ" else (self.fb1, self.fb2)
        first.add(a)
        second.add(b)

    def merge(self, other: "_Summary") -> None:
        for (a, b), kind in other.pairs.items():
            self.add(kind, a, b)
        self.par |= other.par


def _sources(child: int | _Summary, kind: str) -> set[int]:
    if isinstance(child, int):
        return {child}
    if kind == "SEQ":
        return child.seq2 | child.fb1 | child.fb2 | child.par
    return child.seq1 | child.seq2 | child.par | child.fb2


def _targets(child: int | _Summary, kind: str) -> set[int]:
    if isinstance(child, int):
        return {child}
    if kind == "SEQ":
        return child.seq1 | child.fb1 | child.par
    return child.seq1 | child.seq2 | child.par | child.fb1


class _Lists:
    """The constraint lists of the tree, bottom up; parallel pairs are kept as the position of
    each end point under its parallel operator, not pair by pair (a forAll of n copies would
    make n² of them)."""

    def __init__(self) -> None:
        self.par_positions: dict[int, list[tuple[int, int]]] = {}  # task -> (operator, child position)
        self._operators = 0

    def summary(self, node: TreeNode) -> _Summary:
        children: list[int | _Summary] = [c if isinstance(c, int) else self.summary(c) for c in node.children]
        out = _Summary()
        if node.kind == "PAR":
            self._parallel(children, out)
        else:
            for x, y in zip(children, children[1:]):
                for a in sorted(_sources(x, node.kind)):
                    for b in sorted(_targets(y, node.kind)):
                        out.add(node.kind, a, b)
        for c in children:
            if isinstance(c, _Summary):
                out.merge(c)
        return out

    def _parallel(self, children: list[int | _Summary], out: _Summary) -> None:
        ends = [{c} if isinstance(c, int) else c.ends() for c in children]
        if sum(1 for e in ends if e) < 2:
            return
        self._operators += 1
        for position, tasks in enumerate(ends):
            for t in tasks:
                self.par_positions.setdefault(t, []).append((self._operators, position))
            out.par |= tasks

    def parallel_pair(self, a: int, b: int) -> bool:
        """Whether the root list holds the parallel pair (a, b), ``a`` from an earlier child."""
        at_b = dict(self.par_positions.get(b, []))
        return any(op in at_b and pos < at_b[op] for op, pos in self.par_positions.get(a, []))


def expected_constraints(graph: Graph, tree: TreeNode | None, counts: dict[str, int]) -> Expected:
    """The trimmed constraints between decompositions; ``counts``: decompositions per instance."""
    names = {v.index: v.content for v in graph.tasks}

    def decs(task: int) -> list[Decomposition]:
        return [(names[task], n) for n in range(1, counts.get(names[task], 0) + 1)]

    ordered: dict[tuple[Decomposition, Decomposition], str] = {}
    if tree is not None:
        lists = _Lists()
        root = lists.summary(tree)
        for (a, b), kind in root.pairs.items():
            for da in decs(a):
                for db in decs(b):
                    ordered.setdefault((da, db), kind)
        for (task, n), targets in graph.dependencies.items():
            for b in targets:
                if lists.parallel_pair(task, b):
                    for db in decs(b):
                        ordered.setdefault(((names[task], n), db), "SEQ")
    execution = {frozenset((da, db)): flags for (a, b), flags in graph.execution.items()
                 for da in decs(a) for db in decs(b)}
    return Expected(_trimmed(ordered), execution)


def _trimmed(ordered: dict[tuple[Decomposition, Decomposition], str]) -> dict[tuple[Decomposition, Decomposition], str]:
    """Without a SEQ that a SEQ then a SEQ or FB implies, nor a FB that two FBs imply (§6.4)."""
    succ: dict[str, dict[Decomposition, set[Decomposition]]] = {"SEQ": {}, "FB": {}}
    pred: dict[str, dict[Decomposition, set[Decomposition]]] = {"SEQ": {}, "FB": {}}
    for (a, b), kind in ordered.items():
        succ[kind].setdefault(a, set()).add(b)
        pred[kind].setdefault(b, set()).add(a)

    def implied(a: Decomposition, b: Decomposition, kind: str) -> bool:
        after = succ[kind].get(a, set())
        before = pred[kind].get(b, set()) | (pred["FB"].get(b, set()) if kind == "SEQ" else set())
        small, large = (after, before) if len(after) <= len(before) else (before, after)
        return any(c in large for c in small)

    return {pair: kind for pair, kind in ordered.items() if not implied(*pair, kind)}
