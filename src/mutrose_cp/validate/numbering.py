"""Decomposition numbers: which steps ``AT1_1|n`` stands for (semantics.md §2.1 to §2.4,
docs/formats/hddl.md "Decompositions and their numbers", docs/numbers.md).

An output numbers the decompositions of an abstract task ``|1``, ``|2``, ... in the spec's order,
the same numbers for every instance of the task.  To know what a number must be, the validator
lists the decompositions itself, from the domain alone:

* the methods of a task in declaration order, and for each one every order of its steps that its
  ``:ordering`` allows, its checkpoint first; where several steps may come next they are tried
  as the task decomposition graph numbers its vertices: a subtask that recurses into a task above
  it first (the outermost such task first), then the others as declared;
* each order is followed through a state of *assumed* facts and values over the root task's
  parameter names.  A step whose precondition contradicts what the state knows ends the order
  (the original's verdict: a comparison with a known value decides alone, whatever came before it
  in the step).  A fact or ``=`` value nobody knows is assumed as required, and so is a recursive
  method's ``>`` guard, at its bound less what the rest of the method adds.  A step's effects
  then hold for the steps after it (an increase of an unknown value leaves it unknown); an
  abstract subtask's do not;
* the decompositions of one order are every choice of one decomposition per abstract subtask,
  the later subtask's choice varying slowest; a subtask that has none drops out of the order.

A decomposition through a recursive method records which of its steps the recursion repeats
(:class:`Repeat`); :func:`unrolled` repeats them as often as the world's value of the guard asks.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field, replace
from fractions import Fraction
from typing import Iterator, Mapping, Sequence

from ..model import Comparison, Domain, Literal, Method
from .numbers import AtomKey, compare
from .steps import METHOD, Step, action_step, checkpoint, has_checkpoint

MAX_DEPTH = 64  # nested tasks: a recursion that no guard stops is cut here


class PathError(Exception):
    """The domain's decompositions cannot be listed (a recursion without end, an unbound subtask
    argument)."""


@dataclass(frozen=True)
class Repeat:
    """Steps ``first..last`` of a decomposition, which a recursive method runs again while
    ``function(args) > bound``; each run changes the function by ``change`` (negative)."""

    first: int
    last: int
    function: str
    args: tuple[str, ...]
    bound: float
    change: float

    def extra_runs(self, value: float) -> int:
        """How many more runs than the one the decomposition holds a start ``value`` asks for:
        the guard holds at ``value``, ``value + change``, ... while above ``bound``."""
        runs = math.ceil((Fraction(str(value)) - Fraction(str(self.bound))) / Fraction(str(-self.change)))
        return max(runs, 0) - 1


@dataclass(frozen=True)
class Listed:
    """One numbered decomposition of a task: its steps and the stretches a recursion repeats."""

    steps: tuple[Step, ...]
    repeats: tuple[Repeat, ...] = ()

    @property
    def actions(self) -> tuple[Step, ...]:
        return tuple(s for s in self.steps if s.is_action)


@dataclass(frozen=True)
class _Call:
    """An abstract subtask of a method: the task, its parameters in root terms, and the tasks
    from the root down to the vertex it stands for (an ancestor's, when it recurses)."""

    task: str
    terms: dict[str, str]
    above: tuple[str, ...]


class _Plan:
    """One method under one renaming into root terms: its subtasks in declaration order (actions
    renamed, abstract tasks as calls), then its checkpoint; the order in which they are tried,
    and which must come before which."""

    def __init__(self, domain: Domain, method: Method, names: dict[str, str], above: tuple[str, ...]) -> None:
        self.method = method
        self.entries: list[Step | _Call] = []
        priority: list[tuple[int, int]] = []
        for i, sub in enumerate(method.subtasks):
            callee = domain.task_by_name.get(sub.task)
            if callee is None:
                action = domain.action_by_name[sub.task]
                self.entries.append(action_step(action, {p.name: names[a] for p, a in zip(action.parameters, sub.args)
                                                         if a in names}))
                priority.append((1, i))
                continue
            terms = {p.name: names[a] for p, a in zip(callee.parameters, sub.args) if a in names}
            at = above.index(sub.task) if sub.task in above else None
            self.entries.append(_Call(sub.task, terms, above + (sub.task,) if at is None else above[:at + 1]))
            priority.append((1, i) if at is None else (0, at))
        self.recursive = any(sub.task == method.task for sub in method.subtasks)
        position = {sub.id: i for i, sub in reversed(list(enumerate(method.subtasks)))}
        self.before: list[set[int]] = [set() for _ in self.entries]
        for a, b in method.ordering:
            if a in position and b in position:
                self.before[position[b]].add(position[a])
        if has_checkpoint(method):
            for others in self.before:
                others.add(len(self.entries))
            self.entries.append(checkpoint(method, names))
            self.before.append(set())
            priority.append((2, 0))
        self.tried = sorted(range(len(self.entries)), key=lambda i: (priority[i], i))

    def orders(self) -> Iterator[list[int]]:
        """Every order of the entries that ``before`` allows, tried depth first."""
        def extend(prefix: list[int]) -> Iterator[list[int]]:
            if len(prefix) == len(self.entries):
                yield list(prefix)
                return
            for i in self.tried:
                if i not in prefix and self.before[i] <= set(prefix):
                    yield from extend(prefix + [i])
        return extend([])


@dataclass
class _Verdict:
    """What following a step found: whether it runs, and what it assumes of the state (the first
    assumption of an atom wins); ``guards`` are a recursive method's ``>`` bounds."""

    runs: bool = True
    facts: list[tuple[AtomKey, bool]] = field(default_factory=list)
    values: list[tuple[AtomKey, float]] = field(default_factory=list)
    guards: list[tuple[AtomKey, float]] = field(default_factory=list)


def _added(atom: AtomKey, steps: Sequence[Step]) -> float:
    """What the increases and decreases of ``steps`` add to a function."""
    return sum(n.amount if n.kind == "increase" else -n.amount for s in steps for n in s.numeric_effects
               if (n.function, n.args) == atom and n.kind != "assign")


class _Assumed:
    """The facts and function values one order of a method has set or assumed so far."""

    def __init__(self, facts: dict[AtomKey, bool] | None = None, values: dict[AtomKey, float] | None = None) -> None:
        self.facts = facts if facts is not None else {}
        self.values = values if values is not None else {}

    def copy(self) -> "_Assumed":
        return _Assumed(dict(self.facts), dict(self.values))

    def verdict(self, step: Step, later: Sequence[Step], guard: bool) -> _Verdict:
        found = _Verdict()
        for c in step.preconditions:
            if isinstance(c, Literal):
                self._literal(c, found)
            else:
                self._comparison(c, found, later, guard)
        return found

    def _literal(self, c: Literal, found: _Verdict) -> None:
        atom = (c.predicate, c.args)
        if atom in self.facts:
            found.runs = found.runs and self.facts[atom] == c.positive
        elif (atom, not c.positive) not in found.facts:
            found.facts.append((atom, c.positive))

    def _comparison(self, c: Comparison, found: _Verdict, later: Sequence[Step], guard: bool) -> None:
        atom = (c.function, c.args)
        if atom in self.values:
            found.runs = compare(self.values[atom], c.op, float(c.value))  # decides alone
        elif c.op != ">":
            found.values.append((atom, float(c.value)))
        elif guard:
            found.values.append((atom, float(c.value) - _added(atom, later)))
            found.guards.append((atom, float(c.value)))

    def enter(self, step: Step, found: _Verdict) -> None:
        """The step's assumptions, then its effects."""
        for atom, positive in found.facts:
            self.facts.setdefault(atom, positive)
        for atom, value in found.values:
            self.values.setdefault(atom, value)
        for e in step.effects:
            self.facts[(e.predicate, e.args)] = e.positive
        for n in step.numeric_effects:
            atom = (n.function, n.args)
            if n.kind == "assign":
                self.values[atom] = float(n.amount)
            elif atom in self.values:
                self.values[atom] += n.amount if n.kind == "increase" else -n.amount


def _choices(options: list[list[Listed]]) -> list[Listed]:
    """One decomposition per entry, concatenated in order; the later entry's choice varies slowest."""
    out = []
    for choice in itertools.product(*reversed(options)):
        steps: list[Step] = []
        repeats: list[Repeat] = []
        for part in reversed(choice):
            repeats.extend(replace(r, first=r.first + len(steps), last=r.last + len(steps)) for r in part.repeats)
            steps.extend(part.steps)
        out.append(Listed(tuple(steps), tuple(repeats)))
    return out


class _Listing:
    """The numbered decompositions of the tasks of one domain."""

    def __init__(self, domain: Domain) -> None:
        self.domain = domain

    def task(self, name: str, terms: dict[str, str], above: tuple[str, ...], known: _Assumed,
             depth: int) -> list[Listed]:
        """The decompositions of task ``name`` whose parameters stand for ``terms``, every method
        from its own copy of ``known``; ``above``: the tasks from the root down to it."""
        if depth > MAX_DEPTH:
            raise PathError(f"the decomposition of {name} does not end (a recursion without a numeric guard)")
        task = self.domain.task_by_name[name]
        out: list[Listed] = []
        for method in self.domain.methods_of(name):
            unbound = [p.name for p in task.parameters if p.name not in terms]
            if unbound:
                raise PathError(f"method {method.name}: parameter {unbound[0]} of {name} is not bound by the task above")
            plan = _Plan(self.domain, method, {a: terms[p.name] for a, p in zip(method.task_args, task.parameters)},
                         above)
            for order in plan.orders():
                out.extend(self.order(plan, order, known.copy(), depth))
        return out

    def order(self, plan: _Plan, order: list[int], known: _Assumed, depth: int) -> list[Listed]:
        options: list[list[Listed]] = []
        repeats: list[Repeat] = []
        for k, i in enumerate(order):
            entry = plan.entries[i]
            if isinstance(entry, _Call):
                found = self.task(entry.task, entry.terms, entry.above, known, depth + 1)
                if found:
                    options.append(found)
                continue
            later = [e for e in (plan.entries[j] for j in order[k + 1:]) if isinstance(e, Step)]
            guard = plan.recursive and entry.kind == METHOD
            verdict = known.verdict(entry, later, guard)
            if not verdict.runs:
                return []
            if guard:
                repeats.extend(_repeats(plan, verdict.guards, later))
            known.enter(entry, verdict)
            options.append([Listed((entry,))])
        return [Listed(d.steps, tuple(repeats) + d.repeats) for d in _choices(options)]


def _repeats(plan: _Plan, guards: list[tuple[AtomKey, float]], later: list[Step]) -> Iterator[Repeat]:
    """The stretch a recursive method repeats, for each of its guards that its steps lower."""
    for atom, bound in guards:
        changes = [n for s in later for n in s.numeric_effects if (n.function, n.args) == atom]
        if not changes:
            continue
        change = sum(n.amount if n.kind == "increase" else -n.amount for n in changes)
        if change >= 0 or any(n.kind == "assign" for n in changes):
            raise PathError(f"the recursion of method {plan.method.name} does not decrease {atom[0]}")
        yield Repeat(0, len(plan.entries) - 2, atom[0], atom[1], bound, change)


def task_decompositions(domain: Domain, task: str) -> list[Listed]:
    """The decompositions of ``task`` in number order: item ``n - 1`` is ``|n`` of every instance."""
    identity = {p.name: p.name for p in domain.task_by_name[task].parameters}
    listed = _Listing(domain).task(task, identity, (task,), _Assumed(), 0)
    return [Listed(d.steps, tuple(sorted(d.repeats, key=lambda r: r.first))) for d in listed]


def unrolled(listed: Listed, ground: Mapping[str, tuple[str, ...]],
             value_of: Mapping[AtomKey, float]) -> Listed:
    """``listed`` with each repeated stretch run as often as the world's value of its guard asks
    (docs/numbers.md); a guard the world gives no single value for keeps the one run."""
    steps = list(listed.steps)
    inserted = 0
    for r in listed.repeats:
        atoms = list(itertools.product(*(ground.get(a, (a,)) if a.startswith("?") else (a,) for a in r.args)))
        value = value_of.get((r.function, atoms[0])) if len(atoms) == 1 else None
        extra = 0 if value is None else r.extra_runs(value)
        if extra > 0:
            first, last = r.first + inserted, r.last + inserted
            steps[last + 1:last + 1] = steps[first:last + 1] * extra
            inserted += (last + 1 - first) * extra
    return Listed(tuple(steps))
