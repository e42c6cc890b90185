"""Properties decided over every valid decomposition (solve/verify.py), checked against brute
force: every decomposition the exploratory algorithm lists, evaluated one by one."""
from __future__ import annotations

import json
import re
import os
from pathlib import Path
from typing import Iterable

import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

from mutrose_cp.errors import MissionError, NoDecompositionError
from mutrose_cp.io.properties import command_line_properties
from mutrose_cp.mission import Mission
from mutrose_cp.model.properties import Formula, Implies, Junction, Not, TaskPattern, Uses
from missiongen import load_mission, missions

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "hospital-disinfection"
EXAMPLES = int(os.environ.get("MUTROSE_VERIFY_EXAMPLES", "60"))


def hospital() -> Mission:
    return Mission.load(*(next((EXAMPLE / d).iterdir()) for d in ("hddl", "gm", "configuration")))


def verdict(mission: Mission, text: str):
    return mission.verify(command_line_properties([text])[0])


# --- brute force ------------------------------------------------------------------------------

def used(mission: Mission, decomposition: Iterable[int]) -> set[tuple[str, str]]:
    """What one mission decomposition uses, read straight from its task decompositions."""
    out: set[tuple[str, str]] = set()
    for v in decomposition:
        d = mission.task_graph.decomposition(v).decomposition
        out |= {("task", d.instance.name), ("decomposition", d.id)}
        out |= {("action", s.name) for s in d.path.actions}
        out |= {("capability", c) for s in d.path.actions for c in s.capabilities}
        stack = [d.path.tree]
        while stack:
            node = stack.pop()
            out |= {("method", node.name)} if node.kind == "method" else set()
            stack.extend(node.children)
    return out


def holds(formula: Formula, uses: set[tuple[str, str]]) -> bool:
    if isinstance(formula, Not):
        return not holds(formula.operand, uses)
    if isinstance(formula, Junction):
        results = [holds(f, uses) for f in formula.operands]
        return all(results) if formula.op == "and" else any(results)
    if isinstance(formula, Implies):
        return not holds(formula.premise, uses) or holds(formula.conclusion, uses)
    assert isinstance(formula, Uses)
    target = formula.target
    key = ("task", target.name) if isinstance(target, TaskPattern) else target
    return key in uses


def brute_force(mission: Mission, text: str) -> tuple[str, int, int]:
    prop = command_line_properties([text])[0]
    try:
        listed = mission.exploratory()
    except NoDecompositionError:
        listed = []
    if not listed:
        return "vacuous", 0, 0
    count = sum(holds(prop.formula, used(mission, d)) for d in listed)
    status = {"count": "count", "always": "holds" if count == len(listed) else "fails",
              "never": "holds" if count == 0 else "fails", "some": "holds" if count else "fails"}[prop.quantifier]
    return status, count, len(listed)


@st.composite
def missions_with_properties(draw):
    spec = draw(missions())
    mission = load_mission(spec)
    domain = mission.domain
    names = ([("task", t.name) for t in domain.tasks] + [("method", m.name) for m in domain.methods]
             + [("action", a.name) for a in domain.actions]
             + [("capability", c) for a in domain.actions for c in a.capabilities])
    atom = st.sampled_from(names).map(lambda n: f"uses(task {n[1]})" if n[0] == "task" else f"uses({n[0]} {n[1]})")
    formula = st.recursive(atom, lambda inner: st.one_of(
        inner.map(lambda f: f"not {f}"),
        st.tuples(inner, st.sampled_from(["and", "or", "implies"]), inner).map(lambda t: f"({t[0]} {t[1]} {t[2]})")),
        max_leaves=5)
    quantifier = draw(st.sampled_from(["always", "some", "never", "count"]))
    return mission, f"{quantifier} {draw(formula)}"


@settings(max_examples=EXAMPLES, deadline=None, suppress_health_check=list(HealthCheck))
@given(missions_with_properties())
def test_every_verdict_and_count_agrees_with_brute_force(case):
    mission, text = case
    if mission.decomposition_space().count > 5000:
        return
    expected = brute_force(mission, text)
    found = verdict(mission, text)
    assert (found.status, found.count, found.total) == expected, text
    if found.witness is not None:  # a witness is a valid decomposition that shows the verdict
        assert sorted(found.witness) in [sorted(d) for d in mission.exploratory()]
        shown = holds(found.property.formula, used(mission, found.witness))
        assert shown == (found.property.quantifier != "always")


# --- the bundled example, by hand -------------------------------------------------------------

