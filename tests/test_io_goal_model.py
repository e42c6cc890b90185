"""Goal model reader (spec ``goal-model.md`` §1–§4, §6–§8): reference corpus and bad inputs."""
from __future__ import annotations

import json
import os
from pathlib import Path
from typing import Any

import pytest

from mutrose_cp.errors import MissionError
from mutrose_cp.io.goal_model import load_goal_model, parse_goal_model
from mutrose_cp.model import AnnotationLeaf, AnnotationOp, Atom, BoolOp, Context, GoalModel, RobotNumber, VarDecl

REPO_ROOT = Path(__file__).resolve().parents[1]


def _reference_root() -> Path:
    root = Path(os.environ.get("MUTROSE_REFERENCE", REPO_ROOT / ".." / "shared" / "reference"))
    return root.resolve()


REFERENCE = _reference_root()
REFERENCE_GMS = sorted(REFERENCE.glob("*/*/gm/*.txt")) if REFERENCE.is_dir() else []


def _require_reference() -> None:
    if not REFERENCE_GMS:
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"reference corpus not found at {REFERENCE} (set MUTROSE_REFERENCE)")
        pytest.skip(f"reference corpus not found at {REFERENCE}")


def reference_gm(relative: str) -> GoalModel:
    _require_reference()
    return load_goal_model(REFERENCE / relative)


ROOM_PREPARATION = "missions/room-preparation/gm/Room Preparation.txt"
VITAL_SIGNS = "missions/vital-signs-monitoring/gm/VitalSignsMonitoring.txt"
FOOD_DELIVERY = "missions/food-logistics/gm/FoodLogisticsDelivery.txt"
DELIVER_GOODS = "missions/deliver-goods-equipment/gm/DeliverGoodsEquipment.txt"


# ---------------------------------------------------------------------------------------------
# Reference corpus


def test_reference_corpus_is_present() -> None:
    _require_reference()
    assert len(REFERENCE_GMS) >= 16


@pytest.mark.parametrize(
    "relative", [str(p.relative_to(REFERENCE)) for p in REFERENCE_GMS] or ["<absent>"]
)
def test_every_reference_goal_model_parses(relative: str) -> None:
    gm = reference_gm(relative)
    assert gm.warnings == ()
    assert gm.node(gm.root).parent is None
    assert gm.dfs[0] == gm.root
    assert sorted(gm.dfs) == sorted(n.key for n in gm.nodes)
    for node in gm.nodes:
        assert node.kind in ("goal", "task")
        for child in node.children:  # keys tell apart the two G17 of the scalability VSM
            assert gm.node(child).parent == node.key
        if node.kind == "task":
            assert node.task_name and node.id.startswith("AT")
        if node.goal_type == "Query":
            assert node.query is not None


def test_room_preparation_facts() -> None:
    gm = reference_gm(ROOM_PREPARATION)
    assert gm.root == "G1"
    g1 = gm.node("G1")
    assert g1.children == ("G2", "G3")
    assert g1.annotation == AnnotationOp(";", (AnnotationLeaf("G2"), AnnotationLeaf("G3")))
    g3 = gm.node("G3")
    assert g3.goal_type == "Achieve"
    assert g3.forall is not None
    assert (g3.forall.iterated, g3.forall.iteration) == ("rooms", "current_room")
    assert g3.forall.condition == Atom("current_room.is_prepared", "current_room", "is_prepared")
    assert g3.achieve_text == "rooms->forAll(current_room | current_room.is_prepared)"
    assert g3.monitors == (VarDecl("rooms", "Sequence(Room)"),)
    assert g3.monitors[0].is_collection and g3.monitors[0].base_type == "Room"
    assert g3.controls == (VarDecl("current_room", "Room"),)
    assert gm.node("G4").annotation == AnnotationOp("#", (AnnotationLeaf("G5"), AnnotationLeaf("G10")))
    assert gm.node("G4").context == Context("trigger", "E2")
    assert gm.node("G5").group is False and gm.node("G5").divisible is True
    assert gm.node("G3").group is True
    at3 = gm.node("AT3")
    assert at3.robot_number == RobotNumber(2, 4, fixed=False)
    assert at3.task_name == "FurnitureMoving" and at3.location == "current_room"
    g10 = gm.node("G10")
    assert g10.context is not None and g10.context.kind == "condition"
    assert g10.context.text == "current_room.is_clean"
    assert g10.context.condition == Atom("current_room.is_clean", "current_room", "is_clean")
    g2 = gm.node("G2")
    assert g2.goal_type == "Query" and g2.query is not None
    assert (g2.query.queried, g2.query.variable, g2.query.type) == ("world_db", "r", "Room")
    assert g2.controls == (VarDecl("rooms", "Sequence(Room)"),)
    # vertex order of the original: first appearance in the links sorted by child x (§3)
    assert [n.id for n in gm.nodes] == [
        "G1", "G2", "G6", "AT1", "G5", "G4", "G7", "G8", "G9", "AT2", "G3", "G10", "AT3",
    ]
    assert gm.dfs == ("G1", "G2", "G3", "G4", "G5", "G6", "AT1", "G7", "G8", "G9", "AT2", "G10", "AT3")


