"""HTN decomposition of abstract tasks (spec ``semantics.md`` §2).

For every abstract task of the domain we build its task decomposition graph (TDG) and list its
*decomposition paths*: the sequences of primitive steps that one choice of methods and one
linearisation of each partial order yields, checked against a symbolic world state in which
unknown facts are assumed.  Paths are expressed in the root task's parameter names; their
position in the list is the decomposition number ``|n`` shared by every instance of the task.

The module also grounds a path for one task instance (§2.5): which preconditions and effects
the decomposition has once the instance's variables are bound.
"""
from __future__ import annotations

import itertools
import math
from dataclasses import dataclass, field
from fractions import Fraction
from typing import Callable, Mapping, Sequence

from .conditions import compare
from ..errors import MissionError
from ..model import AbstractTask, Action, Comparison, Domain, Literal, Method, NumericEffect, show_precondition
from ..model.decomposition_paths import Number, Step, TreeNode, Fragment, DecompositionPath, GroundPredicates

PSEUDO_PREFIX = "__method_precondition_"
MAX_RECURSION = 64  # recursive methods must be guarded by a numeric function

_Atom = tuple[str, tuple[str, ...]]
"""A predicate or function applied to arguments: the key of a fact or of a numeric value."""


# ---------------------------------------------------------------------------------------------
# Decomposition paths










# ---------------------------------------------------------------------------------------------
# Task decomposition graph


@dataclass
class _Vertex:
    id: int
    kind: str  # "task" | "method" | "primitive"
    name: str
    parent: int | None
    method: Method | None = None
    action: Action | None = None
    # method vertices: children in plan-step order, with the plan step's arguments and id
    children: list[tuple[int, tuple[str, ...], str]] = field(default_factory=list)


def _pseudo_action(method: Method) -> Action | None:
    """Method preconditions/effects become a primitive step executed first (hddl.md §5.1)."""
    if not (method.preconditions or method.effects or method.numeric_effects):
        return None
    used: set[str] = set()
    for c in (*method.preconditions, *method.effects, *method.numeric_effects):
        used.update(a for a in c.args if a.startswith("?"))
    params = tuple(p for p in method.parameters if p.name in used)
    return Action(
        name=PSEUDO_PREFIX + method.name,
        parameters=params,
        preconditions=method.preconditions,
        effects=method.effects,
        numeric_effects=method.numeric_effects,
    )


class _TDG:
    """Task decomposition graph of one abstract task (§2.1)."""

    def __init__(self, domain: Domain, root_task: str) -> None:
        self.domain = domain
        self.vertices: list[_Vertex] = []
        self.root = self._new("task", root_task, None)
        self._add_task(self.root)

    def _new(self, kind: str, name: str, parent: int | None,
             method: Method | None = None, action: Action | None = None) -> _Vertex:
        v = _Vertex(len(self.vertices), kind, name, parent, method, action)
        self.vertices.append(v)
        return v

    def _ancestor_task(self, vertex: _Vertex, name: str) -> _Vertex | None:
        cur: int | None = vertex.id
        while cur is not None:
            v = self.vertices[cur]
            if v.kind == "task" and v.name == name:
                return v
            cur = v.parent
        return None

    def _add_task(self, task_vertex: _Vertex) -> None:
        domain = self.domain
        for method in domain.methods_of(task_vertex.name):
            m = self._new("method", method.name, task_vertex.id, method=method)
            for step in method.subtasks:
                if step.task in domain.task_by_name:
                    ancestor = self._ancestor_task(m, step.task)
                    if ancestor is not None:  # recursion: edge back to the ancestor
                        m.children.append((ancestor.id, step.args, step.id))
                        continue
                    a = self._new("task", step.task, m.id)
                    m.children.append((a.id, step.args, step.id))
                    self._add_task(a)
                else:
                    action = domain.action_by_name[step.task]
                    p = self._new("primitive", action.name, m.id, action=action)
                    m.children.append((p.id, step.args, step.id))
            pseudo = _pseudo_action(method)
            if pseudo is not None:
                p = self._new("primitive", pseudo.name, m.id, action=pseudo)
                m.children.append((p.id, tuple(q.name for q in pseudo.parameters), "mprec"))

    def orderings(self, m: _Vertex) -> list[list[int]]:
        """All linear extensions of the method's partial order, as child positions (§2.3).

        At each position the remaining children are tried in ascending vertex id order."""
        method = m.method
        assert method is not None
        ids = [c[2] for c in m.children]
        pos = {sid: i for i, sid in enumerate(ids)}
        before: dict[int, set[int]] = {i: set() for i in range(len(ids))}
        for a, b in method.ordering:
            before[pos[b]].add(pos[a])
        if "mprec" in pos:
            mp = pos["mprec"]
            for i in range(len(ids)):
                if i != mp:
                    before[i].add(mp)
        order_key = sorted(range(len(ids)), key=lambda i: (m.children[i][0], i))
        result: list[list[int]] = []

        def extend(prefix: list[int], placed: set[int]) -> None:
            if len(prefix) == len(ids):
                result.append(list(prefix))
                return
            for i in order_key:
                if i not in placed and before[i] <= placed:
                    prefix.append(i)
                    placed.add(i)
                    extend(prefix, placed)
                    prefix.pop()
                    placed.discard(i)

        extend([], set())
        return result


