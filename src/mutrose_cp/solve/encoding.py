"""The space of valid mission decompositions as a boolean model (spec ``semantics.md`` §7).

The exploratory algorithm filters explicit lists; here the same rules become constraints over
*choice literals*: one per OR alternative and one per (task instance, decomposition).  World
facts are carried symbolically: the value of an atom at a point of the Task Graph is "the last
chosen writer in Task Graph order, else the initial value", so preconditions, parallel conflicts and
achieve conditions become clauses over the writers' literals.  Facts that no decomposition
changes are folded in as constants while the model is built.

The model is kept in a small solver-neutral form (:class:`BoolModel`) so it can be split into
independent components before it is handed to CP-SAT (:mod:`mutrose_cp.solve.cpsat`), and every
auxiliary variable is defined by an equivalence, so each solution is a distinct decomposition.
Variables are named by their parts (:func:`variable_name` makes the text when it is read), and
the stamped forAll copies of a class replay their leader's records (:mod:`.replay`).
"""
from __future__ import annotations

import functools
from dataclasses import dataclass, field
from typing import Any, Callable, Collection, Iterable, Mapping, Sequence

from ..model.state_tests import AllOf, FactTest, Test, ValueTest
from ..pipeline.conditions import compare
from ..pipeline.constraints import Constraint
from ..model import Comparison, Configuration, Domain, GoalModel, InitialState, Literal, show_precondition
from ..model.task_graph import TaskGraph, TaskVertex
from .boolean_model import (
    FALSE,
    TRUE,
    BoolModel,
    Compare,
    Difference,
    Exactly,
    Lit,
    Name,
    NumericEffectKind,
    ValueAfter,
    neg,
)
from ..model.world import SCALE, scaled
from .numeric import offset_gap
from .semantics import (
    AtomKey,
    Seen,
    achieve_tests,
    checks_parallel_conflicts,
    contradicts_itself,
    robot_precondition_writers,
    unique_branch_valid,
)
from .encoding_state import V, Chain, EncodingState
from .replay import CHECKS, TASK_RULES, CopyReplay



@dataclass
class Encoding:
    """The model plus the maps from Task Graph entities to its literals."""

    model: BoolModel
    decomposition_lit: dict[int, Lit]  # decomposition vertex -> literal
    task_lit: dict[int, Lit]  # task vertex -> "active" literal
    or_choice_lit: dict[tuple[int, int], Lit]  # (OR operator vertex, child vertex) -> literal
    tasks: list[int]  # task vertices in mission-queue order
    labels: dict[str, str] = field(default_factory=dict)  # record label -> explanation
    # uncertain fact -> its variable, the fact's value at the start (docs/formats/uncertainty.md)
    uncertain: dict[AtomKey, int] = field(default_factory=dict)
    # uncertain number -> one variable per value it may have at the start (exactly one is true)
    uncertain_numbers: dict[AtomKey, tuple[int, ...]] = field(default_factory=dict)


# How the encoder's variables are named: the parts of a name are kept, and the text is made
# when it is read (BoolModel.name).  A name's parts are (kind, atom or None, vertex, extra).
OR_CHOICE, AFTER, KNOWN_AFTER, COMPARED, CONTEXT, PRECONDITION, ACHIEVE, SET_BELOW, CLEARED_BELOW, OFFSET_GAP, \
    UNCERTAIN = range(11)


