"""HTN decomposition rules (semantics §2) on small hand-written domains: which decomposition
paths a task has, in which order, and what a path needs and does once grounded for one task
instance."""
from __future__ import annotations

import pytest

from mutrose_cp.errors import MissionError
from mutrose_cp.pipeline.htn import PSEUDO_PREFIX, expand_path, repetitions, ground_path, task_paths
from mutrose_cp.model.decomposition_paths import DecompositionPath, Fragment, Step, TreeNode
from mutrose_cp.model.domain import Comparison, Literal, NumericEffect
from mutrose_cp.io.hddl import parse_domain

HEADER = """(define (domain unit)
  (:types room - object)
  (:predicates (open ?rm - room) (clean ?rm - room) (near ?r - robot ?rm - room))
  (:functions (objects ?rm - room) (battery ?r - robot))
"""

ACTIONS = """
  (:action open-door :parameters (?r - robot ?rm - room) :effect (open ?rm))
  (:action close-door :parameters (?r - robot ?rm - room) :effect (not (open ?rm)))
  (:action sweep :parameters (?r - robot ?rm - room) :precondition (open ?rm) :effect (clean ?rm))
  (:action mop :parameters (?r - robot ?rm - room) :effect (clean ?rm))
  (:action report :parameters (?r - robot ?rm - room))
  (:action pick :parameters (?r - robot ?rm - room) :effect (decrease (objects ?rm) 1))
"""


def _domain(body: str):
    return parse_domain(HEADER + ACTIONS + body + ")", "unit.hddl")


def _names(path: DecompositionPath) -> list[str]:
    return [s.name for s in path.actions]


# ---------------------------------------------------------------------------------------------
# Method path generation


def test_ordered_method_keeps_declared_order_in_root_parameter_names():
    # task, method and actions name their parameters differently: paths speak the task's names
    domain = _domain("""
  (:task Clean :parameters (?who - robot ?where - room))
  (:method clean-ordered :parameters (?bot - robot ?room - room) :task (Clean ?bot ?room)
      :ordered-subtasks (and (open-door ?bot ?room) (sweep ?bot ?room)))
""")
    [path] = task_paths(domain, "Clean")
    assert [(s.name, s.args) for s in path.steps] == [("open-door", ("?who", "?where")),
                                                      ("sweep", ("?who", "?where"))]
    assert path.steps[1].preconditions == (Literal("open", ("?where",)),)
    assert path.steps[1].effects == (Literal("clean", ("?where",)),)
    assert path.tree == TreeNode("task", "Clean", ("?who", "?where"), (
        TreeNode("method", "clean-ordered", ("?who", "?where"), (
            TreeNode("action", "open-door", ("?who", "?where")),
            TreeNode("action", "sweep", ("?who", "?where")),
        )),
    ))
    assert not path.needs_expansion


def test_partial_order_method_yields_every_linear_extension_in_vertex_order():
    # t3 before t1, t2 free: three linearisations; at each position the remaining subtasks are
    # tried in declaration order, so the one starting with t2 comes first
    domain = _domain("""
  (:task Tidy :parameters (?r - robot ?rm - room))
  (:method tidy-any-order :parameters (?r - robot ?rm - room) :task (Tidy ?r ?rm)
      :subtasks (and (t1 (mop ?r ?rm)) (t2 (report ?r ?rm)) (t3 (open-door ?r ?rm)))
      :ordering (and (< t3 t1)))
""")
    assert [_names(p) for p in task_paths(domain, "Tidy")] == [
        ["report", "open-door", "mop"],
        ["open-door", "mop", "report"],
        ["open-door", "report", "mop"],
    ]


def test_linearisation_whose_step_an_earlier_step_falsifies_is_dropped():
    # sweep needs the door open: after close-door it cannot run, before it the fact is assumed
    domain = _domain("""
  (:task Sweep :parameters (?r - robot ?rm - room))
  (:method sweep-unordered :parameters (?r - robot ?rm - room) :task (Sweep ?r ?rm)
      :subtasks (and (t1 (close-door ?r ?rm)) (t2 (sweep ?r ?rm))))
""")
    assert [_names(p) for p in task_paths(domain, "Sweep")] == [["sweep", "close-door"]]