# ---------------------------------------------------------------------------------------------
# Symbolic world state used while generating paths


class _State:
    """Boolean and numeric facts over root-task variables; absent facts are unknown."""

    __slots__ = ("facts", "values")

    def __init__(self, facts: dict[_Atom, bool] | None = None, values: dict[_Atom, Number] | None = None) -> None:
        self.facts: dict[_Atom, bool] = facts if facts is not None else {}
        self.values: dict[_Atom, Number] = values if values is not None else {}

    def copy(self) -> "_State":
        return _State(dict(self.facts), dict(self.values))

    def apply(self, step: Step) -> None:
        """The step's effects.  An increase or decrease of a value the state does not know
        leaves it unknown (the original takes the amount as the value, as if it had been 0,
        and drops the paths whose later comparisons that 0 refutes; docs/deviations.md)."""
        for e in step.effects:
            self.facts[(e.predicate, e.args)] = e.positive
        for ne in step.numeric_effects:
            key = (ne.function, ne.args)
            if ne.kind == "assign":
                self.values[key] = ne.amount
            elif key in self.values:
                self.values[key] += ne.amount if ne.kind == "increase" else -ne.amount


def _rename(args: Sequence[str], mapping: Mapping[str, str]) -> tuple[str, ...]:
    return tuple(mapping.get(a, a) for a in args)


def _renamed_step(action: Action, mapping: Mapping[str, str]) -> Step:
    conds: list[Literal | Comparison] = []
    for c in action.preconditions:
        if isinstance(c, Literal):
            conds.append(Literal(c.predicate, _rename(c.args, mapping), c.positive))
        else:
            conds.append(Comparison(c.function, _rename(c.args, mapping), c.op, c.value, c.negated))
    return Step(
        name=action.name,
        args=_rename([p.name for p in action.parameters], mapping),
        preconditions=tuple(conds),
        effects=tuple(Literal(e.predicate, _rename(e.args, mapping), e.positive) for e in action.effects),
        numeric_effects=tuple(
            NumericEffect(n.kind, n.function, _rename(n.args, mapping), n.amount) for n in action.numeric_effects
        ),
        capabilities=action.capabilities,
        pseudo=action.name.startswith(PSEUDO_PREFIX),
    )


@dataclass
class _Partial:
    steps: list[Step]
    trees: list[TreeNode]
    fragments: list[Fragment] = field(default_factory=list)
    never_valid: list[str] = field(default_factory=list)

    def then(self, other: "_Partial") -> "_Partial":
        """This path followed by ``other`` (whose fragment indices shift)."""
        n = len(self.steps)
        shifted = [Fragment(f.start + n, f.end + n, f.function, f.args, f.bound, f.decrease) for f in other.fragments]
        return _Partial(self.steps + other.steps, self.trees + other.trees, self.fragments + shifted,
                        self.never_valid + other.never_valid)


