"""Which method choices of the HDDL domain produce a task's listed actions.

An output file lists, per decomposition, only the primitive actions.  To check method
preconditions the validator reconstructs the method tree from the domain alone: a task is
matched against a stretch of the action list by trying each of its methods and each order of
the method's subtasks that its ordering allows, recursively (an order is built as it is matched,
so the actions cut the orders short).  The result is a list of *steps* in execution
order: each method contributes a checkpoint (its preconditions and effects) before its
subtasks, each action its own preconditions and effects.  All arguments are expressed in the
root task's parameter names (``?r``, ``?rm``); a variable the root does not bind becomes
``?~name``, and the literals that mention it are not ground.

This shares nothing with :mod:`mutrose_cp.pipeline.htn`, which generates paths forwards with a symbolic
state; here the domain is read backwards from the file, so a mistake in either shows up as a
mismatch.
"""
from __future__ import annotations

from typing import Iterator, Sequence

from ..io.decomposition_output import OutputAction
from ..model import Domain, Method
from .steps import Step, action_step, checkpoint, has_checkpoint

MAX_EXPLANATIONS = 16  # enough to find one that replays; they all list the same actions


def _rename(args: Sequence[str], subst: dict[str, str]) -> tuple[str, ...]:
    return tuple(subst.get(a, a) for a in args)


def _before(method: Method) -> list[frozenset[int]]:
    """For each subtask, the positions of the subtasks its ordering puts before it."""
    ids = [s.id for s in method.subtasks]
    return [frozenset(ids.index(a) for a, b in method.ordering if b == sid and a in ids) for sid in ids]


class Matcher:
    """Explains the action list of one task of one domain."""

    def __init__(self, domain: Domain, root_parameters: Sequence[str], actions: Sequence[OutputAction]) -> None:
        self.domain = domain
        self.root = frozenset(root_parameters)
        self.actions = actions
        self._stack: set[tuple[str, tuple[str, ...], int]] = set()

    def explain(self, task: str) -> list[list[Step]]:
        """Step lists that produce exactly the whole action list from the root task."""
        terms = tuple(p.name for p in self.domain.task_by_name[task].parameters)
        out: list[list[Step]] = []
        for end, steps in self._task(task, terms, 0):
            if end == len(self.actions):
                out.append(steps)
                if len(out) >= MAX_EXPLANATIONS:
                    break
        return out

    def _task(self, task: str, terms: tuple[str, ...], i: int) -> Iterator[tuple[int, list[Step]]]:
        key = (task, terms, i)
        if key in self._stack:  # a recursion that consumed no action cannot lead anywhere new
            return
        self._stack.add(key)
        try:
            for method in self.domain.methods_of(task):
                # method variables bound to the root task's parameters; the others stay unbound
                subst = {a: t for a, t in zip(method.task_args, terms) if t in self.root}
                unbound = {q.name: "?~" + q.name for q in method.parameters if q.name not in subst}
                first = [checkpoint(method, {**unbound, **subst})] if has_checkpoint(method) else []
                yield from self._sequence(method, _before(method), frozenset(), subst, i, first)
        finally:
            self._stack.discard(key)

    def _sequence(self, method: Method, before: list[frozenset[int]], placed: frozenset[int], subst: dict[str, str],
                  i: int, steps: list[Step]) -> Iterator[tuple[int, list[Step]]]:
        """The subtasks not yet ``placed``, from action ``i`` on: at each place every subtask whose
        predecessors are placed is tried (in declaration order, so that the orders come out as
        the spec lists them), matched against the actions as it is placed."""
        if len(placed) == len(method.subtasks):
            yield i, steps
            return
        for k in range(len(method.subtasks)):
            if k not in placed and before[k] <= placed:
                yield from self._place(method, before, placed, k, subst, i, steps)

    def _place(self, method: Method, before: list[frozenset[int]], placed: frozenset[int], k: int,
               subst: dict[str, str], i: int, steps: list[Step]) -> Iterator[tuple[int, list[Step]]]:
        sub = method.subtasks[k]
        terms = _rename(sub.args, subst)
        action = self.domain.action_by_name.get(sub.task)
        if action is None:
            for j, inner in self._task(sub.task, terms, i):
                yield from self._sequence(method, before, placed | {k}, subst, j, steps + inner)
            return
        if i >= len(self.actions) or self.actions[i].name != action.name:
            return
        given = self.actions[i].args
        if given is not None:
            if len(given) != len(action.parameters):
                return
            # an argument bound to a root parameter is printed as that parameter; an unbound
            # one (or one the call leaves out) keeps the action's own parameter name
            if any(term in self.root and arg != term for term, arg in zip(terms, given)):
                return
        binding = {p.name: t if t in self.root else "?~" + p.name for p, t in zip(action.parameters, terms)}
        step = action_step(action, binding)
        yield from self._sequence(method, before, placed | {k}, subst, i + 1, steps + [step])