_NAMES: dict[int, Callable[[TaskGraph, Any, int, Any], str]] = {  # kind -> (tg, atom, vertex, extra) -> text
    OR_CHOICE: lambda tg, _, v, child: f"{tg.scope(v).goal or tg.vertices[v].content}@{v}->{tg.vertices[child].content}",
    AFTER: lambda tg, atom, w, _: f"{_atom_name(atom)} after {tg.vertices[w].content}",
    KNOWN_AFTER: lambda tg, atom, w, _: f"known {_atom_name(atom)} after {tg.vertices[w].content}",
    COMPARED: lambda tg, atom, _, test: f"cmp({atom}{test[0]}{test[1]})",  # test: (op, bound)
    CONTEXT: lambda tg, _, t, __: f"context({tg.vertices[t].content})",
    PRECONDITION: lambda tg, _, d, __: f"pre({tg.decomposition(d).decomposition.id})",
    ACHIEVE: lambda tg, _, v, goal: f"achieve({goal}@{v})",
    SET_BELOW: lambda tg, atom, v, _: f"{_atom_name(atom)} set below {v}",
    UNCERTAIN: lambda tg, atom, _, __: f"{_atom_name(atom)} at the start",
    CLEARED_BELOW: lambda tg, atom, v, _: f"{_atom_name(atom)} cleared below {v}",
    OFFSET_GAP: lambda tg, atom, _, pair: f"{_atom_name(atom)} offset gap {pair[0]}-{pair[1]}",
}


def variable_name(tg: TaskGraph, parts: tuple[Any, ...]) -> str:
    """The text of a name kept as its parts (see above)."""
    kind, atom, v, extra = parts
    return _NAMES[kind](tg, atom, v, extra)


