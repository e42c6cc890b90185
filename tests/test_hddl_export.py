"""``mutrose-cp export-hddl``: standard HDDL that unified-planning reads, read back by our reader.

Every domain of the reference corpus, the examples and the models is exported and parsed with
unified-planning's HDDL reader (its PDDL reader, which reads HDDL when ``:hierarchy`` is
required); where the mission has a problem form, domain and problem are parsed together.  Our
own reader reads each exported domain back to the same model, up to the documented rewrites.
"""
from __future__ import annotations

import dataclasses
import shutil
from pathlib import Path

import pytest
from unified_planning.io import PDDLReader

from conftest import REFERENCE, ROOT, require_reference
from mutrose_cp.cli.program import main
from mutrose_cp.io.hddl import load_domain, parse_domain
from mutrose_cp.io.hddl_writer import HddlExport
from mutrose_cp.output.hddl_problem import initial_facts
from mutrose_cp.model import Domain, GroundLiteral, InitialState


def _domain_files() -> list[Path]:
    own = [*sorted((ROOT / "examples").glob("*/hddl/*.hddl")), *sorted((ROOT / "models").glob("*/*.hddl"))]
    return [*sorted(REFERENCE.glob("*/*/hddl/*.hddl")), *own]


def _label(path: Path) -> str:
    return "/".join(path.parts[-4:-2]) if path.parent.name == "hddl" else path.parent.name


DOMAINS = _domain_files()


def test_the_corpus_and_the_project_domains_are_all_there():
    require_reference()
    assert len([p for p in DOMAINS if REFERENCE in p.parents]) == 14
    assert len([p for p in DOMAINS if ROOT in p.parents]) == 4  # the three examples and models/delivery


@pytest.mark.parametrize("hddl", DOMAINS, ids=_label)
def test_every_domain_exports_to_hddl_unified_planning_reads(hddl: Path, tmp_path: Path):
    out = tmp_path / "domain.hddl"
    assert main(["export-hddl", str(hddl), "-o", str(out), "-q"]) == 0
    problem = PDDLReader().parse_problem(str(out))
    domain = load_domain(hddl)
    # PDDL names are case-insensitive: unified-planning lower-cases them
    assert {t.name for t in problem.tasks} == {t.name.lower() for t in domain.tasks}
    assert {m.name for m in problem.methods} == {m.name.lower() for m in domain.methods}
    assert {a.name for a in problem.actions} == {a.name.lower() for a in domain.actions}


def _without_positions(domain: Domain) -> dict[str, object]:
    """The parts of a domain its text defines, positions and capabilities left out (capabilities
    are comments in standard HDDL)."""
    def plain(items):
        return [dataclasses.replace(i, line=0, column=0) for i in items]
    return {
        "name": domain.name, "types": domain.types, "constants": domain.constants,
        "predicates": domain.predicates, "functions": domain.functions, "tasks": plain(domain.tasks),
        "actions": [dataclasses.replace(a, capabilities=()) for a in plain(domain.actions)],
        "methods": plain(domain.methods),
    }


def _round_trip(hddl: Path, tmp_path: Path) -> tuple[Domain, Domain, HddlExport]:
    domain = load_domain(hddl)
    export = HddlExport(domain)
    out = tmp_path / "exported.hddl"
    out.write_text(export.domain_text())
    return domain, load_domain(out), export


@pytest.mark.parametrize("hddl", DOMAINS, ids=_label)
def test_our_reader_reads_the_exported_domain_back(hddl: Path, tmp_path: Path):
    domain, again, export = _round_trip(hddl, tmp_path)
    before, after = _without_positions(domain), _without_positions(again)
    rewritten = {"LabSampleLogistics.hddl": "types", "DeliverGoodsEqupments.hddl": "predicates",
                 "FoodLogistics.hddl": "methods"}.get(hddl.name)
    assert bool(export.warnings) == (rewritten is not None), export.warnings
    for part in before:
        if part != rewritten:
            assert before[part] == after[part], part
    assert again.undeclared_types == ()


def test_the_rewrites_of_the_reference_domains(tmp_path: Path):
    reference = require_reference() / "missions"
    _, lab, _ = _round_trip(reference / "lab-samples-logistics/hddl/LabSampleLogistics.hddl", tmp_path)
    assert ("nurse", "object") in lab.types
    _, goods, _ = _round_trip(reference / "deliver-goods-equipment/hddl/DeliverGoodsEqupments.hddl", tmp_path)
    assert [tuple(p.type for p in d.parameters) for d in goods.predicate_declarations("at")] == [("object", "object")]
    food, food_again, _ = _round_trip(reference / "food-logistics/hddl/FoodLogistics.hddl", tmp_path)
    method = next(m for m in food_again.methods if m.name == "pickup-without-door-opening")
    assert method.parameters[-1].name == "?l-2" and method.parameters[-1].type == "location"
    assert method.subtasks[1].args == ("?r1", "?l-2")
    original = next(m for m in food.methods if m.name == "pickup-without-door-opening")
    assert dataclasses.replace(method, parameters=method.parameters[:-1], subtasks=original.subtasks,
                               line=0, column=0) == dataclasses.replace(original, line=0, column=0)