def test_vital_signs_facts() -> None:
    gm = reference_gm(VITAL_SIGNS)
    g3 = gm.node("G3")
    assert g3.annotation == AnnotationOp("FALLBACK", (AnnotationLeaf("G4"), AnnotationLeaf("G17")))
    assert g3.group is False
    g5 = gm.node("G5")
    assert g5.query is not None
    condition = g5.query.condition
    assert isinstance(condition, BoolOp) and condition.op == "&&"
    in_atom, negated = condition.children
    assert isinstance(in_atom, Atom) and in_atom.op == "in"
    assert (in_atom.variable, in_atom.attribute, in_atom.value) == ("p", "name", "current_room.patients")
    assert isinstance(negated, Atom) and negated.negated and negated.attribute == "checked"
    g7 = gm.node("G7")
    assert g7.forall is not None and g7.forall.iterated == "current_room_patients"
    assert gm.node("G4").children == ("G5", "G6", "G7", "G16")
    assert gm.node("G19").context == Context("trigger", "LowBattery")


def test_or_decomposed_goal() -> None:
    gm = reference_gm(FOOD_DELIVERY)
    assert [n.id for n in gm.nodes if n.or_decomposed] == ["G10"]
    assert gm.node("G10").children == ("G11", "G12")
    assert gm.node("G3").group is True and gm.node("G3").divisible is False
    assert gm.node("AT3").robot_number == RobotNumber(1, 2, fixed=False)
    assert gm.node("AT3").params == ("current_patient",)


def test_query_on_a_variable_path() -> None:
    gm = reference_gm(DELIVER_GOODS)
    query = gm.node("G4").query
    assert query is not None
    assert (query.queried, query.variable, query.type, query.condition) == (
        "current_agent.requested_objects", "o", "Object", None,
    )
    assert gm.node("G10").context == Context("trigger", "BatteryLow")


def test_duplicate_goal_ids_are_not_checked() -> None:
    # scalability VSM has two G17 nodes; like the original, lookups find the first one
    gm = reference_gm("scalability/vital-signs-monitoring/gm/VitalSignsMonitoring.txt")
    assert [gm.node(k).id for k in gm.dfs].count("G17") == 2
    assert "G17#2" in gm.dfs  # the second node reusing an id gets its own key
    assert gm.node("G17") is next(n for n in gm.nodes if n.id == "G17")


# ---------------------------------------------------------------------------------------------
# Synthetic models


def node(uid: str, text: str, x: float, kind: str = "istar.Goal", **props: Any) -> dict[str, Any]:
    return {"id": uid, "text": text, "type": kind, "x": x, "y": 100, "customProperties": dict(props)}


def link(child: str, parent: str, kind: str = "istar.AndRefinementLink", lid: str | None = None) -> dict[str, Any]:
    return {"id": lid or f"{child}->{parent}", "type": kind, "source": child, "target": parent}


def document(nodes: list[dict[str, Any]], links: list[dict[str, Any]]) -> str:
    actor = {"id": "a1", "text": "M1: Mission", "type": "istar.Actor", "x": 0, "y": 0,
             "customProperties": {"Description": ""}, "nodes": nodes}
    return json.dumps({"actors": [actor], "orphans": [], "dependencies": [], "links": links,
                       "display": {}, "tool": "pistar.2.0.0", "istar": "2.0"}, indent=2)


