"""Mission constraints from the Task Graph (spec ``semantics.md`` §6).

Sequential (SEQ) and fallback (FB) constraints come from the operator structure, transformed
from task instances to their decompositions; parallel pairs become SEQ only where a context
dependency orders them; execution constraints (EC) come from Group/Divisible.  Redundant
SEQ/FB links are trimmed, and EC partners must agree on robot numbers.
"""
from __future__ import annotations

import itertools
from array import array
from collections import Counter
from enum import StrEnum
from typing import Iterable, Iterator, NamedTuple, Sequence, overload

from ..errors import MissionError
from ..model.task_graph import EdgeKind, OperatorVertex, TaskGraph, TaskVertex


class ConstraintKind(StrEnum):
    SEQ = "SEQ"  # sequential: the first runs before the second
    FB = "FB"  # fallback: the second runs only if the first fails
    EC = "EC"  # execution constraint: the two share robots (Group/Divisible)
    PAR = "PAR"  # parallel: only while generating (§6.1), never in the final list


SEQ, FB, EC, PAR = ConstraintKind.SEQ, ConstraintKind.FB, ConstraintKind.EC, ConstraintKind.PAR


class Constraint(NamedTuple):
    """``kind`` between two vertices (tasks while generating, decompositions when final).

    A named tuple: large missions have around a million of them."""

    kind: ConstraintKind
    first: int
    second: int
    group: bool = True
    divisible: bool = True


class Run(NamedTuple):
    """Rows ``lo .. hi - 1`` of ``source`` with their vertices moved by ``shift``
    (:meth:`Constraints.runs`)."""

    source: "Constraints"
    lo: int
    hi: int
    shift: int


_KINDS = tuple(ConstraintKind)  # a stored kind is its position here
_KIND_CODE = {kind: code for code, kind in enumerate(_KINDS)}
_GROUP = tuple(flag & 1 == 1 for flag in range(4))  # by the stored flags
_DIVISIBLE = tuple(flag & 2 == 2 for flag in range(4))
_FEW_PAIRS = 8  # up to this many pairs, appending them is quicker than building columns to extend by


