"""Mission constraints (``constraints.py``, spec ``semantics.md`` §6) of small generated
missions: SEQ/FB pairs between a task and a nested fallback or sequence, parallel pairs that a
context dependency orders, trimming, EC flags, and the robot-number check of EC partners.

Every task sits below its own means-end goal, so that the trimmed Task Graph keeps the
annotation's order (a kept operator lists its *direct* tasks first, §5.5)."""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from mutrose_cp.pipeline.constraints import generate_constraints
from mutrose_cp.errors import MissionError
from mutrose_cp.mission import Mission

from missiongen import Action, GoalNode, Lit, Method, MissionSpec, Room, Task, TaskNode, load_mission

ACTIONS = (Action("act1", (), ()), Action("act2", (), (Lit("lit", "?rm"),)))


def _task(name: str, *actions: str) -> Task:
    return Task(name, tuple(Method(f"m{name[-1]}{k}", (), (a,)) for k, a in enumerate(actions)))


def _spec(tree: GoalNode, *tasks: Task) -> MissionSpec:
    tasks = tasks or (_task("TaskA", "act1"),)
    room = Room("Room1", True, (("lit", False),), 0)
    return MissionSpec(("lit",), ("charged",), ACTIONS, tasks, (room,), True, "", tree)


def _leaf(task: str = "TaskA") -> GoalNode:
    return GoalNode((TaskNode(task),))


def _constraints(mission: Mission) -> list[tuple[str, str, str]]:
    """(kind, first, second) over decomposition ids, in the generated order."""
    tg = mission.task_graph
    return [(c.kind, tg.vertices[c.first].content, tg.vertices[c.second].content) for c in mission.constraints]


def _annotated(annotation, n: int) -> Mission:
    return load_mission(_spec(GoalNode(tuple(_leaf() for _ in range(n)), annotation=annotation)))


# ---------------------------------------------------------------------------------------------
# SEQ / FB generation (§6.1) and trimming (§6.4)


def test_sequence_of_three():
    """G4;G5;G6: consecutive pairs only."""
    assert _constraints(_annotated(("flat", ";"), 3)) == [
        ("SEQ", "AT1_1|1", "AT2_1|1"), ("SEQ", "AT2_1|1", "AT3_1|1")]


def test_fallback_to_a_sequence_reaches_both_of_its_tasks():
    """FALLBACK(G4, G5;G6): a task falls back to a SEQ subtree through both endpoints."""
    assert sorted(_constraints(_annotated(("FALLBACK", 0, (";", 1, 2)), 3))) == [
        ("FB", "AT1_1|1", "AT2_1|1"), ("FB", "AT1_1|1", "AT3_1|1"), ("SEQ", "AT2_1|1", "AT3_1|1")]


def test_sequence_after_a_fallback_follows_both_of_its_tasks():
    """(FALLBACK(G4,G5));G6: whichever of G4/G5 runs, G6 comes after it."""
    assert sorted(_constraints(_annotated((";", ("FALLBACK", 0, 1), 2), 3))) == [
        ("FB", "AT1_1|1", "AT2_1|1"), ("SEQ", "AT1_1|1", "AT3_1|1"), ("SEQ", "AT2_1|1", "AT3_1|1")]


def test_sequence_from_a_fallback_to_a_parallel_pair():
    """(FALLBACK(G4,G5));(G6#G7): all four endpoint pairs are SEQ."""
    assert sorted(_constraints(_annotated((";", ("FALLBACK", 0, 1), ("#", 2, 3)), 4))) == [
        ("FB", "AT1_1|1", "AT2_1|1"),
        ("SEQ", "AT1_1|1", "AT3_1|1"), ("SEQ", "AT1_1|1", "AT4_1|1"),
        ("SEQ", "AT2_1|1", "AT3_1|1"), ("SEQ", "AT2_1|1", "AT4_1|1"),
    ]


