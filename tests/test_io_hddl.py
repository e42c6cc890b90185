"""HDDL domain reader: the reference corpus, the model built from it, and located static errors."""
from __future__ import annotations

import os
from pathlib import Path

import pytest

from mutrose_cp.errors import MissionError
from mutrose_cp.io.hddl import load_domain, parse_domain
from mutrose_cp.model import Comparison, Domain, Literal, NumericEffect, Parameter, Subtask

REPO_ROOT = Path(__file__).resolve().parents[1]
REFERENCE = Path(os.environ.get("MUTROSE_REFERENCE", REPO_ROOT / ".." / "shared" / "reference"))
# every domain of the corpus but the broken copies that show the original's error messages
ERROR_CASES = REFERENCE / "console" / "errors"
CORPUS = sorted(p for p in REFERENCE.glob("**/*.hddl") if ERROR_CASES not in p.parents) if REFERENCE.is_dir() else []


def _reference(relative: str) -> Path:
    """Path of a corpus file; skips (or fails on CI) when the corpus is not available."""
    path = REFERENCE / relative
    if not path.is_file():
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"reference corpus file missing: {path}")
        pytest.skip(f"reference corpus not available at {REFERENCE}")
    return path


def _errors(text: str) -> list[str]:
    with pytest.raises(MissionError) as info:
        parse_domain(text, "dom.hddl")
    return [str(p) for p in info.value.problems]


def _single_error(text: str) -> str:
    errors = _errors(text)
    assert len(errors) == 1, errors
    return errors[0]


# ---------------------------------------------------------------------------------------------
# Reference corpus


def test_corpus_is_present() -> None:
    if not CORPUS:
        if os.environ.get("CI", "").lower() == "true":
            pytest.fail(f"no *.hddl under the reference corpus {REFERENCE}")
        pytest.skip(f"reference corpus not available at {REFERENCE}")
    tops = {p.relative_to(REFERENCE).parts[0] for p in CORPUS}
    assert {"missions", "ihtn", "scalability"} <= tops


@pytest.mark.parametrize("path", CORPUS, ids=lambda p: str(p.relative_to(REFERENCE)))
def test_every_corpus_domain_parses(path: Path) -> None:
    domain = load_domain(path)
    assert domain.source == str(path)
    assert domain.tasks and domain.actions and domain.methods
    for method in domain.methods:
        assert method.task in domain.task_by_name
        ids = {s.id for s in method.subtasks}
        assert all(a in ids and b in ids for a, b in method.ordering)


def test_room_preparation() -> None:
    domain = load_domain(_reference("missions/room-preparation/hddl/Room Preparation.hddl"))
    assert domain.name == "hospital"
    assert domain.types == (
        ("room", "object"),
        ("robot", "object"),
        ("robotteam", "object"),
        ("MoveRobot", "robot"),
        ("CleanerRobot", "robot"),
    )
    assert domain.robot_sorts == {"robot", "robotteam", "MoveRobot", "CleanerRobot"}
    assert domain.capabilities == ("moveobject", "cleaning", "sanitize", "door-opening")

    first, second = domain.methods_of("RoomCleaning")
    assert first.name == "room-cleaning-door-open"
    assert first.ordered and first.preconditions == (Literal("door-open", ("?rm",)),)
    assert [s.task for s in first.subtasks] == ["clean-room"]
    assert first.subtasks[0].id.startswith("__t_id_")

    assert second.name == "room-cleaning-door-closed"
    assert not second.ordered
    assert second.ordering == (("a1", "a2"),)
    assert second.subtasks == (
        Subtask("a1", "open-door", ("?r", "?rm")),
        Subtask("a2", "clean-room", ("?r", "?rm")),
    )
    assert second.preconditions == (Literal("door-open", ("?rm",), False),)

    clean = domain.action_by_name["clean-room"]
    assert clean.capabilities == ("cleaning",)
    assert clean.preconditions == (Literal("clean", ("?rm",), False),)
    assert clean.effects == (Literal("clean", ("?rm",)), Literal("sanitized", ("?r",), False))
    assert clean.parameters == (Parameter("?r", "CleanerRobot"), Parameter("?rm", "room"))
    assert (clean.line, clean.column) == (38, 14)

    furniture = domain.task_by_name["FurnitureMoving"]
    assert furniture.parameters == (Parameter("?rt", "robotteam"), Parameter("?rm", "room"))
    assert domain.methods_of("FurnitureMoving")[0].preconditions == ()


