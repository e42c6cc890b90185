"""A property's formula grounded on a mission: every atom becomes a set of task decompositions.

A ``?variable`` takes, in the order the formula first names them, every value that the task
instances matching its patterns give it, consistently with the values already taken (in
``before(task EnterRoom(?r, ?rm), task ApproachPatient(?s, ?rm, ?p))``, ``?p`` takes the
patients of the room ``?rm`` is); a variable that no instance gives a value (a robot parameter,
which has none before allocation, or a pattern with no instance left) stays free and matches
any value.  The formula holds when it holds for every binding: the grounded formula is their
conjunction.

Each atom of the grounded formula is then a set of task decompositions (Task Graph vertices),
true of a mission decomposition that chooses one of them, so that the decomposition space's
independent components decide it one by one (:mod:`.verify`) and the embedding model posts it
as clauses (:mod:`.embedding`):

* ``uses``: the decompositions that execute the task, go through the method, hold the action
  or need the capability;
* ``before(A, B)``: each pair of an A and a B decomposition that the sequential and fallback
  constraints leave unordered (paths of a graph built once) becomes ``not (a and b)``;
* ``robots(A) >= k``: not one of the A decompositions whose robot number allows a number that
  does not compare so;
* ``finally(FACT)``: the last chosen writer of the fact's atom, in the order effects apply
  (Task Graph vertex order, spec section 7.3), decides it; with the writers cut into runs of
  equal outcome, "the last run chosen from is run j" is ``T_j and not T_j+1`` over the suffix
  sets ``T_j`` (a writer every decomposition chooses cuts off the runs before it);
* ``initially-needed(FACT)``: some chosen decomposition has a ground precondition that tests
  FACT, and none of the writers of its atom whose effects it sees is chosen.
"""
from __future__ import annotations

import operator
from dataclasses import dataclass
from functools import cached_property
from typing import TYPE_CHECKING, Callable, Iterable, Iterator, Mapping, Sequence

from ..errors import MissionError, Problem
from ..model.domain import Comparison, Domain, Literal
from ..model.goal_model import RobotNumber
from ..model.properties import (
    Before,
    Fact,
    Finally,
    Formula,
    Implies,
    InitiallyNeeded,
    Junction,
    Not,
    Property,
    Robots,
    TaskPattern,
    Uses,
    atoms,
    task_patterns,
)
from ..model.task_graph import Decomposition, TaskGraph
from ..model.world import InitialState
from ..pipeline.constraints import FB, SEQ, Constraint
from .semantics import AtomKey, EffectScopes, Effects, effects_of, is_ground

if TYPE_CHECKING:
    import networkx as nx

#: at most this many bindings of a property's variables
MAX_BINDINGS = 200_000

Grounded = int | tuple[str, tuple["Grounded", ...]]  # an atom's index, or (operator, operands)
TRUE: Grounded = ("and", ())
FALSE: Grounded = ("or", ())


@dataclass(frozen=True)
class GroundedProperty:
    """A property's formula over atoms that are sets of task decompositions (Task Graph
    vertices): ``formula`` is an atom's index, or ``(operator, operands)`` with ``and``, ``or``
    and ``not``.  What the embedding model posts (``DecompositionModel.add_property``)."""

    formula: Grounded
    atoms: tuple[frozenset[int], ...]


def ground(prop: Property, tg: TaskGraph, domain: Domain, constraints: Iterable[Constraint] = (),
           initial: InitialState | None = None) -> GroundedProperty:
    """``prop``'s formula grounded on the mission (its quantifier is not part of it); ``initial``
    is the world's initial state, which ``finally`` atoms read when no writer is chosen."""
    grounding = _Grounding(tg, domain, prop, constraints, initial)
    formula = grounding.ground(prop.formula)
    return GroundedProperty(formula, tuple(grounding.sets))


