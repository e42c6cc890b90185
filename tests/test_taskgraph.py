"""The Task Graph (``taskgraph.py``) on small generated missions: trimming keeps an achieve
goal's operator, context conditions searched through sequences, parallel operators and
fallbacks, execution-constraint flags of nested Group/Divisible goals, and the robot number of
Group=False tasks."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from mutrose_cp.errors import MissionError, NoDecompositionError
from mutrose_cp.mission import Mission
from mutrose_cp.pipeline.constraints import EC
from mutrose_cp.model.task_graph import EdgeKind, OperatorVertex, TaskGraphBuilder

from missiongen import Action, GoalNode, Lit, Method, MissionSpec, Room, Task, TaskNode, load_mission

ACTIONS = (Action("act0", (), (Lit("clean", "?rm"),)), Action("act1", (), ()), Action("act2", (), (Lit("lit", "?rm"),)))


def _task(name: str, action: str) -> Task:
    return Task(name, (Method(f"m{name[-1]}0", (), (action,)),))


def _spec(tree: GoalNode, *tasks: Task, forall: str = "") -> MissionSpec:
    """One room, neither clean nor lit."""
    room = Room("Room1", True, (("clean", False), ("lit", False)), 0)
    return MissionSpec(("clean", "lit"), ("charged",), ACTIONS, tasks, (room,), True, forall, tree)


def _count(mission: Mission) -> int:
    """Valid mission decompositions, the same number by both algorithms."""
    count = mission.decomposition_space().count
    try:
        explored = len(mission.exploratory())
    except NoDecompositionError:
        explored = 0
    assert explored == count
    return count


def _cd_edges(mission: Mission) -> list[tuple[str, str]]:
    tg = mission.task_graph
    return sorted((tg.vertices[a].content, tg.vertices[b].content) for a, b, kind, *_ in tg.edges() if kind == EdgeKind.CD)


def _ecs(mission: Mission) -> set[tuple[str, str, bool, bool]]:
    tg = mission.task_graph
    return {(tg.vertices[c.first].content, tg.vertices[c.second].content, c.group, c.divisible)
            for c in mission.constraints if c.kind == EC}


# ---------------------------------------------------------------------------------------------
# Trimming


@pytest.mark.parametrize("cleans", [True, False])
def test_achieve_goal_left_with_one_child_keeps_its_operator(cleans):
    """G4 (Achieve ``is_clean``) is [G5;AT2], but G5's context (``is_lit``) is false and nothing
    lights the room, so G5 disappears.  G4's operator then has a single child; it is kept anyway
    because its achieve condition must still be checked."""
    g5 = GoalNode((TaskNode("TaskA"),), condition="current_room.is_lit")
    g4 = GoalNode((g5, TaskNode("TaskB")), annotation=("flat", ";"), achieve="current_room.is_clean")
    tree = GoalNode((g4, TaskNode("TaskC")), annotation=("flat", "#"))
    mission = load_mission(_spec(tree, _task("TaskA", "act1"), _task("TaskB", "act0" if cleans else "act1"),
                                 _task("TaskC", "act1")))
    tg = mission.task_graph
    assert sorted(v.content for v in tg.tasks()) == ["AT2_1", "AT3_1"]
    achieve_ops = [v for v in tg.vertices if isinstance(v, OperatorVertex) and v.achieve]
    assert ("G4", 1) in [(v.goal, len(tg.children(v.index))) for v in achieve_ops]
    assert _count(mission) == (1 if cleans else 0)


# ---------------------------------------------------------------------------------------------
# Context conditions (AT1 lights the room; G5 over AT2 needs it lit)


@pytest.mark.parametrize("op, tasks, cd", [
    (";", ["AT1_1", "AT2_1"], []),  # a sequence satisfies the context silently
    ("#", ["AT1_1", "AT2_1"], [("AT1_1|1", "AT2_1")]),  # a parallel task becomes a context dependency
    ("FALLBACK", ["AT1_1"], []),  # a fallback's first branch does not enable the second: G5 disappears
], ids=["sequence", "parallel", "fallback"])
def test_false_context_searched_through_the_operator(op, tasks, cd):
    g5 = GoalNode((TaskNode("TaskB"),), condition="current_room.is_lit")
    tree = GoalNode((TaskNode("TaskA"), g5), annotation=("flat", op))
    mission = load_mission(_spec(tree, _task("TaskA", "act2"), _task("TaskB", "act1")))
    assert sorted(v.content for v in mission.task_graph.tasks()) == tasks
    assert _cd_edges(mission) == cd
    assert _count(mission) == 1


def test_nested_contexts_enabled_by_one_task_give_one_edge():
    """G5 and G6 inside it both need the room lit, and AT1 beside them lights it: both goals
    depend on AT1's decomposition, and both dependencies lead to AT2, which gets one CD edge."""
    g6 = GoalNode((TaskNode("TaskB"),), condition="current_room.is_lit")
    g5 = GoalNode((g6, TaskNode("TaskB")), annotation=("flat", ";"), condition="current_room.is_lit")
    tree = GoalNode((TaskNode("TaskA"), g5), annotation=("flat", "#"))
    mission = load_mission(_spec(tree, _task("TaskA", "act2"), _task("TaskB", "act1")))
    assert _cd_edges(mission) == [("AT1_1|1", "AT2_1"), ("AT1_1|1", "AT3_1")]
    assert _count(mission) == 1


