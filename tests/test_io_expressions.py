"""Expression languages of the goal model: runtime annotations, conditions, select, forAll.

Spec: ``goal-model.md`` §5 (annotations), §7 (forAll), §8 (select), §9 (conditions).
"""
from __future__ import annotations

import pytest

from mutrose_cp.errors import MissionError
from mutrose_cp.io.expressions import make_atom, parse_condition, parse_forall, parse_node_text, parse_select
from mutrose_cp.model import AnnotationLeaf, AnnotationOp, Atom, BoolOp


def L(name: str) -> AnnotationLeaf:
    return AnnotationLeaf(name)


def Seq(*children: object) -> AnnotationOp:
    return AnnotationOp(";", tuple(children))  # type: ignore[arg-type]


def Par(*children: object) -> AnnotationOp:
    return AnnotationOp("#", tuple(children))  # type: ignore[arg-type]


def Fb(*children: object) -> AnnotationOp:
    return AnnotationOp("FALLBACK", tuple(children))  # type: ignore[arg-type]


def annotation(text: str) -> object:
    return parse_node_text(text)[1]


def error_of(call, *args) -> str:
    with pytest.raises(MissionError) as info:
        call(*args)
    return str(info.value)


# ---------------------------------------------------------------------------------------------
# Runtime annotations


def test_node_text_returns_id_and_annotation() -> None:
    assert parse_node_text("G1: Rooms Are Prepared For New Patients [G2;G3]") == ("G1", Seq(L("G2"), L("G3")))


@pytest.mark.parametrize(
    "text",
    [
        "G2: Rooms To Be Prepared Are Fetched",
        "G5: Something []",
        "G5: Something [ ]",
        "G8: Fetch Delivery's Patient",
    ],
)
def test_no_or_empty_annotation_is_none(text: str) -> None:
    assert parse_node_text(text)[1] is None


def test_annotation_without_space_before_bracket() -> None:
    assert annotation("G3: Pickup Dishes and Retrieve Them to Kitchen[G4;G5;G8]") == Seq(L("G4"), L("G5"), L("G8"))


def test_same_kind_operators_are_flattened() -> None:
    assert annotation("G1: x [G2;G3;G4]") == Seq(L("G2"), L("G3"), L("G4"))
    assert annotation("G1: x [G2#G3#G4#G5]") == Par(L("G2"), L("G3"), L("G4"), L("G5"))
    assert annotation("G1: x [(G2;G3);G4]") == Seq(L("G2"), L("G3"), L("G4"))
    assert annotation("G1: x [G2;(G3;G4)]") == Seq(L("G2"), L("G3"), L("G4"))


def test_fallback_flattening_on_both_sides() -> None:
    assert annotation("G1: x [FALLBACK(FALLBACK(G1,G2),G3)]") == Fb(L("G1"), L("G2"), L("G3"))
    assert annotation("G1: x [FALLBACK(G1,FALLBACK(G2,G3))]") == Fb(L("G1"), L("G2"), L("G3"))


def test_different_kinds_stay_nested() -> None:
    assert annotation("G1: x [G2;(G3#G4)]") == Seq(L("G2"), Par(L("G3"), L("G4")))
    assert annotation("G1: x [FALLBACK(G2;G3,G4)]") == Fb(Seq(L("G2"), L("G3")), L("G4"))
    assert annotation("G1: x [FALLBACK(G2,G3);G4]") == Seq(Fb(L("G2"), L("G3")), L("G4"))


def test_parallel_binds_tighter_than_sequence() -> None:
    assert annotation("G1: x [G2#G3;G4#G5]") == Seq(Par(L("G2"), L("G3")), Par(L("G4"), L("G5")))
    assert annotation("G1: x [G2;G3#G4]") == Seq(L("G2"), Par(L("G3"), L("G4")))
    assert annotation("G1: x [(G2;G3)#G4]") == Par(Seq(L("G2"), L("G3")), L("G4"))


def test_leaves_goal_or_task() -> None:
    result = annotation("G1: x [AT1;G2]")
    assert result == Seq(L("AT1"), L("G2"))
    assert isinstance(result, AnnotationOp)
    assert [c.is_goal for c in result.children] == [False, True]  # type: ignore[union-attr]


def test_single_name_annotation() -> None:
    assert annotation("G1: x [G2]") == L("G2")


def test_characters_outside_the_grammar_are_skipped() -> None:
    # apostrophes, digits, hyphens, underscores and accented letters are skipped by the lexer
    assert parse_node_text("G7: Step 2 - l'été_x [G8 ; G9]") == ("G7", Seq(L("G8"), L("G9")))


def test_whitespace_inside_annotation_is_ignored() -> None:
    assert annotation("G1: x [ FALLBACK ( G2 , G3 ) ]") == Fb(L("G2"), L("G3"))


