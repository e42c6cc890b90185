"""Decompositions in a world that is not fully known (solve/uncertain.py), against brute force:
the world file rewritten once per scenario (every uncertain fact given a value), each world
decomposed as today, and robust / possible / probability read off the listed decompositions."""
from __future__ import annotations

import itertools
import json
import math
import os
import shutil
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st
from lxml import etree

from mutrose_cp.errors import MissionError
from mutrose_cp.mission import Mission
from mutrose_cp.pipeline.uncertain_facts import goal_model_reads
from mutrose_cp.model.uncertainty import UncertainEntry, UncertainFact
from mutrose_cp.solve.scenarios import ExpandedSpace, component_key, decided_space, split_shared
from mutrose_cp.solve.uncertain import UncertainComponent, sensing, uncertain_space
from conftest import ROOT, require_reference
from missiongen import MissionSpec, missions

sys.path.insert(0, str(ROOT / "benchmarks"))
from generate import generate  # noqa: E402

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "hospital-disinfection"
EXAMPLES = int(os.environ.get("MUTROSE_UNCERTAIN_EXAMPLES", "40"))

# entity, attribute, and P(true) or None (a boolean), or a number's {value: probability} or
# [values]
Entry = tuple[str, str, "float | None | dict[float, float] | list[float]"]


def entry_values(spec) -> tuple[tuple, tuple | None]:
    """The values an entry's fact may take, and their probabilities (None: not given)."""
    if isinstance(spec, dict):
        return tuple(spec), tuple(spec.values())
    if isinstance(spec, list):
        return tuple(spec), None
    return (False, True), None if spec is None else (1 - spec, spec)


def mission_files(folder: Path) -> tuple[Path, Path, Path]:
    return tuple(next((folder / d).iterdir()) for d in ("hddl", "gm", "configuration"))  # type: ignore[return-value]


def write_uncertainty(path: Path, entries: list[Entry]) -> Path:
    def given(spec) -> dict:
        if isinstance(spec, dict):
            return {"distribution": {f"{v:g}": p for v, p in spec.items()}}
        if isinstance(spec, list):
            return {"values": spec}
        return {} if spec is None else {"probability": spec}
    listed = [{"entity": e, "attribute": a, **given(spec)} for e, a, spec in entries]
    path.write_text(json.dumps({"uncertain": listed}))
    return path


def rewrite_world(world: Path, values: dict[tuple[str, str], bool | float], out: Path) -> None:
    """``world`` with each (entity, attribute) set to its value, written to ``out``."""
    tree = etree.parse(str(world))
    for (entity, attribute), value in values.items():
        records = [el for el in tree.getroot().iter() if el.findtext("name") == entity]
        assert records, entity
        for record in records:  # the entity wherever the world describes it
            field = record.find(attribute)
            if field is None:
                field = etree.SubElement(record, attribute)
            field.text = (("True" if value else "False") if isinstance(value, bool)
                          else str(int(value)) if float(value).is_integer() else str(value))
    tree.write(str(out))


def ids(mission, decomposition) -> frozenset[str]:
    tg = mission.task_graph if isinstance(mission, Mission) else mission
    return frozenset(tg.decomposition(v).decomposition.id for v in decomposition)


def content_keys(tg) -> dict[int, tuple]:
    """Each task decomposition by what it does, not by its task id: its goal-model task, HDDL
    task, location, variable values, method path and actions, and which of equal ones it is (a task whose
    variable values do not tell its forAll copies apart has twins)."""
    seen: dict[tuple, int] = {}
    keys = {}
    for vertex in tg.decompositions():
        d = vertex.decomposition
        i = d.instance
        key = (i.gm_task, i.name, str(i.location), tuple((p.hddl_param, str(p.value)) for p in i.parameters), d.number,
               tuple(a.name for a in d.path.actions))
        seen[key] = seen.get(key, 0) + 1
        keys[vertex.index] = (*key, seen[key])
    return keys


def content(tg, decomposition) -> frozenset[tuple]:
    """A decomposition by content (:func:`content_keys`)."""
    keys = content_keys(tg)
    return frozenset(keys[v] for v in decomposition)


