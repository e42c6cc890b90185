"""Encoding a stamped forAll copy by replaying the records of another copy (spec ``semantics.md`` §7).

A stamped copy (``TaskGraph.stamped_copies``) has its source copy's vertices, tree and
constraints, with other content: the instances of another room, with their own parameter
values.  The encoder meets each copy as one run in each of its phases (vertices are numbered
depth first, and the mission queue is in vertex order), and what it posts there depends on the
copy's structure, on which of its atoms are equal, and on the world: each atom's initial value,
its writers, and the chain of values already built for it.  So two copies of one source post
the same records, up to a renaming of their variables, when

* their task instances' parameter values are equal in the same places (the same *pattern*):
  then one renaming carries one copy's values onto the other's, one to one, and since grounding
  a decomposition is a substitution, it carries every ground precondition and effect across;
* the achieve conditions checked inside them are the same up to that renaming (they are read
  from the world, so they are compared, not assumed);
* every atom one reads or writes has, renamed, the same initial value in the other, writers
  only inside the copy at the same places, and a chain of values that no other run has read;
* no numeric precondition, effect or test is involved (those copies are encoded in full).

The first copy of a source fixes the *templates*: each atom its decompositions read or write,
as the places of its arguments among the copy's parameter values.  A copy's *class* is then
what the world says of its templated atoms (initial value, writers, chain), one dictionary
lookup.  The first copy of each class is encoded in full and leads it: its run of each phase is
kept, compiled into one function that appends the run's variables (names kept as parts), records
and chains of values for another copy, given where that copy's variables start.  The other
copies of the class call it.  The result is the model the full encoding builds, variable for
variable and record for record, in the same order, which the tests check on random missions and
the benchmark worlds.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from itertools import islice
from typing import Any, Callable, Sequence

from ..model.state_tests import AllOf, AnyOf, FactTest, Test
from ..model import Literal
from ..model.task_graph import OperatorVertex, ScopeVertex, TaskVertex
from .boolean_model import FALSE, TRUE, AndOf, Clause, Const, Exactly, Lit, OrOf, Record
from .encoding_state import Chain, EncodingState
from .semantics import NO_EFFECTS, AtomKey, achieve_tests

CHOICES, TASK_RULES, CHECKS = 1, 2, 3  # the encoder's phases
LEADERS = 16  # classes kept per source copy: the copies of a large world fall in a few


_NOBODY: Any = object()  # no run has read an atom's chain


class _Unsupported(Exception):
    """A run that cannot be replayed: something of it the templates do not carry over."""


Template = tuple[str, tuple[int, ...]]  # an atom: its predicate, and the places of its arguments among the values


@dataclass
class _Group:
    """The copies of one source: the same vertices, tree and constraints."""

    source: int
    size: int
    tasks: list[int]  # offsets of the task vertices, in vertex order
    queue: list[int]  # offsets of the mission-queue vertices (tasks and operators), in order
    checked: list[int]  # offsets of the vertices that can have achieve conditions (by structure)
    choices: Callable[..., None] | None = None  # the source's choices, compiled (see _choices_source)
    choices_root: Lit | None = None
    closed: bool = False  # copies are encoded in full: a rule of the module docstring fails
    irregular: list[Any] | None = None  # where the first copy's values are not single values
    pattern: list[int] | None = None  # and where each of its values first appears
    templates: list[Template] = field(default_factory=list)  # atoms read or written by the task rules
    numeric: list[Template] = field(default_factory=list)  # numeric atoms their preconditions compare
    classes: dict[tuple[Any, ...], "_Leader"] = field(default_factory=dict)


@dataclass
class _Copy:
    start: int
    group: _Group
    ranges: dict[int, tuple[int, int]] = field(default_factory=dict)  # phase -> its variables
    leader: "_Leader | None" = None  # the leader of its class (itself when it leads)
    values: list[str] | None = None  # its parameter values (kept from the task rules to the checks)
    atoms: list[AtomKey] | None = None  # its templated atoms (likewise)


@dataclass
class _Leader:
    copy: _Copy
    runs: dict[int, Callable[..., None]] = field(default_factory=dict)  # phase -> its run, compiled
    checks: tuple[Any, ...] | None = None  # the achieve tests inside it, as a shape, and their atoms' class
    checked: list[Template] = field(default_factory=list)


class CopyReplay:
    """The stamped copies of one Task Graph, and the compiled runs of their classes' leaders."""

    def __init__(self, enc: EncodingState) -> None:
        self.enc = enc
        tg = enc.tg
        self.copies: dict[int, _Copy] = {}  # root vertex -> copy
        self.task_starts: dict[int, _Copy] = {}  # first task vertex -> copy
        self.queue_starts: dict[int, _Copy] = {}  # first mission-queue vertex -> copy
        groups: dict[int, _Group] = {}
        for region in tg.stamped_copies:
            for c in region:
                group = groups.get(c.source)
                if group is None:
                    offsets = range(c.size)
                    kinds = [type(tg.vertices[c.source + k]) for k in offsets]
                    group = groups[c.source] = _Group(
                        c.source, c.size, [k for k in offsets if kinds[k] is TaskVertex],
                        [k for k in offsets if kinds[k] in (TaskVertex, OperatorVertex)],
                        [k for k in offsets if self._may_check(c.source + k)])
                copy = _Copy(c.start, group)
                self.copies[c.start] = copy
                if group.tasks:
                    self.task_starts[c.start + group.tasks[0]] = copy
                if group.queue:
                    self.queue_starts[c.start + group.queue[0]] = copy
        self.run_copy: int | None = None  # the copy whose run is being encoded (its root vertex)
        self.touched: dict[AtomKey, bool] | None = None  # a leader's run: atoms whose chains it read
        self.owner: dict[AtomKey, int | None] = {}  # atom -> the copy whose run last read its chain

    def summary(self) -> tuple[int, int]:
        """How many copies replayed a leader's task rules, and how many classes led them."""
        copies = self.copies.values()
        followers = sum(1 for c in copies if c.leader is not None and c.leader.copy is not c)
        groups = {id(c.group): c.group for c in copies}.values()
        return followers, sum(len(g.classes) for g in groups)

    def chain_read(self, atom: AtomKey, numeric: bool) -> None:
        """The encoder reads (and may extend) the chain of values of ``atom``."""
        self.owner[atom] = self.run_copy
        if self.touched is not None:
            self.touched[atom] = self.touched.get(atom, False) or numeric

    # --- phase 1: choices (structure only) --------------------------------------------------------
    def choices(self, copy: _Copy, active: Lit, encode: Callable[[int, Lit], None]) -> None:
        """The choice variables of ``copy``: its source's, replayed, or encoded in full."""
        enc, group = self.enc, copy.group
        m = enc.m
        b = len(m.names)
        if group.choices is not None and self.run_copy is None:
            # the copies of one source are children of one forAll node: one activity literal
            assert active == group.choices_root, "stamped copies below one forAll node share their activity"
            group.choices(m.names, enc.x, enc.active, enc.or_lits, m.records, enc.tg.vertices, b, active, copy.start)
        else:
            counts = (len(m.records), len(enc.x), len(enc.active), len(enc.or_lits))
            outer, self.run_copy = self.run_copy, copy.start
            try:
                encode(copy.start, active)
            finally:
                self.run_copy = outer
            if copy.start == group.source and outer is None and group.choices is None:
                try:
                    group.choices = _compile(_choices_source(enc, copy, active, b, counts))
                    group.choices_root = active
                except _Unsupported:
                    pass
        copy.ranges[CHOICES] = (b, len(m.names))

    # --- phases 2 and 3: task rules and checks ----------------------------------------------------
    def run(self, phase: int, copy: _Copy, vertices: Sequence[int], encode: Callable[[int], None]) -> None:
        """The records of ``copy`` in ``phase`` (``vertices`` are its run there): its class
        leader's, replayed, or encoded in full (and kept, when ``copy`` leads its class)."""
        group = copy.group
        if group.closed or CHOICES not in copy.ranges:
            self._plain(phase, copy, vertices, encode)
            return
        try:
            if phase == TASK_RULES:
                self._task_rules(copy, vertices, encode)
            else:
                self._checks(copy, vertices, encode)
        except _Unsupported:
            group.closed = True
            if phase not in copy.ranges:
                self._plain(phase, copy, vertices, encode)

    def _task_rules(self, copy: _Copy, vertices: Sequence[int], encode: Callable[[int], None]) -> None:
        group = copy.group
        irregular, values = self._bindings(copy)
        pattern = _pattern(values)
        copy.values = values
        if group.irregular is None:  # the first copy: it fixes the templates
            group.irregular, group.pattern = irregular, pattern
            group.templates, group.numeric = self._templates(copy, values)
        elif irregular != group.irregular or pattern != group.pattern:
            self._plain(TASK_RULES, copy, vertices, encode)
            return
        atoms = copy.atoms = _instances(group.templates, values)
        key = (*self._class(copy, atoms), *self._numeric_class(copy, _instances(group.numeric, values)))
        leader = group.classes.get(key)
        if leader is not None and TASK_RULES in leader.runs:
            copy.leader = leader
            self._replay(TASK_RULES, copy, leader, atoms)
        elif leader is None and len(group.classes) < LEADERS and _replayable(key):
            leader = copy.leader = group.classes[key] = _Leader(copy)
            self._lead(TASK_RULES, copy, vertices, encode, atoms)
        else:
            self._plain(TASK_RULES, copy, vertices, encode)

    def _checks(self, copy: _Copy, vertices: Sequence[int], encode: Callable[[int], None]) -> None:
        leader, values, templated = copy.leader, copy.values, copy.atoms
        copy.values = copy.atoms = None  # not needed after the checks
        if leader is None or values is None or templated is None or TASK_RULES not in leader.runs \
                or TASK_RULES not in copy.ranges:
            self._plain(CHECKS, copy, vertices, encode)
            return
        enc, group = self.enc, copy.group
        tests = [(k, achieve_tests(enc.tg, copy.start + k, enc.gm, enc.config)) for k in group.checked]
        if leader.copy is copy:
            shape, atoms = _flatten(tests)
            checked = _templates_of(atoms, values)
            leader.checked = checked
            facts = self._class(copy, atoms)
            if not _replayable(facts):
                self._plain(CHECKS, copy, vertices, encode)
                return
            leader.checks = (shape, *facts)
            self._lead(CHECKS, copy, vertices, encode, templated + atoms)
            return
        run = leader.runs.get(CHECKS)
        if run is not None and leader.checks is not None:
            shape, atoms = _flatten(tests)
            if atoms == _instances(leader.checked, values) and (shape, *self._class(copy, atoms)) == leader.checks:
                self._replay(CHECKS, copy, leader, templated + atoms)
                return
        self._plain(CHECKS, copy, vertices, encode)

    def _plain(self, phase: int, copy: _Copy, vertices: Sequence[int], encode: Callable[[int], None]) -> None:
        b = len(self.enc.m.names)
        self.run_copy = copy.start
        try:
            for v in vertices:
                encode(v)
        finally:
            self.run_copy = None
        copy.ranges[phase] = (b, len(self.enc.m.names))

    def _lead(self, phase: int, copy: _Copy, vertices: Sequence[int], encode: Callable[[int], None],
              atoms: list[AtomKey]) -> None:
        """Encode the run of the leader ``copy`` in full, and keep it compiled (over ``atoms``,
        which the other copies of its class give renamed)."""
        enc, m = self.enc, self.enc.m
        b, r0 = len(m.names), len(m.records)
        self.touched = {}
        try:
            self._plain(phase, copy, vertices, encode)
            touched = self.touched
        finally:
            self.touched = None
        assert copy.leader is not None
        try:
            source = _run_source(enc, copy, phase, b, r0, atoms, touched)
        except _Unsupported:
            return  # its class is encoded in full
        copy.leader.runs[phase] = _compile(source)

    def _replay(self, phase: int, copy: _Copy, leader: _Leader, atoms: list[AtomKey]) -> None:
        enc, m = self.enc, self.enc.m
        run = leader.runs[phase]
        b = len(m.names)
        one = copy.ranges[CHOICES][0]
        two = copy.ranges[TASK_RULES][0] if phase == CHECKS else 0
        run(m.names, m.records, enc.bool_chains, enc.bool_prefixes, self.owner, atoms, enc.tg.vertices,
            b, one, two, enc.active[copy.start], copy.start)
        copy.ranges[phase] = (b, len(m.names))

    # --- what a copy reads --------------------------------------------------------------------------
    def _bindings(self, copy: _Copy) -> tuple[list[Any], list[str]]:
        """The parameter values of the copy's task instances in order (a collection's elements
        one by one), and where they are not single values: an unbound parameter ("") and each
        collection, with its size.  The parameters themselves are the source's (the copies'
        instances are of the same tasks)."""
        vertices = self.enc.tg.vertices
        odd: list[Any] = []
        values: list[str] = []
        start = copy.start
        for k in copy.group.tasks:
            for p in vertices[start + k].instance.parameters:  # type: ignore[union-attr]
                value = p.value
                if value.__class__ is str and value:
                    values.append(value)
                elif isinstance(value, tuple):
                    odd.append((len(values), len(value)))
                    values.extend(value)
                else:
                    odd.append((len(values), ""))
        return odd, values

    def _templates(self, copy: _Copy, values: list[str]) -> tuple[list[Template], list[Template]]:
        """The atoms the copy's task rules read (ground preconditions) or its decompositions
        write, and the numeric atoms its ground preconditions compare, as templates over
        ``values``."""
        enc = self.enc
        tg = enc.tg
        atoms: dict[AtomKey, None] = {}
        numeric: dict[AtomKey, None] = {}
        for k in copy.group.tasks:
            if tg.task(copy.start + k).contexts:
                raise _Unsupported
            for dv in tg.decompositions_of(copy.start + k):
                for c in dv.decomposition.predicates.checked_preconditions:
                    if not any(a.startswith("?") for a in c.args):
                        if isinstance(c, Literal):
                            atoms[(c.predicate, c.args)] = None
                        else:
                            numeric[(c.function, c.args)] = None
                effects = enc.effects.get(dv.index, NO_EFFECTS)
                if effects.numeric:
                    raise _Unsupported
                for atom, _ in effects.facts:
                    atoms[atom] = None
        return _templates_of(list(atoms), values), _templates_of(list(numeric), values)

    def _class(self, copy: _Copy, atoms: list[AtomKey]) -> list[Any]:
        """What the world says of ``atoms`` for ``copy``: initial value, writers (as offsets in
        the copy; None when one is outside it) and who read its chain last (0: nobody, 1: the
        copy, 2: another run)."""
        facts, writers = self.enc.facts, self.enc.bool_writers
        start, size = copy.start, copy.group.size
        out: list[Any] = []
        for atom in atoms:
            written = writers.get(atom)
            offsets: tuple[tuple[int, bool], ...] | None = ()
            if written:  # in vertex order: inside the copy when the first and the last are
                inside = start <= written[0][0] and written[-1][0] < start + size
                offsets = tuple((d - start, value) for d, value in written) if inside else None
            out.append((facts.get(atom), offsets, self._status(atom, start)))
        return out

    def _numeric_class(self, copy: _Copy, atoms: list[AtomKey]) -> list[Any]:
        """What the world says of numeric ``atoms``: initial value, whether anything writes
        them (a run that reads a written one is not kept: its chain is numeric) and who read
        its chain last."""
        values, writers = self.enc.values, self.enc.num_writers
        return [(values.get(atom), bool(writers.get(atom)), self._status(atom, copy.start)) for atom in atoms]

    def _status(self, atom: AtomKey, start: int) -> int:
        """Who read the chain of ``atom`` last: 0 nobody, 1 the copy at ``start``, 2 another run."""
        owner = self.owner.get(atom, _NOBODY)
        return 0 if owner is _NOBODY else 1 if owner == start else 2

    def _may_check(self, v: int) -> bool:
        """Whether vertex ``v`` can have achieve conditions (by its structure alone, which the
        copies of one source share: their vertices and carried achieve goals are stamped)."""
        tg = self.enc.tg
        vertex = tg.vertices[v]
        own = isinstance(vertex, ScopeVertex) and bool(vertex.forall or vertex.achieve) and bool(vertex.goal)
        return own or bool(tg.achieve_carried.get(v))