class Encoder(EncodingState):
    """Builds the :class:`Encoding` of a Task Graph with the exploratory algorithm's semantics."""

    def __init__(self, tg: TaskGraph, constraints: Sequence[Constraint], domain: Domain, gm: GoalModel,
                 config: Configuration, initial: InitialState, explain: bool = False, replay: bool = True,
                 uncertain: Collection[AtomKey] = (), uncertain_numbers: Mapping[AtomKey, Sequence[float]] | None = None,
                 uncertain_aliases: Mapping[AtomKey, AtomKey] | None = None) -> None:
        super().__init__(tg, constraints, domain, gm, config, initial, explain,
                         model=BoolModel(namer=functools.partial(variable_name, tg)))
        # stamped copies replay a leader's records (.replay); explaining labels every record by
        # its own vertices, so it encodes each copy in full, and so does a mission with uncertain
        # facts (a copy's class does not say which of its atoms are uncertain)
        # an atom that starts as an uncertain fact does, which it shares its variables with (one
        # world attribute the configuration maps to several predicates or functions)
        self.aliases: Mapping[AtomKey, AtomKey] = uncertain_aliases or {}
        self.number_values: dict[AtomKey, Sequence[float]] = dict(uncertain_numbers or {})
        self.number_values.update((alias, self.number_values[atom]) for alias, atom in self.aliases.items()
                                  if atom in self.number_values)
        self._replaying = replay and not explain and not uncertain and not self.number_values
        # boolean facts whose start value is a free variable, made when first read
        self.uncertain_atoms = frozenset(uncertain) | {alias for alias, atom in self.aliases.items() if atom in uncertain}
        self.uncertain: dict[AtomKey, int] = {}
        # numbers whose start value is one of a few, chosen by variables made when first read:
        # the choices, and the integer variable equal to the chosen value
        self.uncertain_numbers: dict[AtomKey, tuple[tuple[int, ...], int]] = {}
        self._replay: CopyReplay | None = None  # while encoding
        self.replayed: tuple[int, int] = (0, 0)  # copies that replayed their task rules, classes that led them
        # the comparisons required of values the world does not give, by atom (.numeric)
        self.start_tests: dict[AtomKey, list[_StartTest]] = {}

    # ------------------------------------------------------------------------------------------
    def encode(self) -> Encoding:
        tg = self.tg
        if tg.unique_branch:
            return self._unique_branch()
        if self._replaying and tg.stamped_copies:
            self._replay = CopyReplay(self)
        try:
            self._choices(0, TRUE)
            tasks = [v for v in self.queue if isinstance(tg.vertices[v], TaskVertex)]
            self._each(TASK_RULES, tasks, self._task_rules)
            self._each(CHECKS, self.queue, self._checks)
            self._start_values()
            if self._replay is not None:
                self.replayed = self._replay.summary()
        finally:
            self._replay = None  # it refers back to the encoder: let both go with the encoder
        return Encoding(self.m, self.x, self.active, self.or_lits, tasks, self.labels, self.uncertain,
                        {atom: choices for atom, (choices, _) in self.uncertain_numbers.items()})

    def _each(self, phase: int, vertices: Sequence[int], encode: Callable[[int], None]) -> None:
        """``encode`` each vertex in order; a stamped copy's run of vertices goes to the replay."""
        replay = self._replay
        if replay is None:
            for v in vertices:
                encode(v)
            return
        starts = replay.task_starts if phase == TASK_RULES else replay.queue_starts
        i, n = 0, len(vertices)
        while i < n:
            copy = starts.get(vertices[i])
            if copy is None:
                encode(vertices[i])
                i += 1
                continue
            count = len(copy.group.tasks if phase == TASK_RULES else copy.group.queue)
            replay.run(phase, copy, vertices[i:i + count], encode)
            i += count

    def _checks(self, v: int) -> None:
        """What the mission queue checks at ``v``: parallel conflicts and achieve conditions."""
        if checks_parallel_conflicts(self.tg, v):
            self._conflicts(v)
        for goal, test in achieve_tests(self.tg, v, self.gm, self.config):
            self._achieve(v, goal, test)

    def _unique_branch(self) -> Encoding:
        """§7.7: each initially valid decomposition is a mission decomposition on its own."""
        tasks = [v.index for v in self.tg.tasks()]
        all_x: list[Lit] = []
        for t in tasks:
            self.active[t] = TRUE
            for d in self.tg.decompositions_of(t):
                lit = self.m.new_bool(d.content)
                self.x[d.index] = lit
                all_x.append(lit)
                if not unique_branch_valid(self.tg, d, self.initial, self.gm, self.config):
                    self.m.clause([neg(lit)], self._label(lambda: (
                        f"pre:{d.content}", f"{d.content}: a precondition is false in the initial world state, "
                                            "or an achieve condition after it")))
        self.m.records.append(Exactly(tuple(all_x), TRUE, label="unique-branch"))
        return Encoding(self.m, self.x, self.active, self.or_lits, tasks, self.labels, self.uncertain,
                        {atom: choices for atom, (choices, _) in self.uncertain_numbers.items()})

    def _label(self, key_and_text: Callable[[], tuple[str, str]]) -> str:
        """The label of a record, with its explanation kept, when explaining; else none.  The
        key and text are made only then: a large mission posts a million records, and a label
        names a precondition or fact by its repr."""
        if not self.explain:
            return ""
        key, text = key_and_text()
        self.labels[key] = text
        return key

    # --- choices ---------------------------------------------------------------------------------
    def _choices(self, v: int, active: Lit) -> None:
        """Activity literals: an OR operator picks exactly one child; tasks pick one decomposition."""
        replay = self._replay
        if replay is not None:
            copy = replay.copies.get(v)
            if copy is not None:
                replay.choices(copy, active, self._choose)
                return
        self._choose(v, active)

    def _choose(self, v: int, active: Lit) -> None:
        tg = self.tg
        vx = tg.vertices[v]
        self.active[v] = active
        if isinstance(vx, TaskVertex):
            lits = []
            for d in tg.decompositions_of(v):
                lit = self.m.new_bool(d.content)
                self.x[d.index] = lit
                lits.append(lit)
            self.m.records.append(Exactly(tuple(lits), active,
                                         label=self._label(lambda: (f"task:{vx.content}", f"task instance {vx.content} "
                                                                    "needs exactly one decomposition"))))
            return
        children = tg.children(v)
        if tg.is_or(v):
            lits = []
            for c in children:
                lit = self.m.new_bool((OR_CHOICE, None, v, c))
                self.or_lits[(v, c)] = lit
                lits.append(lit)
                self._choices(c, lit)
            self.m.records.append(Exactly(tuple(lits), active, label=f"or:{v}"))
        else:
            for c in children:
                self._choices(c, active)

    # --- world values ------------------------------------------------------------------------------
    def _bool_value(self, atom: AtomKey, writers: Sequence[tuple[int, bool]]) -> tuple[Lit, Lit]:
        """(known, true) literals of ``atom`` after the chosen ``writers`` (in Task Graph order) have been
        applied to the initial state.

        The value is a chain, one step per writer: after writer ``w`` it is ``w``'s value if ``w`` is
        chosen, else the value before.  Tests that see a common prefix of writers (the tasks of a
        sequence) share its steps, so the whole state of the atom between two tasks is one pair of
        literals: components of tasks coupled through a few facts decompose block by block
        (:mod:`.layered`).  The tasks of a long sequence see ever longer prefixes of the atom's
        writers: those are looked up by length, not walked again, which keeps the encoding linear."""
        root = self._chain_root(atom, self.bool_chains, self._bool_start, False)
        everyone = self.bool_writers.get(atom, ())
        k = len(writers)
        if k and k <= len(everyone) and writers[-1] is everyone[k - 1]:  # a subsequence: this is a prefix
            prefix = self.bool_prefixes.setdefault(atom, [root])
            while len(prefix) <= k:
                prefix.append(self._bool_step(atom, prefix[-1], *everyone[len(prefix) - 1]))
            return prefix[k].value
        node = root
        for w, pol in writers:
            node = self._bool_step(atom, node, w, pol)
        return node.value

    def _bool_step(self, atom: AtomKey, node: "Chain[tuple[Lit, Lit]]", w: int, pol: bool) -> "Chain[tuple[Lit, Lit]]":
        """The chain node after writer ``w`` (setting ``atom`` to ``pol`` if chosen) follows ``node``."""
        step = node.next.get((w, pol))
        if step is None:
            known_before, true_before = node.value
            xw = self.x[w]
            name = (AFTER, atom, w, None)
            value = (self.m.or_of([xw, known_before], (KNOWN_AFTER, atom, w, None)),
                     self.m.or_of([xw, true_before], name) if pol else self.m.and_of([neg(xw), true_before], name))
            step = node.next[(w, pol)] = Chain(value)
        return step

    def _bool_start(self, atom: AtomKey) -> tuple[Lit, Lit]:
        if atom in self.uncertain_atoms:
            return TRUE, self._uncertain(atom)
        init = self.facts.get(atom)
        return (FALSE if init is None else TRUE), (TRUE if init else FALSE)

    def _uncertain(self, atom: AtomKey) -> int:
        """The variable of an uncertain fact's start value: known, but not to the decomposer."""
        atom = self.aliases.get(atom, atom)
        if atom not in self.uncertain:
            self.uncertain[atom] = self.m.new_bool((UNCERTAIN, atom, -1, None))
        return self.uncertain[atom]

    def _uncertain_number(self, atom: AtomKey) -> tuple[tuple[int, ...], int]:
        """An uncertain number's choices (one per value it may start with, exactly one true) and
        the integer variable equal to the chosen value: a chain of assignments, one per choice."""
        atom = self.aliases.get(atom, atom)
        if atom not in self.uncertain_numbers:
            values = self.number_values[atom]
            choices = tuple(self.m.new_bool((UNCERTAIN, atom, -1, v)) for v in values)
            self.m.records.append(Exactly(choices, TRUE))
            span = self._number_span(atom)
            start: int | None = None
            for choice, value in zip(choices, values):
                chosen = self.m.new_int((UNCERTAIN, atom, -1, ("value", value)), -span, span)
                self.m.records.append(ValueAfter(choice, chosen, start, 0, scaled(value), NumericEffectKind.ASSIGN))
                start = chosen
            assert start is not None
            self.uncertain_numbers[atom] = (choices, start)
        return self.uncertain_numbers[atom]

    def _number_span(self, atom: AtomKey) -> int:
        """A bound on the magnitude of a number's start value (scaled), uncertain or not."""
        if atom in self.number_values:
            return max(abs(scaled(v)) for v in self.number_values[atom]) + 1
        return self._num_span(self.start_value(atom))

    def _chain_root(self, atom: AtomKey, chains: dict[AtomKey, "Chain[V]"], start: Callable[[AtomKey], V],
                    numeric: bool) -> "Chain[V]":
        if self._replay is not None:
            self._replay.chain_read(atom, numeric)
        root = chains.get(atom)
        if root is None:
            root = chains[atom] = Chain(start(atom))
        return root

    def _bool_holds(self, atom: AtomKey, positive: bool, writers: Sequence[tuple[int, bool]], name: Name) -> Lit:
        """Literal: the open-world test ``atom == positive`` holds after ``writers``."""
        if not writers:
            if atom in self.uncertain_atoms:
                start = self._uncertain(atom)
                return start if positive else neg(start)
            init = self.facts.get(atom)
            return TRUE if init is None or init == positive else FALSE
        known, true = self._bool_value(atom, writers)
        return self.m.or_of([neg(known), true if positive else neg(true)], name)

    def _num_holds(self, atom: AtomKey, op: str, bound: float, writers: Sequence[tuple[int, str, float]], name: Name,
                   required: "_Requirement | None" = None) -> Lit:
        """Literal: the open-world comparison ``atom op bound`` holds after ``writers``.

        On a value the world does not give (and no chosen writer assigned) the comparison is
        not refuted; when ``required`` (the comparison must hold where ``required.lit`` is
        true), it is kept as a condition on the start value, checked against the others
        (:meth:`_start_values`)."""
        init = self.start_value(atom)
        uncertain = atom in self.number_values
        if not writers:
            if uncertain:  # the choices of the values that compare so
                choices, _ = self._uncertain_number(atom)
                passing = [c for c, v in zip(choices, self.number_values[atom]) if compare(v, op, bound)]
                return self.m.or_of(passing, name) if passing else FALSE
            if init is None:
                self._require_start(atom, op, bound, required, TRUE, None)
                return TRUE
            return TRUE if compare(init, op, bound) else FALSE
        known, value = self._num_value(atom, writers)
        assert isinstance(value, int)
        if init is None:  # (an uncertain number is known: no condition on its start is kept)
            self._require_start(atom, op, bound, required, neg(known), value)
        if known is FALSE:
            return TRUE
        sat = self.m.new_bool((COMPARED, atom, -1, (op, bound)))
        self.m.records.append(Compare(sat, value, op, scaled(bound)))
        return self.m.or_of([neg(known), sat], name)

    def _require_start(self, atom: AtomKey, op: str, bound: float, required: "_Requirement | None", unknown: Lit,
                       offset: int | None) -> None:
        if required is None or unknown is FALSE:
            return
        if self._replay is not None:
            self._replay.chain_read(atom, True)  # a copy whose start values are compared is encoded in full
        self.start_tests.setdefault(atom, []).append(_StartTest(required, unknown, offset, op, scaled(bound)))

    def _start_values(self) -> None:
        """One start value must meet every comparison required on a value the world does not
        give: every two of them, when both are required and both still see the start value,
        must leave it a common value (:mod:`.numeric`; by Helly's theorem that is enough)."""
        for atom, tests in self.start_tests.items():
            for j, second in enumerate(tests):
                for first in tests[:j]:
                    self._start_pair(atom, first, second)

    def _start_pair(self, atom: AtomKey, first: "_StartTest", second: "_StartTest") -> None:
        gap = offset_gap((first.op, first.bound), (second.op, second.bound))
        if gap.always:
            return
        both = [neg(first.required.lit), neg(second.required.lit), neg(first.unknown), neg(second.unknown)]
        label = self._label(lambda: (
            f"start:{atom}:{first.required.describe()}:{second.required.describe()}",
            f"{second.required.describe()} cannot hold together with {first.required.describe()}: the world does not give "
            f"{_atom_name(atom)}, and no value of it meets both"))
        if first.offset == second.offset:  # the same chain value, or both the start value itself
            if not gap.admits(0):
                self.m.clause(both, label)
            return
        difference = self._offset_difference(atom, first.offset, second.offset)
        for op, bound in (("<=", gap.high), (">=", gap.low), ("<>", gap.excluded)):
            if bound is not None:
                holds = self.m.new_bool((COMPARED, atom, -1, (op, bound / SCALE)))
                self.m.records.append(Compare(holds, difference, op, bound))
                self.m.clause([*both, holds], label)

    def _offset_difference(self, atom: AtomKey, first: int | None, second: int | None) -> int:
        """An integer variable equal to offset ``second`` minus offset ``first`` (None: 0)."""
        span = sum(self.m.ints[v].hi for v in (first, second) if v is not None)
        target = self.m.new_int((OFFSET_GAP, atom, -1, (first, second)), -span, span)
        self.m.records.append(Difference(target, second, first))
        return target

    def _num_value(self, atom: AtomKey, writers: Sequence[tuple[int, str, float]]) -> tuple[Lit, int | None]:
        """(known literal, integer variable) of ``atom`` after the chosen ``writers``: a chain of
        :class:`ValueAfter` steps shared by the tests that see a common prefix of writers, and
        looked up by length for a prefix of all of them (as :meth:`_bool_value`); the variable is
        None before the first writer."""
        init = self.start_value(atom)
        if atom in self.number_values:
            root = self._chain_root(atom, self.num_chains, lambda _: (TRUE, self._uncertain_number(atom)[1]), True)
        else:
            root = self._chain_root(atom, self.num_chains, lambda _: (TRUE if init is not None else FALSE, None), True)
        everyone = self.num_writers.get(atom, [])
        k = len(writers)
        if k and k <= len(everyone) and writers[-1] is everyone[k - 1]:  # a subsequence: this is a prefix
            prefix = self.num_prefixes.setdefault(atom, [(root, self._number_span(atom))])
            while len(prefix) <= k:
                node, span = prefix[-1]
                w, kind, amount = everyone[len(prefix) - 1]
                span += abs(scaled(amount))
                prefix.append((self._num_step(atom, node, w, kind, amount, span, init), span))
            return prefix[k][0].value
        node, span = root, self._number_span(atom)
        for w, kind, amount in writers:
            span += abs(scaled(amount))
            node = self._num_step(atom, node, w, kind, amount, span, init)
        return node.value

    @staticmethod
    def _num_span(init: float | None) -> int:
        return abs(scaled(init) if init is not None else 0) + 1

    def _num_step(self, atom: AtomKey, node: "Chain[tuple[Lit, int | None]]", w: int, kind: str, amount: float,
                  span: int, init: float | None) -> "Chain[tuple[Lit, int | None]]":
        """The chain node after writer ``w`` (changing ``atom`` by ``kind`` and ``amount`` if chosen)
        follows ``node``; ``span`` bounds the value's magnitude so far."""
        amount_scaled = scaled(amount)
        step = node.next.get((w, kind, amount_scaled))
        if step is None:
            known, prev_var = node.value
            xw = self.x[w]
            nxt = self.m.new_int((AFTER, atom, w, None), -span, span)
            prev_const = scaled(init) if init is not None else 0
            self.m.records.append(ValueAfter(xw, nxt, prev_var, prev_const, amount_scaled, NumericEffectKind(kind)))
            # only an assignment makes a value known: an increase of an unknown value changes
            # its offset (the chain then holds the offset)
            known_after = self.m.or_of([known, xw], (KNOWN_AFTER, atom, w, None)) if kind == "assign" else known
            step = node.next[(w, kind, amount_scaled)] = Chain((known_after, nxt))
        return step

    def _state_test(self, test: Test, decs: Seen, name: Name, required: "_Requirement | None" = None) -> Lit:
        """Literal for an achieve/context test evaluated after the chosen ``decs``; ``required``
        passes to its conjuncts, not into a disjunction (whose comparisons on unknown values
        hold, the open world)."""
        if isinstance(test, FactTest):
            atom = (test.predicate, test.args)
            return self._bool_holds(atom, test.positive, self._bool_writers(atom, decs), name)
        if isinstance(test, ValueTest):
            atom = (test.function, test.args)
            return self._num_holds(atom, test.op, test.value, self._num_writers(atom, decs), name, required)
        if isinstance(test, AllOf):
            return self.m.and_of([self._state_test(p, decs, name, required) for p in test.parts], name)
        return self.m.or_of([self._state_test(p, decs, name) for p in test.parts], name)

    def _bool_writers(self, atom: AtomKey, seen: Seen) -> Sequence[tuple[int, bool]]:
        everyone = self.bool_writers.get(atom, [])
        return seen.select(everyone, self._writer_vertices(atom, everyone)) if everyone else everyone

    def _num_writers(self, atom: AtomKey, seen: Seen) -> Sequence[tuple[int, str, float]]:
        everyone = self.num_writers.get(atom, [])
        return seen.select(everyone, self._writer_vertices(("function", atom), everyone)) if everyone else everyone

    def _writer_vertices(self, key: Any, everyone: Sequence[tuple[Any, ...]]) -> list[int]:
        """The decomposition vertices of an atom's writers, in order (listed once per atom; a
        function's atom keyed apart from a predicate's of the same name)."""
        known = self.writer_positions.get(key)
        if known is None:
            known = self.writer_positions[key] = [w[0] for w in everyone]
        return known

    # --- rules -------------------------------------------------------------------------------------
    def _task_rules(self, t: int) -> None:
        tg = self.tg
        seen = self.scopes.seen_runs_by_task(t)
        writers_seen: dict[AtomKey, Sequence[tuple[int, bool]]] = {}  # the decompositions share them
        for i, context in enumerate(tg.task(t).contexts):
            ok = self._state_test(context, seen, (CONTEXT, None, t, None))
            self.m.clause([neg(self.active[t]), ok], self._label(lambda: (
                f"context:{t}:{i}", f"task instance {tg.vertices[t].content}: the creation condition "
                f"{_show_test(context)} that an earlier task enables does not hold where it starts")))
        for dv in tg.decompositions_of(t):
            d = dv.index
            dec = dv.decomposition
            if contradicts_itself(dec):
                self.m.clause([neg(self.x[d])], self._label(lambda: (
                    f"pre:{dec.id}", f"{dec.id}: its preconditions contradict each other")))
            for c in dec.predicates.checked_preconditions:
                if any(a.startswith("?") for a in c.args):
                    continue
                label = self._label(lambda: (f"pre:{dec.id}:{c}", f"{dec.id}: precondition {show_precondition(c)}"))
                if isinstance(c, Literal):
                    atom = (c.predicate, c.args)
                    if atom not in writers_seen:
                        writers_seen[atom] = self._bool_writers(atom, seen)
                    ok = self._bool_holds(atom, c.positive, writers_seen[atom], (PRECONDITION, None, d, None))
                else:
                    atom = (c.function, c.args)
                    ok = self._num_holds(atom, c.op, c.value, self._num_writers(atom, seen), (PRECONDITION, None, d, None),
                                         _Requirement(self.x[d], functools.partial(_precondition_text, dec.id, c)))
                self.m.clause([neg(self.x[d]), ok], label)
            self._robot_rules(d, t)

    def _robot_rules(self, d: int, t: int) -> None:
        """Robot-related preconditions of ``d``: the last chosen partner that writes one must
        agree with it (an unknown robot fact holds)."""
        tg = self.tg
        dec = tg.decomposition(d).decomposition
        for lit, writers in robot_precondition_writers(self.domain, tg, d, self.index, self.queue_pos):
            later: list[Lit] = []
            for e, value in reversed(writers):
                if value != lit.positive:
                    self.m.clause([neg(self.x[d]), neg(self.x[e])] + later,
                                  self._label(lambda: (f"robot:{dec.id}:{lit}", f"{dec.id}: robot precondition {show_precondition(lit)} "
                                              f"contradicts the effect of {tg.vertices[e].content}")))
                later.append(self.x[e])

    def _conflicts(self, v: int) -> None:
        """AND-parallel: no two chosen decompositions below ``v`` set a fact both ways."""
        for c in self.conflicts.below(v):
            atom = c.atom
            label = self._label(lambda: (
                f"conflict:{v}:{atom}", f"parallel tasks below {self.tg.scope(v).goal or 'operator ' + str(v)} "
                                        f"set {_atom_name(atom)} both true and false"))
            if len(c.setting_true) * len(c.setting_false) <= 16:
                for a in c.setting_true:
                    for b in c.setting_false:
                        if self.tg.vertices[a].parent != self.tg.vertices[b].parent:
                            self.m.clause([neg(self.x[a]), neg(self.x[b])], label)
            else:
                any_pos = self.m.or_of([self.x[a] for a in c.setting_true], (SET_BELOW, atom, v, None))
                any_neg = self.m.or_of([self.x[b] for b in c.setting_false], (CLEARED_BELOW, atom, v, None))
                self.m.clause([neg(any_pos), neg(any_neg)], label)

    def _achieve(self, v: int, goal: str, test: Test) -> None:
        """An achieve condition checked at ``v`` must hold when ``v`` is active, after the
        effects of ``v``'s subtree.  A conjunction is posted part by part (one per forAll
        element), so independent instances stay in independent components."""
        decs = self.scopes.seen_runs_by_achieve(v)
        parts = list(_conjuncts(test))
        for i, part in enumerate(parts):
            holds = self._state_test(part, decs, (ACHIEVE, None, v, goal),
                                     _Requirement(self.active[v], lambda: f"the achieve condition of goal {goal}"))
            self.m.clause([neg(self.active[v]), holds],
                          self._label(lambda: (f"achieve:{v}:{goal}:{i}",
                                               f"achieve condition of goal {goal}: {_show_test(part)}")))