def parse(nodes: list[dict[str, Any]], links: list[dict[str, Any]]) -> GoalModel:
    return parse_goal_model(document(nodes, links), "gm.txt")


def problems(nodes: list[dict[str, Any]], links: list[dict[str, Any]]) -> list[tuple[str, str]]:
    with pytest.raises(MissionError) as info:
        parse(nodes, links)
    return [(p.where, p.message) for p in info.value.problems]


SIMPLE = [
    node("n1", "G1: Root [G2;G3]", 500),
    node("n2", "G2: Left", 100),
    node("n3", "G3: Right", 900),
]
SIMPLE_LINKS = [link("n2", "n1"), link("n3", "n1")]


def test_children_ordered_by_x_not_file_order() -> None:
    nodes = [
        node("r", "G1: Root", 500),
        node("c", "G4: Right", 900),
        node("a", "G2: Left", 100),
        node("b", "G3: Middle", 400),
        node("t", "AT1: DoIt", 950, "istar.Task"),
    ]
    links = [link("c", "r"), link("a", "r"), link("b", "r"), link("t", "c")]
    gm = parse(nodes, links)
    assert gm.root == "G1"
    assert gm.node("G1").children == ("G2", "G3", "G4")
    assert gm.dfs == ("G1", "G2", "G3", "G4", "AT1")
    assert [n.id for n in gm.nodes] == ["G1", "G2", "G3", "G4", "AT1"]
    assert gm.node("AT1").parent == "G4"


def test_or_link_makes_the_parent_or_decomposed() -> None:
    links = [link("n2", "n1", "istar.OrRefinementLink"), link("n3", "n1")]
    gm = parse([node("n1", "G1: Root", 500), *SIMPLE[1:]], links)
    assert gm.node("G1").or_decomposed is True
    assert gm.node("G2").or_decomposed is False


def test_last_actor_wins() -> None:
    data = json.loads(document(SIMPLE, SIMPLE_LINKS))
    data["actors"].insert(0, {"id": "a0", "nodes": [node("z", "G9: Other", 1)]})
    gm = parse_goal_model(json.dumps(data), "gm.txt")
    assert "G9" not in gm.by_id
    assert any("actors" in w for w in gm.warnings)


def test_property_values() -> None:
    nodes = [
        node("n1", "G1: Root [G2;G3]", 500, GoalType="Query",
             QueriedProperty="world_db->select(r:Room|r.flag)",
             Controls=" rooms : Sequence(Room) , other:Thing ", Group="FALSE", Divisible="maybe"),
        node("n2", "G2: Left", 100, Monitors="rooms, other", CreationCondition='assertion trigger "E1,E2"'),
        node("n3", "G3: Right", 900, GoalType="Achieve",
             AchieveCondition="rooms.x = 0 || rooms.y",
             CreationCondition="something else"),
        node("t", "AT1: Pick_Object", 950, "istar.Task", Location="  ", Params=" a , b ,", RobotNumber=" 3 "),
    ]
    gm = parse(nodes, [*SIMPLE_LINKS, link("t", "n3")])
    g1 = gm.node("G1")
    assert g1.controls == (VarDecl("rooms", "Sequence(Room)"), VarDecl("other", "Thing"))
    assert g1.group is False and g1.divisible is True
    assert any("Divisible" in w for w in gm.warnings)
    g2 = gm.node("G2")
    assert g2.monitors == (VarDecl("rooms"), VarDecl("other"))
    assert g2.context == Context("trigger", "E1,E2")  # one opaque event string
    g3 = gm.node("G3")
    assert g3.context is None
    assert g3.forall is None
    assert g3.achieve_text == "rooms.x = 0 || rooms.y"
    assert isinstance(g3.achieve_condition, BoolOp) and g3.achieve_condition.op == "||"
    at1 = gm.node("AT1")
    assert at1.task_name == "Pick"  # first run of letters
    assert at1.location is None
    assert at1.params == ("a", "b")
    assert at1.robot_number == RobotNumber(3, 3, fixed=True)