# --- templates ---------------------------------------------------------------------------------------
def _first_places(values: list[str]) -> dict[str, int]:
    """Where each value first appears among ``values``."""
    first: dict[str, int] = {}
    for i, v in enumerate(values):
        first.setdefault(v, i)
    return first


def _pattern(values: list[str]) -> list[int]:
    """Where each value first appears: two copies with one pattern are renamings of each other."""
    first = _first_places(values)
    return [first[v] for v in values]


def _templates_of(atoms: list[AtomKey], values: list[str]) -> list[Template]:
    place = _first_places(values)
    try:
        return [(predicate, tuple(place[a] for a in args)) for predicate, args in atoms]
    except KeyError:
        raise _Unsupported from None  # an argument that is none of the copy's parameter values


def _instances(templates: list[Template], values: list[str]) -> list[AtomKey]:
    return [(predicate, tuple([values[i] for i in places])) for predicate, places in templates]


def _flatten(tests: list[tuple[int, list[tuple[str, Test]]]]) -> tuple[tuple[Any, ...], list[AtomKey]]:
    """The achieve tests at a copy's vertices as a shape (vertex offsets, goals, connectives,
    polarities) and the atoms they read, in order."""
    shape: list[Any] = []
    atoms: list[AtomKey] = []
    for k, found in tests:
        shape.append((k, len(found)))
        for goal, test in found:
            shape.append(goal)
            _walk(test, shape, atoms)
    return tuple(shape), atoms