@dataclass(frozen=True, slots=True)
class _Requirement:
    """A comparison must hold where ``lit`` is true; ``describe`` names it (for explanations)."""

    lit: Lit
    describe: Callable[[], str]


@dataclass(frozen=True, slots=True)
class _StartTest:
    """A comparison required on a value the world does not give: where ``required`` and
    ``unknown`` (no chosen writer assigned it) hold, the start value plus ``offset`` (an integer
    variable, None: 0) compares ``op`` with ``bound`` (thousandths)."""

    required: _Requirement
    unknown: Lit
    offset: int | None
    op: str
    bound: int


def _precondition_text(dec_id: str, c: Literal | Comparison) -> str:
    return f"{dec_id}: precondition {show_precondition(c)}"


def _atom_name(atom: AtomKey) -> str:
    """``busy(Kitchen)``: an atom as the variable names and explanations show it."""
    return f"{atom[0]}({', '.join(atom[1])})"


def _conjuncts(test: Test) -> Iterable[Test]:
    if isinstance(test, AllOf):
        for p in test.parts:
            yield from _conjuncts(p)
    else:
        yield test


def _show_test(test: Test) -> str:
    if isinstance(test, FactTest):
        return f"{'' if test.positive else 'not '}{test.predicate}({', '.join(test.args)})"
    if isinstance(test, ValueTest):
        return f"{test.function}({', '.join(test.args)}) {test.op} {test.value:g}"
    joiner = " and " if isinstance(test, AllOf) else " or "
    return "(" + joiner.join(_show_test(p) for p in test.parts) + ")"