def test_odd_goal_type_is_kept_with_a_warning() -> None:
    nodes = [node("n1", "G1: Root [G2;G3]", 500, GoalType="Maintain"), *SIMPLE[1:]]
    gm = parse(nodes, SIMPLE_LINKS)
    assert gm.node("G1").goal_type == "Maintain"
    assert gm.node("G2").goal_type == "Perform"
    assert "gm.txt: goal G1: Invalid goal type on node [G1]: [Maintain]. Defaulting to Perform type." in gm.warnings


def test_nested_annotation_parses_to_nested_ops() -> None:
    nodes = [
        node("n1", "G1: Root [G2;(G3#G4)]", 500),
        node("n2", "G2: A", 100),
        node("n3", "G3: B", 600),
        node("n4", "G4: C", 900),
    ]
    gm = parse(nodes, [link("n2", "n1"), link("n3", "n1"), link("n4", "n1")])
    assert gm.node("G1").annotation == AnnotationOp(
        ";", (AnnotationLeaf("G2"), AnnotationOp("#", (AnnotationLeaf("G3"), AnnotationLeaf("G4"))))
    )


def test_single_node_model() -> None:
    gm = parse([node("n1", "G1: Alone", 10)], [])
    assert gm.root == "G1" and gm.dfs == ("G1",)


# ---------------------------------------------------------------------------------------------
# Bad inputs


def test_truncated_json_reports_line_and_column() -> None:
    text = document(SIMPLE, SIMPLE_LINKS)
    truncated = text[: text.index('"links"') + 12]
    with pytest.raises(MissionError) as info:
        parse_goal_model(truncated, "gm.txt")
    (problem,) = info.value.problems
    lines = truncated.splitlines()
    assert problem.where == f"gm.txt:{len(lines)}:{len(lines[-1]) + 1}"
    assert "invalid JSON" in problem.message


def test_missing_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.txt"
    with pytest.raises(MissionError) as info:
        load_goal_model(missing)
    (problem,) = info.value.problems
    assert problem.where == str(missing)
    assert problem.message == "cannot read goal model file: No such file or directory"


def test_load_reads_a_file(tmp_path: Path) -> None:
    path = tmp_path / "My GM.txt"
    path.write_text(document(SIMPLE, SIMPLE_LINKS), encoding="utf-8")
    gm = load_goal_model(path)
    assert gm.source == str(path) and gm.root == "G1"


def test_annotation_syntax_error_is_located() -> None:
    nodes = [node("n1", "G1: Root [G2;;G3]", 500), *SIMPLE[1:]]
    assert problems(nodes, SIMPLE_LINKS) == [
        ("gm.txt: goal G1", "Parse error in runtime annotation: [G2;;G3]: column 5: expected a goal or task name"),
    ]


def test_bad_forall() -> None:
    nodes = [node("n1", "G1: Root [G2;G3]", 500, GoalType="Achieve",
                  AchieveCondition="rooms->forAll(r : Room | r.clean)"), *SIMPLE[1:]]
    assert problems(nodes, SIMPLE_LINKS) == [
        ("gm.txt: goal G1", "AchieveCondition: Invalid forAll statement rooms->forAll(r : Room | r.clean) in GM."),
    ]


def test_bad_select() -> None:
    nodes = [node("n1", "G1: Root [G2;G3]", 500, GoalType="Query",
                  QueriedProperty="world_db->select(r : Room | r.clean)"), *SIMPLE[1:]]
    assert problems(nodes, SIMPLE_LINKS) == [
        ("gm.txt: goal G1", "QueriedProperty: Invalid select statement world_db->select(r : Room | r.clean) in GM."),
    ]


def test_query_goal_without_select() -> None:
    nodes = [node("n1", "G1: Root [G2;G3]", 500, GoalType="Query"), *SIMPLE[1:]]
    assert problems(nodes, SIMPLE_LINKS) == [("gm.txt: goal G1", "QueriedProperty: Invalid select statement  in GM.")]


def test_select_condition_parse_error() -> None:
    select = "world_db->select(r:Room | r.a && )"
    nodes = [node("n1", "G1: Root [G2;G3]", 500, GoalType="Query", QueriedProperty=select), *SIMPLE[1:]]
    [(where, message)] = problems(nodes, SIMPLE_LINKS)
    assert where == "gm.txt: goal G1"
    assert message.startswith(f"QueriedProperty: Parse error in query: {select}: column {len(select)}: expected")


