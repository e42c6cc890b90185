"""The fleet file: the robots that execute a mission, how long actions take, how far places are.

A fleet is a JSON object (``docs/formats/fleet.md``)::

    {"robots": [{"name": "r1", "capabilities": ["navigation"], "start": "Dock", "speed": 1.5}],
     "durations": {"default": 1, "actions": {"navigate": 0}, "capabilities": {"manipulation": 3}},
     "travel": {"metric": "euclidean", "coordinates": {"Dock": [0, 0]},
                "times": {"Dock": {"WardA": 4}}}}

It is read whole before anything is reported, so one run lists every mistake, each at
``file:line:col`` with its key path.  What the fleet says about the mission (capability and
action names, start locations, travel to every task's location) is checked against the mission
by :func:`mutrose_cp.allocate.problem.fleet_problems`.
"""
from __future__ import annotations

import json
import math
import os
import re
import sys
from dataclasses import dataclass, field
from typing import Any, Callable, Mapping

from ..errors import MissionError, Problem, closest
from ..io.located_json import LocatedJson, OutOfRangeNumber, Path, parse_located_json, path_text, read_located_json

METRICS = ("euclidean", "manhattan")
MAX_DURATION = 10**6  # per action: a schedule's times stay far inside CP-SAT's 64-bit range
MAX_TIME = 10**6  # per travel-table entry (at speed 1)
MAX_COORDINATE = 10**9
MIN_SPEED = 10**-3  # the slowest robot's longest trip (coordinates at their bound) stays near 10^12 units
# half of a UTF-16 pair, alone: JSON's "\ud800" decodes to it, but it is no text (no UTF-8 encodes it, and
# the solver's names and the schedule file could not hold it)
LONE_SURROGATE = re.compile("[\ud800-\udfff]")
ESCAPED_SURROGATE = re.compile(r"\\u[dD][89a-fA-F]")
ROBOT_KEYS = frozenset({"name", "capabilities", "start", "speed"})


@dataclass(frozen=True)
class Robot:
    """One robot: what it can do, where it starts and how fast it moves.

    ``speed`` divides every travel time of the fleet's table or coordinates (1 by default); a
    robot without ``start`` is where its first task is (it needs no travel to reach it)."""

    name: str
    capabilities: frozenset[str]
    start: str | None = None
    speed: float = 1.0


@dataclass(frozen=True)
class Durations:
    """How long an action takes: its own entry, else the longest entry of its capabilities,
    else ``default``.  Whole time units."""

    default: int = 1
    actions: Mapping[str, int] = field(default_factory=dict)
    capabilities: Mapping[str, int] = field(default_factory=dict)

    def of_action(self, name: str, capabilities: tuple[str, ...]) -> int:
        if name in self.actions:
            return self.actions[name]
        by_capability = [self.capabilities[c] for c in capabilities if c in self.capabilities]
        return max(by_capability) if by_capability else self.default


@dataclass(frozen=True)
class TravelSpec:
    """Where travel times come from: a table (times at speed 1, both directions unless the
    reverse has its own entry) and coordinates (with ``metric``), which add to or override the
    world's ``x``/``y`` fields."""

    metric: str = "euclidean"
    coordinates: Mapping[str, tuple[float, float]] = field(default_factory=dict)
    times: Mapping[tuple[str, str], float] = field(default_factory=dict)


@dataclass(frozen=True)
class Fleet:
    """A validated fleet file.  ``document`` keeps the positions of its values, so that checks
    against a mission can point into the file."""

    robots: tuple[Robot, ...]
    durations: Durations = Durations()
    travel: TravelSpec = TravelSpec()
    source: str = "<fleet>"
    document: LocatedJson | None = field(default=None, repr=False, compare=False)

    @classmethod
    def read(cls, path: str | os.PathLike[str]) -> "Fleet":
        """Read and validate a fleet file; every problem found is raised at once."""
        return _Reader(read_located_json(path, "fleet")).fleet()

    @classmethod
    def parse(cls, text: str, source: str = "<fleet>") -> "Fleet":
        return _Reader(parse_located_json(text, source)).fleet()

    @classmethod
    def from_dict(cls, data: Mapping[str, Any], source: str = "<fleet>") -> "Fleet":
        """A fleet from the same structure as the file, for programs (validated alike)."""
        return cls.parse(json.dumps(data, indent=1), source)

    def where(self, path: Path, *, key: bool = False) -> str:
        """``file:line:col`` of a value of the fleet file (the file name without a document)."""
        return self.document.at(path, key=key) if self.document is not None else self.source


