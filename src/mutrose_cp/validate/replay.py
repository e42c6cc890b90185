"""Replay of one explanation of a task's actions from the state where the task starts.

Preconditions are checked against what the task changed so far, else the start state, else what
it assumed (an atom nothing knows is assumed as first required, so a task that later requires
its negation fails); effects are recorded.  A function the world does not know may take any
value the task's comparisons on it allow together; what they require of its start value is kept
for the check across the whole mission decomposition (:class:`~.numbers.StartValues`).
"""
from __future__ import annotations

import itertools

from ..io.decomposition_output import OutputTask
from ..model import Comparison, Literal, NumericEffect
from .numbers import AtomKey, StartTests, compare, some_value_meets
from .state import State, TaskEffects
from .steps import Step

Values = dict[str, tuple[str, ...]]


def task_values(task: OutputTask, xml: bool = False) -> Values:
    """Parameter -> ground values as the file gives them (a collection ``[a,b]``, or ``a b`` in
    the XML form, gives several)."""
    out: Values = {}
    for name, _type, value in task.arguments:
        if not value:
            continue
        if value.startswith("[") and value.endswith("]"):
            out[name] = tuple(v.strip() for v in value[1:-1].split(",") if v.strip())
        else:
            out[name] = tuple(value.split()) if xml else (value,)
    return out


def groundings(args: tuple[str, ...], values: Values) -> list[tuple[str, ...]]:
    """Every ground instance of ``args``; empty when some variable is unbound."""
    choices = []
    for a in args:
        if a.startswith("?"):
            if a not in values:
                return []
            choices.append(values[a])
        else:
            choices.append((a,))
    return [tuple(c) for c in itertools.product(*choices)]


def show_literal(predicate: str, args: tuple[str, ...], positive: bool) -> str:
    atom = f"{predicate}({', '.join(args)})"
    return atom if positive else f"not {atom}"


class StepReplay:
    """Replays the steps of one explanation of a task over every grounding of their arguments."""

    def __init__(self, values: Values, start: State, task: str) -> None:
        self.values = values
        self.start = start
        self.task = task
        self.changed = TaskEffects()
        self.facts: dict[AtomKey, bool] = {}  # changed facts
        self.assumed: dict[AtomKey, bool] = {}
        self.nums: dict[AtomKey, float | None] = {}  # function values known or changed here
        # a function nothing knows: what the steps required of its value where the mission
        # starts (op, bound, negated, who), and what they added to it since the task started
        self.required: StartTests = {}
        self.offset: dict[AtomKey, float] = {}
        self.failures: list[str] = []
        self.actions_done = 0  # a message names the action a step is, or that a checkpoint precedes

    def step(self, step: Step) -> None:
        what = f"{step.kind} {step.name}"
        for c in step.preconditions:
            for g in groundings(c.args, self.values):
                if isinstance(c, Literal):
                    self._literal(c, g, what, self.actions_done)
                else:
                    self._comparison(c, g, what, self.actions_done)
        for e in step.effects:
            for g in groundings(e.args, self.values):
                self.facts[(e.predicate, g)] = e.positive
                self.changed.facts[(e.predicate, g)] = e.positive
        for n in step.numeric_effects:
            for g in groundings(n.args, self.values):
                self._numeric_effect(n, (n.function, g))
        self.actions_done += step.is_action

    def _value(self, key: AtomKey) -> float | None:
        return self.nums[key] if key in self.nums else self.start.values.get(key)

    def _literal(self, c: Literal, g: tuple[str, ...], what: str, position: int) -> None:
        key = (c.predicate, g)
        known = self.facts.get(key, self.start.facts.get(key, self.assumed.get(key)))
        if known is None:
            self.assumed[key] = c.positive
        elif known != c.positive:
            self.failures.append(f"precondition {show_literal(c.predicate, g, c.positive)} of {what} "
                                 f"(action {position + 1}) does not hold")

    def _comparison(self, c: Comparison, g: tuple[str, ...], what: str, position: int) -> None:
        """A numeric precondition; a value nothing knows may be anything that the task's
        preconditions on it allow together, and a required equality makes it known."""
        key = (c.function, g)
        value = self._value(key)
        shown = f"precondition {'not ' if c.negated else ''}{c.function}({', '.join(g)}) {c.op} {c.value:g}"
        if value is None:
            required = self.required.setdefault(key, [])
            start = self.start.offsets.get(key, 0.0) + self.offset.get(key, 0.0)
            required.append((c.op, float(c.value) - start, c.negated, f"{self.task}: {shown}"))
            if not some_value_meets(required):
                self.failures.append(f"{shown} of {what} (action {position + 1}) cannot hold together "
                                     f"with the task's earlier preconditions on it (the world does not know it)")
            elif c.op == "=" and not c.negated:
                self.nums[key] = float(c.value)
            return
        if compare(value, c.op, float(c.value)) == c.negated:
            self.failures.append(f"{shown} of {what} (action {position + 1}) does not hold: the value is {value:g}")

    def _numeric_effect(self, n: NumericEffect, key: AtomKey) -> None:
        """An assignment sets the value; an increase or decrease changes a known value only."""
        old = self._value(key)
        change = n.amount if n.kind == "increase" else -n.amount
        if n.kind == "assign":
            self.nums[key] = float(n.amount)
        elif old is not None:
            self.nums[key] = old + change
        else:
            self.offset[key] = self.offset.get(key, 0.0) + change
        self.changed.numeric.append((key, n.kind, float(n.amount)))