def _walk(test: Test, shape: list[Any], atoms: list[AtomKey]) -> None:
    if isinstance(test, FactTest):
        shape.append(test.positive)
        atoms.append((test.predicate, test.args))
    elif isinstance(test, (AllOf, AnyOf)):
        shape.append((type(test).__name__, len(test.parts)))
        for p in test.parts:
            _walk(p, shape, atoms)
    else:
        raise _Unsupported  # a numeric test


def _replayable(facts: Sequence[tuple[Any, Any, int]]) -> bool:
    """Whether a class of atoms can be replayed: every writer inside the copy, and no chain
    read by another run."""
    return all(offsets is not None and status != 2 for _, offsets, status in facts)


def _last(d: dict[Any, Any], before: int) -> list[tuple[Any, Any]]:
    """The items of ``d`` added after it held ``before`` items, in the order added."""
    return list(islice(reversed(d.items()), len(d) - before))[::-1]


# --- compiled runs ------------------------------------------------------------------------------------
# A leader's run becomes the source of one function: its variables' names, records and chains of
# values as expressions over where the replaying copy's variables start (``one``: its choices,
# ``two``: its task rules, ``b``: this run), its root activity literal ``r`` and first vertex ``s``.

def _compile(source: str) -> Callable[..., None]:
    namespace: dict[str, Any] = {"Clause": Clause, "OrOf": OrOf, "AndOf": AndOf, "Exactly": Exactly,
                                 "TRUE": TRUE, "FALSE": FALSE, "Chain": Chain}
    exec(compile(source, "<replayed run>", "exec"), namespace)  # noqa: S102 - source made here, from ints and reprs
    return namespace["replay"]  # type: ignore[no-any-return]