class BruteForce:
    """Each scenario's world decomposed as today: the valid decompositions by id, and each
    scenario's probability."""

    def __init__(self, hddl: Path, gm: Path, config: Path, world: Path, entries: list[Entry],
                 joint: tuple[tuple[int, ...], dict[tuple, float]] | None = None, identity=None) -> None:
        """``joint``: the entries (by index) of one joint table, and its outcomes' probabilities
        (those entries' own specs are ignored).  ``identity``: a decomposition's identity
        (its task decompositions' ids; by content when the worlds expand differently)."""
        identity = identity or ids
        self.valid: list[tuple[float | None, set[frozenset[str]]]] = []
        self.options = [entry_values(spec) for _, _, spec in entries]
        every = list(itertools.product(*(values for values, _ in self.options)))
        self.scenarios = []
        original = world.read_bytes()
        try:
            for values in every:
                # the scenario's probability (None when a fact has none), and whether it can
                # happen: no value of probability 0, whatever the facts without probabilities
                factors: list[float | None] = [
                    None if probabilities is None else probabilities[options.index(value)]
                    for i, ((options, probabilities), value) in enumerate(zip(self.options, values))
                    if joint is None or i not in joint[0]]
                if joint is not None:
                    factors.append(joint[1].get(tuple(values[i] for i in joint[0]), 0.0))
                if any(q == 0 for q in factors):
                    continue  # a scenario that cannot happen
                p = None if None in factors else math.prod(q for q in factors if q is not None)
                self.scenarios.append(values)
                world.write_bytes(original)
                rewrite_world(world, {(e, a): v for (e, a, _), v in zip(entries, values)}, world)
                mission = Mission.load(hddl, gm, config)
                listed = ({identity(mission.task_graph, d) for d in mission.decomposition_space()}
                          if mission.task_graph.tasks() else set())
                self.valid.append((p, listed))
        finally:
            world.write_bytes(original)

    @property
    def possible(self) -> set[frozenset[str]]:
        return set().union(*(v for _, v in self.valid))

    @property
    def robust(self) -> set[frozenset[str]]:
        return set.intersection(*(v for _, v in self.valid)) if self.valid else set()

    def settling_sets(self) -> list[frozenset[int]]:
        """Every set of facts (by index) whose values, once known, leave some decomposition
        valid in every scenario with those values."""
        k = len(self.scenarios[0]) if self.scenarios else 0
        found = []
        for size in range(k + 1):
            for subset in itertools.combinations(range(k), size):
                def settled(values: tuple) -> bool:
                    valid = [v for (_, v), s in zip(self.valid, self.scenarios)
                             if all(s[i] == x for i, x in zip(subset, values))]
                    return bool(set.intersection(*valid)) if valid else True
                if all(settled(values) for values in itertools.product(*(self.options[i][0] for i in subset))):
                    found.append(frozenset(subset))
        return found

    def expected_best(self, fact: int) -> float:
        """The best probability of a decomposition expected once fact ``fact`` is known."""
        total = 0.0
        for value in self.options[fact][0]:
            candidates = self.possible or {frozenset()}
            total += max(math.fsum(p for (p, v), s in zip(self.valid, self.scenarios) if s[fact] == value and d in v)
                         for d in candidates)
        return total

    def probability(self, decomposition: frozenset[str]) -> float | None:
        if any(p is None for p, _ in self.valid):
            return None
        return math.fsum(p for p, v in self.valid if decomposition in v)  # type: ignore[misc]


def agree_judgement(mission: Mission, brute: BruteForce, key, judged) -> None:
    """One possible decomposition's judgement against the brute force: robust, probability, and
    the values it needs (every scenario that allows it gives the fact that value)."""
    assert judged.possible and judged.robust == (key in brute.robust)
    expected = brute.probability(key)
    assert (judged.probability is None) == (expected is None)
    if expected is not None:
        assert judged.probability == pytest.approx(expected, abs=1e-12)
    for fact, value in judged.needs:
        index = mission.uncertainty.facts.index(fact)
        assert all(values[index] == value for (_, valid), values in zip(brute.valid, brute.scenarios) if key in valid)


