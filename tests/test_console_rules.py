"""The rules of the drop-in's stdout, one at a time, on small inputs: the ``-p`` text
(mutrose_cp.output.console) and the original's lexer echo (mutrose_cp.output.lexer_echo).

Where a rule was found by running the original, the expected text is what the original printed
for that input (noted at the test); ``test_console_original.py`` runs the original itself.  The
goal models of the reference missions are edited in temporary copies, with markers made of
characters the lexers echo: ``_3.`` after ``G3:`` tells which goal text was read, and how often.
"""
from __future__ import annotations

import io
import json
import re
import shutil
import sys
from dataclasses import replace
from pathlib import Path
from typing import Callable

import pytest

from conftest import ROOT, require_reference
from mutrose_cp.output.console import (
    constraint_lines,
    decomposition_value,
    heading,
    instance_value,
    print_constraints,
    print_mission_decompositions,
    task_lines,
)
from mutrose_cp.cli.dropin import main, utf8_stdout
from mutrose_cp.model.task_instances import ParameterValue
from mutrose_cp.output.lexer_echo import (
    STDIO_BUFFER,
    LexerEcho,
    condition_echo,
    echoed_text,
    unmatched,
    unmatched_in_condition,
)
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files

EXAMPLE = ROOT / "examples" / "item-delivery"


# -- editing a goal model (also used by test_console_original.py) -----------------------------------

def edit_goal_model(path: Path, edit: Callable[[dict], None]) -> None:
    """Apply ``edit`` to every node of the goal model at ``path`` (a copy), in place."""
    data = json.loads(path.read_text())
    for actor in data["actors"]:
        for node in actor.get("nodes", []):
            edit(node)
    path.write_text(json.dumps(data))


def goal_marker(node: dict) -> None:
    """``G3: Rooms Are Prepared`` -> ``G3: _3. Rooms Are Prepared``: the goal-text lexer echoes
    ``_3.`` wherever the original reads the text."""
    if node["type"] == "istar.Goal":
        gid, _, rest = node["text"].partition(":")
        node["text"] = f"{gid}: _{gid[1:]}.{rest}"


def condition_marker(mark: Callable[[str, str], str]) -> Callable[[dict], None]:
    """An edit putting ``mark(goal number, property)`` (echoed characters) at the start of every
    condition the original lexes: a query's and a forAll's condition (after ``|``), a plain
    achieve condition, a creation condition (not a trigger)."""
    def edit(node: dict) -> None:
        props, number = node["customProperties"], node["text"].partition(":")[0][1:]
        for key in ("QueriedProperty", "AchieveCondition"):
            if key in props:
                text, sign = props[key], mark(number, key)
                props[key] = text.replace("|", f"| {sign} ", 1) if "|" in text else f"{sign} {text}"
        context = props.get("CreationCondition", "")
        if "condition" in context:
            props["CreationCondition"] = context.replace('"', f'"{mark(number, "CreationCondition")} ', 1)
    return edit


def reference_copy(name: str, tmp_path: Path) -> tuple[Path, tuple[Path, Path, Path]]:
    """A copy of the reference mission ``name`` and its HDDL, goal model and configuration."""
    folder = tmp_path / name
    shutil.copytree(require_reference() / "missions" / name, folder, ignore=shutil.ignore_patterns("output"))
    return folder, find_mission_files(folder)


def _echo(folder: Path, files: tuple[Path, Path, Path], monkeypatch) -> str:
    monkeypatch.chdir(folder)
    mission = Mission.load(*files, lenient_xml=True)
    return echoed_text(mission.goal_model, mission.expansion.rat)


@pytest.fixture(scope="module")
def example() -> Mission:
    return Mission.load(*find_mission_files(EXAMPLE))


# -- the -p text -------------------------------------------------------------------------------

def test_headings_are_centred_in_the_109_character_rule():
    assert heading("GENERATED TASK INSTANCES") == "-" * 41 + " GENERATED TASK INSTANCES " + "-" * 42
    assert heading("MISSION CONSTRAINTS") == "-" * 44 + " MISSION CONSTRAINTS " + "-" * 44
    assert heading("POSSIBLE MISSION DECOMPOSITIONS") == "-" * 38 + " POSSIBLE MISSION DECOMPOSITIONS " + "-" * 38


