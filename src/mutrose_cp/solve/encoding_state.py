"""What the encoder knows of a Task Graph while it builds the boolean model, kept apart from the
rules that build it, so that the replay of stamped forAll copies (:mod:`.replay`) reads the same
maps the encoder fills without depending on the encoder itself.

The encoder (:class:`.encoding.Encoder`) is an :class:`EncodingState` that adds the encoding
rules; the replay takes an :class:`EncodingState`.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import Any, Generic, Sequence, TypeVar

from ..pipeline.constraints import Constraint
from ..errors import MissionError
from ..model import Configuration, Domain, GoalModel, InitialState
from ..model.world import MAX_NUMBER, Number
from ..model.task_graph import TaskGraph
from .boolean_model import BoolModel, Lit
from .semantics import (
    NO_EFFECTS,
    AtomKey,
    ConstraintIndex,
    EffectScopes,
    Effects,
    ParallelConflicts,
    application_order,
    effects_of,
    initial_state,
    mission_queue,
)

V = TypeVar("V")  # the value a chain of writers carries


@dataclass
class Chain(Generic[V]):
    """The value of an atom after a prefix of its writers, and the steps to longer prefixes."""

    value: V  # (known, true) literals of a fact; (known literal, integer variable) of a number
    next: dict[tuple[Any, ...], "Chain[V]"] = field(default_factory=dict)


class EncodingState:
    """The Task Graph's writers, effects and order, and the literals made for it so far."""

    def __init__(self, tg: TaskGraph, constraints: Sequence[Constraint], domain: Domain, gm: GoalModel,
                 config: Configuration, initial: InitialState, explain: bool, model: BoolModel) -> None:
        self.tg = tg
        self.domain = domain
        self.gm = gm
        self.config = config
        self.explain = explain
        self.m = model
        self.initial = initial_state(initial)
        self.facts, self.values = self.initial.facts, self.initial.values
        # the effects of the decompositions that have any (a large mission's most have none)
        self.effects: dict[int, Effects] = {}
        for dv in tg.decompositions():
            effects = effects_of(dv.decomposition)
            if effects is not NO_EFFECTS:
                self.effects[dv.index] = effects
        self.index = ConstraintIndex.of(constraints)
        self.scopes = EffectScopes(tg)
        self.queue = mission_queue(tg)
        self.queue_pos = dict(zip(self.queue, range(len(self.queue))))
        self.x: dict[int, Lit] = {}  # decomposition vertex -> its choice literal
        self.active: dict[int, Lit] = {}  # task vertex -> "active" literal
        self.or_lits: dict[tuple[int, int], Lit] = {}  # (OR operator vertex, child vertex) -> literal
        self.labels: dict[str, str] = {}
        # the value of each atom after a prefix of its writers, as a tree of prefixes
        self.bool_chains: dict[AtomKey, Chain[tuple[Lit, Lit]]] = {}
        self.num_chains: dict[AtomKey, Chain[tuple[Lit, int | None]]] = {}
        self.bool_prefixes: dict[AtomKey, list[Chain[tuple[Lit, Lit]]]] = {}  # after the first k writers
        self.writer_positions: dict[Any, list[int]] = {}
        self.num_prefixes: dict[AtomKey, list[tuple[Chain[tuple[Lit, int | None]], int]]] = {}
        self.bool_writers: dict[AtomKey, list[tuple[int, bool]]] = {}
        self.num_writers: dict[AtomKey, list[tuple[int, str, float]]] = {}
        for d in application_order(self.effects):  # writers of each atom, in the order effects apply (§7.3)
            for key, val in self.effects[d].facts:
                self.bool_writers.setdefault(key, []).append((d, val))
            for key, kind, amount in self.effects[d].numeric:
                self.num_writers.setdefault(key, []).append((d, kind, amount))
        self.conflicts = ParallelConflicts(self.scopes, self.bool_writers)

    def start_value(self, atom: AtomKey) -> Number | None:
        """The world's value of a function, as the model reads it; one beyond what 64-bit
        integers in thousandths hold is refused, naming the function (docs/numbers.md)."""
        value = self.values.get(atom)
        if value is not None and not abs(value) <= MAX_NUMBER:
            function, args = atom
            raise MissionError(f"{function}({', '.join(args)}) starts at {value:.6g} in the world, beyond the numbers "
                               f"the CP-SAT decomposer computes with ({MAX_NUMBER:.0e} either way): write a smaller "
                               "value, or decompose with --algorithm exploratory")
        return value