def test_context_dependency_orders_parallel_tasks():
    """The CD edge of AT1 # G5 turns the parallel pair into SEQ; without it there is none."""
    g5 = GoalNode((TaskNode("TaskB"),), condition="current_room.is_lit")
    tree = GoalNode((TaskNode("TaskA"), g5), annotation=("flat", "#"))
    mission = load_mission(_spec(tree, _task("TaskA", "act2"), _task("TaskB", "act1")))
    tg = mission.task_graph
    kinds = sorted((c.kind, tg.vertices[c.first].content, tg.vertices[c.second].content) for c in mission.constraints)
    assert kinds == [("SEQ", "AT1_1|1", "AT2_1|1")]


# ---------------------------------------------------------------------------------------------
# Execution constraints of nested Group/Divisible goals
#
# G3 is [G4;AT3] and G4 is [AT1#AT2].


def _nested(outer: tuple[bool, bool], inner: tuple[bool, bool]) -> Mission:
    g4 = GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), annotation=("flat", "#"), group=inner[0], divisible=inner[1])
    tree = GoalNode((g4, TaskNode("TaskA")), annotation=("flat", ";"), group=outer[0], divisible=outer[1])
    return load_mission(_spec(tree, _task("TaskA", "act1")))


def test_group_false_inside_divisible_false_takes_over():
    """Below a Divisible=False goal (group True) a nested Group=False goal starts its own
    execution constraints: AT1-AT2 carry group False, the pairs with AT3 the outer flags."""
    assert _ecs(_nested((True, False), (False, True))) == {
        ("AT1_1|1", "AT2_1|1", False, True),
        ("AT3_1|1", "AT1_1|1", True, False),
        ("AT3_1|1", "AT2_1|1", True, False),
    }


def test_divisible_false_inside_group_false_keeps_the_outer_flags():
    """Below a Group=False goal nothing nested takes over: every pair carries group False."""
    assert _ecs(_nested((False, True), (True, False))) == {
        ("AT1_1|1", "AT2_1|1", False, True),
        ("AT3_1|1", "AT1_1|1", False, True),
        ("AT3_1|1", "AT2_1|1", False, True),
    }


# ---------------------------------------------------------------------------------------------
# Robot number of Group=False tasks


@pytest.mark.parametrize("robots, ok", [("1", True), ("2", False), ("[1,2]", False)])
def test_group_false_tasks_need_exactly_one_robot(tmp_path: Path, robots, ok):
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), annotation=("flat", "#"), group=False)
    hddl, gm, config = _spec(tree, _task("TaskA", "act1")).write(tmp_path)
    doc = json.loads(gm.read_text())
    for node in doc["actors"][0]["nodes"]:
        if node["text"].startswith("AT1:"):
            node["customProperties"]["RobotNumber"] = robots
    gm.write_text(json.dumps(doc))
    mission = Mission.load(hddl, gm, config)
    if ok:
        assert [v.content for v in mission.task_graph.tasks()] == ["AT1_1", "AT2_1"]
        assert _count(mission) == 1
    else:
        with pytest.raises(MissionError, match=r"Non group task \[AT1_1\] does not have 1 robot"):
            _ = mission.task_graph


