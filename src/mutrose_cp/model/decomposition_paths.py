"""Decomposition paths: the ways an abstract task decomposes into actions (spec
``semantics.md`` §2), and the preconditions and effects of one path ground for one task
instance.

Made by ``pipeline.htn``; read by the Task Graph, the solvers and the writers."""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

from .domain import Comparison, Literal, NumericEffect


Number = int | float


@dataclass(frozen=True)
class Step:
    """A primitive step of a path, renamed to the root task's parameter names."""

    name: str
    args: tuple[str, ...]
    preconditions: tuple[Literal | Comparison, ...]
    effects: tuple[Literal, ...]
    numeric_effects: tuple[NumericEffect, ...]
    capabilities: tuple[str, ...]
    pseudo: bool = False  # a method-precondition pseudo-action (never printed)


@dataclass(frozen=True)
class TreeNode:
    """A node of the complete HTN path (for iHTN export): task, method or action."""

    kind: str  # "task" | "method" | "action"
    name: str
    args: tuple[str, ...]  # renamed declared parameters
    children: tuple["TreeNode", ...] = ()


@dataclass(frozen=True)
class Fragment:
    """A cyclic fragment of a path (steps ``start..end``) repeated while ``function(args) > bound``;
    each repetition changes the function by ``decrease`` (negative)."""

    start: int
    end: int
    function: str
    args: tuple[str, ...]
    bound: Number
    decrease: Number


@dataclass(frozen=True)
class DecompositionPath:
    """One decomposition path of an abstract task."""

    steps: tuple[Step, ...]
    tree: TreeNode  # the root task node with its chosen method subtree
    fragments: tuple[Fragment, ...] = ()  # recursive-method fragments to expand (§7.6)
    # why the path can never run, where the original lists it all the same (a step whose
    # preconditions contradict each other or fail where the original's check lets them pass, a
    # subtask without an executable method): kept so that decomposition numbers stay the
    # original's, and never part of a valid mission decomposition (docs/deviations.md)
    never_valid: tuple[str, ...] = ()

    @property
    def needs_expansion(self) -> bool:
        return bool(self.fragments)

    @property
    def actions(self) -> tuple[Step, ...]:
        return tuple(s for s in self.steps if not s.pseudo)

    @cached_property
    def bare(self) -> bool:
        """Whether no step has a condition or an effect."""
        return not any(s.preconditions or s.effects or s.numeric_effects for s in self.steps)

    @cached_property
    def constants(self) -> frozenset[str]:
        """The constants the steps name (arguments that are no variables): grounding and
        printing keep them as themselves, whatever the instance's values."""
        return frozenset(a for s in self.steps for c in (*s.preconditions, *s.effects, *s.numeric_effects)
                         for a in c.args if not a.startswith("?"))


@dataclass(frozen=True, slots=True)
class GroundPredicates:
    """Preconditions and net effects of a decomposition of one task instance."""

    preconditions: tuple[Literal | Comparison, ...]  # path order, duplicates kept (as printed)
    effects: tuple[Literal, ...]  # net effects, in the order they are first declared
    numeric_effects: tuple[tuple[str, tuple[str, ...], str, int], ...]  # (fn, args, kind, amount)
    # numeric preconditions of later steps on a function that earlier steps only increased or
    # decreased, as conditions on its value where the decomposition starts: (> f N) after
    # (increase f 2) is (> f N-2).  Not printed (the original drops them); checked like the rest.
    shifted: tuple[Comparison, ...] = ()
    # preconditions that earlier steps of the path make false: the decomposition can never run
    unsatisfiable: tuple[str, ...] = ()

    @property
    def checked_preconditions(self) -> tuple[Literal | Comparison, ...]:
        """Every precondition the decomposition's start state must satisfy."""
        return self.preconditions + self.shifted

    @property
    def ground_effects(self) -> tuple[Literal, ...]:
        return tuple(e for e in self.effects if not any(a.startswith("?") for a in e.args))
