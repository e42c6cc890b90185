"""Valid mission decompositions by explicit combination (spec ``semantics.md`` §7).

This is the original MutRoSe algorithm, kept as the baseline: it walks the mission queue of the
Task Graph, carries every partial mission decomposition along, and filters them with
preconditions, parallel conflicts and achieve conditions.  Its cost grows with the product of
the choices, which is what the CP-SAT decomposer avoids.  The rules themselves are decided in
:mod:`.semantics`, which the CP-SAT encoder shares; here they are applied to explicit lists.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable, Sequence

from ..pipeline.constraints import Constraint
from ..errors import NoDecompositionError, Problem
from ..model import Configuration, Domain, GoalModel, InitialState, Literal
from ..model.task_graph import ScopeVertex, TaskGraph, TaskVertex
from .numeric import StartConditions
from .semantics import (
    ConstraintIndex,
    EffectScopes,
    Effects,
    ParallelConflict,
    State,
    achieve_tests,
    application_order,
    checks_parallel_conflicts,
    effects_of,
    ground_preconditions_hold,
    initial_state,
    mission_queue,
    parallel_conflicts,
    precondition_start_conditions,
    robot_precondition_writers,
    unique_branch_valid,
)


@dataclass
class _PartialDecomposition:
    """A partial mission decomposition: the chosen decomposition vertices in mission order,
    the same as a set, and what its comparisons require of the start values the world does
    not give (:mod:`.numeric`)."""

    order: list[int]
    chosen: set[int]
    starts: StartConditions = field(default_factory=StartConditions)

    def extended(self, d: int, starts: StartConditions) -> "_PartialDecomposition":
        return _PartialDecomposition(self.order + [d], self.chosen | {d}, starts)

    def copy(self) -> "_PartialDecomposition":
        return _PartialDecomposition(list(self.order), set(self.chosen), self.starts)


class ExploratoryDecomposer:
    """Walks the mission queue once, extending every partial decomposition at each task."""

    def __init__(self, tg: TaskGraph, constraints: Sequence[Constraint], domain: Domain, gm: GoalModel,
                 config: Configuration, initial: InitialState,
                 progress: Callable[[int, int], None] | None = None) -> None:
        self.tg = tg
        self.domain = domain
        self.gm = gm
        self.config = config
        self.progress = progress
        self.initial = initial_state(initial)
        # one empty partial decomposition to extend
        self.partials: list[_PartialDecomposition] = [_PartialDecomposition([], set())]
        self.failures: list[str] = []  # why partial decompositions were dropped, first first
        self.effects: dict[int, Effects] = {d.index: effects_of(d.decomposition) for d in tg.decompositions()}
        self.scopes = EffectScopes(tg)
        self.queue = mission_queue(tg)
        self.pos = 0  # the next queue entry to visit
        index = ConstraintIndex.of(constraints)
        position = {v: i for i, v in enumerate(self.queue)}
        self.robot_writers: dict[int, list[tuple[Literal, list[tuple[int, bool]]]]] = {
            d.index: robot_precondition_writers(domain, tg, d.index, index, position)
            for d in tg.decompositions()} if not tg.unique_branch else {}

    # ------------------------------------------------------------------------------------------
    def run(self) -> list[list[int]]:
        """All valid mission decompositions, each as decomposition vertices in mission order."""
        if self.tg.unique_branch:
            return self._unique_branch()
        if not self.tg.tasks():
            return []  # every task was removed (false contexts): nothing to decompose
        while self.pos < len(self.queue):
            self._visit()
        if not self.partials and self.failures:
            raise NoDecompositionError([Problem("", f) for f in list(dict.fromkeys(self.failures))[:5]])
        return [m.order for m in self.partials]

    def _dropped_all(self, reason: str) -> None:
        """Record why the last partial decompositions of a branch were dropped.

        The original aborts the whole run at the first task without a valid decomposition;
        here only the affected decompositions are dropped (an OR alternative may still
        succeed), and the run fails only when nothing is left (docs/deviations.md)."""
        self.failures.append(reason)

    def _unique_branch(self) -> list[list[int]]:
        """§7.7: every decomposition valid in the initial state is its own decomposition."""
        return [[d.index] for t in self.tg.tasks() for d in self.tg.decompositions_of(t.index)
                if unique_branch_valid(self.tg, d, self.initial, self.gm, self.config)]

    def _state(self, m: _PartialDecomposition, seen: set[int]) -> State:
        """The initial state changed by the effects of ``m``'s decompositions in ``seen``."""
        state = self.initial.copy()
        for d in application_order(m.chosen & seen):
            state.apply(self.effects[d])
        return state

    def _pop(self) -> ScopeVertex | TaskVertex:
        v = self.tg.vertices[self.queue[self.pos]]
        assert isinstance(v, (ScopeVertex, TaskVertex))
        self.pos += 1
        if self.progress is not None:
            self.progress(self.pos, len(self.queue))
        return v

    def _front_is_child_of(self, v: int) -> bool:
        return self.pos < len(self.queue) and self.tg.vertices[self.queue[self.pos]].parent == v

    def _visit(self) -> None:
        """Visit the next vertex of the queue (§7.3)."""
        v = self._pop()
        if isinstance(v, TaskVertex):
            self._task(v)
        else:
            self._operator(v)

    def _operator(self, v: ScopeVertex) -> None:
        """Visit an operator's children: each extends the partial decompositions in turn, except
        below an OR, where each child extends its own copy of them."""
        if v.content == "#" and self.tg.is_or(v.index):
            saved = self.partials
            collected: list[_PartialDecomposition] = []
            while self._front_is_child_of(v.index):
                self.partials = [m.copy() for m in saved]
                self._visit()
                collected.extend(self.partials)
            self.partials = collected
        else:
            while self._front_is_child_of(v.index):
                self._visit()
            if checks_parallel_conflicts(self.tg, v.index):
                self._solve_conflicts(v, parallel_conflicts(v.index, self.scopes, self.effects))
        self._achieve(v)

    def _achieve(self, v: ScopeVertex | TaskVertex) -> None:
        """§7.5: drop the partial decompositions whose state after ``v``'s subtree violates an
        achieve condition checked at ``v``."""
        tests = achieve_tests(self.tg, v.index, self.gm, self.config)
        if not tests:
            return
        seen = self.scopes.seen_by_achieve(v.index)
        for goal, test in tests:
            kept = []
            for m in self.partials:
                state = self._state(m, seen)
                if not state.satisfies(test):
                    continue
                starts = m.starts.admit(state.required_conditions(test, f"achieve condition of goal {goal}"))
                if starts is not None:
                    m.starts = starts
                    kept.append(m)
            if not kept and self.partials:
                self._dropped_all(f"{self.gm.source}: goal {goal}: No decomposition satisfied achieve "
                                  f"condition of goal {goal}")
            self.partials = kept

    def _solve_conflicts(self, v: ScopeVertex, conflicts: list[ParallelConflict]) -> None:
        """Drop the partial decompositions that choose both sides of a parallel conflict."""
        if not conflicts:
            return
        kept = [m for m in self.partials
                if not any(m.chosen.intersection(c.setting_true) and m.chosen.intersection(c.setting_false)
                           for c in conflicts)]
        if not kept and self.partials:
            self._dropped_all("Could not solve conflicts in valid mission decompositions generation: every "
                              "combination of the parallel tasks below "
                              f"{v.goal} sets some fact both true and false")
        self.partials = kept

    def _robot_ok(self, d: int, m: _PartialDecomposition) -> bool:
        """Robot-related preconditions of ``d``: the last chosen partner that writes one must
        agree with it."""
        for lit, writers in self.robot_writers.get(d, ()):
            chosen = [value for e, value in writers if e in m.chosen]
            if chosen and chosen[-1] != lit.positive:
                return False
        return True

    def _task(self, v: TaskVertex) -> None:
        """Extend each partial decomposition with each decomposition of task ``v`` valid in the
        state where ``v`` starts."""
        decompositions = self.tg.decompositions_of(v.index)
        seen = self.scopes.seen_by_task(v.index)
        emitted: list[_PartialDecomposition] = []
        for m in self.partials:
            start = self._state(m, seen)
            if not all(start.satisfies(c) for c in v.contexts):
                continue  # an enabled creation condition does not hold where the task starts
            for d in decompositions:
                assert d.decomposition is not None
                if not (ground_preconditions_hold(d.decomposition, start) and self._robot_ok(d.index, m)):
                    continue
                starts = m.starts.admit(precondition_start_conditions(d.decomposition, start))
                if starts is not None:
                    emitted.append(m.extended(d.index, starts))
        if not emitted and self.partials:
            assert v.instance is not None
            self._dropped_all(
                f"task instance {v.content}: NO VALID DECOMPOSITIONS FOR TASK {v.content}: {v.instance.name} "
                "(each of its decompositions has a precondition that the world state contradicts; run "
                "`decompose --explain` to see which)"
            )
        self.partials = emitted
        self._achieve(v)
