"""Travel times between the places of a mission, for each robot.

A place is a world location (a record whose type is one of the configuration's
``location_types``) or any name the fleet gives coordinates or travel times to (a dock).  A
place's coordinates are its ``x`` and ``y`` fields in the world file, unless the fleet's
``travel.coordinates`` gives them.  Between two places, the fleet's ``travel.times`` entry
(either direction) wins; otherwise the distance between their coordinates (``travel.metric``).
A table may describe a road network only in part, so with a table the times are shortest paths
through it (a robot may go through a third place when that is quicker).

A robot of speed ``s`` takes ``ceil(t / s)`` whole time units for a trip of ``t``.  Rounding up
keeps the triangle inequality, and the times are never optimistic.

A mission and fleet with no coordinates and no table at all have no travel: every time is 0.
"""
from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property
from typing import Iterable, Mapping

from lxml import etree

from ..errors import MissionError, Problem, located
from ..mission import Mission
from .fleet import MAX_COORDINATE, Fleet, Robot

COORDINATE_FIELDS = ("x", "y")


@dataclass(frozen=True)
class Place:
    """A named place and, when known, its coordinates and where they were written."""

    name: str
    point: tuple[float, float] | None
    where: str  # the world record or the fleet entry, for messages


def world_places(mission: Mission) -> tuple[dict[str, Place], list[Problem]]:
    """The world's locations with the coordinates of their ``x``/``y`` fields, and the problems
    of fields that are not numbers or come alone."""
    knowledge = mission.knowledge
    places: dict[str, Place] = {}
    problems: list[Problem] = []
    for kind in mission.config.location_types:
        for record in knowledge.records_of(kind):
            name = knowledge.record_id(record)
            if not name or name in places:
                continue
            where = located(knowledge.source, _line(record))
            point, problem = _point(record, name, knowledge.source)
            if problem is not None:
                problems.append(problem)
            places[name] = Place(name, point, where)
    return places, problems


def _line(element: etree._Element) -> int | None:
    line = element.sourceline
    return line if isinstance(line, int) else None


def _point(record: etree._Element, name: str, source: str) -> tuple[tuple[float, float] | None, Problem | None]:
    fields = [record.find(f) for f in COORDINATE_FIELDS]
    present = [f for f in fields if f is not None]
    if not present:
        return None, None
    if len(present) == 1:
        return None, Problem(located(source, _line(present[0])),
                             f"location {name} has only one coordinate", "Give both x and y, or neither.")
    values = []
    for f in present:
        text = (f.text or "").strip()
        try:
            value = float(text)
        except ValueError:
            value = math.nan
        if not math.isfinite(value):
            return None, Problem(located(source, _line(f)),
                                 f"location {name}: {f.tag} must be a number, got {text!r}")
        if abs(value) > MAX_COORDINATE:  # as the fleet's coordinates: trip times stay in CP-SAT's range
            return None, Problem(located(source, _line(f)), f"location {name}: {f.tag} {text} is out of range: "
                                                            f"give a number from {-MAX_COORDINATE:g} to {MAX_COORDINATE:g}")
        values.append(value)
    return (values[0], values[1]), None


@dataclass(frozen=True)
class TravelTimes:
    """Travel times at speed 1 between the places a schedule can visit (``base``), and the
    whole time units a given robot needs (:meth:`time`)."""

    places: tuple[str, ...]
    base: tuple[tuple[float, ...], ...]
    modelled: bool  # False: no coordinates and no table anywhere, every time is 0

    def time(self, robot: Robot, a: str | None, b: str | None) -> int:
        """Time units for ``robot`` to go from ``a`` to ``b`` (0 when either is unknown: a robot
        without a start, a task without a location)."""
        if not self.modelled or a is None or b is None or a == b:
            return 0
        distance = self.base[self._position[a]][self._position[b]]
        return math.ceil(distance / robot.speed - 1e-9)

    def among(self, places: Iterable[str]) -> TravelTimes:
        """The times between ``places`` alone (a subset of :attr:`places`): the table of the
        mission's places, checked once, serves an allocation that needs only some of them."""
        kept = sorted(set(places))
        rows = [self.base[self._position[p]] for p in kept]
        return TravelTimes(tuple(kept), tuple(tuple(row[self._position[p]] for p in kept) for row in rows),
                           self.modelled)

    @cached_property
    def _position(self) -> dict[str, int]:
        return {p: i for i, p in enumerate(self.places)}


def build_travel(mission: Mission, fleet: Fleet, needed: Iterable[str]) -> TravelTimes:
    """Travel times between the ``needed`` places (task locations and robot starts).
    Raises :class:`MissionError` naming each place a time is missing for."""
    wanted = sorted(set(needed))
    places, problems = world_places(mission)
    for name, point in fleet.travel.coordinates.items():
        places[name] = Place(name, point, fleet.where(("travel", "coordinates", name)))
    if problems:
        raise MissionError(problems)
    table = fleet.travel.times
    if not table and not any(p.point is not None for p in places.values()):
        return TravelTimes(tuple(wanted), tuple(tuple(0.0 for _ in wanted) for _ in wanted), False)
    names = sorted(set(wanted) | {a for pair in table for a in pair})
    direct = [[_direct(a, b, places, table, fleet.travel.metric) for b in names] for a in names]
    if table:
        direct = _shortest_paths(direct)
    position = {p: i for i, p in enumerate(names)}
    _check_complete(wanted, direct, position, places, fleet)
    base = tuple(tuple(direct[position[a]][position[b]] for b in wanted) for a in wanted)
    return TravelTimes(tuple(wanted), base, True)


def _direct(a: str, b: str, places: dict[str, Place], table: Mapping[tuple[str, str], float],
            metric: str) -> float:
    if a == b:
        return 0.0
    if (a, b) in table:
        return float(table[(a, b)])
    if (b, a) in table:
        return float(table[(b, a)])
    pa, pb = places.get(a), places.get(b)
    if pa is None or pb is None or pa.point is None or pb.point is None:
        return math.inf
    dx, dy = pa.point[0] - pb.point[0], pa.point[1] - pb.point[1]
    return abs(dx) + abs(dy) if metric == "manhattan" else math.hypot(dx, dy)


def _shortest_paths(direct: list[list[float]]) -> list[list[float]]:
    """Shortest paths through the table and the coordinates (SciPy's Floyd-Warshall; an
    infinite entry is a missing edge, a zero one an edge of length 0)."""
    import numpy as np
    from scipy.sparse.csgraph import csgraph_from_dense, floyd_warshall  # type: ignore[import-untyped]

    graph = csgraph_from_dense(np.array(direct, dtype=float), null_value=np.inf)
    return [[float(v) for v in row] for row in floyd_warshall(graph, directed=True)]


def _check_complete(wanted: list[str], direct: list[list[float]], position: dict[str, int],
                    places: dict[str, Place], fleet: Fleet) -> None:
    """Every trip between two wanted places has a time; otherwise each place that misses
    coordinates is named once, where it is defined."""
    problems: list[Problem] = []
    reported: set[str] = set()
    for a in wanted:
        for b in wanted:
            if math.isfinite(direct[position[a]][position[b]]) or a in reported:
                continue
            reported.add(a)
            place = places.get(a)
            where = place.where if place is not None else fleet.source
            known = "" if place is None else " has no coordinates and"
            problems.append(Problem(where, f"place {a}{known or ' is not a world location and has no coordinates, and'} "
                                           f"no travel time to {b}",
                                    "Give it x and y fields in the world, or travel.coordinates or a travel.times "
                                    "entry in the fleet."))
    if problems:
        raise MissionError(problems)