class Constraints(Sequence[Constraint]):
    """The final constraint list, kept by column (kind, first, second, flags) instead of as a
    million named tuples: at 5000 vital-signs rooms a tuple each took 110 MB, the columns take
    10 MB.  Reading it (by index or by iterating) gives :class:`Constraint` tuples, made when
    read; it equals any sequence of the same constraints, a list included."""

    __slots__ = ("_kinds", "_firsts", "_seconds", "_flags", "_pending", "_pending_rows")

    def __init__(self, constraints: Iterable[Constraint] = ()) -> None:
        self._kinds = bytearray()
        self._firsts = array("i")  # vertex indices
        self._seconds = array("i")
        self._flags = bytearray()  # group | divisible << 1
        # runs of another list's rows, moved, that follow the stored ones (:meth:`extend_shifted`)
        self._pending: list[Run] = []
        self._pending_rows = 0
        self.extend(constraints)

    def append(self, c: Constraint) -> None:
        self.append_row(_row_of(c))

    def extend(self, constraints: Iterable[Constraint]) -> None:
        for c in constraints:
            self.append(c)

    def add_all_pairs(self, kind: ConstraintKind, firsts: Sequence[int], seconds: Sequence[int],
                      group: bool = True, divisible: bool = True) -> None:
        """``kind`` between every vertex of ``firsts`` and every vertex of ``seconds``, by first
        vertex and then second (a task pair's constraints, expanded over their decompositions)."""
        code, flag = _KIND_CODE[kind], group | divisible << 1
        self._settle()
        if len(firsts) * len(seconds) <= _FEW_PAIRS:  # most task pairs: one column entry at a time
            for first in firsts:
                for second in seconds:
                    self._kinds.append(code)
                    self._firsts.append(first)
                    self._seconds.append(second)
                    self._flags.append(flag)
            return
        n = len(firsts) * len(seconds)
        self._kinds.extend(bytes([code]) * n)
        for first in firsts:
            self._firsts.extend(array("i", [first]) * len(seconds))
            self._seconds.extend(array("i", seconds))
        self._flags.extend(bytes([flag]) * n)

    def rows(self, lo: int = 0, hi: int | None = None) -> Iterator[tuple[int, int, int, int]]:
        """The stored columns row by row (kind code, first, second, flags), from ``lo`` to
        ``hi``: the generator's own passes over a million constraints read them without making
        the tuples.  Pending runs are stored first, unless the rows asked for are all stored."""
        if hi is None or hi > len(self._kinds):
            self._settle()
        if lo == 0 and hi is None:
            return zip(self._kinds, self._firsts, self._seconds, self._flags)
        return zip(self._kinds[lo:hi], self._firsts[lo:hi], self._seconds[lo:hi], self._flags[lo:hi])

    def runs(self) -> Iterator[Run]:
        """The list as runs of stored rows, in order: rows ``lo .. hi - 1`` of a list with their
        vertices moved by ``shift``.  A stamped forAll copy's run is its source's rows, moved:
        the output formats such a run once and fills in each copy's keys, and nothing needs the
        moved rows stored."""
        pending = tuple(self._pending)  # as they are now: reading the rows of one may store them
        if self._kinds:
            yield Run(self, 0, len(self._kinds), 0)
        yield from pending

    def append_row(self, row: tuple[int, int, int, int]) -> None:
        """Append a row as :meth:`rows` gives it."""
        self._settle()
        code, first, second, flag = row
        self._kinds.append(code)
        self._firsts.append(first)
        self._seconds.append(second)
        self._flags.append(flag)

    def extend_shifted(self, other: "Constraints", lo: int, hi: int, shift: int) -> None:
        """Append rows ``lo .. hi - 1`` of ``other`` with their vertices moved by ``shift``: a
        stamped forAll copy's constraints, from those of the copy it was stamped from.  They
        are stored when first read (:meth:`runs` gives them as they are): at 50,000 vital-signs
        rooms, moving eleven million rows one by one took two seconds that the output does not
        need."""
        if hi > lo:
            other._settle()
            self._pending.append(Run(other, lo, hi, shift))
            self._pending_rows += hi - lo

    def _settle(self) -> None:
        """Store the pending runs (:meth:`extend_shifted`)."""
        for other, lo, hi, shift in self._pending:
            self._kinds += other._kinds[lo:hi]
            self._firsts.extend(map(shift.__add__, other._firsts[lo:hi]) if shift else other._firsts[lo:hi])
            self._seconds.extend(map(shift.__add__, other._seconds[lo:hi]) if shift else other._seconds[lo:hi])
            self._flags += other._flags[lo:hi]
        self._pending.clear()
        self._pending_rows = 0

    def __len__(self) -> int:
        return len(self._kinds) + self._pending_rows

    def count_by_kind(self) -> Counter[str]:
        """How many constraints there are of each kind present (a summary's counts); moving a
        run does not change its kinds, so the pending runs are counted where they are."""
        codes = range(len(_KINDS))
        counts = [self._kinds.count(code) for code in codes]  # a byte count in C per kind
        by_run: dict[tuple[int, int, int], list[int]] = {}  # the copies of one source share its run
        for other, lo, hi, _ in self._pending:
            found = by_run.get((id(other), lo, hi))
            if found is None:
                part = other._kinds[lo:hi]
                found = by_run[(id(other), lo, hi)] = [part.count(code) for code in codes]
            counts = [a + b for a, b in zip(counts, found)]
        return Counter({str(kind): n for kind, n in zip(_KINDS, counts) if n})

    @overload
    def __getitem__(self, i: int) -> Constraint: ...

    @overload
    def __getitem__(self, i: slice) -> list[Constraint]: ...

    def __getitem__(self, i: int | slice) -> Constraint | list[Constraint]:
        self._settle()
        if isinstance(i, slice):
            return [self[j] for j in range(*i.indices(len(self)))]
        return constraint_of_row((self._kinds[i], self._firsts[i], self._seconds[i], self._flags[i]))

    def __iter__(self) -> Iterator[Constraint]:
        # the tuples are made by tuple.__new__ from zipped columns: no Python call per constraint
        self._settle()
        columns = zip(map(_KINDS.__getitem__, self._kinds), self._firsts, self._seconds,
                      map(_GROUP.__getitem__, self._flags), map(_DIVISIBLE.__getitem__, self._flags))
        return map(tuple.__new__, itertools.repeat(Constraint), columns)

    def __eq__(self, other: object) -> bool:
        if isinstance(other, Constraints):
            self._settle()
            other._settle()
            return (self._kinds == other._kinds and self._firsts == other._firsts
                    and self._seconds == other._seconds and self._flags == other._flags)
        if isinstance(other, Sequence) and not isinstance(other, (str, bytes)):
            return len(self) == len(other) and all(a == b for a, b in zip(self, other))
        return NotImplemented

    __hash__ = None  # type: ignore[assignment]  # it changes while it is built

    def __repr__(self) -> str:
        return f"Constraints({list(self)!r})"