@dataclass
class _Checked:
    """What checking a primitive step against the symbolic state found (§2.4).

    ``executable`` is the original's verdict, which decides whether the path exists (and so the
    decomposition numbers); ``broken`` says why the step can never run where that verdict lets
    it pass: a numeric comparison that holds overwrites an earlier failure there (fix 12), and
    a step may require a fact and its negation, or two values of one function.  ``facts`` and
    ``values`` are the unknown facts and function values the step needs, to be assumed true of
    the state (the first assumption of an atom wins, as the original's first matching entry);
    ``guards`` are the ``>`` comparisons among them, with their declared bound, which mark a
    recursive method's guard."""

    executable: bool = True
    broken: list[str] = field(default_factory=list)
    facts: list[tuple[_Atom, bool]] = field(default_factory=list)
    values: list[tuple[_Atom, Number]] = field(default_factory=list)
    equals: list[tuple[_Atom, Number]] = field(default_factory=list)  # the "=" preconditions assumed so far
    guards: list[tuple[_Atom, Number]] = field(default_factory=list)


def _net_change(key: _Atom, steps: Sequence[Step]) -> Number:
    """The sum of the increases and decreases that ``steps`` make to function ``key``."""
    return sum(
        (n.amount if n.kind == "increase" else -n.amount)
        for s in steps for n in s.numeric_effects
        if (n.function, n.args) == key and n.kind != "assign"
    )


def _combine(child_lists: list[list[_Partial]]) -> list[_Partial]:
    """Every concatenation of one path per child, children in method order (§2.4).

    The first child's choice varies fastest, as in the original's enumeration."""
    combined: list[_Partial] = []
    for lst in child_lists:
        if not combined:
            combined = [_Partial(list(p.steps), list(p.trees), list(p.fragments), list(p.never_valid)) for p in lst]
            continue
        combined = [p.then(q) for q in lst for p in combined]
    return combined or [_Partial([], [])]


