"""Standard HDDL from the typed domain (and a mission's problem), for other HTN planners.

The decomposer reads MutRoSe's dialect of HDDL (``docs/formats/hddl.md``); planners such as
PANDA or unified-planning read the standard one (Höller et al., 2020).  This module writes the
frozen :class:`~mutrose_cp.model.Domain` back as standard HDDL, rewriting what the standard has
no form for, each rewrite reported as a warning:

* blocks in the standard order (requirements, types, constants, predicates, functions, tasks,
  methods, actions), with ``:hierarchy`` and the other requirements the domain needs;
* capabilities (``:capabilities``, ``:required-capabilities``) kept as comments;
* orderings written ``(< a b)``; every method gets ``:parameters``;
* every type declared: a sort the domain only uses is declared under ``object``;
* a predicate declared more than once with the same arity is declared once, each parameter
  typed with the nearest common supertype of the declarations; another arity of the same name
  becomes the predicate ``name-N`` (uses renamed alike); ``at`` and ``hascapability``, which
  the decomposer accepts undeclared in preconditions, are declared with ``object`` parameters;
* a subtask given fewer arguments than its task or action has parameters gets a new method
  parameter for each missing one (the decomposer leaves them free: so does the planner);
* a method effect (standard methods have none) becomes an action of its own, the method's first
  subtask, as the decomposer treats it (``__method_precondition_<method>``).

Numeric functions, comparisons and ``increase``/``decrease``/``assign`` effects are written as
PDDL numeric fluents (requirement ``:numeric-fluents``).  What the reader drops (requirements
of the source, ``:rewards``, ``:reliability``, variable constraints, causal links, the bodies of
abstract tasks) is not written.  The text is built from the model alone, in declaration order,
so the same domain always gives the same bytes.
"""
from __future__ import annotations

import re
from dataclasses import dataclass, field
from typing import Iterable, Sequence

from ..model.domain import (
    Action,
    Comparison,
    Declaration,
    Domain,
    Literal,
    Method,
    NumericEffect,
    Parameter,
    Precondition,
    Subtask,
)
from .hddl import signature

STANDARD_NAME = re.compile(r"[A-Za-z][A-Za-z0-9_-]*\Z")
"""A name every standard HDDL reader accepts (MutRoSe also allows ``|``)."""

_IMPLICIT_PREDICATES = ("at", "hascapability")
_INDENT = "  "


@dataclass(frozen=True)
class ProblemData:
    """A mission as an HDDL problem: objects, initial state and one totally ordered network.

    Built by :mod:`mutrose_cp.output.hddl_problem`; ``facts`` and ``values`` use the domain's
    predicate and function names (the writer renames them as it renames their declarations)."""

    name: str
    objects: tuple[tuple[str, str], ...]  # (object, type)
    facts: tuple[tuple[str, tuple[str, ...]], ...]
    values: tuple[tuple[str, tuple[str, ...], int | float], ...]
    parameters: tuple[Parameter, ...]  # variables of the network (unbound robot parameters)
    network: tuple[Subtask, ...]  # totally ordered
    comments: tuple[str, ...] = ()


@dataclass
class _Signature:
    """One exported predicate: its name and parameters (merged over its declarations)."""

    name: str
    parameters: list[Parameter]


