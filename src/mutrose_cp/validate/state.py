"""World states while a mission decomposition is replayed: known facts and function values (an
absent atom is unknown, the open world of the spec), and what a replayed task changed."""
from __future__ import annotations

from collections import ChainMap
from dataclasses import dataclass, field
from typing import MutableMapping, TypeVar

from ..model import InitialState
from .numbers import AtomKey

T = TypeVar("T")


def _layer(table: MutableMapping[AtomKey, T]) -> ChainMap[AtomKey, T]:
    """A copy of ``table`` to change: a new top layer over the layers below, which nothing
    changes (only the top layer of a state is ever written), so that a task's start state is
    not a copy of the whole world."""
    if isinstance(table, ChainMap):
        return ChainMap(dict(table.maps[0]), *table.maps[1:])
    return ChainMap({}, table)


class State:
    """Known facts and function values; an absent atom is unknown.  Of a function the world
    does not give, ``offsets`` holds what the increases and decreases so far added to it (it
    stays unknown until an assignment)."""

    def __init__(self, facts: MutableMapping[AtomKey, bool], values: MutableMapping[AtomKey, float],
                 offsets: MutableMapping[AtomKey, float] | None = None) -> None:
        self.facts = facts
        self.values = values
        self.offsets: MutableMapping[AtomKey, float] = offsets if offsets is not None else {}

    @classmethod
    def initial(cls, initial: InitialState) -> "State":
        return cls(initial.fact_map(), {k: float(v) for k, v in initial.value_map().items()})

    def copy(self) -> "State":
        return State(_layer(self.facts), _layer(self.values), dict(self.offsets))


@dataclass
class TaskEffects:
    """What a replayed task changed: final values of facts, numeric changes in order."""

    facts: dict[AtomKey, bool] = field(default_factory=dict)
    numeric: list[tuple[AtomKey, str, float]] = field(default_factory=list)

    def apply(self, state: State) -> None:
        state.facts.update(self.facts)
        for key, kind, amount in self.numeric:
            change = amount if kind == "increase" else -amount
            if kind == "assign":
                state.values[key] = amount
                state.offsets.pop(key, None)
            elif key in state.values:
                state.values[key] += change
            else:
                state.offsets[key] = state.offsets.get(key, 0.0) + change
