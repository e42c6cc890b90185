"""Valid mission decompositions in a world that is not fully known (docs/formats/uncertainty.md).

Each uncertain fact's start value is a free variable of the boolean model (the encoder makes it
where the fact is first read), so a solution is a decomposition together with the values of
the uncertain facts it reads: a *scenario* under which it is valid.  The model splits into
independent components as before; a component now holds the facts its decompositions read
(a fact read by two components joins them), and it is decided over its scenarios by listing its
(part, scenario) pairs, with the scenarios as CP-SAT variables:

* a part is **robust** when every scenario of its component's facts allows it;
* **possible** when some scenario does, with the assumptions it needs (the values every
  allowing scenario gives a fact);
* its **probability** of being valid is the sum of its allowing scenarios' probabilities (a
  scenario's probability is the product of its independent facts' and of its joint tables';
  the facts of one table are joined into one component, and a scenario of probability 0 is
  none).

A mission decomposition is one part per component, and the components share no fact, so it is
robust when all its parts are, possible when all are, and its probability is the product of its
parts'.  Counting, the most likely decomposition and what to sense first follow component by
component.  A component whose pairs are more than ``MAX_PAIRS`` is answered with bounds, said
so: its parts valid in one scenario are possible, and no other part is robust, while the pairs,
counted, bound the possible parts from above; what needs each part's scenarios (listing,
probabilities, sensing) refuses it, named.  Sensing searches sets of facts up to ``MAX_FACTS``
facts a component.
"""
from __future__ import annotations

import itertools
import math
import operator
from dataclasses import dataclass, field
from functools import cached_property
from typing import Iterable, Iterator, Mapping, Sequence

from ..errors import MissionError
from ..model.uncertainty import (
    AtomKey,
    Joint,
    UncertainFact,
    Uncertainty,
    Value,
    rounded_probability,
    scenario_can_happen,
    scenario_probability,
)
from ..pipeline.stages import MissionStages
from .boolean_model import Clause, Lit, neg
from .cpsat import (
    Component,
    DecompositionSpace,
    decomposition_variables,
    fixed_decompositions,
    solve_components,
    split_components,
)
from .encoding import UNCERTAIN, Encoder, Encoding

#: at most this many uncertain facts of one component whose subsets are searched for sensing
MAX_FACTS = 12
#: at most this many (part, scenario) pairs of one component
MAX_PAIRS = 200_000

Scenario = tuple[Value, ...]  # one value per fact of the component, in its order
Part = tuple[int, ...]  # the component's chosen decomposition vertices, sorted


