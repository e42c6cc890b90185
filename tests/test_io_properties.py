"""The property language's reader: what each form means, and where its errors are located."""
from __future__ import annotations

import pytest

from mutrose_cp.errors import MissionError
from mutrose_cp.io.properties import command_line_properties, read_properties
from mutrose_cp.model.properties import (
    Before,
    Fact,
    Finally,
    Implies,
    InitiallyNeeded,
    Junction,
    Not,
    Robots,
    TaskPattern,
    Uses,
)


def one(text: str):
    return command_line_properties([text])[0]


def error(texts=None, path=None) -> str:
    with pytest.raises(MissionError) as caught:
        read_properties(path) if path is not None else command_line_properties(texts)
    return str(caught.value)


def test_quantifiers_and_atoms():
    disinfect, deliver = TaskPattern("Disinfect", ("?rm",)), TaskPattern("Deliver", ("?rm",))
    p = one("always uses(task Disinfect(?rm)) implies before(task Disinfect(?rm), task Deliver(?rm))")
    assert (p.quantifier, p.formula) == ("always", Implies(Uses(disinfect), Before(disinfect, deliver)))
    assert disinfect.variables == ("?rm",)
    assert one("count uses(method clean-with-uv)").formula == Uses(("method", "clean-with-uv"))
    assert one("some uses(decomposition AT1_1|2)").formula == Uses(("decomposition", "AT1_1|2"))
    assert one("never finally(busy(kitchen))").formula == Finally(Fact("busy", ("kitchen",)))
    assert one("always initially-needed(not open(door1))").formula == InitiallyNeeded(
        Fact("open", ("door1",), negated=True))
    assert one("always finally(stock(kitchen) = 2)").formula == Finally(Fact("stock", ("kitchen",), False, ("==", 2.0)))
    assert one("some robots(task Carry) >= 2").formula == Robots(TaskPattern("Carry", None), ">=", 2)
    assert one("always uses(task Carry())").formula == Uses(TaskPattern("Carry", ()))


def test_precedence_not_and_or_implies():
    a, b, c = (Uses(("action", n)) for n in "abc")
    assert one("some not uses(action a) and uses(action b) or uses(action c)").formula == Junction(
        "or", (Junction("and", (Not(a), b)), c))
    assert one("some uses(action a) implies uses(action b) implies uses(action c)").formula == Implies(a, Implies(b, c))
    assert one("some uses(action a) and (uses(action b) and uses(action c))").formula == Junction("and", (a, b, c))


def test_keywords_can_name_tasks_and_actions():
    assert one("never uses(action before)").formula == Uses(("action", "before"))
    assert one("some uses(task and)").formula == Uses(TaskPattern("and", None))


@pytest.mark.parametrize(("text", "column", "expected"), [
    ("sometimes uses(task A)", 1, "expected always, some, never or count, found 'sometimes'"),
    ("always uses(task)", 17, "expected a name, found ')'"),
    ("always uses(task A) and", 24, "found the end"),
    ("always finally(stock(k) >= x)", 28, "expected a number, found 'x'"),
    ("always robots(task A) >= 1.5", 26, "expected a whole number"),
    ("always uses(widget A)", 13, "expected task or method, action, capability or decomposition"),
])
def test_syntax_errors_are_located(text, column, expected):
    message = error([text])
    assert f"--property 1:{column}:" in message
    assert expected in message


def test_named_command_line_property_keeps_its_columns():
    assert one("kitchen-free: never finally(busy(kitchen))").name == "kitchen-free"
    assert "--property 2:20:" in error(["never uses(action a)", "x: always uses(task)"])


def test_file_lines_names_comments_and_every_problem(tmp_path):
    path = tmp_path / "mission.properties"
    path.write_text("# what must hold\n\nclean-first: always uses(task A)\nfallbacks: count uses(method m)\n")
    props = read_properties(path)
    assert [(p.name, p.quantifier, p.where) for p in props] == [
        ("clean-first", "always", f"{path}:3"), ("fallbacks", "count", f"{path}:4")]
    path.write_text("a: always uses(task A)\nalways uses(task B)\na: some uses(task C)\nb: some uses(task\n")
    message = error(path=path)
    assert f"{path}:2:1: a property needs a name" in message
    assert f"{path}:3:1: property a is also defined at line 1" in message
    assert f"{path}:4:18: property b: expected" in message


def test_empty_file_and_bad_bytes_are_refused(tmp_path):
    path = tmp_path / "empty.properties"
    path.write_text("# nothing yet\n")
    assert "holds no property" in error(path=path)
    path.write_bytes(b"a: always uses(task \xff)\n")
    assert str(path) in error(path=path)


# --- check --properties: the syntax and the names, against the mission, as a user runs it ------

from pathlib import Path  # noqa: E402

from mutrose_cp.cli.program import main  # noqa: E402

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "hospital-disinfection"


def test_check_accepts_properties_that_name_the_domain(tmp_path, capsys):
    path = tmp_path / "hospital.properties"
    path.write_text("uv-opens: some uses(method uv-after-opening-door)\n"
                    "no-doors: never finally(not door-open(RoomA)) and uses(capability door-opening)\n"
                    "cleared: always uses(task ClearRoom(?r, ?rm)) implies before(task ClearRoom(?r, ?rm), "
                    "task UVDisinfection(?u, ?rm))\n")
    assert main(["check", str(EXAMPLE), "--properties", str(path), "-q"]) == 0


def test_check_locates_property_errors(tmp_path, capsys):
    path = tmp_path / "hospital.properties"
    path.write_text("ok: some uses(method uv-after-opening-door)\n"
                    "typo: never uses(action dispose-wastes)\n"
                    "arity: always finally(disinfected(RoomA, RoomB))\n"
                    "syntax: always uses(task ClearRoom\n")
    assert main(["check", str(EXAMPLE), "--properties", str(path), "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{path}:4:35: property syntax: expected" in err  # syntax first: the rest is not read
    path.write_text(path.read_text().rsplit("syntax", 1)[0])
    assert main(["check", str(EXAMPLE), "--properties", str(path), "--property", "never uses(task Mop)", "-q"]) == 2
    err = capsys.readouterr().err
    assert f"{path}:2: property typo: the domain declares no action dispose-wastes (did you mean dispose-waste?)" in err
    assert f"{path}:3: property arity: predicate or function disinfected takes 1 arguments, not 2" in err
    assert "--property 1: property property-1: the domain declares no task Mop" in err
    assert "Traceback" not in err