def test_hospital_verdicts():
    mission = hospital()
    opens = verdict(mission, "some uses(method uv-after-opening-door)")
    assert (opens.status, opens.count, opens.total) == ("holds", 18, 36)
    assert "uv-after-opening-door" in {n for kind, n in used(mission, opens.witness) if kind == "method"}
    never = verdict(mission, "never uses(action open-door)")
    assert (never.status, never.count) == ("fails", 18)
    assert ("action", "open-door") in used(mission, never.witness)
    always = verdict(mission, "always uses(task ClearRoom) or not uses(task ClearRoom)")
    assert (always.status, always.witness) == ("holds", None)


def test_variables_bind_per_value():
    """``?rm`` takes each room of the instances: the property is their conjunction."""
    mission = hospital()
    rooms = {str(p.value) for t in mission.expansion.instances if t.name == "ClearRoom" for p in t.parameters
             if p.hddl_param == "?rm"}
    assert len(rooms) >= 2
    per_room = [verdict(mission, f"count uses(task ClearRoom(?r, {room})) implies uses(task UVDisinfection(?u, {room}))")
                for room in sorted(rooms)]
    joined = verdict(mission, "count uses(task ClearRoom(?r, ?rm)) implies uses(task UVDisinfection(?u, ?rm))")
    listed = mission.exploratory()
    def ok(d, room):
        instances = [mission.task_graph.decomposition(v).decomposition.instance for v in d]
        names = {(t.name, {p.hddl_param: str(p.value) for p in t.parameters}.get("?rm")) for t in instances}
        return ("ClearRoom", room) not in names or ("UVDisinfection", room) in names
    assert joined.count == sum(all(ok(d, room) for room in rooms) for d in listed)
    assert all(v.count == sum(ok(d, room) for d in listed) for v, room in zip(per_room, sorted(rooms)))


def test_facts_whose_variables_take_no_value_are_refused_by_name():
    with pytest.raises(MissionError, match="property property-1: cannot be verified: the variable [?]x of cleared"):
        verdict(hospital(), "always finally(cleared(?x))")
    assert verdict(hospital(), "always uses(task ClearRoom(?r, ?x)) implies finally(cleared(?x))").status == "holds"


# --- mutrose-cp verify, as a user runs it -----------------------------------------------------

import shutil  # noqa: E402

from mutrose_cp.cli.program import main  # noqa: E402

OPENS = "opens: some uses(method uv-after-opening-door)"
NO_DOOR = "no-door: never uses(action open-door)"
SPRAY = "spray: count uses(task SprayDisinfection)"


def copy_of_example(tmp_path: Path) -> Path:
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder)
    return folder


def test_verify_statuses_witnesses_and_exit(tmp_path, capsys):
    folder, witnesses = copy_of_example(tmp_path), tmp_path / "witnesses"
    assert main(["verify", str(folder), "--property", OPENS, "--property", SPRAY, "-q"]) == 0
    assert capsys.readouterr().out.splitlines() == [
        "opens: holds, 18 of 36 valid decompositions satisfy the formula", "spray: 28 of 36 valid decompositions"]
    args = ["verify", str(folder), "--property", OPENS, "--property", NO_DOOR, "--witness-dir", str(witnesses), "-q"]
    assert main(args) == 1
    out = capsys.readouterr().out
    assert f"no-door: fails, 18 of 36 valid decompositions satisfy the formula (witness {witnesses / 'no-door.json'})" in out
    assert sorted(p.name for p in witnesses.iterdir()) == ["no-door.json", "opens.json"]
    for witness in witnesses.iterdir():  # each is one valid decomposition of the mission
        assert main(["validate", str(folder), str(witness), "-q"]) == 0
    first = (witnesses / "no-door.json").read_bytes()
    assert main(args) == 1 and (witnesses / "no-door.json").read_bytes() == first  # deterministic


def test_verify_json_summary(tmp_path, capsys):
    assert main(["verify", str(EXAMPLE), "--property", SPRAY, "--json-summary", "-q"]) == 0
    summary = json.loads(capsys.readouterr().out.splitlines()[-1])
    assert summary["properties"] == [{"name": "spray", "property": "count uses(task SprayDisinfection)",
                                      "status": "count", "count": "28", "total": "36", "witness": None}]


def test_verify_without_decompositions_is_vacuous(tmp_path, capsys):
    folder = copy_of_example(tmp_path)
    hddl = next((folder / "hddl").iterdir())
    hddl.write_text(hddl.read_text().replace(
        "        :task (ClearRoom ?r ?rm)\n",
        "        :task (ClearRoom ?r ?rm)\n        :precondition (and (cleared ?rm) (not (cleared ?rm)))\n"))
    assert main(["verify", str(folder), "--property", NO_DOOR, "-q"]) == 3
    assert "no-door: vacuous" in capsys.readouterr().out