@dataclass
class UncertainComponent:
    """One independent part of the mission: its facts, and for each of its alternative parts
    the scenarios that allow it."""

    number: int
    facts: tuple[UncertainFact, ...]
    allowed: dict[Part, frozenset[Scenario]]  # in the order the parts were found, sorted below
    choice_vars: list[int] = field(default_factory=list)
    # too many pairs to list: (possible at least, possible at most, robust at most), and why
    bounds: tuple[int, int, int] | None = None
    unlisted: str = ""

    def counted(self, robust: bool) -> tuple[int, int]:
        """How many of its parts are robust (or possible): exactly (twice the same number), or
        between two bounds."""
        if self.bounds is not None:
            low, high, robust_high = self.bounds
            return (0, robust_high) if robust else (low, high)
        n = sum(1 for p in self.allowed if not robust or self.robust(p))
        return n, n

    joints: tuple[Joint, ...] = ()  # the joint tables of its facts
    weights: dict[Scenario, float] = field(default_factory=dict, repr=False, compare=False)  # probability by scenario
    happening: dict[Scenario, bool] = field(default_factory=dict, repr=False, compare=False)  # can_happen by scenario

    @cached_property
    def known(self) -> bool:
        """Whether its facts have probabilities (then a scenario of probability 0 is none)."""
        return all(f.probabilities is not None for f in self.facts)

    @cached_property
    def joined(self) -> frozenset[AtomKey]:
        """The atoms of its facts that a joint table weighs (the others are independent)."""
        return frozenset(f.atom for j in self.joints for f in j.facts)

    def can_happen(self, scenario: Scenario) -> bool:
        """Whether ``scenario`` can happen: no value of it has probability 0, whether or not
        its other facts have probabilities (computed once per scenario)."""
        happens = self.happening.get(scenario)
        if happens is None:
            happens = self.happening[scenario] = scenario_can_happen(self.facts, self.joints, scenario)
        return happens

    @cached_property
    def scenarios(self) -> int:
        """How many scenarios its facts can be in: each value of a fact without probabilities,
        each of positive probability of the others, and a joint table's outcomes."""
        count = math.prod(len(f.values) if f.probabilities is None else sum(1 for p in f.probabilities if p > 0)
                          for f in self.facts if f.atom not in self.joined)
        mine = {f.atom for f in self.facts}
        for j in self.joints:
            places = [i for i, f in enumerate(j.facts) if f.atom in mine]
            count *= len({tuple(outcome[i] for i in places) for outcome, p in j.outcomes if p > 0})
        return count

    def robust(self, part: Part) -> bool:
        return len(self.allowed[part]) == self.scenarios

    def probability(self, part: Part) -> float | None:
        """The probability that ``part`` is valid (None when a fact has no probabilities)."""
        if not self.known:
            return None
        return math.fsum(self.scenario_probability(s) for s in self.allowed[part])

    def scenario_probability(self, scenario: Scenario) -> float:
        """The product of its independent facts' probabilities and of its joint tables',
        computed once per scenario (a part's probability sums them, and parts share them)."""
        p = self.weights.get(scenario)
        if p is None:
            p = self.weights[scenario] = scenario_probability(self.facts, self.joints, scenario)
        return p

    def assumptions(self, part: Part) -> list[tuple[UncertainFact, Value]]:
        """The fact values every scenario that allows ``part`` gives (what it needs)."""
        allowed = self.allowed[part]
        return [(fact, value) for i, fact in enumerate(self.facts)
                if len({s[i] for s in allowed}) == 1 for value in (next(iter(allowed))[i],)]