def test_food_logistics_minus_without_space_and_padding() -> None:
    domain = load_domain(_reference("missions/food-logistics/hddl/FoodLogistics.hddl"))
    pickup = domain.methods_of("GetFood")[0]
    assert pickup.parameters[2] == Parameter("?d", "delivery")  # written "?d -delivery"
    assert pickup.ordered and pickup.ordering == ((pickup.subtasks[0].id, pickup.subtasks[1].id),)
    # fewer arguments than the callee declares is legal (PANDA pads the call)
    without_door = next(m for m in domain.methods if m.name == "pickup-without-door-opening")
    assert Subtask(without_door.subtasks[1].id, "approach-door", ("?r1",)) in without_door.subtasks
    assert len(domain.methods_of("PickDishes")) == 3
    assert [m.name for m in domain.methods_of("PickDishes")] == [
        "pick-dishes-with-human",
        "pick-dishes-with-robot-at-location",
        "pick-dishes-with-robot-not-at-location",
    ]
    # generated ids are numbered across the whole domain, in declaration order
    generated = [s.id for m in domain.methods for s in m.subtasks]
    assert generated == [f"__t_id_{n}" for n in range(len(generated))]


def test_object_picking_function_numeric() -> None:
    domain = load_domain(_reference("missions/object-picking-function/hddl/Object Picking.hddl"))
    assert [f.name for f in domain.functions] == ["objects"]
    method = domain.methods_of("PickObject")[0]
    assert method.preconditions == (Comparison("objects", ("?rm",), "=", 1),)
    action = domain.action_by_name["pick-object"]
    assert action.parameters[0] == Parameter("?r", "robot")  # written "?r -robot"
    assert action.numeric_effects == (NumericEffect("decrease", "objects", ("?rm",), 1),)
    assert action.preconditions == () and action.effects == ()


def test_deliver_goods_predicate_declared_twice() -> None:
    domain = load_domain(_reference("missions/deliver-goods-equipment/hddl/DeliverGoodsEqupments.hddl"))
    sorts = [tuple(p.type for p in d.parameters) for d in domain.predicate_declarations("at")]
    assert sorts == [("obj", "storage"), ("location", "agent")]
    assert domain.capabilities == ()


def test_lab_samples_sort_only_mentioned_in_declarations() -> None:
    # `nurse` is never declared in :types but used by a predicate declaration (PANDA creates
    # sorts on the fly): it is accepted and listed as a parentless type.
    domain = load_domain(_reference("missions/lab-samples-logistics/hddl/LabSampleLogistics.hddl"))
    assert ("nurse", None) in domain.types
    assert domain.task_by_name["PickSample"].parameters[1] == Parameter("?n", "nurse")


def test_vital_signs_three_methods() -> None:
    domain = load_domain(_reference("missions/vital-signs-monitoring/hddl/VitalSignsMonitoring.hddl"))
    assert len(domain.methods_of("CollectVitalSigns")) == 3
    collect = domain.action_by_name["infectious-disease-collect"]
    assert collect.capabilities == (
        "check-heart-rate",
        "check-blood-pressure",
        "check-blood-oxigenation",
        "check-body-temperature",
    )


# ---------------------------------------------------------------------------------------------
# Inline well-formed domains

FULL = """; a comment before the domain
(define (domain test) ; trailing comment
  (:requirements :typing :hierarchy :method-preconditions)
  (:types A B - P  C - Q
          D)
  (:types room - object)
  (:constants kitchen hall - room)
  (:predicates (clean ?rm - room) (near ?a - A ?b - B) (near ?rm - room))
  (:functions (objects ?rm - room) (total) - number)
  (:capabilities cap1 cap2)
  (:rewards r1)
  (:task Top :parameters (?r - robot ?rm - room))
  (:task Empty :parameters ())
  (:action act
     :parameters (?r - robot ?rm - room)
     :required-capabilities (cap1 cap2)
     :precondition (and (and (clean ?rm) ()) (not (= (objects ?rm) 2)) (> (objects ?rm) 0.5)
                        (= ?r ?rm) (not (= ?rm kitchen)) (at ?r ?rm) (hascapability ?r cap1)
                        (near ?rm))
     :effect (and (not (clean ?rm)) (increase (objects ?rm) 2) (assign total 0)
                  (and (clean kitchen)))
     :reliability (r1))
  (:action noop :parameters (?r - robot))
  (:method top-partial
     :parameters (?r - robot ?rm - room)
     :task (Top ?r ?rm)
     :precondition (clean ?rm)
     :effect (not (clean ?rm))
     :tasks (and (s1 (act ?r ?rm)) (noop ?r) (s3 (Empty)))
     :order (and (< s1 s3) (s3 < s1))
     :constraints (and (= ?r ?r) (not (= ?r ?rm)) (typeof ?rm - room))
     :causal-links (and (s1 (clean ?rm) s3)))
  (:method top-ordered
     :parameters (?r - robot ?rm - room)
     :task (Top ?r ?rm)
     :ordered-tasks (act ?r kitchen))
  (:method empty-net :task (Empty))
  (:method empty-ordered :task (Empty) :ordered-subtasks () :ordering ())
)
"""