def test_the_finished_graph_knows_its_execution_constraint_edges_both_ways(reference):
    """The finished Task Graph answers from the partner lists (no set of linked pairs, the
    largest index of a large mission): the same answers, both directions."""
    from mutrose_cp.io.mission_files import find_mission_files

    tg = Mission.load(*find_mission_files(reference / "missions" / "vital-signs-monitoring")).task_graph
    tasks = [t.index for t in tg.tasks()]
    linked = {(t, p.task) for t in tasks for p in tg.ec_partners(t)}
    assert linked
    refinements = {(e.source, e.target) for e in tg.edges() if e.kind != EdgeKind.EC}
    for a in tasks:
        for b in tasks:
            assert tg.has_edge(a, b) == ((a, b) in linked or (a, b) in refinements), (a, b)
    assert all((b, a) in linked for a, b in linked)


def _operators(count: int) -> TaskGraphBuilder:
    """A builder holding ``count`` operator vertices: the first is the root, the others its
    children (no edges yet)."""
    b = TaskGraphBuilder()
    for i in range(count):
        b.add(OperatorVertex(index=i, parent=-1 if i == 0 else 0, content="#"))
    return b


def test_the_finished_graph_answers_edge_queries_from_its_successor_lists():
    """The builder looks edges up by vertex pair; the finished graph drops that table and reads
    the successor lists: the same kinds, including an edge whose kind was changed, and a
    vertex without successors answers with an empty sequence."""
    b = _operators(4)
    b.add_edge(0, 1, EdgeKind.AND)
    b.add_edge(0, 2, EdgeKind.OR)
    b.add_edge(0, 3, EdgeKind.AND)
    b.add_edge(0, 1, EdgeKind.OR)  # changed in place: first among the successors, last among the OR ones
    b.add_edge(2, 3, EdgeKind.CD)
    building = [(a, c, b.edge_kind(a, c)) for a in range(4) for c in range(4) if b.has_edge(a, c)]
    tg = b.freeze()
    assert [(a, c, tg.edge_kind(a, c)) for a in range(4) for c in range(4) if tg.has_edge(a, c)] == building == [
        (0, 1, EdgeKind.OR), (0, 2, EdgeKind.OR), (0, 3, EdgeKind.AND), (2, 3, EdgeKind.CD)]
    assert list(tg.successors(0)) == [(1, EdgeKind.OR), (2, EdgeKind.OR), (3, EdgeKind.AND)]
    assert tg.out(0, EdgeKind.OR) == [2, 1] and tg.out(0, EdgeKind.AND) == [3]
    assert tg.children(0) == [1, 2, 3] and tg.children(2) == [] and list(tg.successors(3)) == []
    assert tg.has_edges_of_kind(EdgeKind.CD) and not tg.has_edges_of_kind(EdgeKind.EC)
    assert [(e.source, e.target, e.kind) for e in tg.edges()] == building
    with pytest.raises(KeyError):
        tg.edge_kind(1, 0)


def test_execution_constraints_link_a_task_pair_once():
    """``add_ec_to_all`` skips the tasks already linked to the new one (in either direction, or
    earlier in the same call) and keeps the order of the others, on both partner lists."""
    from mutrose_cp.model.task_graph import ExecutionPartner

    b = _operators(6)
    b.add_ec(5, 2, True, False)
    b.add_ec(3, 5, True, False)
    b.add_ec_to_all([1, 2, 3, 4, 1, 4], 5, False, True)
    assert [p.task for p in b.ec_partners(5)] == [2, 3, 1, 4]
    assert b.ec_partners(1) == b.ec_partners(4) == [ExecutionPartner(5, False, True)]
    assert b.ec_partners(2) == b.ec_partners(3) == [ExecutionPartner(5, True, False)]
    tg = b.freeze()
    assert [a for a in range(6) if tg.has_edge(a, 5)] == [1, 2, 3, 4] and not tg.has_edge(1, 4)


