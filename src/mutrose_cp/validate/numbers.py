"""Numbers in the validator: comparisons, and what one start value of a function the world does
not give must meet (docs/numbers.md).

A function the world does not give has an unknown start value ``u``; every comparison a mission
decomposition requires on it says ``u op bound``.  The decomposition is valid only when one value
meets all of them together, for some choice among the ways each task's actions can be explained
(methods that run the same actions may require different values).
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Callable

AtomKey = tuple[str, tuple[str, ...]]
EPSILON = 1e-9

# (op, bound on the start value, negated, who required it), per function
StartTests = dict[AtomKey, list[tuple[str, float, bool, str]]]


# each operator as a test of ``value - bound``, with a small tolerance on equality (integer and
# decimal values are compared alike)
_TESTS: dict[str, Callable[[float], bool]] = {
    "=": lambda d: abs(d) < EPSILON, "<>": lambda d: abs(d) >= EPSILON, ">": lambda d: d > 0, "<": lambda d: d < 0,
    ">=": lambda d: d >= -EPSILON, "<=": lambda d: d <= EPSILON,
}


def compare(value: float, op: str, bound: float) -> bool:
    """Whether ``value op bound``."""
    return _TESTS.get(op, _TESTS["<="])(value - bound)


def some_value_meets(required: list[tuple[str, float, bool, str]]) -> bool:
    """Whether some number meets every (op, bound, negated) test.  The numbers that meet them
    are a union of intervals and points between the bounds, so trying each bound, a point
    between each two and one beyond each end decides it."""
    if not required:
        return True
    bounds = sorted({bound for _, bound, _, _ in required})
    candidates = bounds + [(a + b) / 2 for a, b in zip(bounds, bounds[1:])] + [bounds[0] - 1, bounds[-1] + 1]
    return any(all(compare(x, op, bound) != negated for op, bound, negated, _ in required) for x in candidates)


def first_conflict(required: list[tuple[str, float, bool, str]]) -> str:
    """Who required what, up to the first test no value meets together with the earlier ones."""
    for k in range(1, len(required) + 1):
        if not some_value_meets(required[:k]):
            return "; ".join(who for *_, who in required[:k])
    return ""


@dataclass
class StartValues:
    """What one mission decomposition requires of the start values the world does not give:
    the achieve conditions' tests (``fixed``), and for each task the tests of each way its
    actions can be explained."""

    fixed: StartTests = field(default_factory=dict)
    tasks: list[tuple[str, list[StartTests]]] = field(default_factory=list)  # (task id, alternatives)

    def conflict(self) -> tuple[str, str] | None:
        """None when some choice of explanations leaves every function a value; else the first
        task (in execution order) that no choice gets past ("" for the achieve conditions
        alone), and the tests that exclude each other."""
        if not all(some_value_meets(v) for v in self.fixed.values()):
            return "", self._excluding(self.fixed)
        reached = [0]
        if self._search(0, {key: list(v) for key, v in self.fixed.items()}, reached):
            return None
        k = min(reached[0], len(self.tasks) - 1)
        tests: StartTests = {key: list(v) for key, v in self.fixed.items()}
        for _, alternatives in self.tasks[:k + 1]:
            for key, more in alternatives[0].items():
                tests[key] = tests.get(key, []) + more
        return self.tasks[k][0], self._excluding(tests)

    def _search(self, k: int, tests: StartTests, reached: list[int]) -> bool:
        """Whether explanations from the ``k``-th task on can be chosen to fit ``tests``."""
        reached[0] = max(reached[0], k)
        if k == len(self.tasks):
            return True
        for alternative in self.tasks[k][1]:
            merged = {key: tests.get(key, []) + more for key, more in alternative.items()}
            if all(some_value_meets(v) for v in merged.values()) and self._search(k + 1, {**tests, **merged}, reached):
                return True
        return False

    @staticmethod
    def _excluding(tests: StartTests) -> str:
        for key, found in tests.items():
            if not some_value_meets(found):
                return f"{first_conflict(found)}: no value of {key[0]}({', '.join(key[1])}) meets them all"
        return "the other tasks' comparisons on values the world does not give exclude each of its explanations"