def test_full_feature_domain() -> None:
    domain = parse_domain(FULL, "full.hddl")
    assert domain.types == (
        ("A", "P"),
        ("B", "P"),
        ("C", "Q"),
        ("D", None),
        ("room", "object"),
        ("robot", "object"),
        ("robotteam", "object"),
        ("P", None),
        ("Q", None),
    )
    assert domain.constants == (("kitchen", "room"), ("hall", "room"))
    assert [d.name for d in domain.predicates] == ["clean", "near", "near"]
    assert [(f.name, len(f.parameters)) for f in domain.functions] == [("objects", 1), ("total", 0)]
    assert [t.name for t in domain.tasks] == ["Top", "Empty"]

    act = domain.action_by_name["act"]
    assert act.capabilities == ("cap1", "cap2")
    assert act.preconditions == (
        Literal("clean", ("?rm",)),
        Comparison("objects", ("?rm",), "=", 2, negated=True),
        Comparison("objects", ("?rm",), ">", 0.5),
        Literal("at", ("?r", "?rm")),
        Literal("hascapability", ("?r", "cap1")),
        Literal("near", ("?rm",)),
    )
    assert act.effects == (Literal("clean", ("?rm",), False), Literal("clean", ("kitchen",)))
    assert act.numeric_effects == (
        NumericEffect("increase", "objects", ("?rm",), 2),
        NumericEffect("assign", "total", (), 0),
    )

    partial, ordered, empty_net, empty_ordered = domain.methods
    assert not partial.ordered
    assert [s.id for s in partial.subtasks] == ["s1", "__t_id_0", "s3"]
    assert partial.ordering == (("s1", "s3"), ("s3", "s1"))
    assert partial.preconditions == (Literal("clean", ("?rm",)),)
    assert partial.effects == (Literal("clean", ("?rm",), False),)
    assert ordered.ordered and ordered.subtasks == (Subtask("__t_id_1", "act", ("?r", "kitchen")),)
    assert ordered.ordering == ()
    assert empty_net.parameters == () and empty_net.subtasks == () and empty_net.ordered
    assert empty_ordered.ordered and empty_ordered.subtasks == ()


def test_native_sorts_without_object_parent() -> None:
    domain = parse_domain(
        "(define (domain d) (:types room place) (:types Cleaner - robot))", "d.hddl"
    )
    assert domain.types == (
        ("room", None),
        ("place", None),
        ("Cleaner", "robot"),
        ("robot", None),
        ("robotteam", None),
    )
    assert domain.parent_of["robot"] is None
    assert domain.robot_sorts == {"robot", "robotteam", "Cleaner"}


def test_native_sorts_join_the_first_object_declaration() -> None:
    domain = parse_domain("(define (domain d) (:types a - thing b c - object d - object))", "d.hddl")
    assert domain.types == (
        ("a", "thing"),
        ("b", "object"),
        ("c", "object"),
        ("robot", "object"),
        ("robotteam", "object"),
        ("d", "object"),
        ("thing", None),
    )


def test_parse_is_fast() -> None:
    actions = "\n".join(
        f"""  (:action act{i}
     :parameters (?r - robot ?rm - room)
     :required-capabilities (cap)
     :precondition (and (clean ?rm) (not (busy ?r)))
     :effect (and (not (clean ?rm)) (busy ?r)))
  (:task T{i} :parameters (?r - robot ?rm - room))
  (:method m{i} :parameters (?r - robot ?rm - room) :task (T{i} ?r ?rm)
     :ordered-subtasks (and (act{i} ?r ?rm)))"""
        for i in range(40)
    )
    text = f"""(define (domain big)
  (:types room - object)
  (:predicates (clean ?rm - room) (busy ?r - robot))
  (:capabilities cap)
{actions}
)"""
    assert text.count("\n") >= 300
    parse_domain(text, "big.hddl")  # builds the cached parser
    domain = parse_domain(text, "big.hddl")
    assert len(domain.actions) == 40 and len(domain.methods) == 40


# ---------------------------------------------------------------------------------------------
# Located errors

HEAD = """(define (domain d)
 (:types room - object)
 (:predicates (clean ?rm - room))
 (:functions (objects ?rm - room))
 (:task T :parameters (?r - robot ?rm - room))
"""