def test_constraints_are_listed_five_to_a_line_each_full_line_ending_in_and():
    assert list(constraint_lines([f"[c{i}]" for i in range(5)])) == ["[c0] AND [c1] AND [c2] AND [c3] AND [c4]"]
    assert list(constraint_lines([f"[c{i}]" for i in range(6)])) == ["[c0] AND [c1] AND [c2] AND [c3] AND [c4] AND ",
                                                                     "[c5]"]
    assert list(constraint_lines([])) == []


def test_an_empty_constraint_list_leaves_its_heading_alone(example):
    out = io.StringIO()
    print_constraints(example.task_graph, [], out)
    assert out.getvalue() == (heading("MISSION CONSTRAINTS") + "\nNumber of Sequential Mission Constraints: 0\n"
                              "Sequential Constraints:\n\nNumber of execution constraints: 0\nExecution Constraints:\n\n"
                              "Number of fallback constraints: 0\nFallback Constraints:\n" + "-" * 109 + "\n\n")


def test_a_collection_loses_its_closing_parenthesis_among_the_task_instances():
    """As the original prints a Sequence(Room) parameter (object-picking-function with a
    collection task, run with the original)."""
    assert [instance_value(v) for v in ("RoomA", (), ("RoomA",), ("RoomA", "RoomB"), ("A", "B", "C"))] == [
        "RoomA", "(", "(RoomA)", "(RoomA,RoomB,", "(A,B,C,"]
    assert [decomposition_value(v) for v in ("RoomA", (), ("RoomA",), ("RoomA", "RoomB"))] == [
        "RoomA", "(", "(RoomA)", "(RoomA,RoomB)"]


def test_a_task_line_names_the_task_its_location_and_every_mapping_of_its_arguments(example):
    dec = example.task_graph.decompositions()[0].decomposition
    assert task_lines(dec, instance_value) == [
        "Task [FetchItem] With ID [AT1_1|1] with required capabilities [manipulation, navigation] at location "
        "[CentralPharmacy] with arguments [?r,?d=Delivery1,?src=CentralPharmacy] decomposed into actions: ",
        "\t-> navigate ?r ?src", "\t-> pick-item ?r ?d ?src"]

    def summary(**changes) -> str:
        return task_lines(replace(dec, instance=replace(dec.instance, **changes)), decomposition_value)[0]

    assert " at locations [] with" in summary(location=None)
    assert " at location [] with" in summary(location="")  # a query that matched nothing
    assert " at locations [WardA, WardB] with" in summary(location=("WardA", "WardB"))
    rooms = ParameterValue("?src", ("WardA", "WardB"), "Sequence(Location)", "rooms")
    twice = summary(parameters=(rooms, rooms))  # mapped by Location and by Params: printed twice
    assert "with arguments [?r,?d,?src=(WardA,WardB),?src=(WardA,WardB)]" in twice
    empty = ParameterValue("?d", "", "Delivery", "current_delivery")
    assert "with arguments [?r,?d,?src]" in summary(parameters=(empty,))  # an empty value binds nothing


def test_mission_decompositions_are_numbered_blocks_of_task_lines_joined_by_and(example):
    tg = example.task_graph
    first, second = [v.index for v in tg.decompositions()][:2]
    out = io.StringIO()
    print_mission_decompositions(tg, [[first], [first, second]], out)
    one, two = ("\n".join(task_lines(tg.decomposition(d).decomposition, decomposition_value)) for d in (first, second))
    rule = "@" * 39
    assert out.getvalue() == (f"{heading('POSSIBLE MISSION DECOMPOSITIONS')}\n{rule} MISSION 1 {rule}\n{one}\n"
                              f"{'@' * 89}\n\n{rule} MISSION 2 {rule}\n{one}\nAND\n{two}\n{'@' * 89}\n"
                              f"{'-' * 109}\n\n")


# -- the lexers ----------------------------------------------------------------------------------

