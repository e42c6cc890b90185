"""Differential tests: the exploratory algorithm and the CP-SAT decomposer agree.

``Mission.exploratory()`` (the original's explicit combination) and
``Mission.decomposition_space()`` (the CP-SAT decomposer) must describe the same valid mission
decompositions: the same sets of decomposition vertices, and ``len(exploratory) == space.count``.
When the exploratory algorithm raises ``NoDecompositionError`` the space must be empty
(``count == 0``); a mission without task instances gives ``[]`` and ``0``.

* ``test_agree_on_random_missions``: random missions from ``missiongen.missions()``.  The number
  of examples comes from ``MUTROSE_DIFF_EXAMPLES`` (default 120, about 10 s, so CI stays well
  under a minute).  The nightly run uses more::

      MUTROSE_DIFF_EXAMPLES=2000 pytest tests/test_differential.py

  Run with ``--hypothesis-show-statistics`` to see how many missions had 0, 1, 2-9, ... valid
  decompositions (``hypothesis.event``); ``hypothesis.target`` steers towards missions with
  many decompositions.
* ``test_strategy_is_not_trivial``: 200 draws with a fixed seed; at least 20% of the missions
  have two or more valid decompositions and some have none; every shape of the mix occurs.
* ``test_agree_on_<shape>``: one bounded property per mission shape of ``missiongen`` (long
  ``;`` sequences, contradictory/duplicate preconditions, unique-branch Task Graphs, nested
  forAll with plain Achieve goals, direct tasks beside goals under ``;``); examples per shape
  from ``MUTROSE_DIFF_SHAPE_EXAMPLES`` (default 30).
* ``test_shape_is_not_trivial[<shape>]``: 40 draws of each shape with a fixed seed really have
  that shape (e.g. >= 10 task vertices under one ``;``, a unique-branch Task Graph, two-level
  forAll instance ids) and a fair share of them has a valid decomposition.
* ``test_agree_on_reference_corpus``: every configuration of the reference missions
  (``MUTROSE_REFERENCE``, default ``../shared/reference``; skipped when absent, except on CI).
* ``test_agree_on_3_power_8``: eight rooms, each an OR choice of three valid tasks: 3**8 = 6561.
* Regression cases: disagreements found by the random test, minimised, as explicit missions;
  the ones that still disagree are ``xfail(strict=True)`` so that a fix shows up as XPASS.
"""
from __future__ import annotations

import json
import os
from pathlib import Path

import pytest
from hypothesis import HealthCheck, Phase, event, given, note, seed, settings, target

from mutrose_cp.errors import NoDecompositionError
from mutrose_cp.model import Literal
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files

from conftest import REFERENCE, require_reference
from missiongen import (
    SHAPES,
    MissionSpec,
    beside_goals,
    contradictory_methods,
    contradictory_missions,
    duplicate_preconditions,
    goal_nodes,
    load_mission,
    long_sequences,
    missions,
    nested_forall_missions,
    or_choices_mission,
    tasks_beside_goals,
    unique_branch_missions,
)

EXAMPLES = int(os.environ.get("MUTROSE_DIFF_EXAMPLES", "120"))
SHAPE_EXAMPLES = int(os.environ.get("MUTROSE_DIFF_SHAPE_EXAMPLES", "30"))


# ---------------------------------------------------------------------------------------------
# Agreement


def decompose_both(mission: Mission):
    """(exploratory result or None when it raised NoDecompositionError, decomposition space)."""
    try:
        explored = mission.exploratory()
    except NoDecompositionError:
        explored = None
    return explored, mission.decomposition_space()


def assert_agree(mission: Mission) -> int:
    """Both algorithms give the same valid mission decompositions; returns their number."""
    explored, space = decompose_both(mission)
    count = space.count
    if explored is None:
        assert count == 0, f"exploratory found no decomposition, the CP-SAT space counts {count}"
        return 0
    listed = [frozenset(x) for x in space] if count else []
    assert len(listed) == count, f"the space lists {len(listed)} decompositions but counts {count}"
    assert {frozenset(x) for x in explored} == set(listed), _difference(explored, listed)
    assert len(explored) == count, f"exploratory gives {len(explored)} decompositions, the space counts {count}"
    return count