def test_sequence_after_a_parallel_operator_is_trimmed():
    """((G4;G5)#G6);G7: G7 follows every endpoint of the parallel subtree, but SEQ (AT1, AT4) is
    implied by SEQ (AT1, AT2) and SEQ (AT2, AT4) and trimmed (§6.4)."""
    found = _constraints(_annotated((";", ("#", (";", 0, 1), 2), 3), 4))
    assert sorted(found) == [
        ("SEQ", "AT1_1|1", "AT2_1|1"), ("SEQ", "AT2_1|1", "AT4_1|1"), ("SEQ", "AT3_1|1", "AT4_1|1")]


def test_constraints_span_every_decomposition_pair():
    """TaskB has two methods: SEQ and FB link every decomposition of one task to every one of
    the other."""
    tree = GoalNode((_leaf("TaskA"), _leaf("TaskB"), _leaf("TaskA")), annotation=(";", 0, ("FALLBACK", 1, 2)))
    mission = load_mission(_spec(tree, _task("TaskA", "act1"), _task("TaskB", "act1", "act1")))
    assert sorted(_constraints(mission)) == [
        ("FB", "AT2_1|1", "AT3_1|1"), ("FB", "AT2_1|2", "AT3_1|1"),
        ("SEQ", "AT1_1|1", "AT2_1|1"), ("SEQ", "AT1_1|1", "AT2_1|2"),
    ]


def test_context_dependency_orders_any_parallel_pair():
    """G4 # G5 # G6 where G6's context (``is_lit``) is false but AT1 lights the room: the
    non-adjacent parallel pair (AT1, AT3) becomes SEQ; the other parallel pairs vanish."""
    g6 = GoalNode((TaskNode("TaskC"),), condition="current_room.is_lit")
    tree = GoalNode((_leaf("TaskA"), _leaf("TaskB"), g6), annotation=("flat", "#"))
    mission = load_mission(_spec(tree, _task("TaskA", "act2"), _task("TaskB", "act1"), _task("TaskC", "act1")))
    assert _constraints(mission) == [("SEQ", "AT1_1|1", "AT3_1|1")]
    assert generate_constraints(mission.task_graph) == mission.constraints


# ---------------------------------------------------------------------------------------------
# Execution constraints and robot numbers (§6.3, §6.5)


def test_execution_constraint_flags():
    for group, divisible in ((False, True), (True, False)):
        tree = GoalNode((_leaf(), _leaf()), annotation=("flat", "#"), group=group, divisible=divisible)
        mission = load_mission(_spec(tree))
        assert [(c.kind, c.group, c.divisible) for c in mission.constraints] == [("EC", group, divisible)]


def _robot_numbers(tmp_path: Path, first: str, second: str) -> Mission:
    """AT1 # AT2 below a Divisible=False goal (the tasks share robots), with RobotNumber values."""
    tree = GoalNode((TaskNode("TaskA"), TaskNode("TaskA")), annotation=("flat", "#"), divisible=False)
    hddl, gm, config = _spec(tree).write(tmp_path)
    doc = json.loads(gm.read_text())
    for node in doc["actors"][0]["nodes"]:
        if node["text"].startswith("AT1:"):
            node["customProperties"]["RobotNumber"] = first
        elif node["text"].startswith("AT2:"):
            node["customProperties"]["RobotNumber"] = second
    gm.write_text(json.dumps(doc))
    return Mission.load(hddl, gm, config)


@pytest.mark.parametrize("first, second, ok", [
    ("2", "2", True), ("2", "3", False), ("3", "2", False),  # fixed/fixed: equal
    ("3", "[2,4]", True), ("[2,4]", "3", True), ("1", "[2,4]", False), ("[2,4]", "5", False),  # fixed in range
    ("[1,2]", "[2,3]", True), ("[2,3]", "[1,2]", True), ("[1,2]", "[3,4]", False), ("[3,4]", "[1,2]", False),
])
def test_robot_numbers_of_execution_constrained_tasks(tmp_path, first, second, ok):
    mission = _robot_numbers(tmp_path, first, second)
    if ok:
        assert [c.kind for c in mission.constraints] == ["EC"]
        assert mission.decomposition_space().count == 1
    else:
        with pytest.raises(MissionError, match=r"Wrong robot number for execution constrained tasks "
                                               r"\[AT1_1\|1\] and \[AT2_1\|1\]"):
            _ = mission.constraints


