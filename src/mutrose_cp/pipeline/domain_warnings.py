"""Warnings about an HDDL domain that the decomposer accepts but that point to a mistake, or
that standard HDDL tools reject (``mutrose-cp check``, docs/cli.md#check).

The reader already refuses what the decomposer cannot use (undeclared predicates, a subtask
given too many arguments, an unknown abstract task).  What it accepts, as the original does,
may still be wrong:

* a sort used without being declared in ``:types`` (the decomposer makes it a root type);
* a predicate or function declared twice with different parameters (a use matches either);
* a subtask given fewer arguments than its task or action has parameters (the missing ones stay
  free variables);
* a predicate, action or method the mission never uses.

"Unused" is relative to the mission: the abstract tasks its goal model names, and every task
and action their methods call, transitively, are *reachable*.  An action that is not reachable
and a method of a task that is not reachable can never be part of a decomposition.  A predicate
is unused when no precondition or effect of any action or method mentions it (reachable or
not: an unreachable action is reported once, as an action), so a semantic mapping that fills it
from the world has no effect on any decomposition.
"""
from __future__ import annotations

from typing import Iterable

from ..errors import Problem, counted, located
from ..io.hddl import signature
from ..model import Domain, GoalModel
from ..model.domain import Action, Declaration, Method



def domain_warnings(domain: Domain, goal_model: GoalModel) -> list[Problem]:
    """Every warning about ``domain`` for the mission of ``goal_model``, in file order."""
    found: list[tuple[int, int, str]] = [
        *undeclared_types(domain),
        *conflicting_declarations(domain.predicates, "predicate"),
        *conflicting_declarations(domain.functions, "function"),
        *short_subtask_calls(domain),
        *unused(domain, [n.task_name for n in goal_model.nodes if n.kind == "task" and n.task_name]),
    ]
    return [Problem(located(domain.source, line, column), message)
            for line, column, message in sorted(found, key=lambda w: (w[0], w[1]))]


def undeclared_types(domain: Domain) -> list[tuple[int, int, str]]:
    return [(t.line, t.column,
             f"type '{t.name}' is used but not declared in (:types ...): the decomposer makes it a type of its "
             f"own, standard HDDL readers reject the domain; declare it, e.g. (:types ... {t.name} - object)")
            for t in domain.undeclared_types]


def conflicting_declarations(declarations: Iterable[Declaration], what: str) -> list[tuple[int, int, str]]:
    """Each later declaration of a name whose parameter types differ from the first one's."""
    first: dict[str, Declaration] = {}
    found: list[tuple[int, int, str]] = []
    for declaration in declarations:
        earlier = first.setdefault(declaration.name, declaration)
        if earlier is declaration or earlier.sorts == declaration.sorts:
            continue
        found.append((declaration.line, declaration.column,
                      f"{what} '{declaration.name}' is declared again with different parameters: "
                      f"{signature(declaration.name, declaration.parameters)} here, "
                      f"{signature(earlier.name, earlier.parameters)} at {earlier.line}:{earlier.column}; the "
                      f"decomposer accepts a use matching either, standard HDDL allows one declaration per name: "
                      f"rename one of them"))
    return found



def short_subtask_calls(domain: Domain) -> list[tuple[int, int, str]]:
    """Subtasks given fewer arguments than their task or action declares parameters."""
    found: list[tuple[int, int, str]] = []
    for method in domain.methods:
        for step in method.subtasks:
            callee = domain.task_by_name.get(step.task) or domain.action_by_name.get(step.task)
            if callee is None or len(step.args) >= len(callee.parameters):
                continue
            missing = " ".join(p.name for p in callee.parameters[len(step.args):])
            found.append((step.line, step.column,
                          f"subtask {step.task} in method '{method.name}' is given "
                          f"{counted(len(step.args), 'argument')} but declares "
                          f"{counted(len(callee.parameters), 'parameter')}: "
                          f"{signature(callee.name, callee.parameters)}; the decomposer leaves {missing} free, "
                          "standard HDDL readers reject the call: pass one argument per parameter"))
    return found


def reachable(domain: Domain, roots: Iterable[str]) -> set[str]:
    """The abstract tasks and actions reachable from the tasks ``roots`` through methods."""
    seen: set[str] = set()
    pending = [r for r in roots if r in domain.task_by_name]
    while pending:
        task = pending.pop()
        if task in seen:
            continue
        seen.add(task)
        for method in domain.methods_of(task):
            pending.extend(s.task for s in method.subtasks if s.task not in seen)
    return seen


def unused(domain: Domain, roots: Iterable[str]) -> list[tuple[int, int, str]]:
    """Actions and methods the mission cannot reach, predicates no action or method mentions."""
    roots = list(roots)
    used = reachable(domain, roots)
    named = ", ".join(sorted(set(roots))) or "none"
    found: list[tuple[int, int, str]] = []
    for action in domain.actions:
        if action.name not in used:
            found.append((action.line, action.column,
                          f"action '{action.name}' is unused: no method reachable from the goal model's tasks "
                          f"({named}) calls it"))
    for method in domain.methods:
        if method.task not in used:
            found.append((method.line, method.column,
                          f"method '{method.name}' is unused: its task {method.task} is not reachable from the "
                          f"goal model's tasks ({named})"))
    mentioned = _mentioned_predicates([*domain.actions, *domain.methods])
    reported: set[str] = set()
    for predicate in domain.predicates:
        if predicate.name not in mentioned and predicate.name not in reported:
            reported.add(predicate.name)
            found.append((predicate.line, predicate.column,
                          f"predicate '{predicate.name}' is unused: no precondition or effect of an action or "
                          "method mentions it, so its facts never matter"))
    return found


def _mentioned_predicates(bodies: Iterable[Action | Method]) -> set[str]:
    names: set[str] = set()
    for body in bodies:
        names.update(getattr(c, "predicate", "") for c in body.preconditions)
        names.update(e.predicate for e in body.effects)
    return names