@dataclass
class HddlExport:
    """The standard-HDDL rendering of ``domain``: :meth:`domain_text`, :meth:`problem_text`
    and the ``warnings`` describing every rewrite (collected as the texts are built)."""

    domain: Domain
    warnings: list[str] = field(default_factory=list)

    def __post_init__(self) -> None:
        self._parents = self._type_parents()
        self._predicates = self._merge_predicates()
        self._effect_actions = self._method_effect_actions()
        self._check_names()

    # ---- names

    def predicate_name(self, name: str, arity: int) -> str:
        """The exported name of predicate ``name`` used with ``arity`` arguments."""
        signature = self._predicates.get((name, arity))
        return signature.name if signature is not None else name

    def _check_names(self) -> None:
        """Standard HDDL names have no ``|``, and readers compare them ignoring case."""
        d = self.domain
        namespaces = {
            "type": [t for t, _ in d.types],
            "predicate": [s.name for s in self._predicates.values()],
            "task or action": [t.name for t in d.tasks] + [a.name for a in d.actions],
            "method": [m.name for m in d.methods],
            "constant": [c for c, _ in d.constants],
        }
        for kind, names in namespaces.items():
            by_case: dict[str, str] = {}
            for name in dict.fromkeys(names):
                if not STANDARD_NAME.match(name):
                    self.warnings.append(f"{kind} name '{name}' is not a standard HDDL name (letters, digits, "
                                         "'-' and '_'): other readers may reject it; rename it")
                other = by_case.setdefault(name.lower(), name)
                if other != name:
                    self.warnings.append(f"{kind} names '{other}' and '{name}' differ only in case: HDDL names "
                                         "are case-insensitive, so other readers take them for one; rename one")

    # ---- types

    def _type_parents(self) -> dict[str, str]:
        """Every sort -> its parent, ``object`` for the roots (declared or only used)."""
        parents: dict[str, str] = {}
        for name, parent in self.domain.types:
            if name != "object":
                parents.setdefault(name, parent or "object")
        for mention in self.domain.undeclared_types:
            self.warnings.append(f"{self.domain.source}:{mention.line}:{mention.column}: type '{mention.name}' is "
                                 "used but not declared: declared under object")
        return parents

    def _ancestry(self, sort: str) -> list[str]:
        chain = [sort]
        while chain[-1] in self._parents and self._parents[chain[-1]] not in chain:
            chain.append(self._parents[chain[-1]])
        return chain if chain[-1] == "object" else [*chain, "object"]

    def _common_supertype(self, sorts: Iterable[str]) -> str:
        """The nearest sort every one of ``sorts`` is (a subtype of)."""
        chains = [self._ancestry(s) for s in sorts]
        return next(s for s in chains[0] if all(s in c for c in chains[1:]))

    # ---- predicates

    def _merge_predicates(self) -> dict[tuple[str, int], _Signature]:
        """(name, arity) -> exported signature, in declaration order; uses the decomposer
        accepts undeclared (``at``, ``hascapability``) are declared with ``object`` sorts."""
        groups: dict[tuple[str, int], list[Declaration]] = {}
        for declaration in self.domain.predicates:
            groups.setdefault((declaration.name, len(declaration.parameters)), []).append(declaration)
        for name, arity in self._implicit_uses(groups):
            parameters = tuple(Parameter(f"?a{i}", "object") for i in range(1, arity + 1))
            groups[(name, arity)] = [Declaration(name, parameters)]
            self.warnings.append(f"predicate '{name}' is used with {arity} arguments without a declaration: "
                                 f"declared as ({name} {' '.join(p.name + ' - object' for p in parameters)})")
        taken = {name.lower() for name, _ in groups}
        first_arity: dict[str, int] = {}
        merged: dict[tuple[str, int], _Signature] = {}
        for (name, arity), declarations in groups.items():
            exported = name
            if first_arity.setdefault(name, arity) != arity:
                exported = _fresh(f"{name}-{arity}", taken)
                self.warnings.append(f"predicate '{name}' is declared with {first_arity[name]} and with {arity} "
                                     f"arguments: the {arity}-argument one is written as '{exported}'")
            merged[(name, arity)] = _Signature(exported, self._merged_parameters(declarations))
        return merged

    def _implicit_uses(self, declared: dict[tuple[str, int], list[Declaration]]) -> list[tuple[str, int]]:
        uses: list[tuple[str, int]] = []
        for condition in self._conditions():
            key = (getattr(condition, "predicate", ""), len(condition.args))
            if key[0] in _IMPLICIT_PREDICATES and key not in declared and key not in uses:
                uses.append(key)
        return uses

    def _merged_parameters(self, declarations: Sequence[Declaration]) -> list[Parameter]:
        first = declarations[0]
        if all(d.sorts == first.sorts for d in declarations):
            return list(first.parameters)
        parameters = [Parameter(p.name, self._common_supertype(d.parameters[i].type for d in declarations))
                      for i, p in enumerate(first.parameters)]
        variants = " and ".join(signature(first.name, d.parameters) for d in declarations)
        self.warnings.append(f"{self.domain.source}:{first.line}:{first.column}: predicate '{first.name}' is "
                             f"declared as {variants}: declared once as "
                             f"{signature(first.name, parameters)}")
        return parameters

    def _conditions(self) -> list[Precondition]:
        """Every precondition of every action and method."""
        bodies: list[Action | Method] = [*self.domain.actions, *self.domain.methods]
        return [c for body in bodies for c in body.preconditions]

    # ---- method effects

    def _method_effect_actions(self) -> dict[str, Action]:
        """method -> the action that carries its effects (for methods that have effects)."""
        taken = self._task_names()
        actions: dict[str, Action] = {}
        for method in self.domain.methods:
            if not (method.effects or method.numeric_effects):
                continue
            name = _fresh(f"method-effects-{method.name}", taken)
            actions[method.name] = Action(name, method.parameters, effects=method.effects,
                                          numeric_effects=method.numeric_effects)
            self.warnings.append(f"{self.domain.source}:{method.line}:{method.column}: method '{method.name}' has "
                                 f"effects, which standard HDDL methods cannot have: they are the action '{name}', "
                                 "the method's first subtask")
        return actions

    def _task_names(self) -> set[str]:
        """The names of the tasks and actions, lower-cased (HDDL names ignore case)."""
        return {t.name.lower() for t in self.domain.tasks} | {a.name.lower() for a in self.domain.actions}

    # ---- the domain text

    def domain_text(self) -> str:
        d = self.domain
        lines = [f"; {d.name}: standard HDDL written by mutrose-cp export-hddl from the MutRoSe domain",
                 f"(define (domain {d.name})",
                 f"{_INDENT}(:requirements {' '.join(self._requirements())})"]
        lines += self._types_block()
        if d.constants:
            lines.append(f"{_INDENT}(:constants {' '.join(_grouped(d.constants))})")
        if self._predicates:
            lines.append(f"{_INDENT}(:predicates")
            lines += [_INDENT * 2 + _atom(s.name, _typed(s.parameters)) for s in self._predicates.values()]
            lines.append(f"{_INDENT})")
        if d.functions:
            lines.append(f"{_INDENT}(:functions")
            lines += [_INDENT * 2 + _atom(f.name, _typed(f.parameters)) + " - number" for f in _unique(d.functions)]
            lines.append(f"{_INDENT})")
        if d.capabilities:
            lines.append(f"{_INDENT}; MutRoSe capabilities: {' '.join(d.capabilities)}")
        lines += [f"{_INDENT}(:task {t.name} :parameters ({' '.join(_typed(t.parameters))}))" for t in d.tasks]
        for method in d.methods:
            lines += self._method(method)
        for action in (*d.actions, *self._effect_actions.values()):
            lines += self._action(action)
        lines.append(")")
        return "\n".join(lines) + "\n"

    def _requirements(self) -> list[str]:
        d = self.domain
        needs = {
            ":negative-preconditions": any(not getattr(c, "positive", True) or getattr(c, "negated", False)
                                           for c in self._conditions()),
            ":method-preconditions": any(m.preconditions for m in d.methods),
            ":numeric-fluents": bool(d.functions),
        }
        return [":typing", ":hierarchy", *(r for r, needed in needs.items() if needed)]

    def _types_block(self) -> list[str]:
        if not self._parents:
            return []
        by_parent: dict[str, list[str]] = {}
        for name, parent in self._parents.items():
            by_parent.setdefault(parent, []).append(name)
        return [f"{_INDENT}(:types",
                *(f"{_INDENT * 2}{' '.join(names)} - {parent}" for parent, names in by_parent.items()),
                f"{_INDENT})"]

    def _action(self, action: Action) -> list[str]:
        lines = [f"{_INDENT}(:action {action.name}"]
        if action.capabilities:
            lines.append(f"{_INDENT * 2}; required capabilities: {' '.join(action.capabilities)}")
        lines.append(f"{_INDENT * 2}:parameters ({' '.join(_typed(action.parameters))})")
        lines += self._body(action.preconditions, action.effects, action.numeric_effects)
        lines.append(f"{_INDENT})")
        return lines

    def _body(self, preconditions: Sequence[Precondition], effects: Sequence[Literal],
              numeric: Sequence[NumericEffect]) -> list[str]:
        lines: list[str] = []
        if preconditions:
            lines.append(f"{_INDENT * 2}:precondition (and {' '.join(self._condition(c) for c in preconditions)})")
        if effects or numeric:
            written = [self._literal(e) for e in effects] + [_numeric_effect(n) for n in numeric]
            lines.append(f"{_INDENT * 2}:effect (and {' '.join(written)})")
        return lines

    def _condition(self, condition: Precondition) -> str:
        if isinstance(condition, Comparison):
            text = f"({condition.op} {_atom(condition.function, condition.args)} {_number(condition.value)})"
            return f"(not {text})" if condition.negated else text
        return self._literal(condition)

    def _literal(self, literal: Literal) -> str:
        atom = _atom(self.predicate_name(literal.predicate, len(literal.args)), literal.args)
        return atom if literal.positive else f"(not {atom})"

    def _method(self, method: Method) -> list[str]:
        steps, extra = self._completed_subtasks(method)
        effect_action = self._effect_actions.get(method.name)
        ordering = list(method.ordering)
        if effect_action is not None:
            # subtask ids are names too: none may read as a task or action name
            ids = {s.id.lower() for s in steps} | self._task_names()
            first = Subtask(_fresh("method-effects", ids), effect_action.name, tuple(p.name for p in method.parameters))
            if not method.ordered:
                steps = [s if s.named else Subtask(_fresh("step", ids), s.task, s.args) for s in steps]
                ordering = [(first.id, s.id) for s in steps] + ordering
            steps = [first, *steps]
        lines = [f"{_INDENT}(:method {method.name}",
                 f"{_INDENT * 2}:parameters ({' '.join(_typed([*method.parameters, *extra]))})",
                 f"{_INDENT * 2}:task {_atom(method.task, method.task_args)}"]
        if method.preconditions:
            lines.append(f"{_INDENT * 2}:precondition "
                         f"(and {' '.join(self._condition(c) for c in method.preconditions)})")
        lines += _network(steps, ordering, method.ordered)
        lines.append(f"{_INDENT})")
        return lines

    def _completed_subtasks(self, method: Method) -> tuple[list[Subtask], list[Parameter]]:
        """The subtasks with one argument per parameter: a new method parameter for each
        argument the domain leaves out."""
        taken = {p.name.lower() for p in method.parameters}
        extra: list[Parameter] = []
        steps: list[Subtask] = []
        for step in method.subtasks:
            callee = self.domain.task_by_name.get(step.task) or self.domain.action_by_name.get(step.task)
            missing = callee.parameters[len(step.args):] if callee is not None else ()
            added = [Parameter(_fresh(p.name, taken), p.type) for p in missing]
            extra += added
            steps.append(Subtask(step.id, step.task, (*step.args, *(p.name for p in added))))
            if added:
                self.warnings.append(
                    f"{self.domain.source}:{step.line}:{step.column}: subtask {step.task} in method '{method.name}' "
                    f"is given {len(step.args)} of {len(callee.parameters) if callee else 0} arguments: "
                    f"new method parameters {' '.join(p.name for p in added)} take their place, free as the "
                    "decomposer leaves them")
        return steps, extra

    # ---- the problem text

    def problem_text(self, problem: ProblemData) -> str:
        lines = [f"; {problem.name}: HDDL problem written by mutrose-cp export-hddl",
                 *(f"; {c}" for c in problem.comments),
                 f"(define (problem {problem.name})",
                 f"{_INDENT}(:domain {self.domain.name})"]
        if problem.objects:
            lines.append(f"{_INDENT}(:objects")
            lines += [f"{_INDENT * 2}{group}" for group in _grouped(problem.objects)]
            lines.append(f"{_INDENT})")
        lines.append(f"{_INDENT}(:htn")
        lines.append(f"{_INDENT * 2}:parameters ({' '.join(_typed(problem.parameters))})")
        lines += _network(list(problem.network), [], True)
        lines.append(f"{_INDENT})")
        lines.append(f"{_INDENT}(:init")
        lines += [_INDENT * 2 + _atom(self.predicate_name(p, len(args)), args) for p, args in problem.facts]
        lines += [f"{_INDENT * 2}(= {_atom(f, args)} {_number(v)})" for f, args, v in problem.values]
        lines.append(f"{_INDENT})")
        lines.append(")")
        return "\n".join(lines) + "\n"