def test_the_constraint_list_reads_back_as_the_tuples_it_was_given():
    """The final list is kept by column; reading it back (iterating, by index, by slice) gives
    the same named tuples with the same kinds and flags, and it equals a list of them."""
    from mutrose_cp.pipeline.constraints import EC, FB, SEQ, Constraint, Constraints

    given = [Constraint(SEQ, 3, 7), Constraint(FB, 7, 2), Constraint(EC, 4, 9, False, True),
             Constraint(EC, 9, 4, True, False), Constraint(EC, 1, 2, False, False)]
    stored = Constraints(given)
    assert list(stored) == given and stored == given and given == stored and stored == Constraints(given)
    assert [stored[i] for i in range(-5, 5)] == given + given and stored[1:4] == given[1:4]
    assert all(type(c) is Constraint and type(c.kind) is type(SEQ) for c in stored)
    assert [(c.group, c.divisible) for c in stored] == [(True, True), (True, True), (False, True), (True, False),
                                                        (False, False)]
    assert stored != given[:4] and stored != [*given[:4], Constraint(EC, 1, 2)]
    assert stored.count_by_kind() == {"SEQ": 1, "FB": 1, "EC": 3}
    stored.add_all_pairs(EC, [5, 6], [8, 9, 10], False, True)  # few pairs: appended one by one
    stored.add_all_pairs(SEQ, [1, 2, 3], [4, 5, 6, 7])  # many: whole columns at once
    assert list(stored)[5:] == [Constraint(EC, a, b, False, True) for a in (5, 6) for b in (8, 9, 10)] + [
        Constraint(SEQ, a, b) for a in (1, 2, 3) for b in (4, 5, 6, 7)]
    copied = Constraints()
    for row in stored.rows():
        copied.append_row(row)
    assert copied == stored and len(list(stored.rows())) == len(stored) == 23


def test_a_list_of_constraints_reads_as_the_rows_it_would_be_stored_as():
    """The output reads constraints as stored rows (a plain list, which the API accepts, is
    stored first): each row stands for its constraint."""
    from mutrose_cp.pipeline.constraints import EC, FB, SEQ, Constraint, Constraints, constraint_of_row

    given = [Constraint(SEQ, 3, 7), Constraint(FB, 7, 2), Constraint(EC, 4, 9, False, True),
             Constraint(EC, 9, 4, True, False), Constraint(EC, 1, 2, False, False)]
    assert [constraint_of_row(row) for row in Constraints(given).rows()] == given


def _stored_with_moved_runs():
    """A list of two stored rows, then moved runs of another list (as a stamped mission's
    constraints are made), and the constraints it stands for."""
    from mutrose_cp.pipeline.constraints import EC, FB, SEQ, Constraint, Constraints

    source = Constraints([Constraint(SEQ, 3, 7), Constraint(FB, 7, 2), Constraint(EC, 4, 9, False, True),
                          Constraint(EC, 9, 4, True, False)])
    stored = Constraints([Constraint(SEQ, 0, 1), Constraint(EC, 1, 0, False, False)])
    for lo, hi, shift in ((0, 4, 0), (1, 3, 10), (0, 2, 20), (2, 2, 5), (0, 2, 30)):
        stored.extend_shifted(source, lo, hi, shift)
    moved = [c._replace(first=c.first + shift, second=c.second + shift)
             for lo, hi, shift in ((0, 4, 0), (1, 3, 10), (0, 2, 20), (0, 2, 30)) for c in list(source)[lo:hi]]
    return stored, [Constraint(SEQ, 0, 1), Constraint(EC, 1, 0, False, False), *moved]


