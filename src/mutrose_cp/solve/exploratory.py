"""Valid mission decompositions by explicit combination (spec ``semantics.md`` §7).

This is the original MutRoSe algorithm, kept as the baseline: it walks the mission queue of the
Task Graph, carries every partial mission decomposition along, and filters them with
preconditions, parallel conflicts and achieve conditions.  Its cost grows with the product of
the choices, which is what the CP-SAT decomposer avoids.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

from ..conditions import holds
from ..constraints import Constraint
from ..errors import NoDecompositionError, Problem
from ..io.config import Configuration
from ..io.goal_model import GoalModel
from ..io.hddl import Domain
from ..taskgraph import ATASK, OP, TaskGraph, Vertex
from ..world import InitialState
from .semantics import (
    ConstraintIndex,
    Effects,
    achieve_tests,
    context_enablers,
    effects_of,
    ground_preconditions_hold,
    initial_state,
    robot_preconditions,
    translate_robot_effects,
    unique_branch_valid,
)


@dataclass
class _VMD:
    """A partial mission decomposition: decomposition vertices in order, and the id set."""

    order: list[int]
    ids: set[str]


class ExploratoryDecomposer:
    def __init__(self, tg: TaskGraph, constraints: list[Constraint], domain: Domain, gm: GoalModel,
                 config: Configuration, initial: InitialState,
                 progress: Callable[[int, int], None] | None = None) -> None:
        self.tg = tg
        self.domain = domain
        self.gm = gm
        self.config = config
        self.progress = progress
        self.initial = initial_state(initial)
        self.vmds: list[_VMD] = [_VMD([], set())]  # one empty partial decomposition to extend
        self.failures: list[str] = []  # why partial decompositions were dropped, first first
        self.effects: dict[int, Effects] = {d.index: effects_of(d.decomposition) for d in tg.decompositions()}
        self.by_id = {d.content: d.index for d in tg.decompositions()}
        index = ConstraintIndex.of(constraints)
        self.ec_partners, self.seq_after = index.ec, index.seq_after
        self.enablers = context_enablers(tg)
        self.robot_pre = {d.index: robot_preconditions(domain, d.decomposition) for d in tg.decompositions()}
        # the mission queue (§7.2): every task and operator vertex of the trimmed Task Graph;
        # trimming keeps only operators with two or more children (or an achieve condition),
        # but an operator whose children were goal leaves (queries) can be left with fewer: it
        # still scopes its subtree (the original then visits that subtree outside its parent)
        self.queue = [v.index for v in tg.vertices if v.kind in (ATASK, OP)]
        self.pos = 0  # the next queue entry to visit

    # ------------------------------------------------------------------------------------------
    def run(self) -> list[list[int]]:
        """All valid mission decompositions, each as decomposition vertices in mission order."""
        if self.tg.unique_branch:
            return self._unique_branch()
        if not self.tg.tasks():
            return []  # every task was removed (false contexts): nothing to decompose
        while self.pos < len(self.queue):
            self._visit({})
        if not self.vmds and self.failures:
            raise NoDecompositionError([Problem("", f) for f in list(dict.fromkeys(self.failures))[:5]])
        return [m.order for m in self.vmds]

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

    def _in_graph_order(self, ids: set[str]) -> list[str]:
        """Decomposition ids in Task Graph vertex order: the order in which the original applies
        effects (its maps are keyed by vertex index, §7.3), which is also the order of the SEQ
        constraints.  The order of the id strings would put ``AT10_1|1`` before ``AT2_1|1``."""
        return sorted(ids, key=self.by_id.__getitem__)

    def _pop(self) -> Vertex:
        v = self.tg.vertices[self.queue[self.pos]]
        self.pos += 1
        if self.progress is not None:
            self.progress(self.pos, len(self.queue))
        return v

    def _front_is_child_of(self, v: int) -> bool:
        return self.pos < len(self.queue) and self.tg.vertices[self.queue[self.pos]].parent == v

    def _visit(self, effects_in: dict[str, Effects]) -> dict[str, Effects]:
        """Visit the next vertex of the queue; ``effects_in`` are the effects of the
        decompositions that precede it in an enclosing sequence (§7.3)."""
        v = self._pop()
        if v.kind == ATASK:
            return self._task(v, effects_in)
        return self._operator(v, effects_in)

    def _operator(self, v: Vertex, effects_in: dict[str, Effects]) -> dict[str, Effects]:
        """Visit an operator's children; returns the effects of its subtree's decompositions.

        Every child sees what precedes the operator, and a sequence's child also what its
        earlier siblings did.  (The original starts a nested operator's children from the
        initial state, so a task could ignore a task that its SEQ constraints put before it;
        docs/deviations.md.)"""
        E: dict[str, Effects] = {}
        if v.content == ";":
            while self._front_is_child_of(v.index):
                E.update(self._visit({**effects_in, **E}))
        elif v.content == "#" and self.tg.is_or(v.index):
            saved = self.vmds
            collected: list[_VMD] = []
            while self._front_is_child_of(v.index):
                self.vmds = [(_VMD(list(m.order), set(m.ids))) for m in saved]
                E.update(self._visit(effects_in))
                collected.extend(self.vmds)
            self.vmds = collected
        else:
            while self._front_is_child_of(v.index):
                E.update(self._visit(effects_in))
            if v.content == "#":
                self._solve_conflicts(v, E)
        self._achieve(v, {**effects_in, **E})
        return E

    def _achieve(self, v: Vertex, E: dict[str, Effects]) -> None:
        """§7.5: drop the partial decompositions whose state after ``v``'s subtree (the initial
        state changed by the effects ``E`` of the subtree's chosen decompositions and of those
        before it) violates an achieve condition checked at ``v``."""
        for goal, test in achieve_tests(self.tg, v.index, self.gm, self.config):
            kept = []
            for m in self.vmds:
                state = self.initial.copy()
                for key in self._in_graph_order(m.ids):
                    if key in E:
                        state.apply(E[key])
                if holds(test, state.fact, state.value):
                    kept.append(m)
            if not kept and self.vmds:
                self._dropped_all(f"{self.gm.source}: goal {goal}: No decomposition satisfied achieve "
                                  f"condition of goal {goal}")
            self.vmds = kept

    def _solve_conflicts(self, v: Vertex, E: dict[str, Effects]) -> None:
        kept = []
        for m in self.vmds:
            seen: dict = {}
            ok = True
            for key in self._in_graph_order(m.ids):
                if key not in E:
                    continue
                for atom, val in E[key].facts:
                    if atom in seen and seen[atom] != val:
                        ok = False
                        break
                    seen[atom] = val
                if not ok:
                    break
            if ok:
                kept.append(m)
        if not kept and self.vmds:
            self._dropped_all("Could not solve conflicts in valid mission decompositions generation: every "
                              "combination of the parallel tasks below "
                              f"{v.related_goal} sets some fact both true and false")
        self.vmds = kept

    def _robot_ok(self, d: int, members: set[str]) -> bool:
        """Robot-related non-ground preconditions against execution-constrained partners."""
        pre = self.robot_pre[d]
        if not pre:
            return True
        partners = self.ec_partners.get(d, set())
        state: dict = {}
        dec = self.tg.vertices[d].decomposition
        for key in self._in_graph_order(members):
            e = self.by_id[key]
            if e == d or e not in partners or e in self.seq_after.get(d, set()):
                continue  # only partners that may run before d can have changed the robot
            for lit in translate_robot_effects(self.domain, self.tg.vertices[e].decomposition, dec):
                state[(lit.predicate, lit.args)] = lit.positive
        for lit in pre:
            known = state.get((lit.predicate, lit.args))
            if known is not None and known != lit.positive:
                return False
        return True

    def _task(self, v: Vertex, effects_in: dict[str, Effects]) -> dict[str, Effects]:
        decs = self.tg.decompositions_of(v.index)
        enablers = self.enablers.get(v.index, set())
        accepted: dict[str, Effects] = {}
        emitted: list[_VMD] = []
        for m in self.vmds:
            work = set(m.ids)
            base = self.initial.copy()
            for key in self._in_graph_order(work):
                if key in effects_in:
                    base.apply(effects_in[key])
                elif self.by_id[key] in enablers:
                    base.apply(self.effects[self.by_id[key]])
            if not all(holds(c, base.fact, base.value) for c in v.contexts):
                continue  # an enabled creation condition does not hold where the task starts
            for d in decs:
                if not ground_preconditions_hold(d.decomposition, base):
                    continue
                if not self._robot_ok(d.index, work):
                    continue
                emitted.append(_VMD(m.order + [d.index], work | {d.content}))
                accepted[d.content] = self.effects[d.index]
        if not emitted and self.vmds:
            self._dropped_all(
                f"task instance {v.content}: NO VALID DECOMPOSITIONS FOR TASK {v.content}: {v.instance.name} "
                "(each of its decompositions has a precondition that the world state contradicts; run "
                "`decompose --explain` to see which)"
            )
        self.vmds = emitted
        self._achieve(v, {**effects_in, **accepted})
        return accepted