class _Coder:
    """Literals and vertices of a leader's run as expressions over another copy's bases.

    Each variable and vertex number the run uses is made once, as a local of the function (a
    vertex number as the vertex's own ``index``), and shared by every record that uses it, as
    in the full encoding: a large mission holds millions of them."""

    def __init__(self, ranges: list[tuple[int, int, str]], root: Lit, start: int) -> None:
        self.ranges = ranges  # (first variable, end, base name)
        self.root = root
        self.start = start
        self.locals: dict[str, str] = {}  # local name -> its expression, in the order first used

    def __call__(self, lit: Lit) -> str:
        if isinstance(lit, Const):
            return "TRUE" if lit is TRUE else "FALSE"
        v = abs(lit)
        if isinstance(self.root, int) and v == abs(self.root):
            return "r" if lit == self.root else "-r"
        for lo, hi, base in self.ranges:
            if lo <= v < hi:
                name = f"{base}_{v - lo}"
                self.locals.setdefault(name, f"{base} + {v - lo}")
                return name if lit > 0 else f"-{name}"
        raise _Unsupported  # a variable from outside the copy's runs

    def vertex(self, v: int) -> str:
        """Vertex ``v`` of the leader, as the same vertex of the other copy (whose first is ``s``)."""
        k = v - self.start
        name = f"k_{k}"
        self.locals.setdefault(name, f"vertices[s + {k}].index")
        return name

    def tuple(self, lits: Sequence[Lit]) -> str:
        return _tuple([self(l) for l in lits])

    def prelude(self) -> list[str]:
        return [f"    {name} = {expr}" for name, expr in self.locals.items()]


