"""Every kind of atom decided by verify (solve/verify.py, solve/property_grounding.py) against
brute force: each decomposition the exploratory algorithm lists, evaluated one by one from its
task decompositions, the constraint order and the world, for each value of ``?rm``."""
from __future__ import annotations

import operator
import os
import sys
from typing import Iterable

import networkx as nx
import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from mutrose_cp.errors import MissionError, NoDecompositionError
from mutrose_cp.io.properties import command_line_properties
from mutrose_cp.mission import Mission
from mutrose_cp.model.domain import Literal
from mutrose_cp.solve.semantics import EffectScopes
from mutrose_cp.solve.property_grounding import ground
from conftest import ROOT, require_reference
from missiongen import load_mission, missions
from test_verify import hospital

sys.path.insert(0, str(ROOT / "benchmarks"))
from generate import generate  # noqa: E402

EXAMPLES = int(os.environ.get("MUTROSE_VERIFY_EXAMPLES", "60"))
COMPARE = {">=": operator.ge, "<=": operator.le, "==": operator.eq, "!=": operator.ne, ">": operator.gt, "<": operator.lt}


class BruteForce:
    """One mission's listed decompositions and what each does, read without the verifier."""

    def __init__(self, mission: Mission) -> None:
        self.mission = mission
        self.tg = mission.task_graph
        try:
            self.listed = [sorted(d) for d in mission.exploratory()]
        except NoDecompositionError:
            self.listed = []
        graph = nx.DiGraph([(c.first, c.second) for c in mission.constraints if c.kind in ("SEQ", "FB")])
        self.order = nx.transitive_closure_dag(graph)
        self.scopes = EffectScopes(self.tg)

    def instance(self, v: int):
        return self.tg.decomposition(v).decomposition.instance

    def room(self, v: int) -> str | None:
        return {p.hddl_param: str(p.value) for p in self.instance(v).parameters}.get("?rm")

    def matches(self, v: int, task: str, room: str | None) -> bool:
        return self.instance(v).name == task and (room is None or self.room(v) == room)

    def final(self, chosen: Iterable[int]) -> dict[tuple[str, tuple[str, ...]], bool]:
        facts = dict(self.mission.initial_state.fact_map())
        for v in sorted(chosen):
            for e in self.tg.decomposition(v).decomposition.predicates.effects:
                if not any(a.startswith("?") for a in e.args):
                    facts[(e.predicate, e.args)] = e.positive
        return facts

    def writes(self, v: int, atom) -> bool:
        return any((e.predicate, e.args) == atom for e in self.tg.decomposition(v).decomposition.predicates.effects)

    def needed(self, chosen: list[int], atom, positive: bool) -> bool:
        for v in chosen:
            d = self.tg.decomposition(v).decomposition
            if any(isinstance(c, Literal) and (c.predicate, c.args) == atom and c.positive == positive
                   for c in d.predicates.checked_preconditions):
                seen = self.scopes.seen_by_task(self.tg.vertices[v].parent)
                if not any(self.writes(w, atom) for w in chosen if w in seen):
                    return True
        return False

    def atom(self, atom: tuple, chosen: list[int], room: str | None) -> bool:
        kind, where = atom[0], room if atom[-1] == "?rm" else atom[-1]
        if kind == "uses":
            return any(self.matches(v, atom[1], where) for v in chosen)
        if kind == "before":
            firsts = [v for v in chosen if self.matches(v, atom[1], where)]
            seconds = [v for v in chosen if self.matches(v, atom[2], where)]
            return all(self.order.has_edge(a, b) for a in firsts for b in seconds if a != b)
        if kind == "robots":
            numbers = [self.instance(v).robot_number for v in chosen if self.matches(v, atom[1], None)]
            return all(COMPARE[atom[2]](n, atom[3]) for r in numbers for n in range(r.min, r.max + 1))
        predicate, positive = atom[1], atom[2]
        if kind == "finally":
            return self.final(chosen).get((predicate, (where,)), False) == positive
        assert kind == "needed"
        return self.needed(chosen, (predicate, (where,)), positive)

    def holds(self, formula, chosen: list[int], room: str | None) -> bool:
        op = formula[0]
        if op == "not":
            return not self.holds(formula[1], chosen, room)
        if op in ("and", "or", "implies"):
            a, b = self.holds(formula[1], chosen, room), self.holds(formula[2], chosen, room)
            return (a and b) if op == "and" else (a or b) if op == "or" else (not a or b)
        return self.atom(formula, chosen, room)

    def rooms(self, formula) -> list[str | None]:
        """The values ``?rm`` takes: the rooms of the instances its task patterns match."""
        tasks = set(_tasks_with_room(formula))
        if not tasks and not _mentions_room(formula):
            return [None]
        return sorted({r for v in self.tg_decompositions() if self.instance(v).name in tasks
                       if (r := self.room(v)) is not None})

    def tg_decompositions(self) -> list[int]:
        return [d.index for d in self.tg.decompositions()]

    def verdict(self, quantifier: str, formula) -> tuple[str, int, int]:
        if not self.listed:
            return "vacuous", 0, 0
        rooms = self.rooms(formula)
        count = sum(all(self.holds(formula, d, r) for r in rooms) for d in self.listed)
        status = {"count": "count", "always": "holds" if count == len(self.listed) else "fails",
                  "never": "holds" if count == 0 else "fails", "some": "holds" if count else "fails"}[quantifier]
        return status, count, len(self.listed)