def refusal(prop: Property, why: str) -> MissionError:
    """The error of a property that is not decided (never answered approximately)."""
    return MissionError(Problem(prop.where, f"property {prop.name}: cannot be verified: {why}"))


Match = tuple[int, tuple[str | None, ...]]  # a decomposition vertex and its pattern variables' values


class _PatternIndex:
    """The task decompositions each task pattern matches, with the values its ``?variables``
    take there (None: a robot parameter, which matches any value), indexed by value so that a
    binding finds its matches without reading every decomposition."""

    def __init__(self, tg: TaskGraph, domain: Domain) -> None:
        self.by_task: dict[str, list[tuple[int, Decomposition]]] = {}
        for vertex in tg.decompositions():
            assert vertex.decomposition is not None
            self.by_task.setdefault(vertex.decomposition.instance.name, []).append((vertex.index, vertex.decomposition))
        self.parameters = {t.name: tuple(p.name for p in t.parameters) for t in domain.tasks}
        self._matches: dict[TaskPattern, list[Match]] = {}
        self._index: dict[TaskPattern, dict[tuple[str, str | None], list[Match]]] = {}

    def matches(self, pattern: TaskPattern) -> list[Match]:
        """Every decomposition ``pattern`` matches, whatever its variables are."""
        if pattern not in self._matches:
            found = [(v, values) for v, d in self.by_task.get(pattern.name, ())
                     if (values := self._values(pattern, d)) is not None]
            index: dict[tuple[str, str | None], list[Match]] = {}
            for match in found:
                for variable, value in zip(pattern.variables, match[1]):
                    index.setdefault((variable, value), []).append(match)
            self._matches[pattern], self._index[pattern] = found, index
        return self._matches[pattern]

    def consistent(self, pattern: TaskPattern, binding: Mapping[str, str]) -> list[Match]:
        """The matches of ``pattern`` that agree with ``binding`` on its variables."""
        found = self.matches(pattern)
        bound = [(i, v) for i, v in enumerate(pattern.variables) if v in binding]
        if not bound:
            return found
        first, variable = bound[0]
        index = self._index[pattern]
        candidates = index.get((variable, binding[variable]), []) + index.get((variable, None), [])
        return [m for m in candidates
                if all(m[1][i] is None or m[1][i] == binding[v] for i, v in bound)]

    def vertices(self, pattern: TaskPattern, binding: Mapping[str, str]) -> list[int]:
        return sorted(v for v, _ in self.consistent(pattern, binding))

    def _values(self, pattern: TaskPattern, d: Decomposition) -> tuple[str | None, ...] | None:
        """The values of ``pattern``'s variables where it matches ``d``'s instance, or None."""
        if pattern.arguments is None:
            return ()
        values = {p.hddl_param: str(p.value) for p in d.instance.parameters}
        declared = self.parameters.get(pattern.name, ())
        if len(pattern.arguments) > len(declared):
            return None
        taken: dict[str, str] = {}
        for argument, parameter in zip(pattern.arguments, declared):
            value = values.get(parameter, "")
            if not value:  # a robot parameter: no value before allocation, matches anything
                continue
            if argument.startswith("?"):
                if taken.setdefault(argument, value) != value:
                    return None
            elif argument != value:
                return None
        return tuple(taken.get(v) for v in pattern.variables)


