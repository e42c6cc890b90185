"""World-state tests: a goal-model condition (context or achieve condition) translated by the
semantic mappings into ground literals and numeric comparisons (spec ``goal-model.md`` §9).

Made by ``pipeline.conditions``; read by the Task Graph and the solvers."""
from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class FactTest:
    """A ground boolean literal that must hold."""

    predicate: str
    args: tuple[str, ...]
    positive: bool


@dataclass(frozen=True)
class ValueTest:
    """A ground numeric comparison ``function(args) op value``."""

    function: str
    args: tuple[str, ...]
    op: str  # = <> > < >= <=
    value: float


@dataclass(frozen=True)
class AllOf:
    parts: tuple["Test", ...]


@dataclass(frozen=True)
class AnyOf:
    parts: tuple["Test", ...]


Test = FactTest | ValueTest | AllOf | AnyOf