def test_methods_give_paths_in_declaration_order_with_preconditions_as_a_first_step():
    domain = _domain("""
  (:task Clean :parameters (?r - robot ?rm - room))
  (:method by-mopping :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :precondition (near ?r ?rm)
      :ordered-subtasks (and (mop ?r ?rm)))
  (:method by-sweeping :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :ordered-subtasks (and (open-door ?r ?rm) (sweep ?r ?rm)))
""")
    mopping, sweeping = task_paths(domain, "Clean")
    assert _names(mopping) == ["mop"] and _names(sweeping) == ["open-door", "sweep"]
    # the method precondition is a pseudo step that runs first and is never printed
    pseudo = mopping.steps[0]
    assert pseudo.pseudo and pseudo.name == PSEUDO_PREFIX + "by-mopping"
    assert pseudo.preconditions == (Literal("near", ("?r", "?rm")),)
    assert len(mopping.steps) == 2 and len(sweeping.steps) == 2


def test_method_whose_preconditions_contradict_each_other_is_never_valid():
    """The original lists such paths (it evaluates each assumed precondition alone), so they
    keep their numbers, marked never valid."""
    domain = _domain("""
  (:task Clean :parameters (?r - robot ?rm - room))
  (:method never :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :precondition (and (open ?rm) (not (open ?rm)))
      :ordered-subtasks (and (mop ?r ?rm)))
  (:method never-numeric :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :precondition (and (= (objects ?rm) 1) (= (objects ?rm) 2))
      :ordered-subtasks (and (mop ?r ?rm)))
  (:method fine :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :precondition (and (open ?rm) (= (objects ?rm) 1) (= (objects ?rm) 1))
      :ordered-subtasks (and (report ?r ?rm)))
""")
    paths = task_paths(domain, "Clean")
    assert [p.tree.children[0].name for p in paths] == ["never", "never-numeric", "fine"]
    assert [p.never_valid for p in paths] == [("it requires not open(?rm) and its negation",),
                                              ("it requires two values of objects(?rm)",), ()]
    assert _names(paths[2]) == ["report"]


def test_subtask_without_any_path_makes_the_enclosing_method_inapplicable():
    domain = _domain("""
  (:task Clean :parameters (?r - robot ?rm - room))
  (:task Impossible :parameters (?r - robot ?rm - room))
  (:method clean-then-impossible :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :ordered-subtasks (and (mop ?r ?rm) (Impossible ?r ?rm)))
  (:method clean-only :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :ordered-subtasks (and (mop ?r ?rm)))
  (:method impossible :parameters (?r - robot ?rm - room) :task (Impossible ?r ?rm)
      :precondition (and (clean ?rm) (not (clean ?rm)))
      :ordered-subtasks (and (report ?r ?rm)))
""")
    [impossible] = task_paths(domain, "Impossible")
    assert impossible.never_valid == ("it requires not clean(?rm) and its negation",)
    # after mop (clean ?rm) holds, and the subtask has no path at all there: the first method
    # keeps its number (the original leaves the subtask out), never valid
    paths = task_paths(domain, "Clean")
    assert [p.tree.children[0].name for p in paths] == ["clean-then-impossible", "clean-only"]
    assert [p.never_valid for p in paths] == [("its subtask Impossible has no executable method",), ()]
    assert _names(paths[0]) == ["mop"]


def test_nested_task_paths_combine_with_the_first_subtask_varying_fastest():
    domain = _domain("""
  (:task Both :parameters (?r - robot ?rm - room))
  (:task First :parameters (?r - robot ?rm - room))
  (:task Second :parameters (?r - robot ?rm - room))
  (:method both :parameters (?r - robot ?rm - room) :task (Both ?r ?rm)
      :ordered-subtasks (and (First ?r ?rm) (Second ?r ?rm)))
  (:method first-a :parameters (?r - robot ?rm - room) :task (First ?r ?rm) :ordered-subtasks (and (mop ?r ?rm)))
  (:method first-b :parameters (?r - robot ?rm - room) :task (First ?r ?rm) :ordered-subtasks (and (report ?r ?rm)))
  (:method second-a :parameters (?r - robot ?rm - room) :task (Second ?r ?rm) :ordered-subtasks (and (pick ?r ?rm)))
  (:method second-b :parameters (?r - robot ?rm - room) :task (Second ?r ?rm)
      :ordered-subtasks (and (open-door ?r ?rm)))
""")
    assert [_names(p) for p in task_paths(domain, "Both")] == [
        ["mop", "pick"], ["report", "pick"], ["mop", "open-door"], ["report", "open-door"],
    ]


