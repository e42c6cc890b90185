"""The solver-neutral boolean model of the decomposition space: variables and typed records.

The encoder (:mod:`.encoding`) writes the rules of valid decompositions as records; the CP-SAT
layer (:mod:`.cpsat`) splits them into independent components and posts each one.  Keeping this
small form between the two lets components be found, compared up to renaming and solved one by
one.  Literals are variable ids (negative for the negation) or one of two constants, which the
helpers fold away while the model is built.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from enum import Enum, StrEnum
from typing import Any, Callable, ClassVar, Final, Iterable, Sequence


class Const(Enum):
    """A literal whose value is known while the model is built."""

    TRUE = "TRUE"
    FALSE = "FALSE"


TRUE: Final = Const.TRUE
FALSE: Final = Const.FALSE
Lit = int | Const  # variable id (negative = negation) or a constant


def neg(lit: Lit) -> Lit:
    if isinstance(lit, int):
        return -lit
    return FALSE if lit is TRUE else TRUE


def _ids(lits: Iterable[Lit]) -> list[int]:
    return [abs(l) for l in lits if isinstance(l, int)]


class RecordKind(StrEnum):
    CLAUSE = "clause"
    EXACTLY = "sum_eq"
    AND = "and_eq"
    OR = "or_eq"
    VALUE_AFTER = "int_sel"
    COMPARE = "cmp_eq"
    DIFFERENCE = "int_sub"


class NumericEffectKind(StrEnum):
    ASSIGN = "assign"
    INCREASE = "increase"  # decreases are increases by a negative amount


@dataclass(frozen=True, slots=True)
class Clause:
    """OR of ``lits``."""

    kind: ClassVar[RecordKind] = RecordKind.CLAUSE
    lits: tuple[Lit, ...]
    label: str = ""  # a key of Encoding.labels: names the rule when explaining infeasibility

    def variables(self) -> list[int]:
        return _ids(self.lits)


@dataclass(frozen=True, slots=True)
class Exactly:
    """The number of true ``lits`` equals ``target`` (0 or 1): exactly one of the choices is
    made when ``target`` holds, none otherwise."""

    kind: ClassVar[RecordKind] = RecordKind.EXACTLY
    lits: tuple[Lit, ...]
    target: Lit
    label: str = ""

    def variables(self) -> list[int]:
        return _ids(self.lits + (self.target,))


@dataclass(frozen=True, slots=True)
class _Definition:
    """An auxiliary variable ``target`` defined by an equivalence over ``lits``."""

    lits: tuple[Lit, ...]
    target: int
    label: str = ""

    def variables(self) -> list[int]:
        return _ids(self.lits) + [self.target]


@dataclass(frozen=True, slots=True)
class AndOf(_Definition):
    """``target`` <=> AND of ``lits``."""

    kind: ClassVar[RecordKind] = RecordKind.AND


@dataclass(frozen=True, slots=True)
class OrOf(_Definition):
    """``target`` <=> OR of ``lits``."""

    kind: ClassVar[RecordKind] = RecordKind.OR


@dataclass(frozen=True, slots=True)
class ValueAfter:
    """Integer ``target`` is a numeric atom's value after one writer: if ``writer`` is chosen,
    the value it assigns, or the value before plus ``amount``; otherwise the value before.  The
    value before is the integer variable ``previous``, or the constant ``previous_value`` for
    the first writer.  (Of a value the world does not give, the chain holds the offset that
    the increases add to it, from 0, until an assignment.)"""

    kind: ClassVar[RecordKind] = RecordKind.VALUE_AFTER
    writer: Lit
    target: int
    previous: int | None
    previous_value: int
    amount: int
    effect: NumericEffectKind
    label: str = ""

    def variables(self) -> list[int]:
        return _ids((self.writer,)) + [self.target] + ([] if self.previous is None else [self.previous])


@dataclass(frozen=True, slots=True)
class Compare:
    """``holds`` <=> (integer ``value`` ``op`` ``bound``)."""

    kind: ClassVar[RecordKind] = RecordKind.COMPARE
    holds: Lit
    value: int
    op: str  # "=", "<>", ">", "<", ">=", "<="
    bound: int
    label: str = ""

    def variables(self) -> list[int]:
        return _ids((self.holds,)) + [self.value]


@dataclass(frozen=True, slots=True)
class Difference:
    """Integer ``target`` equals integer ``first`` minus integer ``second`` (None: 0): how far
    apart two offsets of one unknown value are (``encoding``, start values)."""

    kind: ClassVar[RecordKind] = RecordKind.DIFFERENCE
    target: int
    first: int | None
    second: int | None
    label: str = ""

    def variables(self) -> list[int]:
        return [self.target] + [v for v in (self.first, self.second) if v is not None]


Record = Clause | Exactly | AndOf | OrOf | ValueAfter | Compare | Difference


class VariableGroups:
    """Union-find over variables: the variables of one record belong together, so records
    sharing a variable (directly or through others) fall in one group."""

    def __init__(self, records: Iterable[Record] = ()) -> None:
        self._parent: dict[int, int] = {}
        for r in records:
            self.join_all(r.variables())

    def join_all(self, variables: Sequence[int]) -> None:
        """Put ``variables`` in one group."""
        for v in variables[1:]:
            self.join(variables[0], v)

    def find(self, v: int) -> int:
        parent = self._parent
        parent.setdefault(v, v)
        while parent[v] != v:
            parent[v] = parent[parent[v]]
            v = parent[v]
        return v

    def join(self, a: int, b: int) -> None:
        ra, rb = self.find(a), self.find(b)
        if ra != rb:
            self._parent[max(ra, rb)] = min(ra, rb)


@dataclass
class IntRange:
    lo: int
    hi: int


Name = str | tuple[Any, ...]  # a variable's name, or the parts its model's namer makes it from


@dataclass
class BoolModel:
    """Variables and records; variable ids start at 1 (id 0 is unused, so negation works).

    A name may be kept as the parts it is made from (a tuple), which ``namer`` turns into text
    when it is read (:meth:`name`): a large mission names millions of variables, and only those
    of the components handed to the solver are ever read."""

    names: list[Name] = field(default_factory=lambda: [""])
    ints: dict[int, IntRange] = field(default_factory=dict)
    records: list[Record] = field(default_factory=list)
    namer: Callable[[tuple[Any, ...]], str] | None = field(default=None, repr=False, compare=False)

    def name(self, v: int) -> str:
        """The name of variable ``v``."""
        name = self.names[v]
        if isinstance(name, str):
            return name
        assert self.namer is not None, "a name kept as parts needs the model's namer"
        return self.namer(name)

    def new_bool(self, name: Name) -> int:
        self.names.append(name)
        return len(self.names) - 1

    def new_int(self, name: Name, lo: int, hi: int) -> int:
        v = self.new_bool(name)
        self.ints[v] = IntRange(lo, hi)
        return v

    # --- helpers that fold constants ------------------------------------------------------------
    def clause(self, lits: Iterable[Lit], label: str = "") -> None:
        kept: dict[Lit, None] = {}  # insertion-ordered set
        for l in lits:
            if l is TRUE:
                return
            if l is not FALSE:
                kept[l] = None
        self.records.append(Clause(tuple(kept), label))

    def and_of(self, lits: Sequence[Lit], name: Name) -> Lit:
        """A literal equivalent to the AND of ``lits``."""
        return self._define(AndOf, lits, name, absorbing=FALSE)

    def or_of(self, lits: Sequence[Lit], name: Name) -> Lit:
        """A literal equivalent to the OR of ``lits``."""
        return self._define(OrOf, lits, name, absorbing=TRUE)

    def _define(self, record: type[AndOf] | type[OrOf], lits: Sequence[Lit], name: Name, *, absorbing: Const) -> Lit:
        """A new variable defined by ``record`` over ``lits``, with constants folded: the
        absorbing constant decides alone, the neutral one drops out, one literal stands for
        itself, and repeated literals count once."""
        neutral = neg(absorbing)
        kept: dict[Lit, None] = {}  # insertion-ordered set
        for l in lits:
            if l is absorbing:
                return absorbing
            if l is not neutral:
                kept[l] = None
        if not kept:
            return neutral
        if len(kept) == 1:
            return next(iter(kept))
        v = self.new_bool(name)
        self.records.append(record(tuple(kept), v))
        return v