def test_the_export_is_deterministic_and_replaces_the_file(tmp_path: Path):
    hddl = ROOT / "examples" / "hospital-disinfection" / "hddl" / "hospital-disinfection.hddl"
    out = tmp_path / "out.hddl"
    out.write_text("old content\n")
    assert main(["export-hddl", str(hddl), "-o", str(out), "-q"]) == 0
    first = out.read_bytes()
    assert main(["export-hddl", str(hddl), "-o", str(out), "-q"]) == 0
    assert out.read_bytes() == first and b"old content" not in first
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out.hddl"]  # no temporary file left


DIALECT = """(define (domain dialect)
  (:capabilities arms)
  (:action move :parameters (?r - robot ?x - room) :required-capabilities (arms)
     :precondition (and (at ?r ?x) (hascapability ?r) (> (charge ?r) 0))
     :effect (and (not (p ?x)) (p ?x ?x) (decrease (charge ?r) 1)))
  (:method m :parameters (?r - robot ?x - room) :task (Step ?r ?x)
     :precondition (and (not (p ?x)))
     :effect (and (p ?x))
     :subtasks (and (move ?r ?x) (s2 (move ?r ?x)) (s3 (move ?r)))
     :ordering (and (s2 < s3)))
  (:task Step :parameters (?r - robot ?x - room))
  (:predicates (p ?x - room) (p ?x - room ?y - room))
  (:functions (charge ?r - robot))
  (:types room - object)
)
"""


def test_the_dialect_rewrites_parse_with_unified_planning(tmp_path: Path):
    export = HddlExport(parse_domain(DIALECT, "dialect.hddl"))
    text = export.domain_text()
    order = [text.index(k) for k in ("(:requirements", "(:types", "(:predicates", "(:functions", "(:task",
                                     "(:method", "(:action")]
    assert order == sorted(order)  # blocks in the standard order
    assert "(:requirements :typing :hierarchy :negative-preconditions :method-preconditions :numeric-fluents)" in text
    assert "; MutRoSe capabilities: arms" in text and "; required capabilities: arms" in text
    assert "(p-2 ?x - room ?y - room)" in text and "(p-2 ?x ?x)" in text  # the second arity renamed
    assert "(at ?a1 - object ?a2 - object)" in text and "(hascapability ?a1 - object)" in text
    # the method's effect is an action, first in the network, before every other subtask; the id
    # given to the unnamed subtask is not 'step', which HDDL readers would take for the task Step
    assert "(:action method-effects-m" in text
    assert ":ordering (and (< method-effects step-2) (< method-effects s2) (< method-effects s3) (< s2 s3))" in text
    assert "(s3 (move ?r ?x-2))" in text and "?x-2 - room" in text  # the missing argument
    assert len(export.warnings) == 5, export.warnings  # at, hascapability, p-2, effects, ?x-2
    out = tmp_path / "dialect.hddl"
    out.write_text(text)
    problem = PDDLReader().parse_problem(str(out))
    method = problem.method("m")
    assert [s.task.name for s in method.subtasks] == ["method-effects-m", "move", "move", "move"]
    assert method.partial_order() is not None and len(method.partial_order()) == 4
    assert {a.name for a in problem.actions} == {"move", "method-effects-m"}


def test_domain_and_problem_parse_together(capsys, tmp_path: Path):
    folder = require_reference() / "missions" / "object-picking-function"
    out = tmp_path / "domain.hddl"
    assert main(["export-hddl", str(folder), "--config", "configuration.json", "-o", str(out)]) == 0
    assert "problem " + str(tmp_path / "domain-problem.hddl") in capsys.readouterr().err
    problem = PDDLReader().parse_problem(str(out), str(tmp_path / "domain-problem.hddl"))
    assert [o.name for o in problem.all_objects] == ["rooma"]
    assert [str(v) for v in problem.explicit_initial_values.values()] == ["1"]  # (= (objects RoomA) 1)
    network = problem.task_network
    assert [s.task.name for s in network.subtasks] == ["pickobject"]
    assert [p.name for p in network.variables] == ["r_at1_1"]  # the robot, left to the planner