def agree_sensing(mission: Mission, brute: BruteForce, space):
    """The facts to sense first: a smallest set that settles the mission, or none when no set does."""
    plan = sensing(space)
    settles = brute.settling_sets()
    if plan.facts is None:
        assert not settles
    else:
        chosen = frozenset(mission.uncertainty.facts.index(f) for f in plan.facts)
        assert chosen in settles and len(chosen) == min(len(s) for s in settles)
    return plan


def agree(mission: Mission, brute: BruteForce) -> None:
    """Every answer of the uncertain space against the brute force."""
    space = uncertain_space(mission)
    assert space.count(robust=False) == len(brute.possible)
    assert space.count(robust=True) == len(brute.robust)
    listed = {ids(mission, d): d for d in space.space(robust=False)}
    assert set(listed) == brute.possible
    assert {ids(mission, d) for d in space.space(robust=True)} == brute.robust
    for key, decomposition in listed.items():
        agree_judgement(mission, brute, key, space.judge(decomposition))
    plan = agree_sensing(mission, brute, space)
    if mission.uncertainty.with_probabilities:
        assert plan.best == pytest.approx(max((brute.probability(k) or 0 for k in brute.possible), default=0), abs=1e-12)
        expected = {mission.uncertainty.facts[i].text: brute.expected_best(i) for i in range(len(brute.scenarios[0]))}
        for fact, gain in plan.gains:
            assert gain == pytest.approx(expected[fact.text], abs=1e-12), fact.text
    if mission.uncertainty.with_probabilities and brute.possible:
        best, probability = space.most_likely({})
        assert probability == pytest.approx(max(brute.probability(k) or 0 for k in brute.possible), abs=1e-12)
        assert probability == pytest.approx(brute.probability(ids(mission, best)) or 0, abs=1e-12)


def test_hospital_doors_against_brute_force(tmp_path):
    """The bundled example with its two doors uncertain (one the world gives, one it omits)."""
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder)
    hddl, gm, config = mission_files(folder)
    world = next((folder / "knowledge").iterdir())
    for entries in ([("Room104", "door_open", 0.5), ("Room102", "door_open", 0.2)],
                    [("Room104", "door_open", None)],
                    [("Room101", "occupied", 0.1), ("Room102", "door_open", 0.7), ("Room104", "door_open", 0.4)]):
        brute = BruteForce(hddl, gm, config, world, entries)
        mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(tmp_path / "u.json", entries))
        agree(mission, brute)


@st.composite
def uncertain_missions(draw):
    """A generated mission and 1-8 of its room facts made uncertain (attributes the goal model
    does not read), some with a probability."""
    spec: MissionSpec = draw(missions())
    return spec, draw(st.randoms(use_true_random=False))


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(uncertain_missions())
def test_generated_missions_against_brute_force(tmp_path_factory, case):
    spec, rnd = case
    folder = tmp_path_factory.mktemp("mission")
    hddl, gm, config = spec.write(folder)
    world = folder / "knowledge" / "world_db.xml"
    mission = Mission.load(hddl, gm, config)
    assume(mission.task_graph.tasks() and mission.decomposition_space().count <= 500)
    read = dict(goal_model_reads(mission.goal_model))
    attributes = sorted((m.name, m.mapped_type) for m in mission.config.semantic_mapping
                        if m.type == "attribute" and m.mapped_type in ("predicate", "function") and m.name not in read
                        and m.relates_to == "Room")
    rooms = sorted(mission.initial_state.sorts.get("room", ()))
    candidates = [(r, a, kind) for r in rooms for a, kind in attributes]
    assume(candidates)
    chosen = rnd.sample(candidates, min(len(candidates), rnd.randint(1, 8)))
    # every fact with probabilities, some, or none; a value of probability 0 (a fact certain
    # after all) rules its scenarios out, with or without the other facts' probabilities
    mode = rnd.choice(["all", "all", "some", "none"])

    def spec(kind: str):  # a boolean's P(true), or a number's values (levels 0-2), some with probabilities
        with_probabilities = mode == "all" or (mode == "some" and rnd.random() < 0.5)
        if kind == "predicate":
            return rnd.choice([0.0, 0.1, 0.25, 0.5, 0.9, 1.0]) if with_probabilities else None
        values = rnd.sample([0.0, 1.0, 2.0], rnd.randint(2, 3))
        weights = rnd.choice([[0.5, 0.5], [0.0, 1.0]] if len(values) == 2 else [[0.2, 0.3, 0.5], [0.4, 0.0, 0.6]])
        return dict(zip(values, weights)) if with_probabilities else values
    entries = [(r, a, spec(kind)) for r, a, kind in chosen]
    brute = BruteForce(hddl, gm, config, world, entries)
    try:
        mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(folder / "u.json", entries))
        agree(mission, brute)
    except MissionError as refused:  # only what the decomposer reads straight from the world
        assert "unique-branch" in str(refused) or "read by a recursive method" in str(refused), str(refused)


