"""Checks of properties against the mission's domain: every task, method, action, capability,
predicate and function a property names must be declared, and a fact must have as many
arguments as its declaration.  A misspelt name would otherwise make ``uses`` false in
every decomposition, and ``never uses(action drop-itme)`` would "hold" silently."""
from __future__ import annotations

from typing import Iterable, Iterator

from ..errors import MissionError, Problem, closest
from ..model.domain import Domain
from ..model.properties import Fact, Finally, Formula, InitiallyNeeded, Property, TaskPattern, Uses, atoms, task_patterns


def check_properties(properties: Iterable[Property], domain: Domain) -> None:
    """Raise every problem of :func:`property_problems` together (exit status 2)."""
    problems = property_problems(properties, domain)
    if problems:
        raise MissionError(problems)


def property_problems(properties: Iterable[Property], domain: Domain) -> list[Problem]:
    """Every unknown name or wrong argument count, located at its property's line."""
    known = _DomainNames(domain)
    return [Problem(p.where, f"property {p.name}: {message}")
            for p in properties for message in known.problems(p.formula)]


class _DomainNames:
    """The names a property may use, by kind, and the arity of each task and fact."""

    def __init__(self, domain: Domain) -> None:
        self.arity = {
            "task": {t.name: len(t.parameters) for t in domain.tasks},
            "fact": {d.name: len(d.parameters) for d in (*domain.predicates, *domain.functions)},
        }
        self.names = {
            "method": [m.name for m in domain.methods],
            "action": [a.name for a in domain.actions],
            "capability": [*domain.capabilities, *(c for a in domain.actions for c in a.capabilities)],
            "decomposition": [],  # ids come from the Task Graph: an unknown one is reported by verify
        }

    def problems(self, formula: Formula) -> Iterator[str]:
        for atom in atoms(formula):
            if isinstance(atom, Uses):
                yield from self._target(atom.target)
            elif isinstance(atom, (Finally, InitiallyNeeded)):
                yield from self._fact(atom.fact)
            else:
                for task in task_patterns(atom):
                    yield from self._task(task)

    def _target(self, target: TaskPattern | tuple[str, str]) -> Iterator[str]:
        if isinstance(target, TaskPattern):
            yield from self._task(target)
            return
        kind, name = target
        if kind != "decomposition" and name not in self.names[kind]:
            yield _unknown(kind, name, self.names[kind])

    def _task(self, task: TaskPattern) -> Iterator[str]:
        # a pattern's arguments are matched against the instance's values, which need not be
        # one per parameter (the robot parameters have none): only the name is checked
        yield from _arity("task", task.name, None, self.arity["task"])

    def _fact(self, fact: Fact) -> Iterator[str]:
        yield from _arity("predicate or function", fact.name, fact.arguments, self.arity["fact"])


def _arity(kind: str, name: str, arguments: tuple[str, ...] | None, arity: dict[str, int]) -> Iterator[str]:
    if name not in arity:
        yield _unknown(kind, name, arity)
    elif arguments is not None and len(arguments) != arity[name]:
        yield f"{kind} {name} takes {arity[name]} arguments, not {len(arguments)}"


def _unknown(kind: str, name: str, candidates: Iterable[str]) -> str:
    guess = closest(name, candidates)
    return f"the domain declares no {kind} {name}" + (f" (did you mean {guess}?)" if guess else "")