def test_error_reports_annotation_column_and_expectation() -> None:
    message = error_of(parse_node_text, "G1: x [G2;;G3]")
    assert message == "Parse error in runtime annotation: [G2;;G3]: column 5: expected a goal or task name"


@pytest.mark.parametrize(
    ("text", "shown", "column", "expected"),
    [
        ("G1: x [G2;(G3", "[G2;(G3", 8, "')', ';' or '#'"),
        ("G1: x [G2", "[G2", 4, "';', '#' or ']'"),
        ("G1: x [FALLBACK G2]", "[FALLBACK G2]", 11, "'('"),
        ("G1: x [FALLBACK(G2 G3)]", "[FALLBACK(G2 G3)]", 14, "',', ';' or '#'"),
        ("G1: x [G2] more", "[G2] more", 6, "end of text"),
        ("G1 x [G2]", "G1 x [G2]", 4, "':'"),
        ("G1: first, second", "G1: first, second", 10, "a description word, '[' or end of text"),
        ("G1: FALLBACK plan", "G1: FALLBACK plan", 5, "a description word, '[' or end of text"),
    ],
)
def test_annotation_syntax_errors(text: str, shown: str, column: int, expected: str) -> None:
    message = error_of(parse_node_text, text)
    assert message == f"Parse error in runtime annotation: {shown}: column {column}: expected {expected}"


# ---------------------------------------------------------------------------------------------
# Conditions


def A(text: str) -> Atom:
    return make_atom(text)


def test_or_binds_tighter_than_and() -> None:
    assert parse_condition("a && b || c") == BoolOp("&&", (A("a"), BoolOp("||", (A("b"), A("c")))))
    assert parse_condition("a || b && c") == BoolOp("&&", (BoolOp("||", (A("a"), A("b"))), A("c")))


def test_parentheses_override_precedence() -> None:
    assert parse_condition("(a && b) || c") == BoolOp("||", (BoolOp("&&", (A("a"), A("b"))), A("c")))


def test_same_operator_is_flattened() -> None:
    assert parse_condition("a && b && c") == BoolOp("&&", (A("a"), A("b"), A("c")))
    assert parse_condition("a || b || c || d") == BoolOp("||", (A("a"), A("b"), A("c"), A("d")))
    assert parse_condition("(a && b) && c") == BoolOp("&&", (A("a"), A("b"), A("c")))


@pytest.mark.parametrize("text", ["", "   ", "\t"])
def test_empty_condition_is_none(text: str) -> None:
    assert parse_condition(text) is None


def test_in_atom_is_one_atom() -> None:
    cond = parse_condition("p.name in current_room.patients && !p.checked")
    assert cond == BoolOp(
        "&&",
        (
            Atom("p.name in current_room.patients", "p", "name", False, "in", "current_room.patients"),
            Atom("!p.checked", "p", "checked", True, None, ""),
        ),
    )


@pytest.mark.parametrize(
    ("text", "atom"),
    [
        ("current_room.is_clean", Atom("current_room.is_clean", "current_room", "is_clean")),
        ("!r.is_prepared", Atom("!r.is_prepared", "r", "is_prepared", True)),
        ("not v.flag", Atom("not v.flag", "v", "flag", True)),
        ('r.name = "Kitchen"', Atom('r.name = "Kitchen"', "r", "name", False, "=", "Kitchen")),
        ('r.name == "SanitizationRoom"', Atom('r.name == "SanitizationRoom"', "r", "name", False, "=", "SanitizationRoom")),
        ("current_room.num_objects = 0", Atom("current_room.num_objects = 0", "current_room", "num_objects", False, "=", "0")),
        ("v.a <> 2.5", Atom("v.a <> 2.5", "v", "a", False, "<>", "2.5")),
        ("v.a >= 3", Atom("v.a >= 3", "v", "a", False, ">=", "3")),
        ("v.a<=3", Atom("v.a<=3", "v", "a", False, "<=", "3")),
        ("v.a > 1", Atom("v.a > 1", "v", "a", False, ">", "1")),
        ("v.a < 1", Atom("v.a < 1", "v", "a", False, "<", "1")),
        ("a.b.c", Atom("a.b.c", "a", "b.c")),
    ],
)
def test_atom_fields(text: str, atom: Atom) -> None:
    assert parse_condition(text) == atom


def test_atom_trailing_blanks_removed() -> None:
    cond = parse_condition("  r.clean   ")
    assert cond == Atom("r.clean", "r", "clean")


def test_characters_outside_atoms_are_skipped() -> None:
    # '-' and a leading digit cannot start a token and are skipped like the original lexer does
    assert parse_condition("- 5 r.clean") == Atom("r.clean", "r", "clean")


def test_plain_achieve_condition_example() -> None:
    cond = parse_condition("current_room.staphylococcus = 0 || current_room.occupied")
    assert isinstance(cond, BoolOp) and cond.op == "||"
    assert [c.text for c in cond.children] == ["current_room.staphylococcus = 0", "current_room.occupied"]  # type: ignore[union-attr]