_Child = int | list[Constraint]  # a task vertex, or the constraint list of a subtree


# Which constraints a parent of each kind links through one end only: a child constraint of a
# kind in EXIT_ONCE[parent] is left through its second vertex only (else through both), one in
# ENTER_ONCE[parent] is entered through its first vertex only (else through both).
_EXIT_ONCE = {SEQ: frozenset({SEQ}), FB: frozenset({FB}), PAR: frozenset()}
_ENTER_ONCE = {SEQ: frozenset({SEQ, FB}), FB: frozenset({FB}), PAR: frozenset()}


def _exits(kind: ConstraintKind, child: int | Constraint) -> tuple[int, ...]:
    if isinstance(child, int):
        return (child,)
    return (child.second,) if child.kind in _EXIT_ONCE[kind] else (child.first, child.second)


def _entries(kind: ConstraintKind, child: int | Constraint) -> tuple[int, ...]:
    if isinstance(child, int):
        return (child,)
    return (child.first,) if child.kind in _ENTER_ONCE[kind] else (child.first, child.second)


def _pairs(kind: ConstraintKind, x: _Child, y: _Child) -> list[tuple[int, int]]:
    """Endpoint pairs generated between two children of a SEQ, FB or PAR node (§6.1): every way
    out of each constraint of ``x`` joined to every way into each constraint of ``y`` (a task is
    its own way in and out)."""
    exits = [_exits(kind, l) for l in ([x] if isinstance(x, int) else x)]
    entries = [_entries(kind, r) for r in ([y] if isinstance(y, int) else y)]
    return [(e, n) for out in exits for into in entries for e in out for n in into]


def _combinations(kind: ConstraintKind, children: int, pairs_needed: bool) -> list[tuple[int, int]]:
    """Which children are linked: consecutive ones in a sequence or fallback, every pair below a
    parallel operator (none when no ancestor needs the parallel pairs)."""
    if kind != PAR:
        return [(i, i + 1) for i in range(children - 1)]
    if not pairs_needed:
        return []
    return [(i, j) for i in range(children) for j in range(i + 1, children)]


def _row_of(c: Constraint) -> tuple[int, int, int, int]:
    """The stored row of a constraint (see :meth:`Constraints.rows`)."""
    return _KIND_CODE[c.kind], c.first, c.second, c.group | c.divisible << 1


def constraint_of_row(row: tuple[int, int, int, int]) -> Constraint:
    """The constraint a stored row stands for."""
    code, first, second, flags = row
    return Constraint(_KINDS[code], first, second, _GROUP[flags], _DIVISIBLE[flags])


def _tree_constraints(tg: TaskGraph, v: int, pairs_needed: bool, skip: _Skip = None) -> list[Constraint]:
    """The constraint list of the operator subtree rooted at ``v`` (§6.1).

    Parallel pairs only matter when a sequential or fallback ancestor fans out over their
    endpoints, or when a context dependency turns one into SEQ (§6.2).  Otherwise they would be
    dropped anyway, and there are quadratically many of them (every pair of forAll instances),
    so ``pairs_needed=False`` skips generating them: the result is the same."""
    vx = tg.vertices[v]
    kind = {";": SEQ, "FALLBACK": FB}.get(vx.content, PAR)
    children: list[_Child] = []
    for u in tg.out(v, EdgeKind.AND, EdgeKind.OR):
        if skip is not None and skip[u]:
            continue
        ux = tg.vertices[u]
        if isinstance(ux, TaskVertex):
            children.append(u)
        elif isinstance(ux, OperatorVertex):
            children.append(_tree_constraints(tg, u, pairs_needed or kind != PAR, skip))
    own = [p for i, j in _combinations(kind, len(children), pairs_needed) for p in _pairs(kind, children[i], children[j])]
    return _first_per_pair(kind, own, [c for c in children if isinstance(c, list)])


def _first_per_pair(kind: ConstraintKind, own: list[tuple[int, int]],
                    inherited: list[list[Constraint]]) -> list[Constraint]:
    """The node's own links, each pair once, then its subtrees' constraints.  An own link joins
    two children, a subtree's constraint two vertices of one child, and two children share no
    vertex: no pair is found twice across them (the original keeps the first of each pair; here
    that leaves nothing to drop), so a forAll's parallel node just joins its copies' lists."""
    seen: set[tuple[int, int]] = set()
    out: list[Constraint] = []
    for p in own:
        if p not in seen:
            seen.add(p)
            out.append(Constraint(kind, *p))
    for constraints in inherited:
        out += constraints
    return out