def _difference(explored: list[list[int]], listed: list[frozenset[int]]) -> str:
    a, b = {frozenset(x) for x in explored}, set(listed)
    only_a = sorted(sorted(x) for x in a - b)[:5]
    only_b = sorted(sorted(x) for x in b - a)[:5]
    return (f"exploratory {len(explored)} ({len(a)} distinct), space {len(listed)}; only exploratory: {only_a}; "
            f"only space: {only_b}")


def _bucket(n: int) -> str:
    return "0" if n == 0 else "1" if n == 1 else "2-9" if n < 10 else "10-99" if n < 100 else ">=100"


# ---------------------------------------------------------------------------------------------
# Random missions


def check_random_mission(spec: MissionSpec) -> None:
    """The property of every random test: both algorithms agree on ``spec``."""
    note(spec.summary())
    note(spec.dump())
    mission = load_mission(spec)
    count = assert_agree(mission)
    event(f"shape: {spec.shape}")
    event(f"valid decompositions: {_bucket(count)}")
    event(f"task instances: {len(mission.expansion.instances)}")
    if count >= 2:
        event("at least 2 valid decompositions")
    target(float(min(count, 100)), label="valid decompositions")


RANDOM = settings(max_examples=EXAMPLES, deadline=None,
                  suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])
SHAPED = settings(max_examples=SHAPE_EXAMPLES, deadline=None,
                  suppress_health_check=[HealthCheck.too_slow, HealthCheck.data_too_large])


@RANDOM
@given(missions())
def test_agree_on_random_missions(spec: MissionSpec):
    check_random_mission(spec)