def test_the_goal_text_lexer_echoes_what_is_neither_a_name_nor_annotation_punctuation():
    assert unmatched("G1: Check All Patient's Vital Signs [G2;G3]") == "'"
    assert unmatched("G2: 2nd-floor a_b c.d x9y é\f OPT FALLBACK [FALLBACK(G3,G4)|G5#G6]") == "2-_.é\f"


def test_the_condition_lexer_echoes_what_is_neither_an_atom_nor_a_connective():
    assert unmatched_in_condition('r.name = "Room-1" && !r.is_clean || (r.x)') == '-1"'
    assert unmatched_in_condition("current_room.level > -1") == "-1"
    assert unmatched_in_condition("a & b") == "&"  # a lone & is not &&


def test_the_echo_is_split_after_its_last_full_stdio_buffer_but_one():
    """The original's echo goes through a 4096-byte stdio buffer written out when a byte comes
    to a full buffer: its whole blocks but the last come before everything else, the rest at exit
    (vital-signs with 4095, 4096, 4097 and 8193 echoed bytes, run with the original)."""
    for size, head in ((0, 0), (1, 0), (4095, 0), (4096, 0), (4097, 4096), (8192, 4096), (8193, 8192)):
        echo = LexerEcho.split("'" * size)
        assert (len(echo.head), echo.head + echo.tail) == (head, "'" * size), size
    assert STDIO_BUFFER == 4096


def test_a_character_the_buffer_cuts_in_two_stays_whole_at_the_end():
    """The original writes the first byte of ``é`` in the first block and the second at exit;
    the plug-in would show two replacement characters, so the drop-in prints the character
    whole, last (docs/deviations.md)."""
    echo = LexerEcho.split("'" + "é" * 2048)  # 4097 bytes: byte 4096 is the second byte of an é
    assert (echo.head, echo.tail) == ("'" + "é" * 2047, "é")
    assert len(echo.head.encode()) == 4095
    assert LexerEcho.split("\ud800") == LexerEcho("", "?")  # a lone surrogate, which the original refuses


def test_every_visit_reads_its_parents_text_and_the_annotation_walk_every_expanded_goal(tmp_path, monkeypatch):
    """Vital signs, every goal marked: the order and count of the goal texts the original reads
    (the walk that makes the task instances, then the one that builds the runtime annotation,
    forAll goals over several rooms and patients among them); recorded from the original."""
    folder, files = reference_copy("vital-signs-monitoring", tmp_path)
    edit_goal_model(files[1], goal_marker)
    assert _echo(folder, files, monkeypatch) == (
        "_1.'_1.'_1.'_3._4._4._6._4._7._8._9._8._10._7._11._12._11._13._14._13._15._7._8._9._8._10._7._11._12._11._13."
        "_14._13._15._4._16._16._18._3._19._1.'_3._4._6._7._8._9._10._11._12._13._14._15._8._9._10._11._12._13._14._15."
        "_16._18._19.")


def test_a_root_without_brackets_is_a_parallel_operator_read_once(tmp_path, monkeypatch):
    """object-picking with ``G1: Pick objects`` (no annotation): the original makes it ``#`` and
    reads it as often as with ``[G2;G3]``; recorded from the original."""
    folder, files = reference_copy("object-picking", tmp_path)
    edit_goal_model(files[1], goal_marker)
    edit_goal_model(files[1], lambda n: n.update(text=re.sub(r" \[G2;G3\]$", "", n["text"])))
    assert _echo(folder, files, monkeypatch) == "_1._1._1._3._3._5._5._1._3._5."


def test_a_forall_over_nothing_is_not_expanded(tmp_path, monkeypatch):
    """object-picking-function with no room to pick in: G3's text is read by its visit's
    parent (G1) only, not by the annotation walk; recorded from the original."""
    folder, files = reference_copy("object-picking-function", tmp_path)
    edit_goal_model(files[1], goal_marker)
    world = folder / "knowledge" / "World_db.xml"
    world.write_text(world.read_text().replace("<needs_picking>True", "<needs_picking>False"))
    assert _echo(folder, files, monkeypatch) == "_1._1._1._1."