def _with(body: str) -> str:
    return HEAD + body + "\n)\n"


def test_syntax_error_has_line_and_expectation() -> None:
    error = _single_error(_with(" (:action a :parameters (?r - robot)) oops"))
    assert error.startswith("dom.hddl:6:39: syntax error: expected one of '(', ')'")
    assert "found 'oops'" in error


def test_untyped_parameter_is_a_syntax_error() -> None:
    error = _single_error(_with(" (:action a :parameters (?r))"))
    assert error.startswith("dom.hddl:6:28: syntax error: expected one of '-', a variable")
    assert "found ')'" in error


def test_unknown_predicate() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room) :precondition (and (dirty ?rm)))"))
    assert error == "dom.hddl:6:58: undeclared predicate 'dirty' in the precondition of action 'a'"


def test_unknown_predicate_in_method_effect_and_at_only_exempt_in_preconditions() -> None:
    errors = _errors(
        _with(
            " (:method m :parameters (?r - robot ?rm - room) :task (T ?r ?rm)\n"
            "   :precondition (at ?r ?rm) :effect (at ?r ?rm))"
        )
    )
    assert errors == ["dom.hddl:7:39: undeclared predicate 'at' in the effect of method 'm'"]


def test_predicate_arity_mismatch() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room) :effect (clean ?rm ?rm))"))
    assert error.startswith("dom.hddl:6:47: predicate 'clean' is used with 2 arguments")
    assert "declared with 1" in error


def test_undeclared_function() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room) :precondition (> (things ?rm) 2))"))
    assert error == "dom.hddl:6:56: undeclared function 'things' in the precondition of action 'a'"


def test_unknown_subtask() -> None:
    error = _single_error(
        _with(" (:method m :parameters (?r - robot ?rm - room) :task (T ?r ?rm) :ordered-subtasks (nope ?r))")
    )
    assert error.startswith("dom.hddl:6:85: There is no declaration of the subtask nope")


def test_subtask_with_too_many_arguments() -> None:
    error = _single_error(
        _with(
            " (:action a :parameters (?rm - room))\n"
            " (:method m :parameters (?r - robot ?rm - room) :task (T ?r ?rm) :ordered-subtasks (a ?rm ?r))"
        )
    )
    assert error.startswith("dom.hddl:7:85: subtask a in method 'm' is given 2 arguments")
    assert "declares only 1 parameter" in error


def test_decimal_increase_amount() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room) :effect (increase (objects ?rm) 1.5))"))
    assert error == "dom.hddl:6:70: the amount of increase must be an integer, found 1.5"


def test_unsupported_or() -> None:
    error = _single_error(
        _with(" (:action a :parameters (?rm - room) :precondition (or (clean ?rm) (not (clean ?rm))))")
    )
    assert error == "dom.hddl:6:53: 'or' is not supported by the decomposer"


@pytest.mark.parametrize(
    ("body", "keyword", "column"),
    [
        ("(:action a :parameters (?rm - room) :precondition (imply (clean ?rm) (clean ?rm)))", "imply", 53),
        ("(:action a :parameters (?rm - room) :precondition (exists (?x - room) (clean ?x)))", "exists", 53),
        ("(:action a :parameters (?rm - room) :precondition (forall (?x - room) (clean ?x)))", "forall", 53),
        ("(:action a :parameters (?rm - room) :effect (forall (?x - room) (clean ?x)))", "forall", 47),
        ("(:action a :parameters (?rm - room) :effect (when (clean ?rm) (clean ?rm)))", "when", 47),
    ],
)
def test_other_unsupported_constructs(body: str, keyword: str, column: int) -> None:
    error = _single_error(_with(" " + body))
    assert error.startswith(f"dom.hddl:6:{column}: '{keyword}'")
    assert "not supported by the decomposer" in error


def test_unknown_type() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - rom))"))
    assert error == "dom.hddl:6:32: unknown type 'rom' of parameter ?rm of action 'a'"


def test_undeclared_variable() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room) :effect (clean ?x))"))
    assert error == "dom.hddl:6:53: variable ?x is not a parameter of action 'a'"


def test_undeclared_variable_in_method_subtask() -> None:
    error = _single_error(
        _with(
            " (:action a :parameters (?rm - room))\n"
            " (:method m :parameters (?r - robot ?rm - room) :task (T ?r ?rm) :subtasks (a ?other))"
        )
    )
    assert error == "dom.hddl:7:79: variable ?other is not a parameter of method 'm'"


