"""Located, user-facing errors.

Every stage reports bad input as :class:`Problem` objects carrying *where* (``file:line:col``,
``file: goal G3`` or ``file: var_mapping[0].map[1]``) and *what*.  A :class:`MissionError` holds
one or more problems so that ``check`` can report all of them at once; the CLI turns it into a
message and an exit status, never a traceback.
"""
from __future__ import annotations

import difflib
import re
from dataclasses import dataclass
from typing import Iterable


@dataclass(frozen=True)
class Problem:
    """One located problem in the mission inputs.

    ``message`` keeps the original tool's wording where there is one (users and scripts grep
    for it); ``hint`` says how to fix the input.  The printed form shows both."""

    where: str
    message: str
    hint: str = ""

    def __str__(self) -> str:
        text = f"{self.where}: {self.message}" if self.where else self.message
        if not self.hint:
            return text
        return f"{text} {self.hint}" if text.endswith((".", "!", "?")) else f"{text}. {self.hint}"


    def record(self) -> dict[str, str | int | None]:
        """The problem for scripts: ``file``, ``line`` and ``column`` (None where unknown),
        ``message`` (after the rest of the location, such as ``goal G3``) and ``hint``."""
        found = _FILE_LINE_COLUMN.fullmatch(self.where)
        if found:
            file, line, column = found["file"], int(found["line"]), found["column"]
            return {"file": file, "line": line, "column": int(column) if column else None, "message": self.message,
                    "hint": self.hint}
        file, sep, inside = self.where.partition(": ")
        message = f"{inside}: {self.message}" if sep else self.message
        return {"file": file or None, "line": None, "column": None, "message": message, "hint": self.hint}


_FILE_LINE_COLUMN = re.compile(r"(?P<file>.+?):(?P<line>\d+)(?::(?P<column>\d+))?")


class MissionError(Exception):
    """Invalid mission input (exit status 2 by default)."""

    exit_code = 2

    def __init__(self, problems: Problem | Iterable[Problem] | str, where: str = "") -> None:
        if isinstance(problems, str):
            problems = [Problem(where, problems)]
        elif isinstance(problems, Problem):
            problems = [problems]
        self.problems: list[Problem] = list(problems)
        super().__init__("\n".join(str(p) for p in self.problems))


class NoDecompositionError(MissionError):
    """The mission is well-formed but has no valid mission decomposition (exit status 3)."""

    exit_code = 3


def counted(n: int, noun: str) -> str:
    """``1 argument``, ``2 arguments``: a count in a message."""
    return f"{n} {noun}" if n == 1 else f"{n} {noun}s"


def closest(name: str, candidates: Iterable[str], cutoff: float = 0.75) -> str | None:
    """The candidate closest to a misspelt ``name``, if one is close enough (for "did you mean").

    0.75 suits identifiers; short keys and type names, where one wrong letter is a larger
    share, use 0.6."""
    close = difflib.get_close_matches(name, list(dict.fromkeys(candidates)), n=1, cutoff=cutoff)
    return close[0] if close else None


def located(file: str, line: int | None = None, column: int | None = None) -> str:
    """Format a ``file:line:col`` location (omitting unknown parts)."""
    parts = [file]
    if line is not None:
        parts.append(str(line))
        if column is not None:
            parts.append(str(column))
    return ":".join(parts)