def test_conditions_are_read_first_creation_condition_before_query(tmp_path, monkeypatch):
    """Vital signs with a creation condition on the query goal G5 (after its query in the file)
    and a trigger with echoed characters on G19: ``^5-@5-`` then the goal texts' ``''''``;
    recorded from the original.  A trigger is not lexed."""
    folder, files = reference_copy("vital-signs-monitoring", tmp_path)

    def edit(node: dict) -> None:
        props = node["customProperties"]
        if node["text"].startswith("G5:"):
            props["QueriedProperty"] = props["QueriedProperty"].replace("| ", "| @5- ")
            props["CreationCondition"] = 'assertion condition "^5- current_room.is_occupied"'
        if node["text"].startswith("G19:"):
            props["CreationCondition"] = 'assertion trigger "Low-Battery_1"'
    edit_goal_model(files[1], edit)
    assert _echo(folder, files, monkeypatch) == "^5-@5-''''"


def test_conditions_echo_in_vertex_order_where_the_original_uses_the_file_order(tmp_path, monkeypatch):
    """Room preparation, every condition marked: the original echoes ``@2-$3-^10-@8-`` (the
    nodes in file order); the goal model keeps only the vertex order (docs/deviations.md)."""
    folder, files = reference_copy("room-preparation", tmp_path)
    signs = {"QueriedProperty": "@", "AchieveCondition": "$", "CreationCondition": "^"}
    edit_goal_model(files[1], condition_marker(lambda number, key: f"{signs[key]}{number}-"))
    monkeypatch.chdir(folder)
    mission = Mission.load(*files, lenient_xml=True)
    assert condition_echo(mission.goal_model.nodes) == "@2-@8-$3-^10-"


# -- where the drop-in prints the echo -------------------------------------------------------------

def test_every_mode_prints_the_echo_as_the_original_does(tmp_path, monkeypatch, capsys):
    """Without an option the original prints only its echo (vital signs: ``''''``); with ``-p``
    a long echo's full buffers come before the first heading and the rest after the last rule."""
    folder, files = reference_copy("vital-signs-monitoring", tmp_path)
    monkeypatch.chdir(folder)
    args = [str(p.relative_to(folder)) for p in files]
    assert main(args) == 0
    assert capsys.readouterr().out == "''''"
    edit_goal_model(files[1], lambda n: n.update(text=n["text"].replace("Patient's", "'" * 1025)))
    assert main([*args, "-p"]) == 0  # G1's text read 4 times: 4100 bytes
    out = capsys.readouterr().out
    assert out.startswith("'" * 4096 + heading("GENERATED TASK INSTANCES"))
    assert out.endswith("-" * 109 + "\n\n" + "'" * 4)


def test_stdout_is_utf8_whatever_the_environment_says(monkeypatch):
    """The original writes its inputs' bytes; ``PYTHONIOENCODING=latin-1`` would make an
    ``é`` one byte and a ``😀`` an error."""
    raw = io.BytesIO()
    monkeypatch.setattr("sys.stdout", io.TextIOWrapper(raw, encoding="latin-1"))
    utf8_stdout()
    sys.stdout.write("é😀")
    sys.stdout.flush()
    assert raw.getvalue() == "é😀".encode()


def test_the_documented_example_is_what_the_drop_in_prints(tmp_path, monkeypatch, capsys):
    """docs/cli.md shows item-delivery's ``-p`` output, shortened: every line it shows whole is
    printed, in that order."""
    text = (ROOT / "docs" / "cli.md").read_text(encoding="utf-8")
    shown = re.search(r"### What `-p` prints\n.*?```\n(.*?)```", text, re.S)
    assert shown
    folder = tmp_path / "item-delivery"
    shutil.copytree(EXAMPLE, folder)
    monkeypatch.chdir(folder)
    assert main([str(p.relative_to(folder)) for p in find_mission_files(folder)] + ["-p"]) == 0
    printed = iter(capsys.readouterr().out.splitlines())
    for line in shown[1].splitlines():
        if "…" not in line:
            assert line in printed, line  # consumes the output up to the line: the order holds