class _Decompositions(dict[int, list[int]]):
    """The decomposition vertices of each task, listed once: every constraint of a task pair is
    expanded over them, a million times on large missions."""

    def __init__(self, tg: TaskGraph) -> None:
        super().__init__()
        self.tg = tg

    def __missing__(self, task: int) -> list[int]:
        found = self[task] = [d.index for d in self.tg.decompositions_of(task)]
        return found


def _to_decompositions(tg: TaskGraph, task_constraints: list[Constraint], decs: _Decompositions) -> Constraints:
    """§6.2: SEQ/FB over all decomposition pairs; PAR only where a CD edge orders the pair."""
    out = Constraints()
    for c in task_constraints:
        if c.kind in (SEQ, FB):
            out.add_all_pairs(c.kind, decs[c.first], decs[c.second])
        else:
            for da in decs[c.first]:
                if c.second in tg.out(da, EdgeKind.CD):
                    out.add_all_pairs(SEQ, (da,), decs[c.second])
    return out


def _execution_constraints(tg: TaskGraph, decs: _Decompositions, out: Constraints, skip: _Skip = None) -> None:
    """§6.3: one EC per decomposition pair of every EC-linked task pair, added to ``out``.  The
    robot numbers of each linked pair are checked here, once per task pair (§6.5): every
    decomposition pair of it would fail alike, and the first failing pair is the first failing
    constraint.

    A pair is in the partner lists of both its tasks and is taken from the first of them in
    vertex order: the tasks already visited are all it takes to skip it at the second (a set of
    the pairs done took 75 MB at 5000 vital-signs rooms)."""
    visited: set[int] = set()
    for task in tg.tasks():
        s, number = task.index, task.instance.robot_number
        if skip is not None and skip[s]:
            continue
        for t, group, divisible in tg.ec_partners(s):
            if t in visited:
                continue
            # most linked tasks share one robot-number record (see expansion): those agree
            if decs[s] and decs[t] and tg.task(t).instance.robot_number is not number:
                _check_robot_numbers(tg, decs[s][0], decs[t][0])
            out.add_all_pairs(EC, decs[s], decs[t], group, divisible)
        visited.add(s)


def _drop_implied(constraints: Constraints, out: Constraints) -> None:
    """§6.4: drop SEQ implied through SEQ/FB and FB implied through FB (one pass); the others go
    to ``out``.  The neighbours of each vertex are lists (most vertices have one or two): a set
    each took 70 MB at 5000 vital-signs rooms."""
    seq_succ: dict[int, list[int]] = {}
    fb_succ: dict[int, list[int]] = {}
    seq_pred: dict[int, list[int]] = {}
    fb_pred: dict[int, list[int]] = {}
    seq, fb = _KIND_CODE[SEQ], _KIND_CODE[FB]
    for kind, first, second, _ in constraints.rows():
        if kind == seq:
            seq_succ.setdefault(first, []).append(second)
            seq_pred.setdefault(second, []).append(first)
        elif kind == fb:
            fb_succ.setdefault(first, []).append(second)
            fb_pred.setdefault(second, []).append(first)
    for row in constraints.rows():
        kind, first, second, _ = row
        if kind == seq:
            mids = seq_succ.get(first)
            if mids and (_meet(mids, seq_pred.get(second)) or _meet(mids, fb_pred.get(second))):
                continue
        elif kind == fb:
            if _meet(fb_succ.get(first), fb_pred.get(second)):
                continue
        out.append_row(row)


def _meet(a: list[int] | None, b: list[int] | None) -> bool:
    """Whether two neighbour lists share a vertex (by scanning when both are short)."""
    if not a or not b:
        return False
    if len(a) * len(b) <= 64:
        return any(x in b for x in a)
    return not set(a).isdisjoint(b)


def _check_robot_numbers(tg: TaskGraph, s: int, t: int) -> None:
    """§6.5: execution-constrained decompositions ``s`` and ``t`` need compatible robot numbers."""
    a, b = tg.decomposition(s).instance, tg.decomposition(t).instance
    ra, rb = a.robot_number, b.robot_number
    if ra.fixed and rb.fixed:
        ok = ra.min == rb.min
    else:
        ok = ra.min <= rb.max and rb.min <= ra.max
    if not ok:
        raise MissionError(
            f"Wrong robot number for execution constrained tasks [{tg.vertices[s].content}] and "
            f"[{tg.vertices[t].content}]: they share robots (a Group=False or Divisible=False goal "
            f"above them), so their RobotNumber values must overlap; set RobotNumber on {a.gm_task} or "
            f"{b.gm_task} to agree",
            f"goal model: tasks {a.gm_task} and {b.gm_task}",
        )