def test_verify_bad_input(tmp_path, capsys):
    assert main(["verify", str(EXAMPLE), "-q"]) == 2
    assert "verify needs a property" in capsys.readouterr().err
    assert main(["verify", str(EXAMPLE), "--property", "a: some uses(task A)", "--property", "a: never uses(task A)"]) == 2
    assert "property a is given twice (--property 1 and --property 2)" in capsys.readouterr().err
    assert main(["verify", str(EXAMPLE), "--property", "some uses(task"]) == 2
    assert "--property 1:15:" in capsys.readouterr().err


def test_witnesses_never_overwrite_inputs(tmp_path, capsys):
    folder = copy_of_example(tmp_path)
    gm = next((folder / "gm").iterdir())
    before = gm.read_bytes()
    named = f"{gm.stem}: some uses(method uv-after-opening-door)"
    assert main(["verify", str(folder), "--property", named, "--witness-dir", str(folder / "gm"), "-q"]) == 2
    assert gm.read_bytes() == before
    assert "the output folder holds the input" in capsys.readouterr().err


def test_witnesses_are_written_all_or_nothing(tmp_path, capsys):
    folder, witnesses = copy_of_example(tmp_path), tmp_path / "witnesses"
    (witnesses / "no-door.json").mkdir(parents=True)  # the second witness cannot be written
    assert main(["verify", str(folder), "--property", OPENS, "--property", NO_DOOR,
                 "--witness-dir", str(witnesses), "-q"]) == 2
    assert sorted(p.name for p in witnesses.iterdir()) == ["no-door.json"]  # opens.json was not kept


def test_before_agrees_with_brute_force_over_the_constraint_order():
    """``before`` per room, against each listed decomposition checked pair by pair on the
    transitive closure of the SEQ and FB constraints."""
    import networkx as nx

    mission = hospital()
    order = nx.transitive_closure_dag(nx.DiGraph([(c.first, c.second) for c in mission.constraints
                                                  if c.kind in ("SEQ", "FB")]))
    tg = mission.task_graph

    def room_of(v):
        return {p.hddl_param: str(p.value) for p in tg.decomposition(v).decomposition.instance.parameters}["?rm"]

    def ordered(d, first, second):
        a = [v for v in d if tg.decomposition(v).decomposition.instance.name == first]
        b = [v for v in d if tg.decomposition(v).decomposition.instance.name == second]
        return all(order.has_edge(x, y) for x in a for y in b if room_of(x) == room_of(y))

    listed = mission.exploratory()
    for first, second in [("ClearRoom", "UVDisinfection"), ("UVDisinfection", "ClearRoom"),
                          ("DisposeWaste", "ReportRoomReady"), ("ReportRoomReady", "SprayDisinfection")]:
        found = verdict(mission, f"count before(task {first}(?a, ?rm), task {second}(?b, ?rm))")
        assert found.count == sum(ordered(d, first, second) for d in listed), (first, second)


def test_unknown_decomposition_ids_and_fifo_properties_are_refused(tmp_path, capsys):
    assert main(["verify", str(EXAMPLE), "--property", "never uses(decomposition AT9_9|1)", "-q"]) == 2
    assert "the mission has no task decomposition AT9_9|1" in capsys.readouterr().err
    fifo = tmp_path / "properties"
    os.mkfifo(fifo)
    assert main(["verify", str(EXAMPLE), "--properties", str(fifo), "-q"]) == 2  # at once, never blocking
    assert "not a regular file" in capsys.readouterr().err


def test_embedding_model_requires_or_forbids_a_property():
    """Posted to DecompositionModel, a property keeps exactly the decompositions verify counts."""
    from test_api import enumerate_all

    mission = hospital()
    for text in ["count uses(method uv-after-opening-door)",
                 "count before(task UVDisinfection(?u, ?rm), task ClearRoom(?r, ?rm))",
                 "count uses(task SprayDisinfection) and not uses(action open-door)"]:
        prop = command_line_properties([text])[0]
        counted = mission.verify(prop)
        required = mission.decomposition_model()
        required.add_property(prop)
        forbidden = mission.decomposition_model()
        forbidden.add_property(prop, holds=False)
        kept, dropped = enumerate_all(required).solutions, enumerate_all(forbidden).solutions
        assert (len(kept), len(dropped)) == (counted.count, counted.total - counted.count), text
        assert len(set(kept)) == len(kept)  # one solution per decomposition: the helpers are defined