def test_a_mission_with_a_total_order_gets_its_network(tmp_path: Path):
    folder = require_reference() / "missions" / "lab-samples-logistics"
    out, problem_out = tmp_path / "d.hddl", tmp_path / "p.hddl"
    assert main(["export-hddl", str(folder), "-o", str(out), "--problem-out", str(problem_out), "-q"]) == 0
    text = problem_out.read_text()
    assert "; the world declares no robots" in text
    problem = PDDLReader().parse_problem(str(out), str(problem_out))
    steps = [(s.identifier, s.task.name, [str(p) for p in s.parameters]) for s in problem.task_network.subtasks]
    assert steps == [("at1_1", "approachnurse", ["r_at1_1", "nurse1", "room3"]),
                     ("at2_1", "picksample", ["r_at2_1", "nurse1"]),
                     ("at3_1", "approacharm", ["r_at3_1", "arm1", "pharmacy"]),
                     ("at4_1", "unloadsample", ["r_at4_1", "arm1"])]
    assert problem.task_network.total_order() == ["at1_1", "at2_1", "at3_1", "at4_1"]


def test_a_mission_without_a_total_order_says_why(capsys, tmp_path: Path):
    folder = ROOT / "examples" / "hospital-disinfection"
    out = tmp_path / "d.hddl"
    assert main(["export-hddl", str(folder), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert "note: no problem file: the mission's tasks are not one total order: below goal G9 the tasks" in err
    assert "fallback alternatives" in err and out.is_file() and not (tmp_path / "d-problem.hddl").exists()
    # asked for explicitly, the missing problem is an error
    assert main(["export-hddl", str(folder), "-o", str(out), "--problem-out", str(tmp_path / "p.hddl")]) == 2
    assert "error: the mission's tasks are not one total order" in capsys.readouterr().err


@pytest.mark.parametrize(("args", "message"), [
    (["--gm", "x.json"], "give --gm GM and --config CONFIG, or neither"),
    (["--problem-out", "p.hddl"], "--problem-out needs the mission"),
])
def test_incomplete_mission_options_are_refused(capsys, tmp_path: Path, args, message):
    hddl = ROOT / "examples" / "item-delivery" / "hddl" / "delivery.hddl"
    assert main(["export-hddl", str(hddl), "-o", str(tmp_path / "d.hddl"), *args]) == 2
    assert message in capsys.readouterr().err
    assert not (tmp_path / "d.hddl").exists()


def test_the_output_never_overwrites_the_domain(capsys, tmp_path: Path):
    hddl = tmp_path / "d.hddl"
    hddl.write_text((ROOT / "models" / "delivery" / "delivery.hddl").read_text())
    before = hddl.read_bytes()
    assert main(["export-hddl", str(hddl), "-o", str(hddl)]) == 2
    assert "would overwrite the input" in capsys.readouterr().err and hddl.read_bytes() == before


def test_a_bad_domain_is_a_located_error(capsys, tmp_path: Path):
    hddl = tmp_path / "bad.hddl"
    hddl.write_text("(define (domain d)\n  (:action a :parameters (?x - nosuchtype)))\n")
    assert main(["export-hddl", str(hddl), "-o", str(tmp_path / "out.hddl")]) == 2
    assert f"error: {hddl}:2:32: unknown type 'nosuchtype'" in capsys.readouterr().err


@pytest.mark.parametrize(("context", "reason"), [
    ('assertion trigger \\"SampleReady\\"', "task AT1_1 runs when the event SampleReady occurs"),
    ('assertion condition \\"current_delivery.ready\\"', "goal G7 has the context condition current_delivery.ready"),
])
def test_events_and_context_conditions_have_no_network(capsys, tmp_path: Path, context: str, reason: str):
    folder = tmp_path / "lab"
    shutil.copytree(require_reference() / "missions" / "lab-samples-logistics", folder)
    gm = folder / "gm" / "LabSampleLogistics.txt"
    text = gm.read_text()
    before = '"Monitors": "current_nurse, pickup_location"'
    assert text.count(before) == 1
    gm.write_text(text.replace(before, f'"CreationCondition": "{context}",\n            {before}'))
    assert main(["export-hddl", str(folder), "-o", str(tmp_path / "d.hddl"), "--problem-out", str(tmp_path / "p.hddl")]) == 2
    assert f"error: {reason}" in capsys.readouterr().err


def test_the_initial_state_holds_the_true_facts_the_world_states():
    """Closed world: a false fact is left out; the first literal of an atom decides, as in the
    decomposer; facts about objects the problem does not declare are left out with a warning."""
    state = InitialState(sorts={}, literals=(
        GroundLiteral("clean", ("RoomA",)), GroundLiteral("clean", ("RoomB",), False),
        GroundLiteral("clean", ("RoomA",), False), GroundLiteral("clean", ("Ghost",)),
    ), functions=((("objects", ("RoomA",)), 2), (("objects", ("RoomA",)), 5), (("objects", ("RoomB",)), 1.5)))
    warnings: list[str] = []
    facts, values = initial_facts(state, {"RoomA", "RoomB"}, warnings)
    assert facts == (("clean", ("RoomA",)),)
    assert values == (("objects", ("RoomA",), 2), ("objects", ("RoomB",), 1.5))
    assert warnings == ["facts about Ghost, which are no declared objects, are left out"]