class _Grounding:
    """The grounded atoms of one property: each a set of Task Graph decomposition vertices, kept
    once however often it recurs."""

    def __init__(self, tg: TaskGraph, domain: Domain, prop: Property, constraints: Iterable[Constraint],
                 initial: InitialState | None) -> None:
        self.tg = tg
        self.prop = prop
        self.constraints = constraints
        self.initial = initial
        self.patterns = _PatternIndex(tg, domain)
        self.sets: list[frozenset[int]] = []
        self.index_of: dict[frozenset[int], int] = {}

    def ground(self, formula: Formula) -> Grounded:
        variables = list(dict.fromkeys(_variables(formula)))
        if not variables:
            return self._ground(formula, {})
        return ("and", tuple(self._ground(formula, binding) for binding in self.bindings(formula, variables)))

    def bindings(self, formula: Formula, variables: Sequence[str]) -> list[dict[str, str]]:
        """The bindings of ``variables`` that the task instances give, in order of value."""
        patterns = [p for p in dict.fromkeys(_patterns(formula)) if p.variables]
        holding = {v: [p for p in patterns if v in p.variables] for v in variables}
        found: list[dict[str, str]] = []
        stack: list[tuple[int, dict[str, str]]] = [(0, {})]
        while stack:
            depth, binding = stack.pop()
            if depth == len(variables):
                found.append(binding)
                if len(found) > MAX_BINDINGS:
                    raise self.refused(f"its variables have more than {MAX_BINDINGS} bindings")
                continue
            variable = variables[depth]
            values = sorted({value for p in holding[variable] for _, taken in self.patterns.consistent(p, binding)
                             if (value := taken[p.variables.index(variable)]) is not None})
            if not values:  # no instance gives it a value here: it stays free
                stack.append((depth + 1, binding))
            stack.extend((depth + 1, {**binding, variable: value}) for value in reversed(values))
        return found

    def _ground(self, formula: Formula, binding: Mapping[str, str]) -> Grounded:
        if isinstance(formula, Not):
            return ("not", (self._ground(formula.operand, binding),))
        if isinstance(formula, Junction):
            return (formula.op, tuple(self._ground(f, binding) for f in formula.operands))
        if isinstance(formula, Implies):
            return ("or", (("not", (self._ground(formula.premise, binding),)), self._ground(formula.conclusion, binding)))
        if isinstance(formula, Uses):
            return self._uses(formula.target, binding)
        if isinstance(formula, Before):
            return self._before(formula, binding)
        if isinstance(formula, Robots):
            # every number the instance's robot number allows must compare so: [1,3] >= 2 does not
            short = frozenset(v for v, d in self._decompositions(formula.task, binding)
                              if not _robots_compare(d.instance.robot_number, formula.comparison, formula.bound))
            return ("not", (self.atom(short),))
        if isinstance(formula, Finally):
            return self._finally(formula.fact, binding)
        assert isinstance(formula, InitiallyNeeded)
        return self._initially_needed(formula.fact, binding)

    def _uses(self, target: TaskPattern | tuple[str, str], binding: Mapping[str, str]) -> Grounded:
        if isinstance(target, TaskPattern):
            return self.atom(frozenset(self.patterns.vertices(target, binding)))
        kind, name = target
        chosen = frozenset(v for v, d in self._all() if _used(kind, name, d))
        if not chosen and kind == "decomposition":
            raise self.refused(f"the mission has no task decomposition {name} (the output names them, e.g. AT1_1|1)")
        return self.atom(chosen)

    def _before(self, formula: Before, binding: Mapping[str, str]) -> Grounded:
        """No pair of chosen task decompositions, one of an A instance and one of a B instance,
        that the constraints leave unordered: each such pair becomes ``not (a and b)``."""
        firsts = self.patterns.vertices(formula.first, binding)
        seconds = self.patterns.vertices(formula.second, binding)
        pairs = [(a, b) for a in firsts for b in seconds if a != b and not self._ordered(a, b)]
        return ("and", tuple(("not", (("and", (self.atom(frozenset([a])), self.atom(frozenset([b])))),))
                             for a, b in pairs))

    def _ordered(self, a: int, b: int) -> bool:
        import networkx as nx  # deferred: start-up time, for the properties that order tasks

        return a in self.order and b in self.order and nx.has_path(self.order, a, b)

    def _finally(self, fact: Fact, binding: Mapping[str, str]) -> Grounded:
        atom = self._atom_of(fact, binding)
        outcome = self._outcome(fact)
        writers = self._writers(atom, numeric=fact.comparison is not None)
        base: bool = outcome(self._initial_value(atom, numeric=fact.comparison is not None))
        runs: list[tuple[bool, list[int]]] = []  # consecutive writers with the same outcome
        for vertex, value in writers:
            result = outcome(value)
            if runs and runs[-1][0] == result:
                runs[-1][1].append(vertex)
            else:
                runs.append((result, [vertex]))
        suffixes = [frozenset(v for _, vs in runs[j:] for v in vs) for j in range(len(runs))]
        cases: list[Grounded] = []
        for j, (result, _) in enumerate(runs):
            if result:
                later = [("not", (self.atom(suffixes[j + 1]),))] if j + 1 < len(runs) else []
                cases.append(("and", (self.atom(suffixes[j]), *later)))
        if base:
            cases.append(("not", (self.atom(suffixes[0]),)) if runs else TRUE)
        return ("or", tuple(cases))

    def _initially_needed(self, fact: Fact, binding: Mapping[str, str]) -> Grounded:
        atom = self._atom_of(fact, binding)
        writers = {v for v, _ in self._writers(atom, numeric=fact.comparison is not None, every=True)}
        cases: list[Grounded] = []
        for task in self.tg.tasks():
            readers = [d.index for d in self.tg.decompositions_of(task.index)
                       if d.decomposition is not None and _tests(d.decomposition, fact, atom)]
            if not readers:
                continue
            seen = frozenset(writers & self.scopes.seen_by_task(task.index))
            unwritten: tuple[Grounded, ...] = (("not", (self.atom(seen),)),) if seen else ()
            cases.append(("and", (self.atom(frozenset(readers)), *unwritten)))
        return ("or", tuple(cases))

    def _atom_of(self, fact: Fact, binding: Mapping[str, str]) -> AtomKey:
        arguments = tuple(binding.get(a, a) for a in fact.arguments)
        free = [a for a in arguments if a.startswith("?")]
        if free:
            raise self.refused(f"the variable {free[0]} of {fact.name}({', '.join(fact.arguments)}) takes no value "
                               "(a fact's variables take the values of the task patterns that name them)")
        return (fact.name, arguments)

    def _outcome(self, fact: Fact) -> Callable[[bool | float | None], bool]:
        """Whether a value of the fact's atom makes the fact true (an unknown one never does, and
        a predicate the world does not give is false)."""
        if fact.comparison is None:
            return lambda value: bool(value) != fact.negated
        op, bound = fact.comparison
        test = _COMPARE[op]
        return lambda value: value is not None and not isinstance(value, bool) and test(float(value), bound) != fact.negated

    def _writers(self, atom: AtomKey, numeric: bool, every: bool = False) -> list[tuple[int, bool | float]]:
        """The decompositions that write ``atom``, in the order effects apply, with the value
        each leaves (a numeric increase or decrease is refused unless ``every``: its value
        depends on what came before)."""
        found: list[tuple[int, bool | float]] = []
        for vertex, effects in self.effects:
            if numeric:
                written = [(kind, amount) for key, kind, amount in effects.numeric if key == atom]
                if written and written[-1][0] != "assign" and not every:
                    raise self.refused(f"decomposition {self.tg.vertices[vertex].content} changes "
                                       f"{atom[0]}({', '.join(atom[1])}) by {written[-1][0]}: finally is decided over "
                                       "assignments only")
                if written:
                    found.append((vertex, float(written[-1][1])))
            else:
                values = [value for key, value in effects.facts if key == atom]
                if values:
                    found.append((vertex, values[-1]))
        return found

    def _initial_value(self, atom: AtomKey, numeric: bool) -> bool | float | None:
        if self.initial is None:
            return None
        if numeric:
            value = self.initial.value_map().get(atom)
            return None if value is None else float(value)
        return bool(self.initial.value_of(*atom))

    @cached_property
    def effects(self) -> list[tuple[int, Effects]]:
        """The decompositions that have effects, in Task Graph vertex order (the application
        order of spec section 7.3)."""
        found = []
        for vertex in self.tg.decompositions():
            assert vertex.decomposition is not None
            effects = effects_of(vertex.decomposition)
            if effects.facts or effects.numeric:
                found.append((vertex.index, effects))
        return found

    @cached_property
    def scopes(self) -> EffectScopes:
        return EffectScopes(self.tg)

    @cached_property
    def order(self) -> "nx.DiGraph[int]":
        """The sequential and fallback constraints between task decompositions, as a graph (its
        paths are the transitive order), built once."""
        import networkx as nx

        graph: "nx.DiGraph[int]" = nx.DiGraph()
        graph.add_edges_from((c.first, c.second) for c in self.constraints if c.kind in (SEQ, FB))
        return graph

    def atom(self, decompositions: frozenset[int]) -> int:
        if decompositions not in self.index_of:
            self.index_of[decompositions] = len(self.sets)
            self.sets.append(decompositions)
        return self.index_of[decompositions]

    def _all(self) -> Iterator[tuple[int, Decomposition]]:
        for found in self.patterns.by_task.values():
            yield from found

    def _decompositions(self, pattern: TaskPattern, binding: Mapping[str, str]) -> list[tuple[int, Decomposition]]:
        vertices = set(self.patterns.vertices(pattern, binding))
        return [(v, d) for v, d in self.patterns.by_task.get(pattern.name, ()) if v in vertices]

    def refused(self, why: str) -> MissionError:
        return refusal(self.prop, why)