def test_unclosed_paren_at_end_of_file() -> None:
    error = _single_error(HEAD + " (:action a :parameters (?rm - room)\n)\n")
    assert error.startswith("dom.hddl:8:1: syntax error: expected one of '(', ')'")
    assert "found end of file" in error and "'(' at 1:1 is not closed" in error


def test_duplicate_action() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room))\n (:action a :parameters (?rm - room))"))
    assert error.startswith("dom.hddl:7:11: duplicate action 'a'")
    assert "6:11" in error


def test_action_named_like_a_task() -> None:
    error = _single_error(_with(" (:action T :parameters (?rm - room))"))
    assert error.startswith("dom.hddl:6:11: duplicate action 'T'")
    assert "abstract task at 5:9" in error


def test_ordering_with_unknown_id() -> None:
    error = _single_error(
        _with(
            " (:action a :parameters (?rm - room))\n"
            " (:method m :parameters (?r - robot ?rm - room) :task (T ?r ?rm)\n"
            "   :subtasks (and (s1 (a ?rm)) (s2 (a ?rm))) :ordering (and (s1 < s3)))"
        )
    )
    assert error == "dom.hddl:8:67: ordering of method 'm' refers to unknown subtask id 's3'"


def test_ordering_on_ordered_network() -> None:
    error = _single_error(
        _with(
            " (:action a :parameters (?rm - room))\n"
            " (:method m :parameters (?r - robot ?rm - room) :task (T ?r ?rm)\n"
            "   :ordered-subtasks (and (s1 (a ?rm)) (s2 (a ?rm))) :ordering (< s1 s2))"
        )
    )
    assert error.startswith("dom.hddl:8:54: method 'm' has an explicit :ordering")
    assert "totally ordered" in error


def test_method_task_unknown_or_wrong_arity() -> None:
    errors = _errors(
        _with(" (:method m :parameters (?r - robot) :task (T ?r))\n (:method m2 :task (U))")
    )
    assert errors == [
        "dom.hddl:6:45: method 'm' decomposes 'T' with 1 argument but the task declares 2 parameters",
        "dom.hddl:7:21: method 'm2' decomposes unknown abstract task 'U' (not declared)",
    ]


def test_reserved_words_as_names() -> None:
    error = _single_error(HEAD.replace("(clean ?rm - room)", "(domain ?rm - room)") + ")")
    assert error.startswith("dom.hddl:3:16: syntax error: expected a name, found 'domain'")
    assert "reserved word" in error
    error = _single_error(HEAD.replace("(clean ?rm - room)", "(problem ?rm - room)") + ")")
    assert error == "dom.hddl:3:16: 'problem' is a reserved word and cannot be used as a name"


def test_invalid_character() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room) :effect (clean @x))"))
    assert error.startswith("dom.hddl:6:53: syntax error: expected one of ')', a name, a variable")
    assert "found invalid character '@'" in error


def test_effects_keyword_typo() -> None:
    error = _single_error(_with(" (:action a :parameters (?rm - room) :effects (clean ?rm))"))
    assert error.startswith("dom.hddl:6:38: syntax error: expected one of ")
    assert "':effect'" in error and "found ':effects'" in error


def test_all_static_problems_are_reported_together() -> None:
    errors = _errors(
        _with(
            " (:action a :parameters (?rm - rom) :effect (and (dirty ?rm) (decrease (objects ?rm) 0.5)))\n"
            " (:method m :parameters (?r - robot ?rm - room) :task (T ?r ?rm) :ordered-subtasks (b ?r))"
        )
    )
    assert [e.split(": ", 1)[0] for e in errors] == [
        "dom.hddl:6:32",
        "dom.hddl:6:51",
        "dom.hddl:6:86",
        "dom.hddl:7:85",
    ]


def test_load_domain_missing_file(tmp_path: Path) -> None:
    missing = tmp_path / "nope.hddl"
    with pytest.raises(MissionError) as info:
        load_domain(missing)
    (problem,) = info.value.problems
    assert problem.where == str(missing)
    assert "cannot read" in problem.message and "No such file" in problem.message


def test_load_domain_reports_errors_at_the_given_path(tmp_path: Path) -> None:
    path = tmp_path / "bad.hddl"
    path.write_text("(define (domain d)\n  (:types room - object)\n  (:action a :parameters (?x - rom)))\n")
    with pytest.raises(MissionError) as info:
        load_domain(path)
    assert str(info.value) == f"{path}:3:32: unknown type 'rom' of parameter ?x of action 'a'"


def test_domain_is_a_domain() -> None:
    assert isinstance(parse_domain("(define (domain d))", "d.hddl"), Domain)
