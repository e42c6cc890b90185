"""Two decomposition outputs compared as the reference comparison compares them: up to the
renaming of task keys and the order of every list.

The key of a task (``t4``, ``task4``) is a position in one file; its id (``AT1_2|3``, the task
instance and the number of its decomposition) is what both sides share.  So each file is first
read into an :class:`OutputView` in ids, and two views agree on four aspects:

* **task ids**: the same set of ids;
* **task fields**: for each id on both sides, the same name and the same locations (as a set);
* **constraints**: the same set of constraints, SEQ as ordered pairs of ids, EC as unordered
  pairs with their group and divisible flags, a flag left out reading as true.  The original
  writes a fallback constraint as an EC without flags, so a fallback constraint compares as an
  EC with both flags true, in either order;
* **mission decompositions**: the same set of valid mission decompositions, each a set of ids.

These are the rules of the reference corpus's comparison tool (``compare_outputs.py``, its
``structure`` level); the tests check that both give the same verdicts on the corpus.  The rules
live here so that the package needs nothing outside itself.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Iterable, Mapping, TypeAlias

from ..io.decomposition_output import DecompositionOutput, OutputConstraint

ASPECTS = ("task ids", "task fields", "constraints", "mission decompositions")

# ("SEQ", first, second) or ("EC", (a, b) sorted, group, divisible)
ConstraintView: TypeAlias = tuple[object, ...]
Decomposition: TypeAlias = frozenset[str]


def natural_key(text: str) -> tuple[tuple[int, str], ...]:
    """Sort ids as people read them: ``AT2_1|1`` before ``AT10_1|1``."""
    return tuple((int(part), "") if part.isdigit() else (-1, part) for part in re.split(r"(\d+)", text) if part)


def _constraint(c: OutputConstraint, id_of: Mapping[str, str]) -> ConstraintView:
    first, second = id_of.get(c.first, c.first), id_of.get(c.second, c.second)
    if c.kind in ("EC", "FB"):  # FB: written as an EC without flags (see the module docstring)
        return ("EC", tuple(sorted((first, second))), c.group is not False, c.divisible is not False)
    return (c.kind, first, second)


@dataclass(frozen=True)
class OutputView:
    """An output file in task ids: what the comparison looks at, and nothing else."""

    tasks: Mapping[str, tuple[str, tuple[str, ...]]]  # id -> (name, sorted locations)
    constraints: frozenset[ConstraintView]
    decompositions: frozenset[Decomposition]

    @classmethod
    def of(cls, output: DecompositionOutput) -> OutputView:
        id_of = {key: task.id for key, task in output.tasks.items()}
        tasks = {task.id: (task.name, tuple(sorted(task.locations))) for task in output.tasks.values()}
        return cls(tasks=tasks,
                   constraints=frozenset(_constraint(c, id_of) for c in output.constraints),
                   decompositions=frozenset(frozenset(id_of.get(k, k) for k in md)
                                            for md in output.mission_decompositions))


def ordered(decompositions: Iterable[Decomposition]) -> list[tuple[str, ...]]:
    """Mission decompositions as sorted tuples of ids, in a stable order."""
    return sorted((tuple(sorted(d, key=natural_key)) for d in decompositions),
                  key=lambda ids: [natural_key(i) for i in ids])


def constraint_text(c: ConstraintView) -> str:
    """``SEQ AT1_1|1 -> AT2_1|1`` or ``EC AT1_1|1 AT2_1|1 group=True divisible=False``."""
    if c[0] == "EC":
        pair = c[1]
        assert isinstance(pair, tuple)
        return f"EC {pair[0]} {pair[1]} group={c[2]} divisible={c[3]}"
    return f"{c[0]} {c[1]} -> {c[2]}"


@dataclass(frozen=True)
class OutputDiff:
    """Where ``actual`` differs from ``expected``, aspect by aspect, each list in a stable order
    (``missing``: only in the expected output, ``unexpected``: only in the actual one)."""

    missing_ids: tuple[str, ...]
    unexpected_ids: tuple[str, ...]
    changed_fields: tuple[str, ...]  # "AT1_1|1 name: expected 'A', got 'B'"
    missing_constraints: tuple[str, ...]
    unexpected_constraints: tuple[str, ...]
    missing_decompositions: tuple[tuple[str, ...], ...]
    unexpected_decompositions: tuple[tuple[str, ...], ...]

    def agrees(self, aspect: str) -> bool:
        match aspect:
            case "task ids":
                return not self.missing_ids and not self.unexpected_ids
            case "task fields":
                return not self.changed_fields
            case "constraints":
                return not self.missing_constraints and not self.unexpected_constraints
            case "mission decompositions":
                return not self.missing_decompositions and not self.unexpected_decompositions
        raise ValueError(f"unknown aspect {aspect!r}")

    @property
    def agree(self) -> bool:
        return all(self.agrees(a) for a in ASPECTS)


def _changed_fields(expected: OutputView, actual: OutputView) -> tuple[str, ...]:
    changed = []
    for tid in sorted(expected.tasks.keys() & actual.tasks.keys(), key=natural_key):
        for field, want, got in zip(("name", "locations"), expected.tasks[tid], actual.tasks[tid]):
            if want != got:
                changed.append(f"{tid} {field}: expected {want!r}, got {got!r}")
    return tuple(changed)


def diff_outputs(expected: OutputView, actual: OutputView) -> OutputDiff:
    """Compare two outputs by the rules of the module docstring."""
    def ids(items: Iterable[str]) -> tuple[str, ...]:
        return tuple(sorted(items, key=natural_key))

    def constraints(items: Iterable[ConstraintView]) -> tuple[str, ...]:
        return tuple(sorted((constraint_text(c) for c in items), key=natural_key))

    return OutputDiff(
        missing_ids=ids(expected.tasks.keys() - actual.tasks.keys()),
        unexpected_ids=ids(actual.tasks.keys() - expected.tasks.keys()),
        changed_fields=_changed_fields(expected, actual),
        missing_constraints=constraints(expected.constraints - actual.constraints),
        unexpected_constraints=constraints(actual.constraints - expected.constraints),
        missing_decompositions=tuple(ordered(expected.decompositions - actual.decompositions)),
        unexpected_decompositions=tuple(ordered(actual.decompositions - expected.decompositions)),
    )


def nearest(decomposition: tuple[str, ...], candidates: Iterable[tuple[str, ...]],
            budget: int = 10_000) -> tuple[tuple[str, ...], tuple[str, ...]] | None:
    """How the closest of ``candidates`` (the first with the fewest differing ids, among the
    first ``budget``) differs from ``decomposition``: (ids it lacks, ids it has instead).  Shows
    a difference between two sets of decompositions by the tasks where they part."""
    mine = set(decomposition)
    best: tuple[int, set[str]] | None = None
    for i, other in enumerate(candidates):
        if i >= budget:
            break
        theirs = set(other)
        size = len(mine ^ theirs)
        if best is None or size < best[0]:
            best = (size, theirs)
    if best is None:
        return None
    theirs = best[1]
    return (tuple(sorted(mine - theirs, key=natural_key)), tuple(sorted(theirs - mine, key=natural_key)))