def test_nested_task_argument_not_from_the_enclosing_task_is_refused():
    domain = _domain("""
  (:task Outer :parameters (?r - robot))
  (:task Inner :parameters (?r - robot ?rm - room))
  (:method outer :parameters (?r - robot ?rm - room) :task (Outer ?r) :ordered-subtasks (and (Inner ?r ?rm)))
  (:method inner :parameters (?r - robot ?rm - room) :task (Inner ?r ?rm) :ordered-subtasks (and (mop ?r ?rm)))
""")
    with pytest.raises(MissionError, match=r"method inner: argument \?rm of task Inner is not bound to a parameter "
                                           r"of Outer"):
        task_paths(domain, "Outer")


# ---------------------------------------------------------------------------------------------
# Recursive methods

RECURSIVE = """
  (:task PickAll :parameters (?r - robot ?rm - room))
  (:method pick-multiple :parameters (?r - robot ?rm - room) :task (PickAll ?r ?rm)
      :precondition (and (> (objects ?rm) 1))
      :ordered-subtasks (and (pick ?r ?rm) (PickAll ?r ?rm)))
  (:method pick-single :parameters (?r - robot ?rm - room) :task (PickAll ?r ?rm)
      :precondition (and (= (objects ?rm) 1))
      :ordered-subtasks (and (pick ?r ?rm)))
"""


def test_guarded_recursive_method_is_unrolled_once_with_a_fragment_to_expand():
    multiple, single = task_paths(_domain(RECURSIVE), "PickAll")
    assert _names(multiple) == ["pick", "pick"] and _names(single) == ["pick"]
    # the guard (> objects 1) is assumed at 1 + 1 so that the recursion runs once, then stops
    assert multiple.fragments == (Fragment(0, 1, "objects", ("?rm",), 1, -1),)
    assert [s.name for s in multiple.steps[:2]] == [PSEUDO_PREFIX + "pick-multiple", "pick"]
    assert multiple.needs_expansion and not single.needs_expansion
    inner = multiple.tree.children[0].children[1]
    assert (inner.kind, inner.name, inner.children[0].name) == ("task", "PickAll", "pick-single")


def test_fragment_is_repeated_as_often_as_the_world_value_allows():
    multiple, _ = task_paths(_domain(RECURSIVE), "PickAll")
    values = {("objects", ("RoomA",)): 6}
    warnings: list[str] = []
    expanded = expand_path(multiple, {"?r": "r1", "?rm": "RoomA"}, lambda f, a: values.get((f, a)), "AT1_1|1",
                           warnings.append)
    # ceil((6 - 1) / 1) - 1 = 4 more repetitions of [guard, pick]: six picks empty the room
    assert _names(expanded) == ["pick"] * 6 and not expanded.needs_expansion and not warnings
    ground = ground_path(expanded, {"?r": "r1", "?rm": "RoomA"})
    assert ground.numeric_effects == (("objects", ("RoomA",), "increase", -6),)
    # a bound the world does not give: one unrolling, as the original, and a warning naming it
    once = expand_path(multiple, {"?r": "r1", "?rm": "RoomA"}, lambda f, a: None, "AT1_1|1", warnings.append)
    assert _names(once) == ["pick", "pick"] and not once.needs_expansion
    assert len(warnings) == 1 and "no value for objects(RoomA), which bounds a recursive method" in warnings[0]


@pytest.mark.parametrize(("value", "bound", "step", "runs"), [
    (6, 1, 1, 5), (4.0, 1, 1, 3), (4, 1, 1, 3), (3.5, 1, 1, 3), (6, 1, 2, 3), (7, 1, 2, 3), (7.5, 1, 2, 4),
    (1, 1, 1, 0), (0, 1, 1, 0), (2, 1.5, 0.5, 1), (10, 0, 3, 4), (0.3, 0.1, 0.1, 2)])