def _tasks_with_room(formula) -> Iterable[str]:
    if formula[0] in ("not",):
        yield from _tasks_with_room(formula[1])
    elif formula[0] in ("and", "or", "implies"):
        yield from _tasks_with_room(formula[1])
        yield from _tasks_with_room(formula[2])
    elif formula[0] in ("uses", "before") and formula[-1] == "?rm":
        yield from formula[1:3] if formula[0] == "before" else formula[1:2]


def _mentions_room(formula) -> bool:
    return "?rm" in repr(formula)


def text(formula) -> str:
    op = formula[0]
    if op == "not":
        return f"not {text(formula[1])}"
    if op in ("and", "or", "implies"):
        return f"({text(formula[1])} {op} {text(formula[2])})"
    if op == "uses":
        return f"uses(task {formula[1]}(?a, {formula[2]}))"
    if op == "before":
        return f"before(task {formula[1]}(?a, {formula[3]}), task {formula[2]}(?b, {formula[3]}))"
    if op == "robots":
        return f"robots(task {formula[1]}) {formula[2]} {formula[3]}"
    fact = f"{'' if formula[2] else 'not '}{formula[1]}({formula[3]})"
    return f"finally({fact})" if op == "finally" else f"initially-needed({fact})"


def atoms_of(mission: Mission, room_variable: bool):
    """Atom strategies over the mission's tasks, rooms and predicates."""
    brute = BruteForce(mission)
    tasks = sorted({brute.instance(v).name for v in brute.tg_decompositions()}) or ["TaskA"]
    rooms = sorted({r for v in brute.tg_decompositions() if (r := brute.room(v))} ) or ["Room1"]
    predicates = sorted(p.name for p in mission.domain.predicates if [q.type for q in p.parameters] == ["room"])
    where = st.sampled_from(["?rm", *rooms] if room_variable else rooms)
    task = st.sampled_from(tasks)
    kinds = [st.tuples(st.just("uses"), task, where),
             st.tuples(st.just("before"), task, task, where),
             st.tuples(st.just("robots"), task, st.sampled_from(sorted(COMPARE)), st.integers(1, 3))]
    if predicates:
        kinds += [st.tuples(st.just(kind), st.sampled_from(predicates), st.booleans(), where)
                  for kind in ("finally", "needed")]
    return st.one_of(kinds)


_HOSPITAL: list[Mission] = []


def bundled() -> Mission:
    if not _HOSPITAL:
        _HOSPITAL.append(hospital())
    return _HOSPITAL[0]


@st.composite
def cases(draw):
    """A formula over the bundled example (36 decompositions, every atom kind meaningful) or
    over a generated mission."""
    mission = bundled() if draw(st.booleans()) else load_mission(draw(missions()))
    atom = atoms_of(mission, room_variable=True)
    formula = draw(st.recursive(atom, lambda inner: st.one_of(
        st.tuples(st.just("not"), inner),
        st.tuples(st.sampled_from(["and", "or", "implies"]), inner, inner)), max_leaves=4))
    return mission, draw(st.sampled_from(["always", "some", "never", "count"])), formula


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(cases())
def test_every_atom_kind_agrees_with_brute_force(case):
    mission, quantifier, formula = case
    assume(0 < mission.decomposition_space().count <= 2000)  # vacuous missions: test_verify.py
    prop = command_line_properties([f"{quantifier} {text(formula)}"])[0]
    try:
        found = mission.verify(prop)
    except MissionError as refused:  # only a fact whose ?rm no task pattern binds is refused
        assert "takes no value" in str(refused) and "?rm" in text(formula), str(refused)
        return
    brute = BruteForce(mission)
    assert (found.status, found.count, found.total) == brute.verdict(quantifier, formula), prop.text
    if found.witness is not None:
        witness = sorted(found.witness)
        assert witness in brute.listed
        shown = all(brute.holds(formula, witness, r) for r in brute.rooms(formula))
        assert shown == (quantifier != "always"), prop.text


