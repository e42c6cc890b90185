"""HDDL warnings of ``check`` (docs/cli.md#check) and ``check --strict``.

The three known mistakes of the reference domains are found where they are written; a mission
with an unused action, method or predicate is warned about each; the warnings change neither
check's exit status nor anything ``decompose`` prints or writes, unless ``--strict``.
"""
from __future__ import annotations

import json
from pathlib import Path

import pytest

from conftest import ROOT, require_reference
from mutrose_cp.cli.program import main
from mutrose_cp.pipeline.domain_warnings import conflicting_declarations, short_subtask_calls, undeclared_types
from mutrose_cp.io.hddl import parse_domain

MISSIONS = ("missions/lab-samples-logistics", "missions/deliver-goods-equipment", "missions/food-logistics")


def _warnings(err: str) -> list[str]:
    return [line for line in err.splitlines() if line.startswith("warning: ")]


@pytest.mark.parametrize(("mission", "config", "where", "text"), [
    (MISSIONS[0], None, "LabSampleLogistics.hddl:4:23", "type 'nurse' is used but not declared"),
    (MISSIONS[1], None, "DeliverGoodsEqupments.hddl:6:4",
     "predicate 'at' is declared again with different parameters: (at ?l - location ?a - agent) here, "
     "(at ?o - obj ?s - storage) at 5:4"),
    (MISSIONS[2], "Pickup", "FoodLogistics.hddl:116:5",
     "subtask approach-door in method 'pickup-without-door-opening' is given 1 argument but declares 2 parameters"),
])
def test_known_mistakes_of_the_reference_domains(capsys, mission, config, where, text):
    folder = require_reference() / mission
    extra = ["--config", config] if config else []
    assert main(["check", str(folder), *extra]) == 0
    warned = [w for w in _warnings(capsys.readouterr().err) if f"{where}: " in w]
    assert len(warned) == 1 and text in warned[0], warned

    assert main(["check", str(folder), *extra, "--strict"]) == 2
    err = capsys.readouterr().err
    assert not _warnings(err)
    assert any(line.startswith("error: ") and where in line and text in line for line in err.splitlines())


def _edit_domain(mission: Path, before: str, after: str) -> None:
    hddl = mission / "hddl" / "delivery.hddl"
    text = hddl.read_text()
    assert before in text
    hddl.write_text(text.replace(before, after, 1))


UNUSED = """
    (:task Wave :parameters (?r - DeliveryRobot))
    (:method wave-hand :parameters (?r - DeliveryRobot) :task (Wave ?r) :ordered-subtasks (and (wave ?r)))
    (:action wave :parameters (?r - DeliveryRobot))
    (:action beep :parameters (?r - DeliveryRobot))
"""


def test_unused_actions_methods_and_predicates(capsys, mission: Path):
    assert main(["check", str(mission)]) == 0
    assert not _warnings(capsys.readouterr().err)  # the example is clean

    _edit_domain(mission, "(delivered ?d - delivery)\n", "(delivered ?d - delivery)\n        (broken ?l - location)\n")
    _edit_domain(mission, "    ; actions\n", "    ; actions\n" + UNUSED)
    assert main(["check", str(mission)]) == 0
    warned = [w.split(".hddl:", 1)[1] for w in _warnings(capsys.readouterr().err)]
    assert [w.split(": ", 1)[0] for w in warned] == ["30:10", "90:14", "91:14", "92:14"]  # file order
    assert "predicate 'broken' is unused" in warned[0]
    assert "method 'wave-hand' is unused: its task Wave is not reachable from the goal model's tasks" in warned[1]
    assert "action 'wave' is unused" in warned[2] and "action 'beep' is unused" in warned[3]


def test_warnings_change_nothing_decompose_does(capsys, mission: Path, tmp_path: Path):
    before = tmp_path / "before.json"
    assert main(["decompose", str(mission), "-o", str(before)]) == 0
    err_before = capsys.readouterr().err
    _edit_domain(mission, "    ; actions\n", "    ; actions\n" + UNUSED)
    after = tmp_path / "after.json"
    assert main(["decompose", str(mission), "-o", str(after)]) == 0
    err_after = capsys.readouterr().err
    assert "unused" not in err_after and _warnings(err_before) == _warnings(err_after)
    assert json.loads(before.read_text()) == json.loads(after.read_text())


def test_strict_turns_other_warnings_into_errors_too(capsys, mission: Path):
    """Every warning check prints, not only the domain's: here an annotation naming the children
    of G8 out of diagram order."""
    gm = mission / "gm" / "delivery-gm.json"
    gm.write_text(gm.read_text().replace("[G9;G10]", "[G10;G9]"))
    assert main(["check", str(mission)]) == 0
    assert any("runtime annotation lists G10, G9" in w for w in _warnings(capsys.readouterr().err))
    assert main(["check", str(mission), "--strict"]) == 2
    err = capsys.readouterr().err
    assert not _warnings(err) and "error: " in err and "runtime annotation lists G10, G9" in err


def test_examples_and_models_are_clean(capsys):
    for folder in (ROOT / "examples" / "hospital-disinfection", ROOT / "examples" / "item-delivery"):
        assert main(["check", str(folder), "--strict", "-q"]) == 0, capsys.readouterr().err


DOMAIN = """(define (domain d)
  (:types room - object a - thing)
  (:predicates (p ?x - room) (p ?y - room) (q ?x - room) (q ?r - robot) (s ?r - robot ?x - room))
  (:task T :parameters (?r - robot ?x - room))
  (:method m :parameters (?r - robot ?x - room) :task (T ?r ?x)
    :ordered-subtasks (and (go ?r) (go ?r ?x) (T ?r ?x)))
  (:action go :parameters (?r - robot ?x - room)))
"""


def _at(text: str, line: int, fragment: str) -> tuple[int, int]:
    """(line, column) of ``fragment`` in line ``line`` of ``text`` (1-based)."""
    return line, text.splitlines()[line - 1].index(fragment) + 1


def test_each_rule_on_a_small_domain():
    domain = parse_domain(DOMAIN, "d.hddl")
    # the undeclared parent 'thing'
    assert [(line, col) for line, col, _ in undeclared_types(domain)] == [_at(DOMAIN, 2, "thing")]
    # the second q (robot, not room); the identical second p is no conflict
    conflicts = conflicting_declarations(domain.predicates, "predicate")
    assert [(line, col) for line, col, _ in conflicts] == [_at(DOMAIN, 3, "q ?r")]
    short = short_subtask_calls(domain)
    assert [(line, col) for line, col, _ in short] == [_at(DOMAIN, 6, "go ?r)")]
    assert "leaves ?x free" in short[0][2]