def test_repetitions_run_the_fragment_while_the_guard_holds(value, bound, step, runs):
    """The fragment runs once per value above the bound, counting down by the step: the
    original's formulas give 4 runs for 4.0 (4 picks beside 3, the mission fails) and 2 for
    (6, 1, 2), whose third value (2) is still above the bound."""
    fragment = Fragment(0, 1, "objects", ("?rm",), bound, -step)
    assert repetitions(value, fragment) == runs - 1 if runs else repetitions(value, fragment) <= -1
    brute, v = 0, value
    while v > bound:
        brute, v = brute + 1, v - step
    assert brute == runs


def test_unguarded_recursion_is_cut_at_the_depth_limit():
    domain = _domain("""
  (:task Patrol :parameters (?r - robot ?rm - room))
  (:method patrol-again :parameters (?r - robot ?rm - room) :task (Patrol ?r ?rm)
      :ordered-subtasks (and (report ?r ?rm) (Patrol ?r ?rm)))
  (:method patrol-stop :parameters (?r - robot ?rm - room) :task (Patrol ?r ?rm)
      :ordered-subtasks (and (report ?r ?rm)))
""")
    with pytest.raises(MissionError, match="recursive decomposition of task Patrol does not terminate"):
        task_paths(domain, "Patrol")


def test_recursion_whose_guard_is_not_decreased_is_refused():
    domain = _domain("""
  (:action unpick :parameters (?r - robot ?rm - room) :effect (increase (objects ?rm) 1))
  (:task Grow :parameters (?r - robot ?rm - room))
  (:method grow :parameters (?r - robot ?rm - room) :task (Grow ?r ?rm)
      :precondition (and (> (objects ?rm) 1))
      :ordered-subtasks (and (unpick ?r ?rm) (Grow ?r ?rm)))
  (:method stop :parameters (?r - robot ?rm - room) :task (Grow ?r ?rm)
      :precondition (and (= (objects ?rm) 1))
      :ordered-subtasks (and (report ?r ?rm)))
""")
    with pytest.raises(MissionError, match=r"Infinite expansion generated with method \[grow\]"):
        task_paths(domain, "Grow")


# ---------------------------------------------------------------------------------------------
# Grounding a path for one task instance


def _step(name: str, pre=(), eff=(), num=()) -> Step:
    return Step(name, ("?r", "?rm"), tuple(pre), tuple(eff), tuple(num), ())


def _path(*steps: Step) -> DecompositionPath:
    return DecompositionPath(tuple(steps), TreeNode("task", "T", ("?r", "?rm")))


def test_ground_path_binds_root_parameters_and_spreads_collections():
    path = _path(_step("visit", pre=[Literal("near", ("?r", "?rm")), Literal("open", ("?rm",), False),
                                     Literal("clean", ("?other",))]))
    ground = ground_path(path, {"?r": "r1", "?rm": ("RoomA", "RoomB")})
    assert ground.preconditions == (
        Literal("near", ("r1", "RoomA")), Literal("near", ("r1", "RoomB")),
        Literal("open", ("RoomA",), False), Literal("open", ("RoomB",), False),
        Literal("clean", ("?other",)),  # an unbound variable stays as written
    )
    assert ground.unsatisfiable == () and ground.shifted == ()


def test_ground_path_net_effects_and_preconditions_the_path_provides_itself():
    path = _path(
        _step("open-door", eff=[Literal("open", ("?rm",))]),
        _step("sweep", pre=[Literal("open", ("?rm",))], eff=[Literal("clean", ("?rm",))]),
        _step("close-door", eff=[Literal("open", ("?rm",), False), Literal("clean", ("?x",))]),
    )
    ground = ground_path(path, {"?r": "r1", "?rm": "RoomA"})
    # open(RoomA) is made true by the first step: no precondition of the decomposition
    assert ground.preconditions == ()
    # a later effect on an atom replaces the earlier one in its place
    assert ground.effects == (Literal("open", ("RoomA",), False), Literal("clean", ("RoomA",)),
                              Literal("clean", ("?x",)))
    assert ground.ground_effects == ground.effects[:2]
    assert ground.unsatisfiable == ()