@dataclass
class UncertainSpace:
    """The mission's decompositions with the scenarios that allow them, by component."""

    encoding: Encoding
    uncertainty: Uncertainty
    components: list[UncertainComponent]
    var_to_dec: dict[int, int]

    @cached_property
    def fixed(self) -> list[int]:
        """Decompositions chosen in every decomposition."""
        return fixed_decompositions(self.encoding)

    def count(self, robust: bool) -> int:
        """How many decompositions are valid whatever the facts (``robust``), or for some value
        of them; a component whose pairs were too many to list refuses (:meth:`bounds`)."""
        self.require_listed()
        return self.bounds(robust)[0]

    def bounds(self, robust: bool) -> tuple[int, int]:
        """:meth:`count` between two bounds, equal when every component was listed."""
        if not self.encoding.tasks:
            return 0, 0
        counted = [c.counted(robust) for c in self.components]
        return math.prod(low for low, _ in counted), math.prod(high for _, high in counted)

    def require_listed(self) -> None:
        """Refuse, naming the part, when a component's pairs were too many to list."""
        for c in self.components:
            if c.bounds is not None:
                raise MissionError(c.unlisted)

    def space(self, robust: bool) -> DecompositionSpace:
        """The robust (or possible) decompositions as an ordinary decomposition space, for
        listing, sampling and writing as any other."""
        self.require_listed()
        components = []
        dec_to_var = {d: v for v, d in self.var_to_dec.items()}
        for c in self.components:
            parts = [p for p in c.allowed if not robust or c.robust(p)]
            if not c.choice_vars:  # a condition on the facts alone: all or nothing
                if not parts:
                    components.append(Component([], [], solutions=[], count=0))
                continue
            solutions = sorted((frozenset(dec_to_var[d] for d in p) for p in parts), key=sorted)
            components.append(Component([], list(c.choice_vars), solutions=solutions, count=len(solutions)))
        return DecompositionSpace(self.encoding, components, self.var_to_dec)

    def parts(self, decomposition: Iterable[int]) -> list[Part]:
        """``decomposition``'s part in each component."""
        found: list[list[int]] = [[] for _ in self.components]
        for d in sorted(decomposition):
            number = self.component_of.get(d)
            if number is not None:
                found[number].append(d)
        return [tuple(part) for part in found]

    @cached_property
    def component_of(self) -> dict[int, int]:
        """Decomposition vertex -> the index of its component in :attr:`components`."""
        return {self.var_to_dec[v]: i for i, c in enumerate(self.components) for v in c.choice_vars}

    def judge(self, decomposition: Iterable[int]) -> "Judgement":
        """What the uncertain facts mean for one decomposition."""
        robust, probability, needs = True, 1.0, []
        known = self.uncertainty.with_probabilities
        for component, part in zip(self.components, self.parts(decomposition)):
            if part not in component.allowed:
                return Judgement(False, False, 0.0 if known else None, ())
            robust = robust and component.robust(part)
            p = component.probability(part)
            probability = probability * p if p is not None else probability
            needs.extend(component.assumptions(part))
        return Judgement(True, robust, probability if known else None, tuple(needs))

    def most_likely(self, costs: Mapping[int, int]) -> tuple[list[int], float]:
        """The decomposition most likely to be valid, ties broken by the least cost (``costs``
        per decomposition vertex), then by the listing order; and its probability."""
        parts, probability = self.likeliest_parts(costs)
        return sorted([*self.fixed, *(d for p in parts for d in p)]), probability

    def likeliest_parts(self, costs: Mapping[int, int]) -> tuple[list[Part], float]:
        """Each component's part most likely to be valid (the least costly among equals, then the
        first listed), and the product of their probabilities."""
        self.require_listed()
        if not self.uncertainty.with_probabilities:
            missing = next(f for f in self.uncertainty.facts if f.probabilities is None)
            raise MissionError(f"the most likely decomposition needs every fact's probabilities, and "
                               f"{missing.entry.entity}.{missing.entry.attribute} ({missing.text}) has none "
                               f"({missing.entry.where})")
        parts, probability = [], 1.0
        for c in self.components:
            if not c.allowed:
                raise MissionError("no decomposition is valid in any scenario")

            def key(p: Part, c: UncertainComponent = c) -> tuple[float, int]:  # equal as written: a tie
                return -rounded_probability(c.probability(p) or 0.0), sum(costs.get(d, 0) for d in p)
            best = min(c.allowed, key=key)  # the first of the listing order among equals
            parts.append(best)
            probability *= c.probability(best) or 0.0
        return parts, probability


@dataclass(frozen=True)
class Judgement:
    """One decomposition under the uncertain facts: valid in some scenario (``possible``), in
    every one (``robust``), its probability (None without probabilities), and the fact values
    it needs."""

    possible: bool
    robust: bool
    probability: float | None
    needs: tuple[tuple[UncertainFact, Value], ...]


