"""Which method choices of the HDDL domain produce a task's listed actions.

An output file lists, per decomposition, only the primitive actions.  To check method
preconditions the validator reconstructs the method tree from the domain alone: a task is
matched against a stretch of the action list by trying each of its methods and each linear
order of the method's subtasks, recursively.  The result is a list of *steps* in execution
order: each method contributes a checkpoint (its preconditions and effects) before its
subtasks, each action its own preconditions and effects.  All arguments are expressed in the
root task's parameter names (``?r``, ``?rm``); a variable the root does not bind becomes
``?~name``, and the literals that mention it are not ground.

This shares nothing with :mod:`mutrose_cp.htn`, which generates paths forwards with a symbolic
state; here the domain is read backwards from the file, so a mistake in either shows up as a
mismatch.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass
from typing import Iterable, Iterator, Sequence

from ..io.decomposition_output import OutputAction
from ..model import Comparison, Domain, Literal, Method, NumericEffect

MAX_EXPLANATIONS = 16  # enough to find one that replays; they all list the same actions


@dataclass(frozen=True)
class Step:
    """A method checkpoint or an action, with its conditions over root-task terms."""

    kind: str  # "method" | "action"
    name: str
    preconditions: tuple[Literal | Comparison, ...]
    effects: tuple[Literal, ...]
    numeric_effects: tuple[NumericEffect, ...]
    position: int  # index of the action this step precedes or is


def _rename(args: Sequence[str], subst: dict[str, str]) -> tuple[str, ...]:
    return tuple(subst.get(a, a) for a in args)


def _renamed(kind: str, name: str, pre: Iterable[Literal | Comparison], eff: Iterable[Literal],
             num: Iterable[NumericEffect], subst: dict[str, str], position: int) -> Step:
    return Step(
        kind,
        name,
        tuple(Literal(c.predicate, _rename(c.args, subst), c.positive) if isinstance(c, Literal)
              else Comparison(c.function, _rename(c.args, subst), c.op, c.value, c.negated) for c in pre),
        tuple(Literal(e.predicate, _rename(e.args, subst), e.positive) for e in eff),
        tuple(NumericEffect(n.kind, n.function, _rename(n.args, subst), n.amount) for n in num),
        position,
    )


def _linear_orders(method: Method) -> Iterator[tuple[int, ...]]:
    """Every order of the method's subtasks that respects its ordering pairs."""
    ids = [s.id for s in method.subtasks]
    before = {i: {ids.index(a) for a, b in method.ordering if b == ids[i] and a in ids} for i in range(len(ids))}
    if len(ids) > 7:  # 8! orders: follow the declared order only
        yield tuple(range(len(ids)))
        return
    for perm in itertools.permutations(range(len(ids))):
        placed: set[int] = set()
        ok = True
        for i in perm:
            if not before[i] <= placed:
                ok = False
                break
            placed.add(i)
        if ok:
            yield perm


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
                checkpoint = _renamed("method", method.name, method.preconditions, method.effects,
                                      method.numeric_effects, {**unbound, **subst}, i)
                for order in _linear_orders(method):
                    yield from self._sequence(method, order, 0, subst, i, [checkpoint])
        finally:
            self._stack.discard(key)

    def _sequence(self, method: Method, order: tuple[int, ...], k: int, subst: dict[str, str], i: int,
                  steps: list[Step]) -> Iterator[tuple[int, list[Step]]]:
        if k == len(order):
            yield i, steps
            return
        sub = method.subtasks[order[k]]
        terms = _rename(sub.args, subst)
        action = self.domain.action_by_name.get(sub.task)
        if action is None:
            for j, inner in self._task(sub.task, terms, i):
                yield from self._sequence(method, order, k + 1, subst, j, steps + inner)
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
        step = _renamed("action", action.name, action.preconditions, action.effects, action.numeric_effects,
                        binding, i)
        yield from self._sequence(method, order, k + 1, subst, i + 1, steps + [step])
