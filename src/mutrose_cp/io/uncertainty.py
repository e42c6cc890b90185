"""Reading an uncertainty file (docs/formats/uncertainty.md): which world attributes are not
known for sure, with their values' probabilities when known.

    {"uncertain": [
        {"entity": "Room104", "attribute": "door_open"},
        {"entity": "Room102", "attribute": "door_open", "probability": 0.3},
        {"entity": "Kitchen", "attribute": "stock", "distribution": {"0": 0.25, "2": 0.75}},
        {"entity": "Kitchen", "attribute": "trays", "values": [0, 1, 2]}
    ]}

Every problem is reported at once, at ``file:line:col`` of the value at fault (exit 2).  What
the entries mean for the mission (the attribute's mapping, the entity's record) is checked by
:mod:`mutrose_cp.pipeline.uncertain_facts`.
"""
from __future__ import annotations

import math
import os
import re
from typing import Any

from ..errors import MissionError, Problem
from ..model.uncertainty import JointEntry, UncertainEntry, Value
from ..model.world import MAX_NUMBER, scaled
from .located_json import LocatedJson, Path, path_text, read_located_json

KEYS = ("entity", "attribute", "probability", "values", "distribution")
#: at most this many values of one numeric fact
MAX_VALUES = 64
#: probabilities of one fact must add up to 1 within this
TOLERANCE = 1e-9


def read_uncertainty(path: str | os.PathLike[str]) -> tuple[list[UncertainEntry], list[JointEntry], list[Problem]]:
    """The well-formed entries and joint tables of the uncertainty file at ``path``, in file
    order, and the problems of the others (so that the caller reports them with those it finds
    in the entries).  A file that cannot be read, or is not JSON, raises."""
    reader = _Reader(read_located_json(path, "uncertainty"))
    entries, problems = reader.entries()
    return entries, reader.joints(), problems