def uncertain_space(stages: MissionStages) -> UncertainSpace:
    """The mission's decompositions with the scenarios that allow each (``stages.uncertainty``
    must be set)."""
    uncertainty = stages.uncertainty
    assert uncertainty is not None and not uncertainty.expanded  # those: solve/scenarios.py
    tg = stages.task_graph
    if tg.unique_branch and tg.tasks():  # (a mission of no task has no decomposition either way)
        raise MissionError("the mission is unique-branch (spec semantics.md section 7.7), whose validity the "
                           "decomposer reads straight from the world: uncertain facts are not supported there")
    by_atom = {f.atom: f for f in uncertainty.facts}
    atom_of = {atom: f.atom for f in uncertainty.facts for atom in f.atoms}
    read_by_recursion = stages.initial_state.forgotten_reads() & {a for f in uncertainty.facts if f.numeric for a in f.atoms}
    if read_by_recursion:
        fact = by_atom[atom_of[min(read_by_recursion)]]
        raise MissionError(f"{fact.entry.where}: {fact.text} is read by a recursive method to know how often it "
                           "repeats, so the task decompositions would differ from value to value: it cannot be uncertain")
    enc = Encoder(tg, stages.constraints, stages.domain, stages.goal_model, stages.config, stages.initial_state,
                  uncertain=[f.atom for f in uncertainty.facts if not f.numeric],
                  uncertain_numbers={f.atom: [float(v) for v in f.values] for f in uncertainty.facts if f.numeric},
                  uncertain_aliases={alias: f.atom for f in uncertainty.facts for alias in f.aliases}).encode()
    # each fact's variables, read as its value (a boolean's one variable; a number's choices)
    decoders = {by_atom[atom]: _Decoder((v,), (True,)) for atom, v in enc.uncertain.items()}
    decoders.update((by_atom[atom], _Decoder(choices, by_atom[atom].values))
                    for atom, choices in enc.uncertain_numbers.items())
    fact_of = {v: fact for fact, decoder in decoders.items() for v in decoder.variables}
    order = {f.atom: i for i, f in enumerate(uncertainty.facts)}
    var_to_dec = decomposition_variables(enc)
    _rule_out_impossible_scenarios(enc, uncertainty, decoders)
    kept: list[tuple[int, Component, list[UncertainFact]]] = []
    for number, comp in enumerate(split_components(enc)):
        facts = sorted({fact_of[v] for r in comp.records for v in r.variables() if v in fact_of},
                       key=lambda f: order[f.atom])
        kept.append((number, comp, facts))
    # each component solved with its facts among its choices: its (part, scenario) pairs; the
    # components that are the same up to renaming (one per forAll instance) are solved once
    pairs = [Component(comp.records, [*comp.choice_vars, *(v for f in facts for v in decoders[f].variables)],
                       solutions=comp.solutions, count=comp.count)
             for _, comp, facts in kept]
    solve_components(enc.model, [p for p in pairs if p.records], keep=True, list_limit=MAX_PAIRS)
    # a component of neither choices nor facts only constrains: kept when it rules out everything
    components = [_decided(enc, number, comp, facts, decoders, solved, var_to_dec, uncertainty.joints)
                  for (number, comp, facts), solved in zip(kept, pairs)
                  if comp.choice_vars or facts or solved.count == 0]
    return UncertainSpace(enc, uncertainty, components, var_to_dec)


def _rule_out_impossible_scenarios(enc: Encoding, uncertainty: Uncertainty,
                                   decoders: Mapping[UncertainFact, "_Decoder"]) -> None:
    """Post to the model that no scenario of probability 0 happens: a value of probability 0
    is never taken, and the facts of a joint table take one of its outcomes of positive
    probability (on the facts the domain reads).  So the listing never enumerates what cannot
    happen (a table of two outcomes over 20 facts: 2 scenarios, not 2^20), and a table's facts
    are decided together, in one component."""
    m = enc.model
    joined = {f.atom for j in uncertainty.joints for f in j.facts}
    for fact, decoder in decoders.items():
        if fact.probabilities is not None and fact.atom not in joined:
            for value, p in zip(fact.values, fact.probabilities):
                if p == 0:
                    m.clause([neg(decoder.holds(value))])
    for joint in uncertainty.joints:
        read = [i for i, f in enumerate(joint.facts) if f in decoders]
        if not read:
            continue
        combinations = sorted({tuple(outcome[i] for i in read) for outcome, p in joint.outcomes if p > 0}, key=repr)
        m.clause([m.and_of([decoders[joint.facts[i]].holds(v) for i, v in zip(read, combination)],
                           (UNCERTAIN, joint.facts[read[0]].atom, -1, ("outcome", combination)))
                  for combination in combinations])


@dataclass(frozen=True)
class _Decoder:
    """A fact's variables in a solution, read as its value: the value of the true one (a
    boolean's one variable: True when true, False when not)."""

    variables: tuple[int, ...]
    values: tuple[Value, ...]

    def value(self, solution: frozenset[int]) -> Value:
        for v, value in zip(self.variables, self.values):
            if v in solution:
                return value
        return False

    def holds(self, value: Value) -> Lit:
        """The literal true when the fact has ``value``."""
        if len(self.variables) == 1 and self.values == (True,):
            return self.variables[0] if value else neg(self.variables[0])
        return self.variables[self.values.index(value)]

    def fixed(self, value: Value) -> list[Clause]:
        """Clauses that give the fact ``value`` (and none of its other values)."""
        return [Clause((self.holds(option) if option == value else neg(self.holds(option)),)) for option in self.values]