class _PathGenerator:
    """Path generation with a symbolic world state (§2.4)."""

    def __init__(self, domain: Domain, tdg: _TDG) -> None:
        self.domain = domain
        self.tdg = tdg
        self.root_task = domain.task_by_name[tdg.vertices[tdg.root.id].name]

    def task_paths(self, vid: int, state: _State, mapping: dict[str, str], depth: int) -> list[_Partial]:
        """Abstract vertex: the concatenated paths of its methods, each from a copy of ``state``.

        A task decomposes through any of its methods, so its paths are those of every method
        in declaration order; ``depth`` counts nested tasks to cut a recursion that never ends."""
        if depth > MAX_RECURSION:
            raise MissionError(
                f"recursive decomposition of task {self.tdg.vertices[vid].name} does not terminate: "
                "a recursive method needs a numeric precondition that its actions decrease",
                where=self.domain.source,
            )
        task = self.domain.task_by_name[self.tdg.vertices[vid].name]
        task_node_args = _rename([p.name for p in task.parameters], mapping)
        out: list[_Partial] = []
        for mid in (c for c in self.tdg.vertices if c.parent == vid and c.kind == "method"):
            method = mid.method
            assert method is not None
            m_map = self._method_mapping(task, method, mapping)
            method_node_args = _rename([p.name for p in method.parameters], m_map)
            for partial in self.method_paths(mid, state.copy(), m_map, depth):
                method_node = TreeNode("method", method.name, method_node_args, tuple(partial.trees))
                out.append(_Partial(partial.steps, [TreeNode("task", task.name, task_node_args, (method_node,))],
                                    partial.fragments, partial.never_valid))
        return out

    def _method_mapping(self, task: AbstractTask, method: Method, mapping: dict[str, str]) -> dict[str, str]:
        """The method's task arguments renamed to root parameters through the task's ``mapping``.

        Paths speak only of the root task's parameters, so every argument a nested task
        receives must come from the enclosing task."""
        m_map: dict[str, str] = {}
        for i, arg in enumerate(method.task_args):
            param = task.parameters[i].name
            if param not in mapping:
                raise MissionError(
                    f"method {method.name}: argument {arg} of task {task.name} is not bound to a "
                    f"parameter of {self.root_task.name}; nested abstract subtasks must receive "
                    "every argument from the enclosing task",
                    where=f"{self.domain.source}:{method.line}:{method.column}",
                )
            m_map[arg] = mapping[param]
        return m_map

    def method_paths(self, m: _Vertex, incoming: _State, mu: dict[str, str], depth: int) -> list[_Partial]:
        """The paths of method vertex ``m``: those of each linearisation of its subtasks, in order."""
        recursive = any(c[0] == m.parent for c in m.children)  # a cycle with the direct parent task
        results: list[_Partial] = []
        for order in self.tdg.orderings(m):
            results.extend(self._ordering_paths(m, order, incoming.copy(), mu, depth, recursive))
        return results

    def _ordering_paths(self, m: _Vertex, order: list[int], state: _State, mu: dict[str, str], depth: int,
                        recursive: bool) -> list[_Partial]:
        """The paths of one linearisation ``order`` of method ``m``, run from ``state``.

        Empty when a primitive step cannot execute by the original's check.  An abstract subtask
        without a path is left out, as by the original, and the paths that skip it are marked
        never valid: they skip work the domain requires (fix 15, docs/deviations.md)."""
        child_lists: list[list[_Partial]] = []
        fragments: list[Fragment] = []
        broken: list[str] = []
        for k, idx in enumerate(order):
            vid, args, _sid = m.children[idx]
            child = self.tdg.vertices[vid]
            if child.kind != "primitive":
                callee = self.domain.task_by_name[child.name]
                nu = {p.name: mu[a] for p, a in zip(callee.parameters, args) if a in mu}
                paths = self.task_paths(vid, state, nu, depth + 1)
                if paths:
                    child_lists.append(paths)
                else:
                    broken.append(f"its subtask {child.name} has no executable method")
                continue
            step = self._step(child, args, mu)
            later = self._later_steps(m, order[k + 1:], mu)
            checked = self._check(step, state, later, guard=step.pseudo and recursive)
            if not checked.executable:
                return []
            broken += checked.broken
            for key, positive in checked.facts:
                state.facts.setdefault(key, positive)
            for key, value in checked.values:
                state.values.setdefault(key, value)
            if step.pseudo and recursive:
                fragments += self._fragments(m, checked.guards, later)
            state.apply(step)
            child_lists.append([_Partial([step], [] if step.pseudo else [TreeNode("action", step.name, step.args)])])
        combined = _combine(child_lists)
        for p in combined:
            p.fragments = fragments + p.fragments
            p.never_valid = broken + p.never_valid
        return combined

    def _fragments(self, m: _Vertex, guards: list[tuple[_Atom, Number]], later: list[Step]) -> list[Fragment]:
        """Expansion metadata of a recursive method whose ``>`` guard was assumed (hddl.md §7)."""
        out: list[Fragment] = []
        method = m.method
        assert method is not None
        for key, bound in guards:
            effects = [n for s in later for n in s.numeric_effects if (n.function, n.args) == key]
            if not effects:
                continue
            if any(n.kind == "assign" for n in effects):
                raise MissionError(f"Assignment expressions on expansion cycle are not allowed (method "
                                   f"{method.name}): the recursion must decrease {key[0]}",
                                   f"{self.domain.source}:{method.line}:{method.column}")
            delta = sum(n.amount if n.kind == "increase" else -n.amount for n in effects)
            if delta >= 0:
                raise MissionError(f"Infinite expansion generated with method [{method.name}]: its actions "
                                   f"must decrease {key[0]}, which guards the recursion",
                                   f"{self.domain.source}:{method.line}:{method.column}")
            out.append(Fragment(0, len(m.children) - 2, key[0], key[1], bound, delta))
        return out

    def _check(self, step: Step, state: _State, later: list[Step], guard: bool) -> _Checked:
        """Check a primitive step's preconditions against ``state``.

        The original lets a numeric comparison that holds overwrite an earlier failure; every
        precondition must hold for the step to run, so such a step is kept (its path keeps its
        number) and marked (docs/deviations.md, fix 12).  The ``not`` of a comparison is
        ignored, as in the original.  Unknown facts are assumed, and so are ``=`` values (the
        value is then pinned there); a recursive method's ``>`` ``guard`` is assumed at ``N -
        sum of later decrements``, so that the method runs once more and then stops.  Any other
        ``>`` on an unknown value leaves it unknown: the original assumes that value there too,
        and drops the paths whose later comparisons it refutes (docs/deviations.md, fix 25)."""
        checked = _Checked()
        for c in step.preconditions:
            if isinstance(c, Literal):
                _check_literal(c, state, checked)
            else:
                _check_comparison(c, state, later, checked, guard)
        if checked.broken and not step.pseudo:
            checked.broken = [f"{reason} in action {step.name}" for reason in checked.broken]
        return checked

    def _step(self, vertex: _Vertex, args: tuple[str, ...], mu: dict[str, str]) -> Step:
        """The primitive ``vertex`` called with ``args``, renamed to root parameters through ``mu``."""
        action = vertex.action
        assert action is not None
        mapping = {p.name: mu[a] for p, a in zip(action.parameters, args) if a in mu}
        return _renamed_step(action, mapping)

    def _later_steps(self, m: _Vertex, positions: list[int], mu: dict[str, str]) -> list[Step]:
        """The renamed primitive steps that follow in the ordering (for ``>`` guards)."""
        out: list[Step] = []
        for j in positions:
            vid, args, _ = m.children[j]
            v = self.tdg.vertices[vid]
            if v.kind == "primitive" and v.action is not None:
                out.append(self._step(v, args, mu))
        return out


