"""The steps of a decomposition as the validator reads them, in the root task's parameter names.

A decomposition is a sequence of *steps*: each action, and before the subtasks of every method
that has preconditions or effects of its own, that method's *checkpoint* (its conditions are
checked where the method starts, semantics.md §2.2).  The listing of a task's numbered
decompositions (:mod:`.numbering`) and the reading of a file's actions back into method trees
(:mod:`.htn_match`) both produce steps, so that what a number stands for and what a file's
actions require are compared, printed and replayed in one vocabulary.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import Mapping, Sequence

from ..model import Action, Comparison, Literal, Method, NumericEffect, Precondition

ACTION, METHOD = "action", "method"


@dataclass(frozen=True)
class Step:
    """An action, or a method's checkpoint; ``args`` are an action's declared parameters as the
    output prints them (a method's checkpoint has none)."""

    kind: str  # ACTION | METHOD
    name: str
    args: tuple[str, ...]
    preconditions: tuple[Precondition, ...]
    effects: tuple[Literal, ...]
    numeric_effects: tuple[NumericEffect, ...]

    @property
    def is_action(self) -> bool:
        return self.kind == ACTION


def _terms(args: Sequence[str], names: Mapping[str, str]) -> tuple[str, ...]:
    return tuple(names.get(a, a) for a in args)


def _conditions(source: Action | Method, names: Mapping[str, str]) -> tuple[
        tuple[Precondition, ...], tuple[Literal, ...], tuple[NumericEffect, ...]]:
    pre = tuple(Literal(c.predicate, _terms(c.args, names), c.positive) if isinstance(c, Literal)
                else Comparison(c.function, _terms(c.args, names), c.op, c.value, c.negated)
                for c in source.preconditions)
    eff = tuple(Literal(e.predicate, _terms(e.args, names), e.positive) for e in source.effects)
    num = tuple(NumericEffect(n.kind, n.function, _terms(n.args, names), n.amount) for n in source.numeric_effects)
    return pre, eff, num


def action_step(action: Action, names: Mapping[str, str]) -> Step:
    """``action`` with its parameters renamed by ``names`` (a parameter not in it keeps its name)."""
    return Step(ACTION, action.name, _terms([p.name for p in action.parameters], names), *_conditions(action, names))


def has_checkpoint(method: Method) -> bool:
    return bool(method.preconditions or method.effects or method.numeric_effects)


def checkpoint(method: Method, names: Mapping[str, str]) -> Step:
    """The method's own preconditions and effects, its parameters renamed by ``names`` (a
    constant among the method's task arguments stays itself)."""
    own = {p.name for p in method.parameters}
    return Step(METHOD, method.name, (), *_conditions(method, {k: v for k, v in names.items() if k in own}))