def test_hospital_facts_agree_with_brute_force():
    """``finally`` and ``initially-needed`` on the bundled example, each room and polarity."""
    mission = hospital()
    brute = BruteForce(mission)
    for predicate in ("door-open", "disinfected", "cleared", "occupied", "loaded"):
        for room in ("Room101", "Room102", "Room104"):
            for positive in (True, False):
                for kind in ("finally", "needed"):
                    formula = (kind, predicate, positive, room)
                    if predicate == "loaded":
                        continue
                    prop = command_line_properties([f"count {text(formula)}"])[0]
                    found = mission.verify(prop)
                    assert (found.status, found.count, found.total) == brute.verdict("count", formula), prop.text
    # the door of Room104 is unknown, so only the decompositions that open it leave it open
    opened = mission.verify(command_line_properties(["count finally(door-open(Room104))"])[0])
    assert 0 < opened.count < opened.total


@settings(max_examples=max(10, EXAMPLES // 3), deadline=None, suppress_health_check=list(HealthCheck))
@given(missions(shape="long_sequence"))
def test_facts_written_in_sequence_agree_with_brute_force(spec):
    """Long sequences set, unset and test one room predicate many times over: ``finally`` reads
    the last writer chosen, ``initially-needed`` a test that no earlier chosen writer answers."""
    mission = load_mission(spec)
    brute = BruteForce(mission)
    assume(brute.listed and mission.decomposition_space().count <= 2000)
    rooms = sorted({r for v in brute.tg_decompositions() if (r := brute.room(v))})
    for predicate in sorted(p.name for p in mission.domain.predicates if [q.type for q in p.parameters] == ["room"]):
        for room in rooms:
            for positive in (True, False):
                for kind in ("finally", "needed"):
                    formula = (kind, predicate, positive, room)
                    found = mission.verify(command_line_properties([f"count {text(formula)}"])[0])
                    assert (found.status, found.count, found.total) == brute.verdict("count", formula), text(formula)


@pytest.mark.parametrize(("family", "n", "texts"), [
    ("coupled-sequence", 5, ["count uses(method food-pickup-mark)", "count finally(busy(Kitchen))",
                             "count finally(not busy(Kitchen))", "count initially-needed(not busy(Kitchen))"]),
    ("coupled", 3, ["count uses(method food-pickup-mark) and not uses(method food-pickup-free)",
                    "count finally(busy(Kitchen))", "count initially-needed(not busy(Kitchen))"]),
    ("vital-signs", 2, ["count before(task EnterRoom(?r, ?rm), task ApproachPatient(?s, ?rm, ?p))",
                        "count before(task ApproachPatient(?s, ?rm, ?p), task CollectVitalSigns(?t, ?rm, ?p))",
                        "count uses(method unavailable-patient-approach)"]),
])
def test_generated_families_agree_with_the_listed_decompositions(tmp_path, family, n, texts):
    """The benchmark families at sizes small enough to list: a coupled sequence (one layered
    component, folded by verify's forward pass), coupled deliveries, and two variables bound
    together (each room's patients), against each decomposition the exploratory algorithm lists."""
    require_reference()
    mission = Mission.load(*generate(family, n, tmp_path))
    listed = [sorted(d) for d in mission.exploratory()]
    for text in texts:
        prop = command_line_properties([text])[0]
        found = mission.verify(prop)
        grounded = ground(prop, mission.task_graph, mission.domain, mission.constraints, mission.initial_state)
        expected = sum(_holds(grounded, set(d)) for d in listed)
        assert (found.count, found.total) == (expected, len(listed)), text
    if family == "coupled-sequence":
        assert any(c.layers is not None for c in mission.decomposition_space().components)


def _holds(grounded, chosen: set[int]) -> bool:
    """A grounded formula on one listed decomposition (the grounding is read, the folding is not)."""
    def value(f) -> bool:
        if isinstance(f, int):
            return not grounded.atoms[f].isdisjoint(chosen)
        op, operands = f
        return (not value(operands[0]) if op == "not" else all(map(value, operands)) if op == "and"
                else any(map(value, operands)))
    return value(grounded.formula)
