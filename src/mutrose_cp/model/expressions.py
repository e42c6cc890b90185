"""The expression languages of the goal model (spec ``goal-model.md`` §5, §7–§9), as values.

* runtime annotations (:data:`Annotation`): ``[G2;(G3#G4);FALLBACK(G5,G6)]``, the order in which
  a goal's children run;
* conditions (:data:`Condition`): achieve and context conditions, select bodies;
* ``select`` queries (:class:`Select`) and ``forAll`` achieve conditions (:class:`ForAll`).

Produced by the parsers of :mod:`mutrose_cp.io.expressions` while the goal model is read; read
by the expansion (annotations, queries, forAll), the world-state tests of
:mod:`mutrose_cp.pipeline.conditions` and the query evaluator :mod:`mutrose_cp.pipeline.query`.
"""
from __future__ import annotations

from dataclasses import dataclass

# ---------------------------------------------------------------------------------------------
# Runtime annotations


@dataclass(frozen=True)
class AnnotationLeaf:
    """A goal (``G..``) or task (anything else) reference inside an annotation."""

    name: str

    @property
    def is_goal(self) -> bool:
        """Whether the leaf names a goal (the original tells goals by their ``G`` prefix)."""
        return self.name.startswith("G")


@dataclass(frozen=True)
class AnnotationOp:
    """``;`` (sequence), ``#`` (parallel) or ``FALLBACK``; same-kind operands are flattened."""

    op: str
    children: tuple["Annotation", ...]


Annotation = AnnotationLeaf | AnnotationOp

# ---------------------------------------------------------------------------------------------
# Conditions


@dataclass(frozen=True)
class Atom:
    """One condition atom, e.g. ``!r.is_clean``, ``r.name = "RoomA"``, ``p.name in r.patients``.

    ``text`` is the atom as written (trimmed).  The structured fields are a best-effort split
    used by evaluators: ``variable``/``attribute`` from ``v.a`` on the left, ``negated`` for a
    leading ``!`` or ``not``, ``op`` one of ``= <> > < >= <= in`` (None for a bare ``v.a``),
    ``value`` the right-hand side text (quotes stripped).
    """

    text: str
    variable: str = ""
    attribute: str = ""
    negated: bool = False
    op: str | None = None
    value: str = ""


@dataclass(frozen=True)
class BoolOp:
    """``&&`` or ``||`` over two or more operands."""

    op: str
    children: tuple["Condition", ...]


Condition = Atom | BoolOp


@dataclass(frozen=True)
class Select:
    """``queried->select(var:Type | condition)``; ``condition`` is None when empty."""

    queried: str  # "world_db", "v" or "v.a1.a2"
    variable: str
    type: str
    condition: Condition | None
    text: str


@dataclass(frozen=True)
class ForAll:
    """``iterated->forAll(iteration | condition)``; ``condition`` is None when empty."""

    iterated: str
    iteration: str
    condition: Condition | None
    condition_text: str
    text: str