@pytest.mark.parametrize(("family", "n", "attribute", "entities"), [
    ("delivery", 8, "can_fetch", ["Patient2", "Patient5", "Patient7"]),  # the other copies are replayed
    ("coupled", 2, "can_fetch", ["Patient1", "Patient2"]),
    ("vital-signs", 2, "available", ["Patient1", "Patient2", "Patient4"]),
])
def test_benchmark_families_against_brute_force(tmp_path, family, n, attribute, entities):
    """The benchmark families, whose forAll copies the encoder otherwise replays from one
    another: one uncertain fact per delivery (or patient), each with its probability."""
    require_reference()
    hddl, gm, config = generate(family, n, tmp_path)
    world = next(tmp_path.glob("*.xml"))
    entries = [(e, attribute, p) for e, p in zip(entities, (0.8, 0.3, 0.6))]
    brute = BruteForce(hddl, gm, config, world, entries)
    mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(tmp_path / "u.json", entries))
    assert brute.possible != brute.robust  # the facts matter
    agree(mission, brute)


def test_components_past_the_listing_limit_are_answered_with_bounds(tmp_path, monkeypatch, capsys):
    """With fewer pairs listed than a component has, its counts are bounds that hold the exact
    answers, said so; what needs every pair (listing, sensing) refuses, naming the part."""
    from mutrose_cp.cli.program import main
    from mutrose_cp.errors import MissionError as Refused
    from mutrose_cp.solve import uncertain

    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder)
    hddl, gm, config = mission_files(folder)
    world = next((folder / "knowledge").iterdir())
    entries = [("Room101", "occupied", 0.1), ("Room102", "door_open", 0.7), ("Room104", "door_open", 0.4)]
    brute = BruteForce(hddl, gm, config, world, entries)
    path = write_uncertainty(tmp_path / "u.json", entries)
    monkeypatch.setattr(uncertain, "MAX_PAIRS", 3)
    space = uncertain_space(Mission.load(hddl, gm, config, uncertainty=path))
    assert any(c.bounds is not None for c in space.components)
    for robust, exact in ((False, len(brute.possible)), (True, len(brute.robust))):
        low, high = space.bounds(robust)
        assert low <= exact <= high
    assert space.bounds(False)[0] < space.bounds(False)[1]  # bounds, not an exact count
    for ask in (lambda: space.count(robust=False), lambda: space.space(robust=True), lambda: sensing(space)):
        with pytest.raises(Refused, match="pairs of a decomposition and a scenario of its"):
            ask()
    assert main(["count", str(folder), "--uncertain", str(path)]) == 0
    out, err = capsys.readouterr()
    low, high = space.bounds(False)
    assert out.splitlines()[-1] == f"{low}..{high}" and "bounds, not exact counts: part" in err