def _check_literal(c: Literal, state: _State, checked: _Checked) -> None:
    """A boolean precondition holds if the state agrees or does not know (then it is assumed).

    A failure stops the step, unless a later numeric comparison overwrites it (the original's
    verdict); a step that requires a fact and its negation runs there, and never can."""
    key = (c.predicate, c.args)
    if key in state.facts:
        if state.facts[key] != c.positive:
            checked.executable = False
            checked.broken.append(f"precondition {show_precondition(c)} is false after the steps before it")
    elif (key, not c.positive) in checked.facts:
        checked.broken.append(f"it requires {show_precondition(c)} and its negation")
    else:
        checked.facts.append((key, c.positive))


def _check_comparison(c: Comparison, state: _State, later: list[Step], checked: _Checked, guard: bool) -> None:
    """A numeric precondition is compared with a known value, its verdict overwriting the
    step's (the original's), else assumed (see ``_check``)."""
    key = (c.function, c.args)
    if key in state.values:
        checked.executable = compare(state.values[key], c.op, c.value)
        if not checked.executable:
            checked.broken.append(f"precondition {show_precondition(c)} is false after the steps before it")
    elif c.op == ">":
        if guard:
            checked.values.append((key, c.value - _net_change(key, later)))
            checked.guards.append((key, c.value))
    else:
        if any(k == key and v != c.value for k, v in checked.equals):
            checked.broken.append(f"it requires two values of {c.function}({', '.join(c.args)})")
        checked.equals.append((key, c.value))
        checked.values.append((key, c.value))


def task_paths(domain: Domain, task: str) -> list[DecompositionPath]:
    """The decomposition paths of abstract ``task`` in decomposition-number order."""
    tdg = _TDG(domain, task)
    gen = _PathGenerator(domain, tdg)
    root = domain.task_by_name[task]
    identity = {p.name: p.name for p in root.parameters}
    return [
        DecompositionPath(tuple(p.steps), p.trees[0], tuple(sorted(p.fragments, key=lambda f: f.start)),
                          tuple(dict.fromkeys(p.never_valid)))
        for p in gen.task_paths(tdg.root.id, _State(), identity, 0)
    ]