class _Reader:
    def __init__(self, doc: LocatedJson) -> None:
        self.doc = doc
        self.problems: list[Problem] = []

    def problem(self, path: Path, message: str) -> None:
        self.problems.append(Problem(self.doc.at(path), f"{path_text(path)}: {message}" if path else message))

    def entries(self) -> tuple[list[UncertainEntry], list[Problem]]:
        data = self.doc.data
        if not isinstance(data, dict) or "uncertain" not in data:
            raise MissionError(Problem(self.doc.at(()), 'an uncertainty file is an object with a list "uncertain" '
                                                        '(docs/formats/uncertainty.md)'))
        for key in data:
            if key not in ("uncertain", "joint"):
                self.problem((key,), 'unknown key: an uncertainty file holds "uncertain" and "joint"')
        listed = data["uncertain"]
        if not isinstance(listed, list):
            raise MissionError(Problem(self.doc.at(("uncertain",)), "uncertain: expected a list of entries"))
        found = [entry for i, item in enumerate(listed) if (entry := self.entry(item, ("uncertain", i))) is not None]
        seen: dict[tuple[str, str], str] = {}
        unique = []
        for entry in found:
            earlier = seen.setdefault((entry.entity, entry.attribute), entry.where)
            if earlier != entry.where:  # reported here, and not resolved again
                self.problems.append(Problem(entry.where, f"{entry.entity}.{entry.attribute} is already uncertain "
                                                          f"at {earlier}"))
            else:
                unique.append(entry)
        return unique, self.problems

    def joints(self) -> list[JointEntry]:
        """The ``joint`` tables: facts that are not independent, with the probability of each
        combination of their values."""
        tables = self.doc.data.get("joint", []) if isinstance(self.doc.data, dict) else []
        if not isinstance(tables, list):
            self.problem(("joint",), "expected a list of tables")
            return []
        found = []
        for i, table in enumerate(tables):
            path: Path = ("joint", i)
            if not isinstance(table, dict) or set(table) != {"facts", "outcomes"}:
                self.problem(path, 'expected an object {"facts": [...], "outcomes": [...]}')
                continue
            facts = table["facts"]
            if not isinstance(facts, list) or len(facts) < 2 or not all(
                    isinstance(f, dict) and set(f) == {"entity", "attribute"} and all(isinstance(v, str) for v in f.values())
                    for f in facts):
                self.problem((*path, "facts"), 'expected a list of two or more {"entity": ..., "attribute": ...}')
                continue
            names = [(f["entity"].strip(), f["attribute"].strip()) for f in facts]
            twice = next((i for i, name in enumerate(names) if name in names[:i]), None)
            if twice is not None:
                self.problem((*path, "facts", twice), f"{names[twice][0]}.{names[twice][1]} is listed twice in this table")
                continue
            outcomes = self.outcomes(table["outcomes"], (*path, "outcomes"), len(facts))
            if outcomes is not None:
                found.append(JointEntry(tuple(names), outcomes, self.doc.at(path)))
        return found

    def outcomes(self, listed: Any, path: Path, size: int) -> tuple[tuple[tuple[Value, ...], float], ...] | None:
        if not isinstance(listed, list) or not listed:
            self.problem(path, 'expected a list of {"values": [...], "probability": p}')
            return None
        found: list[tuple[tuple[Value, ...], float]] = []
        for i, outcome in enumerate(listed):
            where: Path = (*path, i)
            values = outcome.get("values") if isinstance(outcome, dict) else None
            if not isinstance(outcome, dict) or set(outcome) != {"values", "probability"} or not isinstance(values, list) \
                    or len(values) != size or not all(isinstance(v, bool) or _finite(v) is not None for v in values):
                self.problem(where, f'expected {{"values": [one per fact, {size}], "probability": p}}')
                return None
            p = self.probability(outcome["probability"], (*where, "probability"))
            if p is None:
                return None
            key = tuple(v if isinstance(v, bool) else float(v) for v in values)
            if any(_same(key, earlier) for earlier, _ in found):
                self.problem(where, "this combination of values is listed twice")
                return None
            found.append((key, p))
        total = math.fsum(p for _, p in found)
        if abs(total - 1) > TOLERANCE:
            self.problem(path, f"the probabilities add up to {total:g}, not 1")
            return None
        return tuple(found)

    def entry(self, item: Any, path: Path) -> UncertainEntry | None:
        """One entry, or None when it has a problem (reported)."""
        if not isinstance(item, dict):
            self.problem(path, 'expected an object {"entity": ..., "attribute": ...}')
            return None
        before = len(self.problems)
        for key in item:
            if key not in KEYS:
                self.problem((*path, key), f"unknown key (one of {', '.join(KEYS)})")
        entity, attribute = (self.name(item, path, key) for key in ("entity", "attribute"))
        given = [key for key in ("probability", "values", "distribution") if key in item]
        values: tuple[Value, ...] | None = None  # None: a boolean, either way
        probabilities: tuple[float, ...] | None = None
        if len(given) > 1:
            self.problem((*path, given[1]), f"give one of probability, values and distribution, not {' and '.join(given)}")
        elif given == ["probability"]:
            p = self.probability(item["probability"], (*path, "probability"))
            values, probabilities = (False, True), (None if p is None else (1 - p, p))
        elif given == ["values"]:
            values = self.values(item["values"], (*path, "values"))
        elif given == ["distribution"]:
            values, probabilities = self.distribution(item["distribution"], (*path, "distribution"))
        if len(self.problems) > before or entity is None or attribute is None:
            return None
        return UncertainEntry(entity, attribute, values, probabilities, self.doc.at(path),
                              numeric=given in (["values"], ["distribution"]))

    def name(self, item: dict[str, Any], path: Path, key: str) -> str | None:
        value = item.get(key)
        if not isinstance(value, str) or not value.strip():
            self.problem((*path, key) if key in item else path, f"{key}: expected a non-empty string")
            return None
        return value.strip()

    def probability(self, value: Any, path: Path) -> float | None:
        if isinstance(value, bool) or not isinstance(value, (int, float)) or not 0 <= value <= 1 or math.isnan(value):
            self.problem(path, f"expected a probability between 0 and 1, not {_shown(value)}")
            return None
        return float(value)

    def number(self, value: Any, path: Path) -> float | None:
        number = _finite(value)
        if number is None:
            self.problem(path, f"expected a number of at most {MAX_NUMBER:.0e} either way, not {_shown(value)}")
        return number

    def values(self, listed: Any, path: Path) -> tuple[Value, ...] | None:
        if not isinstance(listed, list) or not 2 <= len(listed) <= MAX_VALUES:
            self.problem(path, f"expected a list of 2 to {MAX_VALUES} numbers")
            return None
        numbers = [self.number(v, (*path, i)) for i, v in enumerate(listed)]
        if any(n is None for n in numbers):
            return None
        if len({scaled(n) for n in numbers if n is not None}) != len(numbers):
            self.problem(path, "a value is listed twice (values are told apart in thousandths)")
            return None
        return tuple(n for n in numbers if n is not None)

    def distribution(self, table: Any, path: Path) -> tuple[tuple[Value, ...] | None, tuple[float, ...] | None]:
        if not isinstance(table, dict) or not 2 <= len(table) <= MAX_VALUES:
            self.problem(path, f'expected an object of 2 to {MAX_VALUES} values and their probabilities, {{"0": 0.25, "2": 0.75}}')
            return None, None
        values: list[float] = []
        probabilities: list[float] = []
        for key, p in table.items():
            value = float(key) if _DECIMAL.fullmatch(key.strip()) else math.nan
            if not math.isfinite(value):
                self.problem((*path, key), f"{_shown(key)} is not a number")
                continue
            if _finite(value) is None:  # the same limit as a value of "values"
                self.problem((*path, key), f"expected a number of at most {MAX_NUMBER:.0e} either way, not {_shown(key)}")
                continue
            if any(scaled(value) == scaled(v) for v in values):
                self.problem((*path, key), f"the value {key} is given twice (values are told apart in thousandths)")
                continue
            checked = self.probability(p, (*path, key))
            if checked is not None:
                values.append(value)
                probabilities.append(checked)
        if len(values) != len(table):
            return None, None
        if abs(math.fsum(probabilities) - 1) > TOLERANCE:
            self.problem(path, f"the probabilities add up to {math.fsum(probabilities):g}, not 1")
            return None, None
        return tuple(values), tuple(probabilities)


#: a number as a distribution's key writes it: ASCII digits, a point, an exponent
_DECIMAL = re.compile(r"[+-]?(?:\d+\.?\d*|\.\d+)(?:[eE][+-]?\d+)?", re.ASCII)


def _finite(value: Any) -> float | None:
    """A JSON number as a float; None for anything else (a boolean, a string, a number beyond
    the decomposer's numbers, :data:`MAX_NUMBER`)."""
    if isinstance(value, bool) or not isinstance(value, (int, float)):
        return None
    try:
        number = float(value)
    except OverflowError:
        return None
    return number if abs(number) <= MAX_NUMBER else None


def _same(first: tuple[Value, ...], second: tuple[Value, ...]) -> bool:
    """Two combinations of values alike, a truth value never alike a number (``true`` is not 1)."""
    return all(type(a) is type(b) and a == b for a, b in zip(first, second))


def _shown(value: Any) -> str:
    """A value as an error quotes it, cut short when long."""
    text = repr(value)
    return text if len(text) <= 40 else f"{text[:37]}..."