# ---------------------------------------------------------------------------------------------
# Text helpers


def _atom(name: str, terms: Iterable[str]) -> str:
    return "(" + " ".join([name, *terms]) + ")"


def _typed(parameters: Iterable[Parameter]) -> list[str]:
    return [f"{p.name} - {p.type}" for p in parameters]


def _grouped(items: Iterable[tuple[str, str]]) -> list[str]:
    """``a b - t`` groups of (name, type) pairs, types in order of first appearance."""
    by_type: dict[str, list[str]] = {}
    for name, sort in items:
        by_type.setdefault(sort, []).append(name)
    return [f"{' '.join(names)} - {sort}" for sort, names in by_type.items()]



def _unique(declarations: Iterable[Declaration]) -> list[Declaration]:
    """The first declaration of each name (functions are looked up by name)."""
    first: dict[str, Declaration] = {}
    for declaration in declarations:
        first.setdefault(declaration.name, declaration)
    return list(first.values())


def _number(value: int | float) -> str:
    return str(value) if isinstance(value, int) else repr(float(value))


def _numeric_effect(effect: NumericEffect) -> str:
    return f"({effect.kind} {_atom(effect.function, effect.args)} {effect.amount})"


def _fresh(name: str, taken: set[str]) -> str:
    """``name``, or ``name-2``, ``name-3``... whichever is not in ``taken``, which holds
    lower-cased names (HDDL names ignore case); the name returned is added to it."""
    candidate, n = name, 1
    while candidate.lower() in taken:
        n += 1
        candidate = f"{name}-{n}"
    taken.add(candidate.lower())
    return candidate


def _network(steps: list[Subtask], ordering: Sequence[tuple[str, str]], ordered: bool) -> list[str]:
    """``:ordered-subtasks`` for a total order, else ``:subtasks`` and ``:ordering (< a b)``."""
    if not steps:
        return []
    keyword = ":ordered-subtasks" if ordered else ":subtasks"
    lines = [f"{_INDENT * 2}{keyword} (and"]
    lines += [_INDENT * 3 + (f"({s.id} {_atom(s.task, s.args)})" if s.named else _atom(s.task, s.args))
              for s in steps]
    lines[-1] += ")"
    if ordering and not ordered:
        lines.append(f"{_INDENT * 2}:ordering (and {' '.join(f'(< {a} {b})' for a, b in ordering)})")
    return lines