def test_an_uncertain_number_read_after_an_increase(tmp_path):
    """An uncertain number (Room201's stock of doses: 0, 1 or 2) that the robot increases on
    entering, and that the hand-over's methods test afterwards: its start value goes through
    the chain of values, not only through tests of the start."""
    folder = tmp_path / "mission"
    shutil.copytree(ROOT / "examples" / "medication-round", folder)
    config = folder / "configuration" / "configuration.json"
    data = json.loads(config.read_text())
    data["semantic_mapping"].append({"type": "attribute", "name": "stock", "relates_to": "Room", "belongs_to": "world_db",
                                     "mapped_type": "function", "map": {"pred": "doses", "arg_sorts": ["room"]}})
    del data["uncertainty"]
    config.write_text(json.dumps(data, indent=1))
    hddl = folder / "hddl" / "medication-round.hddl"
    text = hddl.read_text().replace("    (:capabilities", "    (:functions (doses ?rm - room))\n\n    (:capabilities")
    text = text.replace('''        :effect ()
    )
    (:action call-nurse-to-unlock''', '''        :effect (and
            (increase (doses ?rm) 1)
        )
    )
    (:action call-nurse-to-unlock''')
    text = text.replace('''        :precondition (and
            (patient-present ?rm)
        )
        :ordered-subtasks (and
            (give-dose ?r ?rm)
        )
    )''', '''        :precondition (and
            (patient-present ?rm)
            (> (doses ?rm) 1)
        )
        :ordered-subtasks (and
            (give-dose ?r ?rm)
        )
    )
    (:method hand-from-the-last-dose
        :parameters (?r - NurseRobot ?rm - room)
        :task (HandOverDose ?r ?rm)
        :precondition (and
            (patient-present ?rm)
            (= (doses ?rm) 1)
        )
        :ordered-subtasks (and
            (give-dose ?r ?rm)
        )
    )''')
    hddl.write_text(text)
    world = folder / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace("<is_served>False</is_served>", "<is_served>False</is_served><stock>1</stock>"))
    hddl_path, gm, config_path = mission_files(folder)
    entries = [("Room201", "stock", {0.0: 0.5, 1.0: 0.3, 2.0: 0.2}), ("Room203", "patient_present", 0.6)]
    brute = BruteForce(hddl_path, gm, config_path, world, entries)
    assert len({frozenset(v) for _, v in brute.valid}) > 2  # the stock decides the method
    mission = Mission.load(hddl_path, gm, config_path, uncertainty=write_uncertainty(tmp_path / "u.json", entries))
    agree(mission, brute)


def test_facts_that_are_not_independent(tmp_path):
    """Two doors read by one sensor: open together or closed together (a joint table), beside an
    independent fact; a combination the table leaves out cannot happen."""
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder)
    hddl, gm, config = mission_files(folder)
    world = next((folder / "knowledge").iterdir())
    entries = [("Room102", "door_open", None), ("Room104", "door_open", None), ("Room101", "occupied", 0.1)]
    table = {(True, True): 0.7, (False, False): 0.3}
    brute = BruteForce(hddl, gm, config, world, entries, ((0, 1), table))
    assert len(brute.scenarios) == 4  # 2 of the 4 door combinations, times the patient's 2
    path = tmp_path / "u.json"
    path.write_text(json.dumps({
        "uncertain": [{"entity": e, "attribute": a, **({} if p is None else {"probability": p})} for e, a, p in entries],
        "joint": [{"facts": [{"entity": "Room102", "attribute": "door_open"}, {"entity": "Room104", "attribute": "door_open"}],
                   "outcomes": [{"values": list(v), "probability": p} for v, p in table.items()]}]}))
    mission = Mission.load(hddl, gm, config, uncertainty=path)
    assert mission.uncertainty.facts[0].probabilities == pytest.approx((0.3, 0.7))  # the table's marginal
    agree(mission, brute)
    joined = [c for c in uncertain_space(mission).components if len(c.facts) > 1]
    assert joined and {f.text for f in joined[0].facts} >= {"door-open(Room102)", "door-open(Room104)"}


