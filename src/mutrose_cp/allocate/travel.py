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
from typing import TYPE_CHECKING, Iterable, Mapping

from lxml import etree

from ..errors import MissionError, Problem, located
from ..pipeline.stages import MissionStages
from .budget import NEVER, Deadline
from .fleet import MAX_COORDINATE, Fleet, Robot

if TYPE_CHECKING:
    import numpy as np

COORDINATE_FIELDS = ("x", "y")


@dataclass(frozen=True)
class Place:
    """A named place and, when known, its coordinates and where they were written."""

    name: str
    point: tuple[float, float] | None
    where: str  # the world record or the fleet entry, for messages


def world_places(mission: MissionStages) -> tuple[dict[str, Place], list[Problem]]:
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

    def among(self, places: Iterable[str], deadline: Deadline = NEVER) -> TravelTimes:
        """The times between ``places`` alone (a subset of :attr:`places`): the table of the
        mission's places, checked once, serves an allocation that needs only some of them.
        Raises :class:`~.budget.OutOfTime` when the ``deadline`` passes first."""
        kept = sorted(set(places))
        columns = [self._position[p] for p in kept]
        rows = []
        for p in kept:
            deadline.check()
            row = self.base[self._position[p]]
            rows.append(tuple(row[c] for c in columns))
        return TravelTimes(tuple(kept), tuple(rows), self.modelled)

    @cached_property
    def _position(self) -> dict[str, int]:
        return {p: i for i, p in enumerate(self.places)}


def build_travel(mission: MissionStages, fleet: Fleet, needed: Iterable[str]) -> TravelTimes:
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
    if table:  # NumPy and SciPy imported below: reading and checking a fleet without travel stays light
        times = _shortest_paths(wanted, places, table, fleet.travel.metric)
    else:
        times = _distances(wanted, places, fleet.travel.metric)
    _check_complete(wanted, times, places, fleet)
    return TravelTimes(tuple(wanted), tuple(map(tuple, times.tolist())), True)


def _distances(names: list[str], places: dict[str, Place], metric: str) -> np.ndarray:
    """The distance between the coordinates of each two of ``names`` (infinite where one has
    none; 0 from a place to itself), in arrays."""
    import numpy as np

    points = np.full((len(names), 2), np.nan)
    for i, name in enumerate(names):
        place = places.get(name)
        if place is not None and place.point is not None:
            points[i] = place.point
    dx = points[:, None, 0] - points[None, :, 0]
    dy = points[:, None, 1] - points[None, :, 1]
    distance = np.abs(dx) + np.abs(dy) if metric == "manhattan" else np.hypot(dx, dy)
    distance[np.isnan(distance)] = np.inf
    np.fill_diagonal(distance, 0.0)
    table: np.ndarray = distance
    return table


def _shortest_paths(wanted: list[str], places: dict[str, Place], table: Mapping[tuple[str, str], float],
                    metric: str) -> np.ndarray:
    """The quickest trips between the ``wanted`` places through the road network: the table's
    entries (both ways, unless the reverse has its own) and the straight lines between places
    with coordinates, where no entry replaces them.  Dijkstra from each wanted place on the
    sparse network (SciPy): a network of thousands of junctions costs its roads, not the cube
    of its junctions."""
    import numpy as np
    from scipy.sparse import csr_matrix  # type: ignore[import-untyped]
    from scipy.sparse.csgraph import dijkstra  # type: ignore[import-untyped]

    names = sorted(set(wanted) | {a for pair in table for a in pair})
    position = {p: i for i, p in enumerate(names)}
    roads = {(position[a], position[b]): t for (a, b), t in table.items() if a != b}
    roads.update({(b, a): t for (a, b), t in list(roads.items()) if (b, a) not in roads})
    pointed = [i for i, name in enumerate(names) if (place := places.get(name)) is not None and place.point is not None]
    block = _distances([names[i] for i in pointed], places, metric)
    at = np.asarray(pointed, dtype=np.int64)
    source, target = np.meshgrid(at, at, indexing="ij")
    keep = source != target
    if roads:  # a table entry wins over the straight line
        keys = np.fromiter((i * len(names) + j for i, j in roads), dtype=np.int64, count=len(roads))
        keep &= ~np.isin(source * len(names) + target, keys)
    rows = np.concatenate([source[keep], np.fromiter((i for i, _ in roads), dtype=np.int64, count=len(roads))])
    columns = np.concatenate([target[keep], np.fromiter((j for _, j in roads), dtype=np.int64, count=len(roads))])
    lengths = np.concatenate([block[keep], np.fromiter(roads.values(), dtype=float, count=len(roads))])
    graph = csr_matrix((lengths, (rows, columns)), shape=(len(names), len(names)))  # zeros stay roads of length 0
    indices = [position[p] for p in wanted]
    return np.asarray(dijkstra(graph, directed=True, indices=indices), dtype=float)[:, indices]


def _check_complete(wanted: list[str], times: np.ndarray, places: dict[str, Place], fleet: Fleet) -> None:
    """Every trip between two wanted places has a time; otherwise each place that misses
    coordinates is named once, where it is defined."""
    import numpy as np

    problems: list[Problem] = []
    for i in np.flatnonzero(~np.isfinite(times).all(axis=1)):
        a = wanted[i]
        b = wanted[int(np.flatnonzero(~np.isfinite(times[i]))[0])]
        place = places.get(a)
        where = place.where if place is not None else fleet.source
        known = "" if place is None else " has no coordinates and"
        problems.append(Problem(where, f"place {a}{known or ' is not a world location and has no coordinates, and'} "
                                       f"no travel time to {b}",
                                "Give it x and y fields in the world, or travel.coordinates or a travel.times "
                                "entry in the fleet."))
    if problems:
        raise MissionError(problems)