def generate_constraints(tg: TaskGraph) -> Constraints:
    """The final constraint list over decomposition vertices, in the original's order: those of
    the operators (without the implied ones), then the execution constraints.  The forAll
    copies the Task Graph stamped get the constraints of their source copies, moved
    (:func:`_stamped`), where each copy's constraints stay inside it."""
    if tg.stamped_copies:
        stamped = _stamped(tg)
        if stamped is not None:
            return stamped
    decs = _Decompositions(tg)
    constraints = _operator_constraints(tg, decs)
    _execution_constraints(tg, decs, constraints)
    return constraints


_Skip = bytearray | None  # by vertex: 1 for the stamped copies left to :func:`_stamped`


def _operator_constraints(tg: TaskGraph, decs: _Decompositions, skip: _Skip = None) -> Constraints:
    """SEQ and FB (and PAR made SEQ) constraints between decompositions, without the implied ones."""
    out = Constraints()
    if not tg.unique_branch:
        root = tg.vertices[0]
        if not isinstance(root, OperatorVertex):
            raise MissionError("Could not generate constraints: the Task Graph root is not an operator")
        has_cd = tg.has_edges_of_kind(EdgeKind.CD)
        out = _to_decompositions(tg, _tree_constraints(tg, 0, has_cd, skip), decs)
    constraints = Constraints()
    _drop_implied(out, constraints)
    return constraints


def _stamped(tg: TaskGraph) -> Constraints | None:
    """Both parts of the constraints generated without the copies stamped from another, each
    with those copies' constraints made from their sources' in their places; None when a
    constraint joins a copy to a vertex outside it, or a forAll's copies' constraints are not
    one run, copy after copy (then a copy's constraints need not be its source's, moved)."""
    skip = bytearray(len(tg.vertices))
    owner = array("i", [-1]) * len(tg.vertices)  # vertex -> its copy, numbered across the forAlls
    region: list[int] = []  # copy -> its forAll
    for r, copies in enumerate(tg.stamped_copies):
        for copy in copies:
            owner[copy.start:copy.start + copy.size] = array("i", [len(region)]) * copy.size
            region.append(r)
            if copy.source != copy.start:
                skip[copy.start:copy.start + copy.size] = b"\x01" * copy.size
    decs = _Decompositions(tg)
    operators = _operator_constraints(tg, decs, skip)
    execution = Constraints()
    _execution_constraints(tg, decs, execution, skip)
    out = Constraints()
    for part in (operators, execution):
        runs = _runs(part, owner, region)
        if runs is None:
            return None
        _stamp_runs(tg, part, runs, owner, region, out)
    return out


def _runs(part: Constraints, owner: "array[int]", region: list[int]) -> list[tuple[int, int, int]] | None:
    """``part`` in runs of one copy each (lo, hi, copy; copy -1 outside the copies); None when a
    constraint joins two copies or a copy and the outside, or a forAll's runs are not together
    and in copy order."""
    runs: list[tuple[int, int, int]] = []
    for i, (_, first, second, _) in enumerate(part.rows()):
        k = owner[first]
        if owner[second] != k:
            return None
        if runs and runs[-1][2] == k:
            runs[-1] = (runs[-1][0], i + 1, k)
        else:
            runs.append((i, i + 1, k))
    closed: set[int] = set()  # forAlls whose run of copies is over
    previous = (-1, -1)  # (forAll, copy) of the run before
    for _, _, k in runs:
        r = region[k] if k >= 0 else -1
        if r >= 0 and (r in closed or (previous[0] == r and previous[1] >= k)):
            return None  # a forAll's copies in more than one run, or out of order
        if previous[0] >= 0 and previous[0] != r:
            closed.add(previous[0])
        previous = (r, k)
    return runs


def _stamp_runs(tg: TaskGraph, part: Constraints, runs: list[tuple[int, int, int]], owner: "array[int]",
                region: list[int], out: Constraints) -> None:
    """Append ``part`` to ``out``, each forAll's built copies' runs replaced by the runs of all its
    copies, in order, each made from its source's."""
    spans = {k: (lo, hi) for lo, hi, k in runs if k >= 0}
    done: set[int] = set()
    for lo, hi, k in runs:
        if k < 0:
            out.extend_shifted(part, lo, hi, 0)
            continue
        if region[k] in done:
            continue
        done.add(region[k])
        for copy in tg.stamped_copies[region[k]]:
            span = spans.get(owner[copy.source])
            if span is not None:
                out.extend_shifted(part, span[0], span[1], copy.start - copy.source)