@pytest.mark.parametrize(("comparison", "bound"), [(">=", 2), (">=", 3), ("<=", 2), ("==", 1), ("!=", 2), (">", 1), ("<", 3)])
def test_robots_agrees_with_brute_force(comparison, bound):
    """``robots(task T) OP k``: every chosen T instance's robot number allows only numbers that
    compare so; checked per task name against each listed decomposition."""
    import operator

    compare = {">=": operator.ge, "<=": operator.le, "==": operator.eq, "!=": operator.ne,
               ">": operator.gt, "<": operator.lt}[comparison]
    mission = hospital()
    tg, listed = mission.task_graph, mission.exploratory()
    names = sorted({t.name for t in mission.expansion.instances})
    assert any(t.robot_number.min != t.robot_number.max for t in mission.expansion.instances)  # a range among them
    for name in names:
        def ok(d):
            numbers = [tg.decomposition(v).decomposition.instance.robot_number for v in d
                       if tg.decomposition(v).decomposition.instance.name == name]
            return all(compare(n, bound) for r in numbers for n in range(r.min, r.max + 1))
        found = verdict(mission, f"count robots(task {name}) {comparison} {bound}")
        assert found.count == sum(ok(d) for d in listed), name


def test_a_witness_is_drawn_from_its_file(tmp_path, capsys):
    """``graph --view decomposition --from-output WITNESS`` draws exactly the witness's task
    decompositions, and refuses a file that is not one of the mission's valid decompositions."""
    folder, witnesses = copy_of_example(tmp_path), tmp_path / "witnesses"
    assert main(["verify", str(folder), "--property", NO_DOOR, "--witness-dir", str(witnesses), "-q"]) == 1
    witness = witnesses / "no-door.json"
    drawn = tmp_path / "no-door.dot"
    assert main(["graph", str(folder), "--view", "decomposition", "--from-output", str(witness), "-o", str(drawn), "-q"]) == 0
    text = drawn.read_text()
    listed = json.loads(witness.read_text())
    ids = sorted(listed["tasks"][key]["id"] for key in listed["mission_decompositions"][0])
    assert sorted(set(re.findall(r'"(AT\d+_\d+\|\d+)"', text))) == ids and "open-door" in text
    # a forged file: one task decomposition swapped for another of the same task
    mission = hospital()
    other = {v.decomposition.id for v in mission.task_graph.decompositions()} - set(ids)
    same_task = sorted(i for i in other if i.split("|")[0] in {j.split("|")[0] for j in ids})
    forged = json.loads(witness.read_text())
    key = next(k for k in forged["mission_decompositions"][0] if forged["tasks"][k]["id"].split("|")[0] == same_task[0].split("|")[0])
    forged["tasks"][key]["id"] = same_task[0]
    (tmp_path / "forged.json").write_text(json.dumps(forged))
    capsys.readouterr()
    args = ["graph", str(folder), "--view", "decomposition", "-o", str(tmp_path / "f.dot"), "-q", "--from-output"]
    assert main([*args, str(tmp_path / "forged.json")]) == 2
    assert "forged.json: mission_decompositions[0]: not a valid decomposition of this mission" in capsys.readouterr().err
    forged["tasks"][key]["id"] = "AT99_1|1"
    (tmp_path / "foreign.json").write_text(json.dumps(forged))
    assert main([*args, str(tmp_path / "foreign.json")]) == 2
    assert "which this mission does not have" in capsys.readouterr().err
    assert main([*args, str(witness), "--index", "1"]) == 2
    assert "no decomposition 1: the file lists 1" in capsys.readouterr().err
    assert main(["graph", str(folder), "--view", "task-graph", "--from-output", str(witness), "-o", str(drawn)]) == 2
    assert main(["graph", str(folder), "--view", "decomposition", "--from-output", str(witness), "-o", str(witness)]) == 2
    assert json.loads(witness.read_text()) == listed  # the witness was not overwritten
    assert not (tmp_path / "f.dot").exists()


def test_a_witness_read_from_a_fifo_never_blocks(tmp_path, capsys):
    fifo = tmp_path / "witness.json"
    os.mkfifo(fifo)
    assert main(["graph", str(EXAMPLE), "--view", "decomposition", "--from-output", str(fifo),
                 "-o", str(tmp_path / "w.dot"), "-q"]) == 2
    assert "not a regular file" in capsys.readouterr().err and not (tmp_path / "w.dot").exists()