def test_moved_runs_are_counted_and_read_as_the_rows_they_stand_for():
    """Moved runs (a stamped copy's constraints) are kept as runs until something reads the
    rows: the length, the counts by kind and the runs come without storing them; every other
    read, and every append, stores them first, in their place."""
    from mutrose_cp.pipeline.constraints import EC, SEQ, Constraint

    stored, expected = _stored_with_moved_runs()
    assert len(stored) == len(expected) == 12
    assert stored.count_by_kind() == {"SEQ": 4, "FB": 4, "EC": 4}
    assert [(run.lo, run.hi, run.shift) for run in stored.runs()] == [(0, 2, 0), (0, 4, 0), (1, 3, 10), (0, 2, 20),
                                                                    (0, 2, 30)]
    assert list(stored) == expected and stored[5] == expected[5]
    stored, _ = _stored_with_moved_runs()
    assert [row[1:3] for row in stored.rows(4, 7)] == [(c.first, c.second) for c in expected[4:7]]
    stored, _ = _stored_with_moved_runs()
    runs = []
    for run in stored.runs():  # the runs as they were when asked for, though reading stores them
        runs.append([row[1:3] for row in run.source.rows(run.lo, run.hi)])
        assert len(list(stored.rows())) == 12
    assert len(runs) == 5 and runs[2] == [(7, 2), (4, 9)]
    stored, _ = _stored_with_moved_runs()
    stored.append_row((0, 50, 51, 3))
    stored.add_all_pairs(EC, [60], [61], False, True)
    assert list(stored) == [*expected, Constraint(SEQ, 50, 51), Constraint(EC, 60, 61, False, True)]
    assert [(run.lo, run.hi, run.shift) for run in stored.runs()] == [(0, 14, 0)]


def test_the_constraints_section_is_each_constraint_formatted_in_order(monkeypatch):
    """The constraints' text is filled in templates, a run at a time (a moved run fills its
    source's template with its own keys): it is each constraint's own text, in order, and the
    streamed list holds them in order."""
    import io

    from mutrose_cp.output import boost_json, constraint_texts as texts

    def one_by_one(constraints):
        return [(lambda head, tail: head + f"t{c.first}" + texts._BETWEEN_KEYS + f"t{c.second}" + tail)(
            *texts.constraint_text_parts(c)) for c in constraints]

    key = "t{}".format
    stored, expected = _stored_with_moved_runs()
    monkeypatch.setattr(texts, "RUN_ROWS", 3)  # the stored run is cut in templates of 3 rows
    made = list(texts.constraint_texts(stored, key))
    assert len(made) == 6 and texts.SEPARATOR.join(made) == texts.SEPARATOR.join(one_by_one(expected))
    assert len(list(stored.runs())) == 5  # the moved runs were written without being stored
    assert texts.SEPARATOR.join(texts.constraint_texts(expected, key)) == texts.SEPARATOR.join(one_by_one(expected))
    assert '"group": "False",\n            "divisible": "True"' in made[1]
    fh = io.StringIO()
    boost_json.write_list(fh, texts.constraint_texts(stored, key), 4)
    assert fh.getvalue() == "[\n        " + ",\n        ".join(one_by_one(expected)) + "\n    ]"
    fh = io.StringIO()
    boost_json.write_list(fh, texts.constraint_texts([], key), 4)
    assert fh.getvalue() == '""'


def test_implied_constraints_are_found_through_short_and_long_neighbour_lists():
    """Dropping implied constraints asks whether two neighbour lists share a vertex: scanned when
    both are short, through a set when they are long; absent lists share nothing."""
    from mutrose_cp.pipeline.constraints import _meet

    assert _meet([1, 2], [3, 2]) and not _meet([1, 2], [3, 4])
    assert _meet(list(range(100)), [500, 99]) and not _meet(list(range(100)), list(range(100, 200)))
    assert not _meet(None, [1]) and not _meet([1], None) and not _meet([], [])
