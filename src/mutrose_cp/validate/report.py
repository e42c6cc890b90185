"""What ``validate`` found: located violations, the number of mission decompositions checked,
and notes on what could not be checked."""
from __future__ import annotations

from dataclasses import dataclass, field


@dataclass(frozen=True)
class Violation:
    """One reason a mission decomposition (or the file) is not valid, located."""

    decomposition: int | None  # index in mission_decompositions; None for the whole file
    task: str  # task id ("AT1_1|2") or goal id, "" when neither applies
    message: str

    def __str__(self) -> str:
        where = [] if self.decomposition is None else [f"decomposition {self.decomposition}"]
        if self.task:
            where.append(self.task)
        return f"{': '.join(where)}: {self.message}" if where else self.message


@dataclass
class Report:
    checked: int = 0  # mission decompositions checked
    violations: list[Violation] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # what could not be checked, and why
    task_instances: int | None = None  # of the mission, None when they could not be rebuilt

    @property
    def valid(self) -> bool:
        return not self.violations
