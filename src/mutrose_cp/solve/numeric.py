"""Numbers in a mission decomposition: known values, and values the world does not give.

A function's value at a point of a mission decomposition is either

* **known**: the world gives it (or an ``assign`` set it), changed by the increases and
  decreases applied since; a comparison on it is decided; or
* **unknown + offset**: the world is silent, and the increases and decreases applied so far add
  up to ``offset``.  The value is ``u + offset`` for one unknown start value ``u`` of that
  function, the same all along the decomposition.

A comparison on an unknown value is not refuted on its own (the open world), but a mission
decomposition needs *one* start value ``u`` that meets every comparison it requires: each one
is a condition ``u op bound - offset``.  An ``=`` *pins* ``u``, and later comparisons compute
from it, in the same task or in a later one.  The conditions are intervals of ``u`` (``<>`` a
line without one point), so by Helly's theorem in one dimension they have a common value
exactly when every two of them have one: that is the rule both decomposers apply, the CP-SAT
encoder as one clause per pair (:func:`offset_gap`), the exploratory algorithm as a list of the
conditions met so far (:class:`StartConditions`).  (Two ``<>`` and an interval of one point can
exclude each other only three at a time; a ``<>`` is therefore only compared with ``=``.)

Values are compared in thousandths, as integers (:func:`mutrose_cp.model.world.scaled`), as the
CP-SAT model holds them, so both decomposers decide every comparison alike (docs/numbers.md).
"""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True, slots=True)
class StartCondition:
    """``u op bound`` on the start value ``u`` of one function (``bound`` in thousandths), and
    what required it (for messages)."""

    op: str
    bound: int
    source: str = field(default="", compare=False)


def _interval(op: str, bound: int) -> tuple[int | None, int | None]:
    """The closed integer interval of ``u op bound`` (None: unbounded at that end)."""
    if op == "=":
        return bound, bound
    if op == ">":
        return bound + 1, None
    if op == ">=":
        return bound, None
    if op == "<":
        return None, bound - 1
    if op == "<=":
        return None, bound
    raise ValueError(op)


@dataclass(frozen=True, slots=True)
class Gap:
    """The differences ``d`` for which two conditions meet: ``low <= d <= high`` (None:
    unbounded) and ``d != excluded`` (None: no such point)."""

    low: int | None = None
    high: int | None = None
    excluded: int | None = None

    @property
    def always(self) -> bool:
        return self.low is None and self.high is None and self.excluded is None

    def admits(self, difference: int) -> bool:
        return ((self.low is None or difference >= self.low) and (self.high is None or difference <= self.high)
                and difference != self.excluded)


def offset_gap(first: tuple[str, int], second: tuple[str, int]) -> Gap:
    """For comparisons ``u + a op1 b1`` and ``u + c op2 b2`` (``first = (op1, b1)``, ``second =
    (op2, b2)``, bounds in thousandths), the values of ``c - a`` for which some ``u`` meets both."""
    (op1, b1), (op2, b2) = first, second
    if "<>" in (op1, op2):
        if {op1, op2} == {"<>", "="}:
            return Gap(excluded=b2 - b1)  # u = b1 - a and u != b2 - c
        return Gap()
    lo1, hi1 = _interval(op1, b1)
    lo2, hi2 = _interval(op2, b2)
    # u in [lo1 - a, hi1 - a] and in [lo2 - c, hi2 - c]: lo1 - a <= hi2 - c and lo2 - c <= hi1 - a
    high = None if lo1 is None or hi2 is None else hi2 - lo1
    low = None if lo2 is None or hi1 is None else lo2 - hi1
    return Gap(low, high)


def compatible(first: StartCondition, second: StartCondition) -> bool:
    """Whether some start value meets both conditions."""
    return offset_gap((first.op, first.bound), (second.op, second.bound)).admits(0)


@dataclass
class StartConditions:
    """The conditions a partial mission decomposition put on the start values of functions the
    world does not give, by function atom."""

    by_atom: dict[tuple[str, tuple[str, ...]], tuple[StartCondition, ...]] = field(default_factory=dict)

    def copy(self) -> "StartConditions":
        return StartConditions(dict(self.by_atom))

    def conflict(self, atom: tuple[str, tuple[str, ...]], condition: StartCondition) -> StartCondition | None:
        """The condition already required that ``condition`` cannot hold together with, if any."""
        for earlier in self.by_atom.get(atom, ()):
            if not compatible(earlier, condition):
                return earlier
        return None

    def add(self, atom: tuple[str, tuple[str, ...]], condition: StartCondition) -> None:
        self.by_atom[atom] = self.by_atom.get(atom, ()) + (condition,)

    def admit(self, required: list[tuple[tuple[str, tuple[str, ...]], StartCondition]]) -> "StartConditions | None":
        """These conditions and ``required`` together, or None when some two cannot hold together."""
        if not required:
            return self
        out = self.copy()
        for atom, condition in required:
            if out.conflict(atom, condition) is not None:
                return None
            out.add(atom, condition)
        return out