def _tuple(items: Sequence[str]) -> str:
    return "(" + ", ".join(items) + ("," if len(items) == 1 else "") + ")"


def _choices_source(enc: EncodingState, copy: _Copy, active: Lit, b: int, counts: tuple[int, int, int, int]) -> str:
    """The source copy's choices (variables, the decomposition, activity and OR maps, records)
    as a function of another copy's first variable ``b``, root literal ``r`` and first vertex ``s``."""
    m = enc.m
    e, start, size = len(m.names), copy.start, copy.group.size
    code = _Coder([(b, e, "b")], active, start)

    def vertex(v: int) -> str:
        if not 0 <= v - start < size:
            raise _Unsupported
        return code.vertex(v)

    names: list[str | None] = [None] * (e - b)
    x = []
    for d, lit in _last(enc.x, counts[1]):
        if not isinstance(lit, int) or not b <= lit < e:
            raise _Unsupported
        names[lit - b] = f"vertices[s + {d - start}].content"
        x.append(f"({vertex(d)}, {code(lit)})")
    or_lits = []
    for (v, c), lit in _last(enc.or_lits, counts[3]):
        if not isinstance(lit, int) or not b <= lit < e:
            raise _Unsupported
        names[lit - b] = f"({m.names[lit][0]!r}, None, {vertex(v)}, {vertex(c)})"
        or_lits.append(f"(({vertex(v)}, {vertex(c)}), {code(lit)})")
    if any(n is None for n in names):
        raise _Unsupported
    activity = [f"({vertex(v)}, {code(lit)})" for v, lit in _last(enc.active, counts[2])]
    records = [_exactly(r, code, vertex) for r in m.records[counts[0]:]]
    return "\n".join([
        "def replay(names, x, active, or_lits, records, vertices, b, r, s):",
        *code.prelude(),
        f"    names.extend({_tuple([n for n in names if n is not None])})",
        f"    x.update({_tuple(x)})",
        f"    or_lits.update({_tuple(or_lits)})",
        f"    active.update({_tuple(activity)})",
        f"    records.extend({_tuple(records)})",
    ])