def _decided(enc: Encoding, number: int, comp: Component, facts: Sequence[UncertainFact],
             decoders: Mapping[UncertainFact, _Decoder], solved: Component,
             var_to_dec: Mapping[int, int], joints: Sequence[Joint]) -> UncertainComponent:
    listed = _pairs(solved)
    if listed is None:
        return _bounded(enc, number, comp, facts, decoders, solved, _joints_of(facts, joints))
    component = UncertainComponent(number, tuple(facts), {}, list(comp.choice_vars), joints=_joints_of(facts, joints))
    allowed: dict[Part, set[Scenario]] = {}
    for solution in listed:
        part = tuple(sorted(var_to_dec[v] for v in solution if v in var_to_dec))
        scenario = tuple(decoders[f].value(solution) for f in facts)
        if component.can_happen(scenario):
            allowed.setdefault(part, set()).add(scenario)
    component.allowed = dict(sorted(((p, frozenset(s)) for p, s in allowed.items()), key=lambda item: item[0]))
    return component


def _bounded(enc: Encoding, number: int, comp: Component, facts: Sequence[UncertainFact],
             decoders: Mapping[UncertainFact, _Decoder], solved: Component,
             joints: Sequence[Joint]) -> UncertainComponent:
    """A component with too many (part, scenario) pairs to list, between bounds: its parts valid
    in one scenario that can happen (:func:`_likeliest`) are possible, and no other part is
    robust; the pairs, counted, bound the possible parts from above, and the robust ones too,
    divided by the scenarios (each robust part is a pair with every one)."""
    likeliest = _likeliest(facts, joints)
    likely = Component([*comp.records, *(c for f in facts for c in decoders[f].fixed(likeliest[f.atom]))],
                       list(comp.choice_vars))
    solve_components(enc.model, [likely], keep=False)
    why = (f"part {number + 1} of the mission has {solved.count} pairs of a decomposition and a scenario of its "
           f"{len(facts)} uncertain facts ({', '.join(f.text for f in facts[:4])}{', ...' if len(facts) > 4 else ''}), "
           f"more than the {MAX_PAIRS} that are listed")
    component = UncertainComponent(number, tuple(facts), {}, list(comp.choice_vars), joints=tuple(joints),
                                   unlisted=why)
    # a robust part is valid in the likeliest scenario, and is a pair with each of the scenarios
    # that can happen (the model lists no other): at most the pairs over the scenarios
    component.bounds = (likely.count, solved.count, min(likely.count, solved.count // max(component.scenarios, 1)))
    return component


def _likeliest(facts: Sequence[UncertainFact], joints: Sequence[Joint]) -> dict[AtomKey, Value]:
    """A scenario that can happen, by atom: each fact at its likeliest value (the first of the
    likeliest; its first without probabilities), the facts of a joint table at its likeliest
    outcome (their marginals' likeliest values may be a combination the table leaves out)."""
    values: dict[AtomKey, Value] = {}
    for fact in facts:
        weights = fact.probabilities or (0.0,) * len(fact.values)
        values[fact.atom] = fact.values[max(range(len(fact.values)), key=lambda i: (weights[i], -i))]
    for joint in joints:
        outcome, _ = max(joint.outcomes, key=lambda item: item[1])
        values.update((f.atom, v) for f, v in zip(joint.facts, outcome))
    return values


def _joints_of(facts: Sequence[UncertainFact], joints: Sequence[Joint]) -> tuple[Joint, ...]:
    mine = {f.atom for f in facts}
    return tuple(j for j in joints if any(f.atom in mine for f in j.facts))


def _pairs(comp: Component) -> Iterator[frozenset[int]] | list[frozenset[int]] | None:
    """Every solution of a component solved with its facts among its choices (None when they
    were more than are listed, or only counted)."""
    if comp.solutions is not None and len(comp.solutions) <= MAX_PAIRS:
        return comp.solutions
    if comp.layers is not None and comp.count <= MAX_PAIRS:
        return (frozenset(s) for s in comp.layers.solutions())
    return None


# --- what to sense first ------------------------------------------------------------------


@dataclass(frozen=True)
class Sensing:
    """What sensing would settle.  ``facts``: the smallest set of uncertain facts whose values,
    once known, leave some decomposition certainly valid whatever they turn out to be (empty
    when a robust decomposition exists already; None when no decomposition is valid in any
    scenario).  With probabilities, ``best``: the probability of the most likely decomposition
    now, and ``gains``: for each fact, the expected best probability once its value is known,
    the highest first."""

    facts: tuple[UncertainFact, ...] | None
    best: float | None
    gains: tuple[tuple[UncertainFact, float], ...]
    reason: str = ""  # why nothing settles the mission (facts None)


def sensing(space: UncertainSpace) -> Sensing:
    """Component by component (they share no fact): the smallest set of facts that settles
    each, and the expected gain of sensing each fact."""
    space.require_listed()
    for c in space.components:
        if len(c.facts) > MAX_FACTS:
            raise MissionError(f"part {c.number + 1} of the mission reads {len(c.facts)} uncertain facts "
                               f"({', '.join(f.text for f in c.facts[:4])}, ...): the sets of them to sense are "
                               f"searched up to {MAX_FACTS} facts a part")
    chosen: list[UncertainFact] | None = []
    reason = ""
    for c in space.components:
        settled = _smallest_settling(c)
        if settled is None:
            hopeless = next((s for s in scenarios(c.facts)
                             if c.can_happen(s) and not any(s in allowed for allowed in c.allowed.values())), ())
            values = ", ".join(f.shown(v) for f, v in zip(c.facts, hopeless)) or "whatever the facts are"
            chosen, reason = None, f"no decomposition is valid when {values}: sensing cannot settle the mission"
            break
        assert chosen is not None
        chosen.extend(settled)
    facts = None if chosen is None else tuple(chosen)
    if not space.uncertainty.with_probabilities:
        return Sensing(facts, None, (), reason)
    bests = [max((c.probability(p) or 0.0 for p in c.allowed), default=0.0) for c in space.components]
    best = math.prod(bests)
    # the product of the other components' bests, from running products both ways
    before = list(itertools.accumulate(bests[:-1], operator.mul, initial=1.0))
    after = list(itertools.accumulate(reversed(bests[1:]), operator.mul, initial=1.0))[::-1]
    gains = []
    for number, c in enumerate(space.components):
        others = before[number] * after[number]
        for i, fact in enumerate(c.facts):
            expected = math.fsum(max((math.fsum(c.scenario_probability(s) for s in c.allowed[p] if s[i] == value)
                                      for p in c.allowed), default=0.0) for value in fact.values)
            gains.append((fact, expected * others))
    order = {f.atom: i for i, f in enumerate(space.uncertainty.facts)}
    gains.sort(key=lambda item: (-rounded_probability(item[1]), order[item[0].atom]))
    return Sensing(facts, best, tuple(gains), reason)


def _smallest_settling(c: UncertainComponent) -> tuple[UncertainFact, ...] | None:
    """The fewest of ``c``'s facts (the first such set in fact order) such that for every value
    they take, some part is allowed by every scenario with those values; None when no part is
    allowed in some scenario (then no set does)."""
    k = len(c.facts)
    every = [s for s in scenarios(c.facts) if c.can_happen(s)]
    for size in range(k + 1):
        for subset in itertools.combinations(range(k), size):
            def settled(values: tuple[Value, ...]) -> bool:
                consistent = {s for s in every if all(s[i] == v for i, v in zip(subset, values))}
                return any(consistent <= allowed for allowed in c.allowed.values())
            if all(settled(values) for values in itertools.product(*(c.facts[i].values for i in subset))):
                return tuple(c.facts[i] for i in subset)
    return None


def scenarios(facts: Sequence[UncertainFact]) -> Iterator[Scenario]:
    """Every scenario of ``facts``, in order (each fact's values in its order: false first)."""
    return itertools.product(*(f.values for f in facts))


__all__ = ["AtomKey", "Judgement", "Sensing", "UncertainComponent", "UncertainSpace", "scenarios", "sensing",
           "uncertain_space"]