def agree_expanded(mission: Mission, brute: BruteForce) -> None:
    """Every answer where the goal model reads uncertain facts, against the brute force by
    content: counts, the robust listing, each possible decomposition's judgement (in a world
    where it exists), the most likely one, and what to sense."""
    space = decided_space(mission)
    assert isinstance(space, ExpandedSpace)
    assert space.count(robust=False) == len(brute.possible)
    assert space.count(robust=True) == len(brute.robust)
    if brute.robust:
        frame = space.frame_world.stages.task_graph
        assert {content(frame, d) for d in space.space(robust=True)} == brute.robust
    else:
        assert space.space(robust=True).count == 0
    worlds = [(i, {k: d for d, k in content_keys(w.stages.task_graph).items()})
              for i, w in enumerate(space.worlds) if w.live]
    for key in brute.possible:
        i, by_content = next((i, keys) for i, keys in worlds if set(keys) >= key)
        space.frame = i
        agree_judgement(mission, brute, key, space.judge([by_content[k] for k in key]))
    plan = agree_sensing(mission, brute, space)
    if mission.uncertainty.with_probabilities and brute.possible:
        best_probability = max(brute.probability(k) or 0 for k in brute.possible)
        assert plan.best == pytest.approx(best_probability, abs=1e-12)
        expected = {mission.uncertainty.facts[i].text: brute.expected_best(i) for i in range(len(brute.scenarios[0]))}
        for fact, gain in plan.gains:
            assert gain == pytest.approx(expected[fact.text], abs=1e-12), fact.text
        best, probability = space.most_likely({})
        assert probability == pytest.approx(best_probability, abs=1e-12)
        frame = space.frame_world.stages.task_graph
        assert brute.probability(content(frame, best)) == pytest.approx(probability, abs=1e-12)


@pytest.mark.parametrize("entries", [
    [("Room101", "needs_disinfection", 0.3)],
    [("Room101", "needs_disinfection", 0.3), ("Room104", "door_open", 0.5)],
    [("Room104", "needs_disinfection", None), ("Room102", "door_open", None)],
    [("Room101", "needs_disinfection", 0.6), ("Room103", "needs_disinfection", 0.5), ("Room101", "occupied", 0.2),
     ("Room104", "door_open", 0.4)],
    [("Room102", "is_disinfected", 0.5), ("Room102", "door_open", 0.7)],  # a forAll condition, mapped to HDDL too
    [("Room103", "is_restocked", 0.8)],  # an achieve condition
    [("Room101", "is_restocked", None), ("Room101", "needs_disinfection", 0.5), ("Room101", "occupied", 0.3)],
    # the query negated: the rooms that need no disinfection, so the first world (false) has the most tasks
    [("Room101", "needs_disinfection", 0.4), "negated"],
    [("Room103", "needs_disinfection", 0.5), ("Room101", "needs_disinfection", None), ("Room103", "occupied", 0.5),
     "negated"],
])
def test_facts_the_goal_model_reads_against_brute_force(tmp_path, entries):
    """Which rooms need disinfection (a query reads it) decides which task instances exist: the
    mission is expanded once per world and compared by content with every world decomposed."""
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder)
    hddl, gm, config = mission_files(folder)
    if entries[-1] == "negated":
        entries = entries[:-1]
        gm.write_text(gm.read_text().replace("r.needs_disinfection)", "!r.needs_disinfection)"))
    world = next((folder / "knowledge").iterdir())
    brute = BruteForce(hddl, gm, config, world, entries, identity=content)
    mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(tmp_path / "u.json", entries))
    assert mission.uncertainty.expanded
    agree_expanded(mission, brute)