_COMPARE: dict[str, Callable[[float, float], bool]] = {
    ">=": operator.ge, "<=": operator.le, "==": operator.eq, "!=": operator.ne, ">": operator.gt, "<": operator.lt}


def _robots_compare(number: RobotNumber, comparison: str, bound: int) -> bool:
    """Whether every robot number the instance allows compares so with ``bound``."""
    allowed = (number.min, number.max)
    return all(_COMPARE[comparison](n, bound) for n in allowed) if comparison != "!=" else \
        not number.min <= bound <= number.max


def _tests(d: Decomposition, fact: Fact, atom: AtomKey) -> bool:
    """Whether one of ``d``'s ground preconditions tests ``fact`` (a comparison: the same one)."""
    for c in d.predicates.checked_preconditions:
        if (c.predicate if isinstance(c, Literal) else c.function, c.args) != atom or not is_ground(c.args):
            continue
        if isinstance(c, Literal):
            if fact.comparison is None and c.positive != fact.negated:
                return True
        elif fact.comparison is not None and isinstance(c, Comparison):
            op, bound = fact.comparison
            if {"==": "="}.get(op, op) == c.op and float(c.value) == bound and c.negated == fact.negated:
                return True
    return False


def _used(kind: str, name: str, d: Decomposition) -> bool:
    if kind == "decomposition":
        return d.id == name
    steps = d.path.actions
    if kind == "action":
        return any(s.name == name for s in steps)
    if kind == "capability":
        return any(name in s.capabilities for s in steps)
    return name in _methods(d)


def _methods(d: Decomposition) -> set[str]:
    names: set[str] = set()
    stack = [d.path.tree]
    while stack:
        node = stack.pop()
        if node.kind == "method":
            names.add(node.name)
        stack.extend(node.children)
    return names


def _patterns(formula: Formula) -> Iterator[TaskPattern]:
    for atom in atoms(formula):
        yield from task_patterns(atom)


def _variables(formula: Formula) -> Iterator[str]:
    for atom in atoms(formula):
        for pattern in task_patterns(atom):
            yield from pattern.variables
        if isinstance(atom, (Finally, InitiallyNeeded)):
            yield from (a for a in atom.fact.arguments if a.startswith("?"))