def test_successors_of_one_kind_read_like_a_list_of_pairs_once_frozen():
    """A finished graph reads the successors of a vertex whose edges all have one kind from its
    list by kind: the same pairs in the same order, by index, slice or iteration; a vertex with
    edges of two kinds, or an edge whose kind was changed out of order, keeps its list."""
    b = _operators(6)
    b.add_edge(0, 1, EdgeKind.OR)
    b.add_edge(0, 2, EdgeKind.OR)
    b.add_edge(1, 3, EdgeKind.AND)
    b.add_edge(1, 4, EdgeKind.CD)
    b.add_edge(2, 4, EdgeKind.AND)
    b.add_edge(2, 5, EdgeKind.OR)
    b.add_edge(2, 4, EdgeKind.OR)  # all OR now, but 4 comes after 5 among the OR successors
    expected = {v: list(b.successors(v)) for v in range(6)}
    tg = b.freeze()
    for v in range(6):
        successors = tg.successors(v)
        assert successors == expected[v] and list(successors) == expected[v] and len(successors) == len(expected[v])
        assert [successors[i] for i in range(len(successors))] == expected[v] and successors[1:] == expected[v][1:]
    assert expected[0] == [(1, EdgeKind.OR), (2, EdgeKind.OR)] and expected[2] == [(4, EdgeKind.OR), (5, EdgeKind.OR)]
    assert tg.out(2, EdgeKind.OR) == [5, 4] and tg.children(2) == [5, 4]
    assert [v for v in range(6) if tg.is_or(v)] == [0, 2]
    assert type(tg.successors(0)) is not list and type(tg.successors(1)) is list and type(tg.successors(2)) is list


def test_decomposition_keys_number_the_decompositions_in_vertex_order():
    """The output keys ``t0, t1, ...`` follow the decomposition vertices in index order, built
    once for everything that names them."""
    from mutrose_cp.io.mission_files import find_mission_files

    tg = Mission.load(*find_mission_files(Path(__file__).resolve().parent.parent / "examples" / "item-delivery")).task_graph
    keys = tg.decomposition_keys
    assert list(keys) == [d.index for d in tg.decompositions()] == sorted(keys)
    assert list(keys.values()) == [f"t{i}" for i in range(len(keys))] and tg.decomposition_keys is keys


def test_a_tasks_decompositions_are_its_decomposition_vertices_in_order():
    """A task's decompositions are the decomposition vertices whose parent it is, in vertex
    order, on the finished graph as while it is built; other vertices have none."""
    from mutrose_cp.io.mission_files import find_mission_files
    from mutrose_cp.model.task_graph import DecompositionVertex, TaskVertex

    tg = Mission.load(*find_mission_files(Path(__file__).resolve().parent.parent / "examples" / "item-delivery")).task_graph
    for v in tg.vertices:
        expected = [d for d in tg.vertices if isinstance(d, DecompositionVertex) and d.parent == v.index]
        assert tg.decompositions_of(v.index) == expected
    assert tg.decompositions_of(-1) == [] and tg.decompositions_of(len(tg.vertices)) == []

    b = TaskGraphBuilder()
    b.add(OperatorVertex(index=0, parent=-1, content="#"))
    task = tg.vertices[next(t.index for t in tg.tasks())]
    b.add(TaskVertex(index=1, parent=0, content=task.content, instance=task.instance))
    dec = tg.decompositions_of(task.index)[0]
    first = b.add(DecompositionVertex(index=2, parent=1, content=dec.content, decomposition=dec.decomposition))
    b.add(DecompositionVertex(index=3, parent=1, content=dec.content, decomposition=dec.decomposition))
    b.add_edge(1, 2, EdgeKind.AND)  # the second decomposition has no edge: it is still the task's
    assert [d.index for d in b.decompositions_of(1)] == [2, 3]
    kept = b.freeze()
    assert [d.index for d in kept.decompositions_of(1)] == [2, 3] and kept.decompositions_of(1)[0] is first