@settings(max_examples=max(EXAMPLES // 2, 5), deadline=None, suppress_health_check=list(HealthCheck))
@given(uncertain_missions())
def test_generated_missions_whose_goal_model_reads_uncertain_facts(tmp_path_factory, case):
    """1-3 room attributes the generated goal model reads (which rooms are active, a forAll or
    context condition) and up to 3 it does not, against every world decomposed by content."""
    spec, rnd = case
    folder = tmp_path_factory.mktemp("mission")
    hddl, gm, config = spec.write(folder)
    world = folder / "knowledge" / "world_db.xml"
    mission = Mission.load(hddl, gm, config)
    assume(mission.task_graph.tasks() and not mission.task_graph.unique_branch
           and mission.decomposition_space().count <= 300)
    read = dict(goal_model_reads(mission.goal_model))
    rooms = sorted(mission.initial_state.sorts.get("room", ()))
    records = {el.findtext("name"): el for el in etree.parse(str(world)).getroot().iter() if el.findtext("name")}
    boolean = {"true", "false"}
    numbers = {m.name for m in mission.config.semantic_mapping if m.type == "attribute" and m.mapped_type == "function"}
    goal = [(r, a) for r in rooms for a in sorted(read)  # booleans: by the world's text, and no function's
            if (records[r].findtext(a) or "true").strip().lower() in boolean and a not in numbers]
    domain = [(r, m.name) for r in rooms for m in mission.config.semantic_mapping
              if m.type == "attribute" and m.mapped_type == "predicate" and m.name not in read and m.relates_to == "Room"]
    assume(goal)
    mode = rnd.choice(["all", "all", "some", "none"])  # facts with probabilities: every one, some or none
    chosen = rnd.sample(goal, min(len(goal), rnd.randint(1, 3))) + rnd.sample(domain, min(len(domain), rnd.randint(0, 3)))
    entries = [(r, a, rnd.choice([0.0, 0.2, 0.5, 0.7, 1.0])
                if mode == "all" or (mode == "some" and rnd.random() < 0.5) else None) for r, a in chosen]
    brute = BruteForce(hddl, gm, config, world, entries, identity=content)
    try:
        mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(folder / "u.json", entries))
        assert mission.uncertainty.expanded
        agree_expanded(mission, brute)
    except MissionError as refused:  # what is read straight from the world, in some world
        assert "unique-branch" in str(refused) or "read by a recursive method" in str(refused), str(refused)



def test_components_are_shared_across_worlds_only_with_the_same_scenarios():
    """A component is decided once for every world only when each world has it with the same
    alternatives allowed in the same scenarios: alternatives alike but allowed in other scenarios
    are where the worlds differ (shared, one world's scenarios would stand for both), and a
    component one world has twice is shared once."""
    entry = UncertainEntry("Room104", "door_open", None, None, "u.json:1:1")
    door = UncertainFact(entry, ("door-open", ("Room104",)), False, (False, True), None)
    either = frozenset({(False,), (True,)})
    first = {(1,): frozenset({(True,)}), (2,): either}
    second = {(1,): either, (2,): either}

    def keyed(*alloweds):
        return [(component_key((door,), a), UncertainComponent(n, (door,), a)) for n, a in enumerate(alloweds)]
    common, apart = split_shared([keyed(first), keyed(second)])
    assert common == [] and [[c.allowed for c in a] for a in apart] == [[first], [second]]
    common, apart = split_shared([keyed(first, second), keyed(dict(first))])
    assert [c.allowed for c in common] == [first] and [[c.allowed for c in a] for a in apart] == [[second], []]


def test_a_recursion_repeated_by_a_number_the_goal_model_reads(tmp_path):
    """RoomB holds 2 or 3 objects (the achieve condition reads the number, so each world expands
    the recursion by its value): two picks empty the room in one world only, so no plan is
    robust and each is valid with probability 0.5, against every world decomposed."""
    from test_recursion import RECURSIVE_DOMAIN, WORLD
    folder = tmp_path / "mission"
    shutil.copytree(require_reference() / "missions" / "object-picking-function", folder,
                    ignore=shutil.ignore_patterns("output"))
    next((folder / "hddl").glob("*.hddl")).write_text(RECURSIVE_DOMAIN)
    world = next((folder / "knowledge").glob("*.xml"))
    world.write_text(WORLD)
    (folder / "configuration" / "configuration.xml").unlink()
    hddl, gm, config = (next((folder / d).iterdir()) for d in ("hddl", "gm", "configuration"))
    entries: list[Entry] = [("RoomB", "num_objects", {2.0: 0.5, 3.0: 0.5})]
    brute = BruteForce(hddl, gm, config, world, entries, identity=content)
    assert len(brute.possible) == 2 and not brute.robust
    mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(tmp_path / "u.json", entries))
    agree_expanded(mission, brute)