def all_task_paths(domain: Domain) -> dict[str, list[DecompositionPath]]:
    """Paths of every abstract task of the domain (used or not, as the original does)."""
    return {t.name: task_paths(domain, t.name) for t in domain.tasks}


# ---------------------------------------------------------------------------------------------
# Grounding a path for one task instance (§2.5)

Value = str | tuple[str, ...]




def _groundings(args: tuple[str, ...], binding: Mapping[str, Value]) -> list[tuple[str, ...]] | None:
    """Ground argument tuples (cartesian over collection values), or None if some is unbound."""
    single: list[str] = []
    values: list[Value] = []
    for a in args:
        v = binding.get(a)
        if v is None:
            return None
        values.append(v)
        if isinstance(v, str):
            single.append(v)
    if len(single) == len(values):  # the common case, no collection: one grounding
        return [tuple(single)]
    return [tuple(c) for c in itertools.product(*(v if isinstance(v, tuple) else (v,) for v in values))]


class _Grounder:
    """Grounds a path's steps in order, remembering what earlier steps did to each ground atom.

    A precondition of a step on an atom that an earlier step of the same path set is no
    precondition of the decomposition: the path itself provides it (or makes it impossible).
    Atoms whose arguments the instance does not bind stay in the root's variable names."""

    def __init__(self, binding: Mapping[str, Value]) -> None:
        self.binding = binding
        self.pre: list[Literal | Comparison] = []
        # net effects in declaration order: a later effect on an atom replaces the earlier one in
        # its place; ground and non-ground atoms never share a key (only the latter hold "?")
        self.net_eff: dict[_Atom, bool] = {}
        self.numeric: dict[_Atom, tuple[str, int]] = {}  # ground function -> (kind, amount) so far
        self.free_numeric: list[tuple[str, tuple[str, ...], str, int]] = []
        self.seen_ground: set[_Atom] = set()
        self.seen_free: set[_Atom] = set()
        self.shifted: list[Comparison] = []
        self.unsatisfiable: list[str] = []

    def step(self, step: Step) -> None:
        """Preconditions first (against the effects of the steps before), then the effects."""
        for c in step.preconditions:
            if isinstance(c, Literal):
                self._literal(c)
            else:
                self._comparison(c)
        for e in step.effects:
            self._effect(e)
        for n in step.numeric_effects:
            self._numeric_effect(n)

    def _literal(self, c: Literal) -> None:
        grounds = _groundings(c.args, self.binding)
        if grounds is None:
            if (c.predicate, c.args) not in self.seen_free:
                self.pre.append(c)
            return
        for g in grounds:
            if (c.predicate, g) not in self.seen_ground:
                self.pre.append(Literal(c.predicate, g, c.positive))
            elif self.net_eff[(c.predicate, g)] != c.positive:
                # an earlier step of the path (inside an abstract subtask, whose effects
                # path generation does not pass on) made it false: never executable
                self.unsatisfiable.append(f"{'' if c.positive else 'not '}{c.predicate}({', '.join(g)})")

    def _comparison(self, c: Comparison) -> None:
        grounds = _groundings(c.args, self.binding)
        if grounds is None:
            self.pre.append(c)
            return
        for g in grounds:
            earlier = self.numeric.get((c.function, g))
            if earlier is None:
                self.pre.append(Comparison(c.function, g, c.op, c.value, c.negated))
            elif earlier[0] != "assign":
                # only changed by amounts so far: a condition on the starting value (the
                # original drops it, which accepts the path whatever the world says)
                self.shifted.append(Comparison(c.function, g, c.op, c.value - earlier[1], c.negated))
            elif not compare(earlier[1], c.op, c.value):
                self.unsatisfiable.append(f"{c.function}({', '.join(g)}) {c.op} {c.value}")

    def _effect(self, e: Literal) -> None:
        grounds = _groundings(e.args, self.binding)
        if grounds is None:
            self.net_eff[(e.predicate, e.args)] = e.positive
            self.seen_free.add((e.predicate, e.args))
            return
        for g in grounds:
            self.net_eff[(e.predicate, g)] = e.positive
            self.seen_ground.add((e.predicate, g))

    def _numeric_effect(self, n: NumericEffect) -> None:
        """An assignment fixes the value; increases and decreases add up to a net change."""
        grounds = _groundings(n.args, self.binding)
        if grounds is None:
            self.free_numeric.append((n.function, n.args, n.kind, n.amount))
            return
        for g in grounds:
            key = (n.function, g)
            if n.kind == "assign":
                self.numeric[key] = ("assign", n.amount)
            else:
                delta = n.amount if n.kind == "increase" else -n.amount
                kind, old = self.numeric.get(key, ("increase", 0))
                self.numeric[key] = (kind, old + delta)

    def result(self) -> GroundPredicates:
        return GroundPredicates(
            preconditions=tuple(self.pre),
            effects=tuple(Literal(p, a, v) for (p, a), v in self.net_eff.items()),
            numeric_effects=tuple((f, a, k, v) for (f, a), (k, v) in self.numeric.items()) + tuple(self.free_numeric),
            shifted=tuple(self.shifted),
            unsatisfiable=tuple(self.unsatisfiable),
        )