def _exactly(r: Record, code: _Coder, vertex: Callable[[int], str]) -> str:
    """An Exactly record of the choices (labelled by its OR vertex, or not at all)."""
    if not isinstance(r, Exactly):
        raise _Unsupported
    if r.label == "":
        label = "''"
    elif r.label.startswith("or:"):
        label = f"'or:' + str({vertex(int(r.label[3:]))})"
    else:
        raise _Unsupported
    return f"Exactly({code.tuple(r.lits)}, {code(r.target)}, {label})"


def _rule(r: Record, code: _Coder) -> str:
    """A record of the task rules or checks: a clause or a definition, unlabelled."""
    if r.label:
        raise _Unsupported
    if isinstance(r, Clause):
        return f"Clause({code.tuple(r.lits)})"
    if isinstance(r, (OrOf, AndOf)):
        return f"{type(r).__name__}({code.tuple(r.lits)}, {code(r.target)})"
    raise _Unsupported


def _run_source(enc: EncodingState, copy: _Copy, phase: int, b: int, r0: int, atoms: list[AtomKey],
                touched: dict[AtomKey, bool]) -> str:
    """A leader's run of ``phase`` (variables from ``b``, records from ``r0``) as a function of
    another copy's bases and of its ``atoms`` (the leader's, in the same order, renamed)."""
    m = enc.m
    e, start, size = len(m.names), copy.start, copy.group.size
    ranges = [(*copy.ranges[CHOICES], "one"), (b, e, "b")]
    if phase == CHECKS:
        ranges.append((*copy.ranges[TASK_RULES], "two"))
    code = _Coder(ranges, enc.active[start], start)
    place = {atom: i for i, atom in reversed(list(enumerate(atoms)))}
    names = []
    for name in m.names[b:e]:
        if isinstance(name, str):
            raise _Unsupported
        kind, atom, v, extra = name
        if atom is not None and atom not in place or not 0 <= v - start < size \
                or extra is not None and not isinstance(extra, str):
            raise _Unsupported
        names.append(f"({kind!r}, {'None' if atom is None else f'atoms[{place[atom]}]'}, {code.vertex(v)}, {extra!r})")
    records = [_rule(r, code) for r in m.records[r0:]]
    body = [f"    names.extend({_tuple(names)})",
            f"    records.extend({_tuple(records)})"]
    for atom, numeric in touched.items():
        if numeric or atom not in place:
            raise _Unsupported
        body.extend(_chain_lines(enc, atom, f"atoms[{place[atom]}]", start, size, code))
    return "\n".join(["def replay(names, records, chains, prefixes, owner, atoms, vertices, b, one, two, r, s):",
                      *code.prelude(), *body])


def _chain_lines(enc: EncodingState, atom: AtomKey, key: str, start: int, size: int, code: _Coder) -> list[str]:
    """Statements that rebuild the chain of values of ``atom`` (and its prefixes) for another copy."""
    root = enc.bool_chains[atom]
    lines = [f"    n0 = Chain(({code(root.value[0])}, {code(root.value[1])}))"]
    place = {id(root): 0}
    todo = [root]
    while todo:
        node = todo.pop(0)
        for (w, pol), child in node.next.items():
            if not 0 <= w - start < size:
                raise _Unsupported
            n = place[id(child)] = len(place)
            lines.append(f"    n{n} = Chain(({code(child.value[0])}, {code(child.value[1])}))")
            lines.append(f"    n{place[id(node)]}.next[({code.vertex(w)}, {pol!r})] = n{n}")
            todo.append(child)
    lines.append(f"    chains[{key}] = n0")
    prefixes = enc.bool_prefixes.get(atom)
    if prefixes:
        lines.append(f"    prefixes[{key}] = [{', '.join(f'n{place[id(p)]}' for p in prefixes)}]")
    else:
        lines.append(f"    prefixes.pop({key}, None)")
    lines.append(f"    owner[{key}] = s")
    return lines
