"""What the world knowledge does not know for sure, as values (docs/formats/uncertainty.md).

An uncertain fact is one world attribute of one entity (``Room104``'s ``door_open``), read by
the configuration's semantic mapping as one ground atom (``door-open(Room104)``), whose value
is not the one the world file gives (or omits) but one of several: a boolean either way, with
P(true) when it is known, or a number among a few values, each with its probability when known.
Facts are independent: the probability of a scenario (one value for every fact) is the product
of its values' probabilities.

A fact that the goal model reads (a query's condition, a forAll or achieve condition, a
context) decides which task instances exist: it is *expanded*, the mission expanded once per
value (``pipeline/scenarios.py``); every other fact is *decided* by the boolean model.

Produced by :mod:`mutrose_cp.io.uncertainty` (the file as written) and
:mod:`mutrose_cp.pipeline.uncertain_facts` (resolved against the mission).
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from decimal import Decimal
from typing import Sequence

AtomKey = tuple[str, tuple[str, ...]]
Value = bool | float


@dataclass(frozen=True)
class UncertainEntry:
    """One entry of an uncertainty file, as written: the entity and attribute, and the values
    with their probabilities (None: each value possible, none more likely)."""

    entity: str
    attribute: str
    values: tuple[Value, ...] | None  # None: a boolean, either way
    probabilities: tuple[float, ...] | None
    where: str  # file:line:col of the entry
    numeric: bool = False  # given as numbers (values, distribution), not a probability of true


@dataclass(frozen=True)
class JointEntry:
    """A ``joint`` table of an uncertainty file, as written: facts that are not independent, by
    (entity, attribute), and the probability of each combination of their values (a combination
    it does not list has probability 0)."""

    facts: tuple[tuple[str, str], ...]
    outcomes: tuple[tuple[tuple[Value, ...], float], ...]
    where: str


@dataclass(frozen=True)
class UncertainFact:
    """An entry resolved against the mission: the atom it is, and the values it may take."""

    entry: UncertainEntry
    atom: AtomKey
    numeric: bool
    values: tuple[Value, ...]
    probabilities: tuple[float, ...] | None  # aligned with ``values``; None when not given
    # the goal and condition that read it, when the goal model does (then it is expanded)
    read_by_goal: str = ""
    # the other atoms the configuration maps the same attribute to (``door_locked`` read as
    # ``door-locked(Room202)`` and ``badge-needed(Room202)``): they start with the same value
    aliases: tuple[AtomKey, ...] = ()

    @property
    def atoms(self) -> tuple[AtomKey, ...]:
        """Every atom the domain reads the fact as."""
        return (self.atom, *self.aliases)

    @property
    def text(self) -> str:
        """``door-open(Room104)``."""
        return f"{self.atom[0]}({', '.join(self.atom[1])})"

    def shown(self, value: Value) -> str:
        """The fact with one of its values: ``door-open(Room104)``, ``not door-open(Room104)``,
        ``stock(Kitchen) = 2``."""
        if not self.numeric:
            return self.text if value else f"not {self.text}"
        return f"{self.text} = {value_text(value)}"

    def probability(self, value: Value) -> float | None:
        if self.probabilities is None:
            return None
        return self.probabilities[self.values.index(value)]


@dataclass(frozen=True)
class Joint:
    """Facts with a joint distribution: each outcome gives every fact of ``facts`` a value."""

    facts: tuple[UncertainFact, ...]
    outcomes: tuple[tuple[tuple[Value, ...], float], ...]

    def probability(self, values: dict[AtomKey, Value]) -> float:
        """The probability that the facts of ``values`` (some of this table's) have those values."""
        return math.fsum(p for outcome, p in self.outcomes
                         if all(values.get(f.atom, v) == v for f, v in zip(self.facts, outcome)))


#: probabilities are written, and compared for ties, to this many significant digits: sums of
#: products of decimal probabilities carry float error (0.08 + 0.87 is not 0.95), which must
#: neither break a tie nor print differently from machine to machine
PROBABILITY_DIGITS = 12


def rounded_probability(p: float) -> float:
    """``p`` to :data:`PROBABILITY_DIGITS` significant digits: what is written, and compared."""
    return float(f"{p:.{PROBABILITY_DIGITS}g}")


def value_text(value: Value) -> str:
    """A value as a world file writes it, read back exactly: ``True``/``False``; an integral
    number without a point (``1234567``); any other in plain decimals (``0.0000001``), since
    the world's reader takes a number without a point for an integer and ignores an exponent."""
    if isinstance(value, bool):
        return "True" if value else "False"
    if float(value).is_integer():
        return str(int(value))
    return format(Decimal(repr(float(value))), "f")


def scenario_factors(facts: Sequence[UncertainFact], joints: Sequence[Joint], values: Sequence[Value]
                     ) -> list[float | None]:
    """What the probability of ``facts`` having ``values`` is the product of: each joint table's
    probability of its facts' values, and each other fact's probability of its value (None for a
    fact without probabilities)."""
    given = {f.atom: v for f, v in zip(facts, values)}
    joined = {f.atom for j in joints for f in j.facts}
    return [*(j.probability(given) for j in joints),
            *(fact.probability(value) for fact, value in zip(facts, values) if fact.atom not in joined)]


def scenario_can_happen(facts: Sequence[UncertainFact], joints: Sequence[Joint], values: Sequence[Value]) -> bool:
    """Whether ``facts`` having ``values`` has a positive probability: no joint table leaves the
    combination out and no fact has probability 0 for its value.  A fact without probabilities
    allows each of its values, and takes nothing from the others' probabilities of 0."""
    return all(p is None or p > 0 for p in scenario_factors(facts, joints, values))


def scenario_probability(facts: Sequence[UncertainFact], joints: Sequence[Joint], values: Sequence[Value]) -> float:
    """The probability of ``facts`` having ``values``: the product of the joint tables' (over the
    facts they hold) and of the other facts' own probabilities (every fact must have some)."""
    factors = scenario_factors(facts, joints, values)
    assert None not in factors
    return math.prod(p for p in factors if p is not None)


@dataclass(frozen=True)
class Uncertainty:
    """The uncertain facts of a mission, in file order, and their joint tables."""

    source: str
    facts: tuple[UncertainFact, ...]
    joints: tuple[Joint, ...] = ()

    @property
    def with_probabilities(self) -> bool:
        """Whether every fact has probabilities (then every answer has one)."""
        return all(f.probabilities is not None for f in self.facts)

    @property
    def expanded(self) -> tuple[UncertainFact, ...]:
        """The facts the goal model reads: one expansion of the mission per scenario of them."""
        return tuple(f for f in self.facts if f.read_by_goal)

    @property
    def decided(self) -> tuple[UncertainFact, ...]:
        """The facts only the domain reads: free variables of the boolean model."""
        return tuple(f for f in self.facts if not f.read_by_goal)