class _Reader:
    """Validates the decoded document and collects every problem, located."""

    def __init__(self, doc: LocatedJson) -> None:
        self.doc = doc
        self.problems: list[Problem] = []
        # a decoded string holds a lone surrogate only where the text escapes one (\\udXXX) or, in a
        # text given by a program (Fleet.parse), holds one: a text without either is not searched
        # string by string
        self.escapes = ESCAPED_SURROGATE.search(doc.text) is not None or LONE_SURROGATE.search(doc.text) is not None
        self.lists: dict[tuple[str, ...], frozenset[str]] = {}  # capability lists read already

    def problem(self, path: Path, message: str, hint: str = "", *, key: bool = False) -> None:
        where = self.doc.at(path, key=key)
        self.problems.append(Problem(where, f"{path_text(path)}: {message}" if path else message, hint))

    # -- shapes -------------------------------------------------------------------------------

    def obj(self, value: Any, path: Path, keys: tuple[str, ...]) -> dict[str, Any]:
        """``value`` as an object whose keys are among ``keys`` (others are reported)."""
        if not isinstance(value, dict):
            self.problem(path, f"expected an object, got {_kind(value)}")
            return {}
        for k in value:
            if k not in keys:
                near = closest(k, keys, 0.6)
                self.problem((*path, k), f"unknown key {k!r}", f"Did you mean {near!r}?" if near else
                             "Expected " + ", ".join(repr(x) for x in keys) + ".", key=True)
        return value

    def string(self, value: Any, path: Path) -> str | None:
        if isinstance(value, str) and value.strip():
            return value.strip() if self.text(value, path) else None
        self.problem(path, f"expected a non-empty string, got {_kind(value)}")
        return None

    def text(self, value: str, path: Path, *, key: bool = False) -> bool:
        """Whether ``value`` (a name, or a key with ``key``) is text: a lone surrogate is not."""
        found = LONE_SURROGATE.search(value) if self.escapes else None
        if found is None:
            return True
        self.problem(path, f"{'the key' if key else 'the string'} {value!r} holds a lone surrogate "
                           f"(\\u{ord(found.group()):04x}), which is no character",
                     "Write the character itself (or its full \\u pair); a lone half of a UTF-16 pair is not "
                     "text.", key=key)
        return False

    def number(self, value: Any, path: Path, *, low: float, high: float, whole: bool = False) -> float | None:
        """``value`` as a number from ``low`` to ``high``.  An integer is compared as it is:
        one too large for a float (JSON has no limit) is out of range, not an overflow."""
        what = "a whole number" if whole else "a number"
        if isinstance(value, OutOfRangeNumber):
            self.problem(path, f"{value} is out of range: give a number from {low:g} to {high:g}")
            return None
        if isinstance(value, float) and math.isinf(value):  # 1e400: beyond the largest float
            self.problem(path, f"a number beyond {sys.float_info.max:.3g} is out of range: give a number from "
                               f"{low:g} to {high:g}")
            return None
        if isinstance(value, bool) or not isinstance(value, (int, float)):
            self.problem(path, f"expected {what}, got {_kind(value)}")
            return None
        if whole and isinstance(value, float) and not value.is_integer():
            self.problem(path, f"expected {what}, got {value!r}", "Times are whole time units.")
            return None
        if not low <= value <= high:
            self.problem(path, f"{_kind(value)} is out of range: give a number from {low:g} to {high:g}")
            return None
        return float(value)

    def duration(self, value: Any, path: Path) -> int | None:
        number = self.number(value, path, low=0, high=MAX_DURATION, whole=True)
        return None if number is None else int(number)

    def table(self, value: Any, path: Path, entry: Callable[[Any, Path], Any]) -> dict[str, Any]:
        """An object of ``name -> entry`` (every key a name, every value read by ``entry``)."""
        if not isinstance(value, dict):
            self.problem(path, f"expected an object, got {_kind(value)}")
            return {}
        out = {}
        for k, v in value.items():
            if not self.text(k, (*path, k), key=True):
                continue
            read = entry(v, (*path, k))
            if read is not None:
                out[k] = read
        return out

    # -- sections -----------------------------------------------------------------------------

    def fleet(self) -> Fleet:
        top = self.obj(self.doc.data, (), ("robots", "durations", "travel"))
        if isinstance(self.doc.data, dict) and "robots" not in top:
            self.problem((), 'missing key "robots"', 'A fleet lists its robots: {"robots": [{"name": "r1", '
                         '"capabilities": [...]}]}.')
        robots = self.robots(top.get("robots", []))
        durations = self.durations(top.get("durations", {}))
        travel = self.travel(top.get("travel", {}))
        if self.problems:
            raise MissionError(self.problems)
        return Fleet(tuple(robots), durations, travel, self.doc.source, self.doc)

    def robots(self, value: Any) -> list[Robot]:
        path: Path = ("robots",)
        if not isinstance(value, list) or not value:
            self.problem(path, f"expected a non-empty list of robots, got {_kind(value)}")
            return []
        robots: list[Robot] = []
        seen: set[str] = set()
        for i, item in enumerate(value):
            robot = self.robot(item, (*path, i))
            if robot is None:
                continue
            if robot.name in seen:
                self.problem((*path, i, "name"), f"robot {robot.name!r} is listed twice", "Robot names are unique.")
            seen.add(robot.name)
            robots.append(robot)
        return robots

    def robot(self, value: Any, path: Path) -> Robot | None:
        quick = self.plain_robot(value)
        if quick is not None:
            return quick
        item = self.obj(value, path, ("name", "capabilities", "start", "speed"))
        if not item:
            if isinstance(value, dict):
                self.problem(path, "a robot needs a name and its capabilities")
            return None
        for required in ("name", "capabilities"):
            if required not in item:
                self.problem(path, f'missing key "{required}"', 'A robot has a name and lists what it can do: '
                             '"capabilities": [] for nothing.' if required == "capabilities" else "")
        name = self.string(item["name"], (*path, "name")) if "name" in item else None
        capabilities = (self.capabilities(item["capabilities"], (*path, "capabilities"))
                        if "capabilities" in item else None)
        start = self.string(item["start"], (*path, "start")) if "start" in item else None
        speed = self.number(item.get("speed", 1.0), (*path, "speed"), low=MIN_SPEED, high=MAX_TIME)
        if name is None or capabilities is None or speed is None or ("start" in item and start is None):
            return None
        return Robot(name, capabilities, start, speed)

    def plain_robot(self, value: Any) -> Robot | None:
        """The robot of an entry with nothing to report, read without the checks that locate a
        mistake: a fleet of 100,000 robots is mostly such entries, of a few kinds (capability
        lists read already).  None: the entry is read the full way, which reports what is wrong."""
        if type(value) is not dict or not value.keys() <= ROBOT_KEYS or self.escapes:
            return None
        name, listed, start, speed = (value.get("name"), value.get("capabilities"), value.get("start", ""),
                                      value.get("speed", 1.0))
        if type(name) is not str or type(start) is not str or type(listed) is not list:
            return None
        try:
            capabilities = self.lists.get(tuple(listed))
        except TypeError:  # an object in the list: not a plain entry
            return None
        name, start = name.strip(), start.strip()
        if (capabilities is None or not name or (not start and "start" in value)
                or type(speed) not in (int, float) or not MIN_SPEED <= speed <= MAX_TIME):
            return None
        return Robot(name, capabilities, start or None, float(speed))

    def capabilities(self, value: Any, path: Path) -> frozenset[str] | None:
        if not isinstance(value, list):
            self.problem(path, f"expected a list of capability names, got {_kind(value)}")
            return None
        key = tuple(value) if all(isinstance(c, str) for c in value) else None
        if key is not None and key in self.lists:  # a fleet of thousands lists a few kinds of robot
            return self.lists[key]
        names = [self.string(c, (*path, i)) for i, c in enumerate(value)]
        if None in names:
            return None
        capabilities = frozenset(n for n in names if n is not None)
        if key is not None:
            self.lists[key] = capabilities
        return capabilities

    def durations(self, value: Any) -> Durations:
        path: Path = ("durations",)
        section = self.obj(value, path, ("default", "actions", "capabilities"))
        default = self.duration(section.get("default", 1), (*path, "default"))
        actions = self.table(section.get("actions", {}), (*path, "actions"), self.duration)
        capabilities = self.table(section.get("capabilities", {}), (*path, "capabilities"), self.duration)
        return Durations(default if default is not None else 1, actions, capabilities)

    def travel(self, value: Any) -> TravelSpec:
        path: Path = ("travel",)
        section = self.obj(value, path, ("metric", "coordinates", "times"))
        metric = section.get("metric", "euclidean")
        if metric not in METRICS:
            self.problem((*path, "metric"), f"unknown metric {metric!r}", "Expected \"euclidean\" or \"manhattan\".")
        coordinates = self.table(section.get("coordinates", {}), (*path, "coordinates"), self.point)
        rows = self.table(section.get("times", {}), (*path, "times"),
                          lambda row, at: self.table(row, at, self.time))
        times: dict[tuple[str, str], float] = {}
        for a, row in rows.items():
            for b, t in row.items():
                if a == b and t != 0:
                    self.problem((*path, "times", a, b), "travel from a place to itself takes no time")
                times[(a, b)] = t
        return TravelSpec(metric if metric in METRICS else "euclidean", coordinates, times)

    def point(self, value: Any, path: Path) -> tuple[float, float] | None:
        if not isinstance(value, list) or len(value) != 2:
            self.problem(path, f"expected a point [x, y], got {_kind(value)}")
            return None
        x, y = (self.number(v, (*path, i), low=-MAX_COORDINATE, high=MAX_COORDINATE) for i, v in enumerate(value))
        return None if x is None or y is None else (x, y)

    def time(self, value: Any, path: Path) -> float | None:
        return self.number(value, path, low=0, high=MAX_TIME)


def _kind(value: Any) -> str:
    """How a JSON value is named in messages."""
    if isinstance(value, bool):
        return json.dumps(value)
    if isinstance(value, int) and abs(value) >= 10**20:  # a number of hundreds of digits, said shortly
        digits = len(str(abs(value)))
        return f"{str(value)[:8]}... ({digits} digits)"
    if isinstance(value, (int, float, OutOfRangeNumber)):
        return str(value) if isinstance(value, OutOfRangeNumber) else repr(value)
    if isinstance(value, str):
        return f"the string {value!r}" if value.strip() else "an empty string"
    if value is None:
        return "null"
    if isinstance(value, list):
        return "an empty list" if not value else "a list"
    return "an object"