_NO_PREDICATES = GroundPredicates((), (), ())


def ground_path(path: DecompositionPath, binding: Mapping[str, Value]) -> GroundPredicates:
    """Instantiate a path with an instance's parameter values (root parameter -> value).  A
    path without conditions or effects (a third of vital signs' 950,000 decompositions at
    50,000 rooms) shares one empty record: it is frozen."""
    if path.bare and not path.never_valid:
        return _NO_PREDICATES
    grounder = _Grounder(binding)
    grounder.unsatisfiable.extend(path.never_valid)
    for step in path.steps:
        grounder.step(step)
    return grounder.result()


def repetitions(value: Number, fragment: Fragment) -> int:
    """How many more times ``fragment`` runs after the one the path holds, from ``value``: the
    guard ``f > N`` holds at ``value - j*d`` for j = 0, 1, ... while ``j < (value - N) / d``,
    so the fragment runs ``ceil((value - N) / d)`` times in all.  Exact for integer and decimal
    world values and any step ``d`` (the original's formulas are short by one for a decimal
    value such as 4.0, and when ``d`` does not divide ``value - N``; docs/deviations.md)."""
    distance = Fraction(str(value)) - Fraction(str(fragment.bound))
    runs = math.ceil(distance / Fraction(str(-fragment.decrease)))
    return max(runs, 0) - 1


def expand_path(path: DecompositionPath, binding: Mapping[str, Value],
                value_of: Callable[[str, tuple[str, ...]], Number | None], where: str,
                warn: Callable[[str], None]) -> DecompositionPath:
    """Repeat the recursive fragments of ``path`` as often as the world allows (§7.6).

    ``value_of(function, args)`` gives the function's value (None if unknown).  For the guard
    ``f > N`` with a decrease ``d`` per repetition and a current value ``v``, the fragment is
    inserted after itself as often as :func:`repetitions` says.  A guard the world gives no
    value for keeps the path's one unrolling, as the original, and ``warn`` says so."""
    steps = list(path.steps)
    offset = 0
    for frag in path.fragments:
        grounds = _groundings(frag.args, binding)
        if grounds is None or len(grounds) != 1:
            raise MissionError(f"Function predicate in task {where} cannot contain collection-related variables "
                               f"({frag.function} {' '.join(frag.args)})", where)
        v = value_of(frag.function, grounds[0])
        if v is None:
            warn(f"decomposition {where}: the world gives no value for {frag.function}({', '.join(grounds[0])}), "
                 "which bounds a recursive method, so its recursion is unrolled once, as the original does")
            continue
        k = repetitions(v, frag)
        start, end = frag.start + offset, frag.end + offset
        block = steps[start:end + 1]
        if k > 0:
            steps[end + 1:end + 1] = block * k
            offset += len(block) * k
    return DecompositionPath(tuple(steps), path.tree, (), path.never_valid)