def test_an_attribute_mapped_to_two_predicates_is_uncertain_in_both(tmp_path):
    """Room202's lock read as door-locked (entering through the door) and as badge-needed
    (entering with the nurse's badge): both atoms start with the one uncertain value, against
    every world decomposed; a predicate and a function for one attribute is refused, located."""
    folder = tmp_path / "mission"
    shutil.copytree(ROOT / "examples" / "medication-round", folder)
    hddl, gm, config = mission_files(folder)
    data = json.loads(config.read_text())
    del data["uncertainty"]
    data["semantic_mapping"].append({"type": "attribute", "name": "door_locked", "relates_to": "Room",
                                     "belongs_to": "world_db", "mapped_type": "predicate",
                                     "map": {"pred": "badge-needed", "arg_sorts": ["room"]}})
    config.write_text(json.dumps(data))
    domain = hddl.read_text().replace("(door-locked ?rm - room)", "(door-locked ?rm - room)\n        (badge-needed ?rm - room)")
    badge = domain.index("enter-with-nurse-badge")
    hddl.write_text(domain[:badge] + domain[badge:].replace("(door-locked ?rm)", "(badge-needed ?rm)", 1))
    world = folder / "knowledge" / "world_db.xml"
    entries: list[Entry] = [("Room202", "door_locked", 0.2), ("Room203", "patient_present", 0.6)]
    brute = BruteForce(hddl, gm, config, world, entries)
    assert len(brute.possible) == 4
    mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(tmp_path / "u.json", entries))
    assert mission.uncertainty.facts[0].atoms == (("door-locked", ("Room202",)), ("badge-needed", ("Room202",)))
    agree(mission, brute)
    data["semantic_mapping"].append({"type": "attribute", "name": "door_locked", "relates_to": "Room",
                                     "belongs_to": "world_db", "mapped_type": "function",
                                     "map": {"pred": "locks", "arg_sorts": ["room"]}})
    config.write_text(json.dumps(data))
    hddl.write_text(hddl.read_text().replace("    (:capabilities", "    (:functions (locks ?rm - room))\n\n    (:capabilities"))
    with pytest.raises(MissionError, match="u.json:1:.*Room202.door_locked is mapped to the predicate door-locked and "
                                           "the predicate badge-needed and the function locks"):
        Mission.load(hddl, gm, config, uncertainty=write_uncertainty(tmp_path / "u.json", entries)).uncertainty


def test_a_mapping_of_another_type_with_the_same_sort_is_not_an_alias(tmp_path):
    """Room and Pharmacy are both HDDL rooms, and door_locked is mapped for each to its own
    predicate: Room202 is a Room record, so its lock is door-locked(Room202) alone, as the world
    reads it, not pharmacy-locked(Room202) too; against every world decomposed."""
    folder = tmp_path / "mission"
    shutil.copytree(ROOT / "examples" / "medication-round", folder)
    hddl, gm, config = mission_files(folder)
    data = json.loads(config.read_text())
    del data["uncertainty"]
    data["type_mapping"].append({"hddl_type": "room", "ocl_type": "Pharmacy"})
    data["semantic_mapping"].insert(0, {"type": "attribute", "name": "door_locked", "relates_to": "Pharmacy",
                                        "belongs_to": "world_db", "mapped_type": "predicate",
                                        "map": {"pred": "pharmacy-locked", "arg_sorts": ["room"]}})
    config.write_text(json.dumps(data))
    gm.write_text(gm.read_text().replace('"Controls": "rooms : Sequence(Room)"', '"Controls": "rooms : Sequence(Room), ph : Pharmacy"'))
    domain = hddl.read_text().replace("(door-locked ?rm - room)", "(door-locked ?rm - room)\n        (pharmacy-locked ?rm - room)")
    badge = domain.index("enter-with-nurse-badge")
    hddl.write_text(domain[:badge] + domain[badge:].replace("(door-locked ?rm)", "(door-locked ?rm)\n            (not (pharmacy-locked ?rm))", 1))
    world = folder / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace("</world_db>", "<Pharmacy><name>Ph1</name><door_locked>True</door_locked>"
                                                              "</Pharmacy></world_db>"))
    entries: list[Entry] = [("Room202", "door_locked", 0.3)]
    brute = BruteForce(hddl, gm, config, world, entries)
    mission = Mission.load(hddl, gm, config, uncertainty=write_uncertainty(tmp_path / "u.json", entries))
    assert mission.uncertainty.facts[0].atoms == (("door-locked", ("Room202",)),)
    agree(mission, brute)