def test_context_condition_parse_error() -> None:
    nodes = [*SIMPLE[:2], node("n3", "G3: Right", 900, CreationCondition='assertion condition "(a.b"')]
    [(where, message)] = problems(nodes, SIMPLE_LINKS)
    assert where == "gm.txt: goal G3"
    assert message == "CreationCondition: Parse error in condition: (a.b: column 5: expected '&&', '||' or ')'"


@pytest.mark.parametrize("value", ["[1, 2]", "two", "[1,2", "-1"])
def test_bad_robot_number(value: str) -> None:
    nodes = [*SIMPLE, node("t", "AT1: Work", 950, "istar.Task", RobotNumber=value)]
    assert problems(nodes, [*SIMPLE_LINKS, link("t", "n3")]) == [
        ("gm.txt: task AT1", f"Invalid declaration of robot number: {value}"),
    ]


def test_invalid_property() -> None:
    nodes = [*SIMPLE[:2], node("n3", "G3: Right", 900, FailureCondition="x")]
    assert problems(nodes, SIMPLE_LINKS) == [("gm.txt: goal G3", "Invalid property FailureCondition in vertex G3: Right")]


def test_invalid_variable_declaration() -> None:
    nodes = [*SIMPLE[:2], node("n3", "G3: Right", 900, Controls="a : A, : B")]
    assert problems(nodes, SIMPLE_LINKS) == [("gm.txt: goal G3", "Controls: Invalid variable declaration  : B in GM.")]


def test_unknown_link_endpoint() -> None:
    links = [*SIMPLE_LINKS, link("ghost", "n1", lid="L7")]
    assert problems(SIMPLE, links) == [("gm.txt: link L7", "link source ghost is not a node of the goal model")]


def test_bad_node_fields() -> None:
    broken = node("n3", "G3: Right", 900)
    broken["x"] = "left"
    del broken["customProperties"]
    assert problems([*SIMPLE[:2], broken], SIMPLE_LINKS) == [
        ("gm.txt: goal G3", "node is missing 'customProperties'"),
        ("gm.txt: goal G3", "node 'x' must be a number, not \"left\""),
    ]


def test_unsupported_node_type() -> None:
    nodes = [*SIMPLE, node("q", "Q1: Quality", 700, "istar.Quality")]
    assert problems(nodes, [*SIMPLE_LINKS, link("q", "n1")]) == [
        ("gm.txt: node q", "unsupported node type istar.Quality: only istar.Goal and istar.Task are supported"),
    ]


def test_goal_without_id() -> None:
    nodes = [*SIMPLE[:2], node("n3", "Right goal", 900)]
    [(where, message)] = problems(nodes, SIMPLE_LINKS)
    assert where == "gm.txt: node n3"
    assert "G<k>" in message


def test_all_problems_are_collected() -> None:
    nodes = [
        node("n1", "G1: Root [G2;;G3]", 500),
        node("n2", "G2: Left", 100, Bogus="1"),
        node("n3", "G3: Right", 900, GoalType="Achieve", AchieveCondition="a &&"),
    ]
    found = problems(nodes, [*SIMPLE_LINKS, link("n9", "n1", lid="L9")])
    assert [w for w, _ in found] == ["gm.txt: goal G1", "gm.txt: goal G2", "gm.txt: goal G3", "gm.txt: link L9"]
    assert found[2][1] == "AchieveCondition: Parse error in condition: a &&: column 5: expected an atom such as v.attr"


def test_node_with_two_parents() -> None:
    nodes = [*SIMPLE, node("t", "AT1: Work", 950, "istar.Task")]
    links = [*SIMPLE_LINKS, link("t", "n2"), link("t", "n3")]
    assert problems(nodes, links) == [("gm.txt: task AT1", "node has more than one parent (G2, G3)")]


def test_not_a_json_object() -> None:
    with pytest.raises(MissionError) as info:
        parse_goal_model("[1, 2]", "gm.txt")
    assert info.value.problems[0].where == "gm.txt"