def test_ground_path_numeric_effects_add_up_and_shift_later_conditions():
    path = _path(
        _step("charge", num=[NumericEffect("increase", "battery", ("?r",), 5)]),
        _step("work", pre=[Comparison("battery", ("?r",), ">", 7)],
              num=[NumericEffect("decrease", "battery", ("?r",), 2), NumericEffect("assign", "objects", ("?rm",), 0)]),
        _step("check", pre=[Comparison("objects", ("?rm",), "=", 0)]),
    )
    ground = ground_path(path, {"?r": "r1", "?rm": "RoomA"})
    assert ground.numeric_effects == (("battery", ("r1",), "increase", 3), ("objects", ("RoomA",), "assign", 0))
    # battery > 7 after +5 is battery > 2 where the decomposition starts; objects = 0 holds
    assert ground.preconditions == ()
    assert ground.shifted == (Comparison("battery", ("r1",), ">", 2),)
    assert ground.checked_preconditions == ground.shifted
    assert ground.unsatisfiable == ()


def test_ground_path_unsatisfiable_when_an_earlier_step_falsifies_a_precondition():
    path = _path(
        _step("close-door", eff=[Literal("open", ("?rm",), False)]),
        _step("sweep", pre=[Literal("open", ("?rm",))]),
        _step("empty", num=[NumericEffect("assign", "objects", ("?rm",), 0)]),
        _step("pick", pre=[Comparison("objects", ("?rm",), ">", 0)]),
    )
    ground = ground_path(path, {"?r": "r1", "?rm": "RoomA"})
    assert ground.unsatisfiable == ("open(RoomA)", "objects(RoomA) > 0")
    assert ground.preconditions == ()


def test_unsatisfiable_path_through_an_abstract_subtask():
    # path generation does not pass an abstract subtask's effects on, so the path exists; the
    # grounding sees that the subtask closed the door that sweep needs open
    domain = _domain("""
  (:task Shut :parameters (?r - robot ?rm - room))
  (:task Clean :parameters (?r - robot ?rm - room))
  (:method shut :parameters (?r - robot ?rm - room) :task (Shut ?r ?rm) :ordered-subtasks (and (close-door ?r ?rm)))
  (:method shut-then-sweep :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :ordered-subtasks (and (Shut ?r ?rm) (sweep ?r ?rm)))
  (:method open-then-sweep :parameters (?r - robot ?rm - room) :task (Clean ?r ?rm)
      :ordered-subtasks (and (open-door ?r ?rm) (sweep ?r ?rm)))
""")
    shut_first, open_first = task_paths(domain, "Clean")
    assert _names(shut_first) == ["close-door", "sweep"]
    binding = {"?r": "r1", "?rm": "RoomA"}
    assert ground_path(shut_first, binding).unsatisfiable == ("open(RoomA)",)
    assert ground_path(open_first, binding).unsatisfiable == ()


def test_an_unknown_value_stays_unknown_in_path_generation():
    """A method needing objects > 0, then a pick (objects - 1), then a step needing objects = 5:
    from 6 objects this runs.  The original assumes objects = 1 for the > (it assumes the
    value where a recursion would stop) and takes a decrease of an unknown value as the value
    -1, so it drops the path; here the values stay unknown and the path is kept, its later
    comparison moved to the start value (= 6 there)."""
    domain = _domain("""
  (:action need-five :parameters (?r - robot ?rm - room) :precondition (= (objects ?rm) 5))
  (:task Take :parameters (?r - robot ?rm - room))
  (:method take :parameters (?r - robot ?rm - room) :task (Take ?r ?rm)
      :precondition (and (> (objects ?rm) 0))
      :ordered-subtasks (and (pick ?r ?rm) (need-five ?r ?rm)))
  (:task Lower :parameters (?r - robot ?rm - room))
  (:method lower :parameters (?r - robot ?rm - room) :task (Lower ?r ?rm)
      :ordered-subtasks (and (pick ?r ?rm) (pick ?r ?rm) (need-five ?r ?rm)))
""")
    [take] = task_paths(domain, "Take")
    assert _names(take) == ["pick", "need-five"] and not take.never_valid
    ground = ground_path(take, {"?r": "r1", "?rm": "RoomA"})
    assert ground.checked_preconditions == (Comparison("objects", ("RoomA",), ">", 0),
                                            Comparison("objects", ("RoomA",), "=", 6))
    [lower] = task_paths(domain, "Lower")  # -1 - 1 = 5 fails in the original
    assert ground_path(lower, {"?r": "r1", "?rm": "RoomA"}).shifted == (Comparison("objects", ("RoomA",), "=", 7),)
