"""Checking many mission decompositions in time linear in the output.

An output may list hundreds of thousands of mission decompositions that differ in a few
choices.  The tasks of the file are split into *parts* that cannot affect each other's checks,
and each part's checks are made once per distinct choice in it:

* the decompositions of one task instance are in one part (an instance chosen twice);
* tasks that read or write one ground atom (a precondition, an effect, a goal condition over
  it) are in one part: a task's replay, its effects and the conditions on its atoms depend only
  on the chosen tasks before it that change those atoms, and a parallel conflict is on one atom;
* the tasks below one OR goal with one instance number, and those below one achieve or forAll
  condition's copy, are in one part;
* tasks on a cycle of the SEQ/FB constraints, and execution-constrained tasks with incompatible
  robot numbers, are in one part (when the constraints have no cycle, no decomposition has one).

A mission decomposition's violations are then the union of its parts' (each part's result is
kept by the keys chosen in it), plus those of the parts it chooses nothing in.
"""
from __future__ import annotations

from typing import Callable, Iterable

import networkx as nx

from ..io.decomposition_output import DecompositionOutput, OutputTask
from ..model import Comparison, NumericEffect
from .conditions import variables
from .decompositions import DecompositionChecker, Found, after_condition, robots_compatible
from .numbers import AtomKey
from .replay import groundings
from .report import Violation

Progress = Callable[[int, int], None]
PROGRESS_EVERY = 2000  # mission decompositions between two progress calls


class _Union:
    def __init__(self, items: Iterable[str]) -> None:
        self.parent = {k: k for k in items}

    def find(self, k: str) -> str:
        root = k
        while self.parent[root] != root:
            root = self.parent[root]
        while self.parent[k] != root:
            self.parent[k], k = root, self.parent[k]
        return root

    def join(self, keys: list[str]) -> None:
        if len(keys) > 1:
            first = self.find(keys[0])
            for k in keys[1:]:
                self.parent[self.find(k)] = first


class Parts:
    """The parts of a file's tasks and the memoised checks of each."""

    def __init__(self, checker: DecompositionChecker) -> None:
        self.checker = checker
        out = checker.out
        union = _Union(out.tasks)
        shared: dict[object, list[str]] = {}
        for key, task in out.tasks.items():
            for link in self._links(task):
                shared.setdefault(link, []).append(key)
        for keys in shared.values():
            union.join(keys)
        self._constraint_links(union)
        roots: dict[str, int] = {}
        self.part_of = {k: roots.setdefault(union.find(k), len(roots)) for k in out.tasks}
        self.scope: list[set[str]] = [set() for _ in roots]
        for k, p in self.part_of.items():
            self.scope[p].add(out.tasks[k].instance)
        self._cache: dict[tuple[int, tuple[str, ...]], Found] = {}
        self._mandatory: list[tuple[int, Found]] | None = None

    def _links(self, task: OutputTask) -> Iterable[object]:
        """What joins ``task`` to the others: its instance, its atoms, its OR and condition copies."""
        yield ("instance", task.instance)
        yield from self._atoms(task)
        rel, cond = self.checker.rel, self.checker.cond
        number = task.instance.partition("_")[2]
        outermost_or = None
        for goal in rel.task_path.get(task.gm_task, []):
            if goal.or_decomposed:
                outermost_or = goal.key
            if goal.context is not None and goal.context.kind == "condition" and goal.context.condition is not None:
                yield from cond.atoms(goal.context.condition, cond.binding(task))
            after, group_by = after_condition(goal)
            if after is not None:
                yield from cond.atoms(after, cond.binding(task))
                yield ("copy", goal.key, number)
                names = variables(after) | ({group_by} if group_by else set())
                group = self.checker.group_key(goal, names, task)
                if group is not None:  # a task that binds none joins its element's group ("copy")
                    yield ("group", goal.key, group)
        if outermost_or is not None:
            yield ("or", outermost_or, number)

    def _atoms(self, task: OutputTask) -> Iterable[AtomKey]:
        values = self.checker.values(task)
        for steps in self.checker.explanations(task) or []:
            for step in steps:
                for c in (*step.preconditions, *step.effects, *step.numeric_effects):
                    name = c.function if isinstance(c, (Comparison, NumericEffect)) else c.predicate
                    for g in groundings(c.args, values):
                        yield (name, g)

    def _constraint_links(self, union: _Union) -> None:
        checker = self.checker
        if not checker.acyclic:
            for scc in nx.strongly_connected_components(checker.seq_fb):
                union.join(sorted(scc))
        for a, b in checker.ec:
            ra, rb = checker.out.tasks[a].robots, checker.out.tasks[b].robots
            if ra is not None and rb is not None and not robots_compatible(ra, rb):
                union.join([a, b])

    def part(self, p: int, keys: tuple[str, ...]) -> Found:
        found = self._cache.get((p, keys))
        if found is None:
            found = self._cache[(p, keys)] = self.checker.check(list(keys), self.scope[p])
        return found

    def mandatory(self) -> list[tuple[int, Found]]:
        """The parts that have violations when nothing in them is chosen (required instances)."""
        if self._mandatory is None:
            self._mandatory = [(p, found) for p in range(len(self.scope)) if (found := self.part(p, ()))]
        return self._mandatory

    def decomposition(self, md: tuple[str, ...]) -> Found:
        chosen: dict[int, list[str]] = {}
        found: Found = []
        for k in md:
            p = self.part_of.get(k)
            if p is None:
                found.append((k, "not a task of the file"))
            else:
                chosen.setdefault(p, []).append(k)
        for p, keys in chosen.items():
            found.extend(self.part(p, tuple(keys)))
        for p, missing in self.mandatory():
            if p not in chosen:
                found.extend(missing)
        return found


def check_all(checker: DecompositionChecker, out: DecompositionOutput, progress: Progress | None) -> list[Violation]:
    """The violations of every mission decomposition of ``out``, in file order."""
    parts = Parts(checker)
    found: list[Violation] = []
    total = len(out.mission_decompositions)
    for i, md in enumerate(out.mission_decompositions):
        found.extend(Violation(i, task, message) for task, message in parts.decomposition(md))
        if progress is not None and (i + 1) % PROGRESS_EVERY == 0:
            progress(i + 1, total)
    if progress is not None:
        progress(total, total)
    return found