def test_strategy_is_not_trivial():
    """200 draws with a fixed seed: at least 20% of the missions have two or more valid
    decompositions, some have none (the strategy exercises choices and failures), and every
    shape of the mix occurs."""
    counts: list[int] = []
    shapes: list[str] = []

    @seed(20251122)
    @settings(max_examples=200, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(missions())
    def draw(spec: MissionSpec) -> None:
        counts.append(load_mission(spec).decomposition_space().count)
        shapes.append(spec.shape)

    draw()
    assert len(counts) >= 190, f"only {len(counts)} missions drawn"
    several = sum(1 for c in counts if c >= 2)
    assert several >= 0.2 * len(counts), f"{several}/{len(counts)} missions with >= 2 decompositions"
    assert any(c == 0 for c in counts), "no mission without a valid decomposition"
    for shape in SHAPES:  # a tenth of each expected; hypothesis's generation is far from uniform
        assert shapes.count(shape) >= 2, f"shape {shape}: {shapes.count(shape)}/{len(shapes)} draws"


# ---------------------------------------------------------------------------------------------
# Mission shapes (missiongen.SHAPES): one bounded property each


@SHAPED
@given(long_sequences())
def test_agree_on_long_sequences(spec: MissionSpec):
    """10-15 tasks under one ``;`` that set, unset and require one room predicate: the order in
    which effects are applied matters (``AT10_1`` sorts before ``AT2_1`` as a string)."""
    check_random_mission(spec)


@SHAPED
@given(contradictory_missions())
def test_agree_on_contradictory_preconditions(spec: MissionSpec):
    """Self-contradictory and duplicate method preconditions."""
    check_random_mission(spec)


@SHAPED
@given(unique_branch_missions())
def test_agree_on_unique_branch_missions(spec: MissionSpec):
    """Unique-branch Task Graphs (§5.5, §7.7) with numeric (level) preconditions."""
    check_random_mission(spec)


@SHAPED
@given(nested_forall_missions())
def test_agree_on_nested_forall(spec: MissionSpec):
    """A forAll over the items of each room (a second Query + forAll level) with plain Achieve
    goals and tasks over the item inside."""
    check_random_mission(spec)


@SHAPED
@given(tasks_beside_goals())
def test_agree_on_tasks_beside_goals(spec: MissionSpec):
    """Direct tasks beside goals under a ``;`` annotation (``[G4;AT2;G5]``)."""
    check_random_mission(spec)


def _semicolon_tasks(mission: Mission) -> int:
    """The most task vertices directly below one ``;`` operator of the (trimmed) Task Graph."""
    tg = mission.task_graph
    return max([sum(1 for u in tg.children(v.index) if tg.vertices[u].kind == "task")
                for v in tg.vertices if v.kind == "op" and v.content == ";"] or [0])


def _toggles(mission: Mission) -> bool:
    """Some decomposition sets a room predicate that another one unsets."""
    effects = {(e.predicate, e.args, e.positive) for d in mission.task_graph.decompositions()
               for e in d.decomposition.predicates.effects}
    return any((p, a, False) in effects for p, a, positive in effects if positive)


def _numeric_preconditions(mission: Mission) -> bool:
    return any(not isinstance(c, Literal) for d in mission.task_graph.decompositions()
               for c in d.decomposition.predicates.preconditions)


def _shape_facts(spec: MissionSpec, mission: Mission) -> dict[str, bool]:
    """What makes a drawn mission an instance of its shape (each fact is checked for a share of
    the draws, see ``SHAPE_FACTS``)."""
    tree_goals = list(goal_nodes(spec.tree))
    item_foralls = [g for g in tree_goals if g.forall is not None]
    return {
        "long ; sequence": _semicolon_tasks(mission) >= 10,
        "set and unset one predicate": _toggles(mission),
        "contradictory precondition": bool(contradictory_methods(spec)),
        "duplicate precondition": bool(duplicate_preconditions(spec)),
        "unique branch": mission.task_graph.unique_branch,
        "numeric precondition": _numeric_preconditions(mission),
        "item forAll": bool(item_foralls),
        "two-level instance ids": any(i.id.count("_") == 2 for i in mission.expansion.instances),
        "plain Achieve below the item forAll": any(g.achieve for f in item_foralls for g in goal_nodes(f)),
        "direct task beside goals under ;": bool(beside_goals(spec.tree)),
        "; operator with a direct task": any(
            v.kind == "op" and v.content == ";" and any(mission.task_graph.vertices[u].kind == "task"
                                                        for u in mission.task_graph.children(v.index))
            for v in mission.task_graph.vertices),
    }


# shape -> {fact: least share of the draws that have it}
SHAPE_FACTS = {
    "long_sequence": {"long ; sequence": 0.8, "set and unset one predicate": 0.8},
    "contradictory": {"contradictory precondition": 1.0, "duplicate precondition": 1.0},
    "unique_branch": {"unique branch": 1.0, "numeric precondition": 0.4},
    "nested_forall": {"item forAll": 1.0, "two-level instance ids": 0.6, "plain Achieve below the item forAll": 0.5},
    "tasks_beside_goals": {"direct task beside goals under ;": 1.0, "; operator with a direct task": 0.5},
}


@pytest.mark.parametrize("shape", sorted(SHAPE_FACTS))
def test_shape_is_not_trivial(shape: str):
    """40 draws of a shape with a fixed seed: they have the shape's facts (``SHAPE_FACTS``), at
    least 20% of them have a valid decomposition and some have several (the agreement is not
    only about failures)."""
    facts: list[dict[str, bool]] = []
    counts: list[int] = []

    @seed(20251123)
    @settings(max_examples=40, deadline=None, database=None, phases=[Phase.generate],
              suppress_health_check=list(HealthCheck))
    @given(missions(shape))
    def draw(spec: MissionSpec) -> None:
        assert spec.shape == shape
        mission = load_mission(spec)
        facts.append(_shape_facts(spec, mission))
        counts.append(mission.decomposition_space().count)

    draw()
    assert len(facts) >= 38, f"only {len(facts)} missions drawn"
    for fact, share in SHAPE_FACTS[shape].items():
        have = sum(1 for f in facts if f[fact])
        assert have >= share * len(facts), f"{shape}: {fact} in {have}/{len(facts)} draws"
    valid = sum(1 for c in counts if c >= 1)
    assert valid >= 0.2 * len(counts), f"{shape}: {valid}/{len(counts)} missions with a valid decomposition"
    assert any(c >= 2 for c in counts), f"{shape}: no mission with two or more valid decompositions"


# ---------------------------------------------------------------------------------------------
# Reference corpus


def _corpus_cases():
    base = REFERENCE / "missions"
    if not base.is_dir():
        return [pytest.param(None, None, id="corpus-missing")]
    return [pytest.param(cfg.parent.parent, cfg, id=f"{cfg.parent.parent.name}/{cfg.name}")
            for cfg in sorted(base.glob("*/configuration/*")) if cfg.suffix.lower() in (".json", ".xml")]


@pytest.mark.parametrize("folder,cfg", _corpus_cases())
def test_agree_on_reference_corpus(folder: Path, cfg: Path, monkeypatch):
    require_reference()
    hddl, gm, config = find_mission_files(folder, cfg.name)  # the goal model matching the configuration
    monkeypatch.chdir(folder)  # configuration paths are relative to the mission folder
    assert_agree(Mission.load(hddl, gm, config))


# ---------------------------------------------------------------------------------------------
# A large product


def test_agree_on_3_power_8():
    """Eight rooms, each with an OR goal over three always-valid task alternatives: eight
    independent 3-way choices, 3**8 = 6561 valid mission decompositions."""
    mission = load_mission(or_choices_mission(rooms=8, alternatives=3))
    assert len(mission.expansion.instances) == 8 * 3
    explored, space = decompose_both(mission)
    assert space.count == 3 ** 8
    assert explored is not None and len(explored) == 3 ** 8
    listed = {frozenset(x) for x in space}
    assert len(listed) == 3 ** 8
    assert {frozenset(x) for x in explored} == listed
    assert all(len(x) == 8 for x in listed)  # one task decomposition per room


# ---------------------------------------------------------------------------------------------
# Regression cases (minimised disagreements found by test_agree_on_random_missions)

# Two rooms; the only goal below the forAll has a condition context that is false in both rooms
# and that no task can enable, so the Task Graph keeps no task vertex (just the forAll's parallel
# operator), although the expansion created two task instances.
#   exploratory():        [[]]   (one mission decomposition with no task)
#   decomposition_space(): count 0, lists nothing
# A single room gives [] and 0 in both.  The original starts from an empty list of mission
# decompositions, so with no task vertex it outputs none (0 / []).
EMPTY_TASK_GRAPH = {
    "hddl": """\
(define (domain generated)
    (:types room - object Bot - robot)
    (:predicates (checked ?rm - room))
    (:task TaskA :parameters (?r - Bot ?rm - room))
    (:method mA0
        :parameters (?r - Bot ?rm - room)
        :task (TaskA ?r ?rm)
        :ordered-subtasks (and (act0 ?r ?rm)))
    (:action act0 :parameters (?r - Bot ?rm - room) :precondition () :effect ())
)
""",
    "gm": {
        "actors": [{"id": "actor", "text": "Regression", "type": "istar.Actor", "x": 40, "y": 20,
                    "customProperties": {"Description": ""}, "nodes": [
            {"id": "n1", "text": "G1: Root [G2;G3]", "type": "istar.Goal", "x": 120, "y": 60,
             "customProperties": {"Description": ""}},
            {"id": "n2", "text": "G2: Rooms Are Listed", "type": "istar.Goal", "x": 230, "y": 170,
             "customProperties": {"Description": "", "GoalType": "Query", "Controls": "rooms : Sequence(Room)",
                                  "QueriedProperty": "world_db->select(r:Room | )"}},
            {"id": "n3", "text": "G3: Every Room Is Handled", "type": "istar.Goal", "x": 340, "y": 170,
             "customProperties": {"Description": "", "GoalType": "Achieve", "Monitors": "rooms : Sequence(Room)",
                                  "Controls": "current_room : Room",
                                  "AchieveCondition": "rooms->forAll(current_room | )"}},
            {"id": "n4", "text": "G4: Checked Room Is Handled", "type": "istar.Goal", "x": 450, "y": 280,
             "customProperties": {"Description": "", "Monitors": "current_room",
                                  "CreationCondition": "assertion condition \"current_room.is_checked\""}},
            {"id": "n5", "text": "AT1: TaskA", "type": "istar.Task", "x": 560, "y": 390,
             "customProperties": {"Description": "", "Location": "current_room"}},
        ]}],
        "orphans": [], "dependencies": [], "display": {}, "tool": "pistar.2.0.0", "istar": "2.0",
        "links": [
            {"id": "l1", "type": "istar.AndRefinementLink", "source": "n2", "target": "n1"},
            {"id": "l2", "type": "istar.AndRefinementLink", "source": "n3", "target": "n1"},
            {"id": "l3", "type": "istar.AndRefinementLink", "source": "n4", "target": "n3"},
            {"id": "l4", "type": "istar.AndRefinementLink", "source": "n5", "target": "n4"},
        ],
    },
    "config": {
        "world_db": {"type": "file", "file_type": "xml", "path": "knowledge/world_db.xml", "xml_root": "world_db",
                     "unique_id": "name"},
        "output": {"output_type": "file", "file_path": "output/mission.json", "file_type": "json"},
        "location_types": ["Room"],
        "type_mapping": [{"hddl_type": "room", "ocl_type": "Room"}],
        "var_mapping": [{"task_id": "AT1", "map": [{"gm_var": "current_room", "hddl_var": "?rm"}]}],
        "semantic_mapping": [{"type": "attribute", "name": "is_checked", "relates_to": "Room",
                              "belongs_to": "world_db", "mapped_type": "predicate",
                              "map": {"pred": "checked", "arg_sorts": ["room"]}}],
    },
    "world": """\
<world_db>
    <Room><name>Room1</name><is_checked>False</is_checked></Room>
    <Room><name>Room2</name><is_checked>False</is_checked></Room>
</world_db>
""",
}


def load_case(case: dict, directory: Path) -> Mission:
    """Write a regression case (hddl/ gm/ configuration/ knowledge/) and load it."""
    files = {"hddl": directory / "hddl" / "domain.hddl", "gm": directory / "gm" / "gm.json",
             "config": directory / "configuration" / "configuration.json",
             "world": directory / "knowledge" / "world_db.xml"}
    for key, path in files.items():
        path.parent.mkdir(parents=True, exist_ok=True)
        value = case[key]
        if key == "config":
            value = {**value, "world_db": {**value["world_db"], "path": str(files["world"])}}
        path.write_text(value if isinstance(value, str) else json.dumps(value, indent=2))
    return Mission.load(files["hddl"], files["gm"], files["config"])


def test_regression_empty_task_graph_premise(tmp_path):
    """The case still describes what it is about: task instances, but no task vertex."""
    mission = load_case(EMPTY_TASK_GRAPH, tmp_path)
    assert len(mission.expansion.instances) == 2
    assert not mission.task_graph.tasks()
    assert mission.decomposition_space().count == 0


def test_regression_empty_task_graph(tmp_path):
    """Once found by the random test: the exploratory algorithm returned one empty mission
    decomposition when condition contexts removed every task vertex."""
    assert_agree(load_case(EMPTY_TASK_GRAPH, tmp_path))