@pytest.mark.parametrize(
    ("text", "column", "expected"),
    [
        ("a &&", 5, "an atom such as v.attr"),
        ("(a", 3, "'&&', '||' or ')'"),
        ("a ) b", 3, "'&&', '||' or end of expression"),
        ("()", 2, "an atom such as v.attr"),
    ],
)
def test_condition_syntax_errors(text: str, column: int, expected: str) -> None:
    assert error_of(parse_condition, text) == f"Parse error in condition: {text}: column {column}: expected {expected}"


# ---------------------------------------------------------------------------------------------
# select


def test_select_fields() -> None:
    s = parse_select("world_db->select(r:Room | r.is_occupied)")
    assert (s.queried, s.variable, s.type) == ("world_db", "r", "Room")
    assert s.condition == Atom("r.is_occupied", "r", "is_occupied")
    assert s.text == "world_db->select(r:Room | r.is_occupied)"


def test_select_on_variable_path_with_empty_condition() -> None:
    s = parse_select("current_agent.requested_objects->select(o:Object | )")
    assert (s.queried, s.variable, s.type, s.condition) == ("current_agent.requested_objects", "o", "Object", None)


def test_select_without_spaces() -> None:
    s = parse_select("world_db->select(r:Room|!r.is_prepared)")
    assert s.condition == Atom("!r.is_prepared", "r", "is_prepared", True)


def test_select_condition_with_and() -> None:
    s = parse_select("world_db->select(p:Patient | p.name in current_room.patients && !p.checked)")
    assert isinstance(s.condition, BoolOp) and s.condition.op == "&&"
    assert [c.op for c in s.condition.children] == ["in", None]  # type: ignore[union-attr]


@pytest.mark.parametrize(
    "text",
    [
        "",
        "world_db->select(r : Room | x)",  # spaces around ':'
        "world_db->select(r:R | x)",  # one-letter type
        "world_db.select(r:Room | x)",
        "world_db->select(r:Room x)",  # no '|'
        "world_db->select(r:Room | x",  # no ')'
        " world_db->select(r:Room | x)",  # the whole value must match
    ],
)
def test_select_regex_failures(text: str) -> None:
    assert error_of(parse_select, text) == f"Invalid select statement {text} in GM."


def test_select_condition_error_is_a_query_error_with_column_in_the_select() -> None:
    text = "world_db->select(r:Room | r.a && )"
    assert error_of(parse_select, text) == (
        f"Parse error in query: {text}: column {len(text)}: expected an atom such as v.attr"
    )


# ---------------------------------------------------------------------------------------------
# forAll


def test_forall_fields() -> None:
    f = parse_forall("rooms->forAll(current_room | current_room.is_prepared)")
    assert (f.iterated, f.iteration) == ("rooms", "current_room")
    assert f.condition == Atom("current_room.is_prepared", "current_room", "is_prepared")
    assert f.condition_text == "current_room.is_prepared"


@pytest.mark.parametrize(
    "text", ["occupied_rooms->forAll(current_room | )", "deliveries_requested->forAll(current_delivery |)"]
)
def test_forall_empty_condition(text: str) -> None:
    f = parse_forall(text)
    assert f.condition is None and f.condition_text == ""


def test_forall_numeric_condition() -> None:
    f = parse_forall("rooms->forAll(current_room | current_room.num_objects = 0)")
    assert f.condition == Atom("current_room.num_objects = 0", "current_room", "num_objects", False, "=", "0")


def test_forall_condition_stops_at_first_closing_parenthesis() -> None:
    f = parse_forall("rooms->forAll(r | r.a) && r.b)")
    assert f.condition_text == "r.a"


@pytest.mark.parametrize(
    "text",
    [
        "rooms->forAll(r : Room | r.clean)",  # typed iteration variable (HEAD rejects it)
        "rooms->forAll(r r.clean)",
        "rooms.forAll(r | r.clean)",
        "->forAll(r | )",
    ],
)
def test_forall_regex_failures(text: str) -> None:
    assert error_of(parse_forall, text) == f"Invalid forAll statement {text} in GM."


def test_forall_condition_error_has_column_in_the_forall() -> None:
    text = "rooms->forAll(r | r.a && )"
    assert error_of(parse_forall, text) == (
        f"Parse error in condition: {text}: column {len(text)}: expected an atom such as v.attr"
    )


@pytest.mark.parametrize("op", [";", "#"])
def test_a_long_chain_of_one_operator_is_one_flat_node(op: str) -> None:
    """A sequence of thousands of goals (a generated mission) must not nest a node per operator:
    transforming such a tree recursed once per goal and crashed past Python's recursion limit."""
    names = [f"G{i}" for i in range(2, 5002)]
    _, annotation = parse_node_text(f"G1: root [{op.join(names)}]")
    assert annotation == AnnotationOp(op, tuple(AnnotationLeaf(n) for n in names))
