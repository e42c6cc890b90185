"""Uncertain worlds on the command line (count, decompose, explain, check), attacked: bad
values, located errors, FIFOs, outputs onto the uncertainty file, options without a file,
determinism, and byte-identical outputs without one."""
from __future__ import annotations

import json
import os
import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLE = ROOT / "examples" / "medication-round"
HOSPITAL = ROOT / "examples" / "hospital-disinfection"


@pytest.fixture
def mission(tmp_path: Path) -> Path:
    folder = tmp_path / "medication-round"
    shutil.copytree(EXAMPLE, folder)
    return folder


def run(capsys, *argv: str) -> tuple[int, str, str]:
    status = main(list(argv))
    out, err = capsys.readouterr()
    return status, out, err


def test_the_example_counts_explains_and_decomposes(mission, capsys, tmp_path):
    """The story of examples/medication-round: Room202's lock and Room203's patient."""
    assert run(capsys, "count", str(mission), "-q")[:2] == (0, "4\n")
    assert run(capsys, "count", str(mission), "-q", "--possible")[:2] == (0, "4\n")
    assert run(capsys, "count", str(mission), "-q", "--robust")[:2] == (0, "0\n")  # an answer, not a failure
    status, out, _ = run(capsys, "explain", str(mission), "-q")
    assert status == 0
    assert "sense first: door-locked(Room202), patient-present(Room203)" in out
    assert "most likely decomposition now: valid with probability 0.48" in out
    assert out.index("patient-present(Room203) first raises it to 0.8") < out.index("door-locked(Room202) first raises it to 0.6")
    plan = tmp_path / "plan.json"
    assert run(capsys, "decompose", str(mission), "--most-likely", "-o", str(plan), "-q")[0] == 0
    written = json.loads(plan.read_text())
    section = written["mission_decomposition_uncertainty"]
    assert (section["possible"], section["robust"]) == ("4", "0")
    assert section["decompositions"] == [{"robust": "False", "probability": "0.48",
                                          "needs": ["not door-locked(Room202)", "patient-present(Room203)"]}]
    ids = sorted(written["tasks"][k]["id"] for k in written["mission_decompositions"][0])
    assert ids == ["AT1_1|1", "AT1_2|1", "AT1_3|1", "AT2_1|1", "AT2_2|1", "AT2_3|1"]
    assert run(capsys, "decompose", str(mission), "--robust", "-o", str(tmp_path / "r.json"), "-q")[0] == 3
    assert not (tmp_path / "r.json").exists()


def test_listed_decompositions_carry_their_assumptions_in_both_json_styles(mission, capsys, tmp_path):
    boost, standard = tmp_path / "boost.json", tmp_path / "standard.json"
    assert run(capsys, "decompose", str(mission), "-o", str(boost), "-q")[0] == 0
    assert run(capsys, "decompose", str(mission), "-o", str(standard), "-q", "--json-style", "standard")[0] == 0
    listed = json.loads(boost.read_text())
    section = listed["mission_decomposition_uncertainty"]
    assert len(section["decompositions"]) == len(listed["mission_decompositions"]) == 4
    assert sum(float(d["probability"]) for d in section["decompositions"]) == pytest.approx(1.0)
    typed = json.loads(standard.read_text())["mission_decomposition_uncertainty"]
    assert typed["possible"] == "4" and typed["decompositions"][0]["robust"] is False
    assert typed["decompositions"][0]["probability"] == pytest.approx(0.48)
    first = boost.read_bytes()
    assert run(capsys, "decompose", str(mission), "-o", str(boost), "-q")[0] == 0
    assert boost.read_bytes() == first  # deterministic


def test_without_uncertainty_the_output_is_what_it_was(mission, capsys, tmp_path):
    """The configuration's key removed, or another command: the world as written, byte for
    byte the output of a mission that never had an uncertainty file."""
    config = mission / "configuration" / "configuration.json"
    plain_config = json.loads(config.read_text())
    del plain_config["uncertainty"]
    plain = tmp_path / "plain"
    shutil.copytree(mission, plain)
    (plain / "configuration" / "configuration.json").write_text(json.dumps(plain_config, indent=4))
    (plain / "knowledge" / "uncertain.json").unlink()
    a, b = tmp_path / "a.json", tmp_path / "b.json"
    assert run(capsys, "decompose", str(plain), "-o", str(a), "-q")[0] == 0
    assert "mission_decomposition_uncertainty" not in a.read_text()
    assert run(capsys, "count", str(mission), "-q", "--as-written")[:2] == (0, "1\n")  # the file ignored
    status, out, _ = run(capsys, "compare", str(mission), "-q")  # both decomposers, the world as written
    assert status == 0 and "agree: cpsat, exploratory (1 valid mission decompositions)" in out
    # verify reads the world as written, and says so
    status, out, err = run(capsys, "verify", str(mission), "--property", "count uses(method hand-to-patient)")
    assert status == 0 and "1 of 1 valid decompositions" in out
    assert "does not read the uncertainty file" in err
    assert run(capsys, "graph", str(mission), "-o", str(tmp_path / "g.dot"), "-q")[0] == 0
    # the hospital example has no uncertainty file: its output is unchanged by this feature
    assert run(capsys, "decompose", str(HOSPITAL), "-o", str(b), "-q")[0] == 0
    assert "mission_decomposition_uncertainty" not in b.read_text()


def test_options_that_need_an_uncertainty_file(capsys):
    for argv, message in ((["count", str(HOSPITAL), "--robust"], "--robust counts decompositions under uncertain facts"),
                          (["decompose", str(HOSPITAL), "--most-likely"], "--most-likely chooses among"),
                          (["explain", str(HOSPITAL)], "explain says which uncertain facts to sense")):
        status, _, err = run(capsys, *argv)
        assert status == 2 and message in err, err
    status, _, err = run(capsys, "decompose", str(EXAMPLE), "--algorithm", "exploratory", "-q")
    assert status == 2 and "uncertain facts are decided by the CP-SAT decomposer" in err
    status, _, err = run(capsys, "decompose", str(EXAMPLE), "--most-likely", "--sample", "2", "-q")
    assert status == 2 and "cannot be combined with --sample" in err


def test_bad_uncertainty_files_are_located(mission, capsys, tmp_path):
    bad = tmp_path / "bad.json"
    bad.write_text(json.dumps({"uncertain": [
        {"entity": "Room202", "attribute": "door_lockd", "probability": 0.2},
        {"entity": "Room230", "attribute": "patient_present"},
        {"entity": "Room201", "attribute": "door_locked", "probability": 1.5},
        {"entity": "Room201", "attribute": "patient_present", "values": [1, 2]},
        {"entity": "Room203", "attribute": "patient_present", "colour": "red"},
        {"entity": "Room201", "attribute": "door_locked", "probability": 0.1},
        {"entity": "Room201", "attribute": "door_locked", "probability": 0.3},
        "Room205",
    ]}, indent=1))
    status, _, err = run(capsys, "check", str(mission), "--uncertain", str(bad))
    assert status == 2
    for expected in ("bad.json:3:", "(did you mean door_locked?)", "the world has no Room Room230",
                     "uncertain[2].probability: expected a probability between 0 and 1, not 1.5",
                     "is the predicate patient-present: give \"probability\"", "uncertain[4].colour: unknown key",
                     "Room201.door_locked is already uncertain at", "uncertain[7]: expected an object"):
        assert expected in err, (expected, err)
    assert "Traceback" not in err
    for text, message in (("[1, 2", "invalid JSON"), ("[]", 'an uncertainty file is an object with a list "uncertain"'),
                          ('{"uncertain": {}}', "uncertain: expected a list of entries"),
                          ('{"uncertain": [], "more": 1}', "more: unknown key")):
        bad.write_text(text)
        status, _, err = run(capsys, "count", str(mission), "--uncertain", str(bad), "-q")
        assert status == 2 and message in err, (text, err)


def write_json(path: Path, data: object) -> Path:
    path.write_text(json.dumps(data))
    return path


def test_what_the_goal_model_reads_is_expanded_per_world(tmp_path, capsys):
    """Whether Room101 needs disinfection (a query reads it) decides its tasks: counted over both
    worlds, the most likely plan written in the world it assumes, which validate then checks."""
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection", "probability": 0.3},
        {"entity": "Room104", "attribute": "door_open", "probability": 0.5}]})
    status, out, err = run(capsys, "count", str(HOSPITAL), "--uncertain", str(u))
    assert (status, out) == (0, "48\n") and "expanded in 2 worlds of the 1 fact the goal model reads" in err
    assert run(capsys, "count", str(HOSPITAL), "--uncertain", str(u), "--robust", "-q")[:2] == (0, "0\n")
    summary = json.loads(run(capsys, "count", str(HOSPITAL), "--uncertain", str(u), "--json-summary")[1].splitlines()[0])
    assert summary["worlds"] == 2 and summary["possible"] == ["48", "48"]
    status, out, _ = run(capsys, "explain", str(HOSPITAL), "--uncertain", str(u), "-q")
    assert status == 0 and "sense first: needs_disinfection(Room101)" in out
    assert "sensing needs_disinfection(Room101) first raises it to 1 (expected)" in out
    plan, again = tmp_path / "plan.json", tmp_path / "again.json"
    for path in (plan, again):
        assert run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "--most-likely", "-o", str(path),
                   "-q")[0] == 0
    assert plan.read_bytes() == again.read_bytes()  # deterministic
    section = json.loads(plan.read_text())["mission_decomposition_uncertainty"]
    assert section["world"] == [{"entity": "Room101", "attribute": "needs_disinfection", "value": "False"}]
    assert section["decompositions"] == [{"robust": "False", "probability": "0.7",
                                          "needs": ["not needs_disinfection(Room101)"]}]
    status, _, err = run(capsys, "validate", str(HOSPITAL), str(plan))
    assert status == 0 and "checked in the world the output was expanded in: Room101.needs_disinfection = False" in err
    drawn = tmp_path / "plan.dot"
    assert run(capsys, "graph", str(HOSPITAL), "--view", "decomposition", "--from-output", str(plan), "-o", str(drawn),
               "-q")[0] == 0
    assert "Room102" in drawn.read_text() and "Room101" not in drawn.read_text()  # drawn in its world
    # the plain listing would mix the tasks of two expansions: refused, saying what works
    status, _, err = run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "-o", str(tmp_path / "x.json"))
    assert status == 2 and "list the robust ones (--robust) or the most likely (--most-likely)" in err
    assert not (tmp_path / "x.json").exists()
    # XML has no uncertainty section to name the world in: refused rather than written unnamed
    status, _, err = run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "--most-likely", "--format", "xml",
                         "-o", str(tmp_path / "x.xml"))
    assert status == 2 and "write JSON" in err and not (tmp_path / "x.xml").exists()
    status, _, err = run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "--robust", "-o",
                         str(tmp_path / "x.json"))
    assert status == 3 and "whatever the uncertain facts are" in err


def test_robust_decompositions_of_every_world_are_listed_in_one(tmp_path, capsys):
    """Room103 needs no disinfection, so whether it is restocked changes nothing: every world
    has the same decompositions, all robust, listed in the first world's task ids."""
    u = write_json(tmp_path / "u.json", {"uncertain": [{"entity": "Room103", "attribute": "is_restocked"}]})
    out = tmp_path / "robust.json"
    assert run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "--robust", "-o", str(out), "-q")[0] == 0
    written = json.loads(out.read_text())
    assert len(written["mission_decompositions"]) == 36
    assert all(d["robust"] == "True" for d in written["mission_decomposition_uncertainty"]["decompositions"])
    assert run(capsys, "validate", str(HOSPITAL), str(out), "-q")[0] == 0


def test_what_the_goal_model_reads_is_checked_and_bounded(tmp_path, capsys, monkeypatch):
    """A record the world does not have, a joint table over both kinds of fact, and more worlds
    than are expanded: each refused, located, before any expansion."""
    bad = write_json(tmp_path / "bad.json", {"uncertain": [
        {"entity": "Room110", "attribute": "needs_disinfection"}]})
    status, _, err = run(capsys, "check", str(HOSPITAL), "--uncertain", str(bad))
    assert status == 2 and f"{bad}:1:" in err and "the world has no record Room110 (did you mean" in err
    mixed = write_json(tmp_path / "mixed.json", {
        "uncertain": [{"entity": "Room101", "attribute": "needs_disinfection"},
                      {"entity": "Room104", "attribute": "door_open"}],
        "joint": [{"facts": [{"entity": "Room101", "attribute": "needs_disinfection"},
                             {"entity": "Room104", "attribute": "door_open"}],
                   "outcomes": [{"values": [True, True], "probability": 1.0}]}]})
    status, _, err = run(capsys, "count", str(HOSPITAL), "--uncertain", str(mixed), "-q")
    assert status == 2 and "a table holds either kind, not both" in err
    many = write_json(tmp_path / "many.json", {"uncertain": [
        {"entity": room, "attribute": attribute} for room in ("Room101", "Room102", "Room103")
        for attribute in ("needs_disinfection", "is_restocked")]})
    for command in ("count", "check"):
        status, _, err = run(capsys, command, str(HOSPITAL), "--uncertain", str(many), "-q")
        assert status == 2 and "give 64 worlds to expand the mission in, more than the 16" in err, command
        assert "goal G2 reads needs_disinfection" in err and f"{many}:1:" in err
    from mutrose_cp.solve import scenarios
    two = write_json(tmp_path / "two.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection"}, {"entity": "Room101", "attribute": "door_open"}]})
    exact = [int(run(capsys, "count", str(HOSPITAL), "--uncertain", str(two), "-q", *kind)[1]) for kind in ([], ["--robust"])]
    # where the worlds differ, too many pairs to list: bounds that hold the exact counts, said so
    monkeypatch.setattr(scenarios, "MAX_PAIRS", 2)
    for kind, count in zip(([], ["--robust"]), exact):
        status, out, err = run(capsys, "count", str(HOSPITAL), "--uncertain", str(two), *kind)
        low, high = map(int, out.strip().split(".."))
        assert status == 0 and low <= count <= high and low < high, (kind, out)
        assert "bounds, not exact counts: the worlds of the uncertain facts the goal model reads differ" in err
    for command in (["explain"], ["decompose", "--robust", "-o", str(tmp_path / "b.json")]):
        status, _, err = run(capsys, *command[:1], str(HOSPITAL), "--uncertain", str(two), *command[1:])
        assert status == 2 and "more than the 2 that are listed" in err, command


def test_an_output_that_names_another_world(tmp_path, capsys):
    """validate checks an output in the world its uncertainty section names: a record the world
    lacks, or a section that is not a list of {entity, attribute, value}, is refused, located."""
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection", "probability": 0.3}]})
    plan = tmp_path / "plan.json"
    assert run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "--most-likely", "-o", str(plan), "-q")[0] == 0
    data = json.loads(plan.read_text())
    data["mission_decomposition_uncertainty"]["world"][0]["entity"] = "Room999"
    forged = write_json(tmp_path / "forged.json", data)
    status, _, err = run(capsys, "validate", str(HOSPITAL), str(forged))
    assert status == 2 and "mission_decomposition_uncertainty.world" in err and "no record Room999" in err
    data["mission_decomposition_uncertainty"]["world"] = {"Room101": "False"}
    status, _, err = run(capsys, "validate", str(HOSPITAL), str(write_json(tmp_path / "bad.json", data)))
    assert status == 2 and "mission_decomposition_uncertainty.world: expected a list" in err
    data["mission_decomposition_uncertainty"]["world"] = [{"entity": "Room101", "attribute": "needs_disinfection",
                                                           "value": "True"}]  # the other world: not its tasks
    status, out, _ = run(capsys, "validate", str(HOSPITAL), str(write_json(tmp_path / "other.json", data)), "-q")
    assert status == 1 and "is missing" in out


def test_fifos_missing_files_and_outputs_onto_the_uncertainty_file(mission, capsys, tmp_path):
    fifo = tmp_path / "fifo.json"
    os.mkfifo(fifo)
    status, _, err = run(capsys, "count", str(mission), "--uncertain", str(fifo), "-q")  # at once, never blocking
    assert status == 2 and "not a regular file" in err
    status, _, err = run(capsys, "count", str(mission), "--uncertain", str(tmp_path / "none.json"), "-q")
    assert status == 2 and "cannot read uncertainty file" in err
    uncertain = mission / "knowledge" / "uncertain.json"
    before = uncertain.read_bytes()
    status, _, err = run(capsys, "decompose", str(mission), "-o", str(uncertain), "-q")
    assert status == 2 and uncertain.read_bytes() == before
    status, _, err = run(capsys, "decompose", str(mission), "--uncertain", str(fifo), "-o", str(fifo), "-q")
    assert status == 2


def with_function(tmp_path: Path, attribute: str, function: str) -> tuple[Path, Path]:
    """examples/medication-round in ``tmp_path``, each room's ``attribute`` mapped to the function
    ``function``, which the domain declares: the mission folder and its domain file."""
    folder = tmp_path / "m"
    shutil.copytree(EXAMPLE, folder)
    config = folder / "configuration" / "configuration.json"
    data = json.loads(config.read_text())
    data["semantic_mapping"].append({"type": "attribute", "name": attribute, "relates_to": "Room",
                                     "belongs_to": "world_db", "mapped_type": "function",
                                     "map": {"pred": function, "arg_sorts": ["room"]}})
    config.write_text(json.dumps(data))
    hddl = folder / "hddl" / "medication-round.hddl"
    hddl.write_text(hddl.read_text().replace("    (:capabilities", f"    (:functions ({function} ?rm - room))\n\n    (:capabilities"))
    return folder, hddl


def test_numeric_uncertain_facts_are_checked_and_decided(tmp_path, capsys):
    """A distribution over a function must add up to 1; then it is decided like a boolean (a
    number nothing reads changes no count) and written with its values and probabilities."""
    folder, _ = with_function(tmp_path, "stock", "doses")
    u = folder / "knowledge" / "uncertain.json"
    u.write_text(json.dumps({"uncertain": [{"entity": "Room201", "attribute": "stock", "distribution": {"0": 0.5, "1": 0.4}}]}))
    status, _, err = run(capsys, "check", str(folder), "-q")
    assert status == 2 and "the probabilities add up to 0.9, not 1" in err
    u.write_text(json.dumps({"uncertain": [{"entity": "Room201", "attribute": "stock", "distribution": {"0": 0.5, "2": 0.5}},
                                           {"entity": "Room203", "attribute": "patient_present", "probability": 0.6}]}))
    assert run(capsys, "check", str(folder), "-q")[0] == 0
    assert run(capsys, "count", str(folder), "-q")[:2] == (0, "2\n")
    out = tmp_path / "out.json"
    assert run(capsys, "decompose", str(folder), "-q", "-o", str(out))[0] == 0
    facts = json.loads(out.read_text())["mission_decomposition_uncertainty"]["uncertain_facts"]
    assert facts[0] == {"fact": "doses(Room201)", "entity": "Room201", "attribute": "stock", "values": ["0", "2"],
                        "probabilities": ["0.5", "0.5"]}


def test_bad_joint_tables_are_located(mission, capsys, tmp_path):
    bad = tmp_path / "joint.json"
    door, patient = {"entity": "Room202", "attribute": "door_locked"}, {"entity": "Room203", "attribute": "patient_present"}
    cases = [
        ({"uncertain": [door], "joint": [{"facts": [door, patient], "outcomes": [{"values": [True, True], "probability": 1}]}]},
         'Room203.patient_present: a joint table names only facts listed under "uncertain"'),
        ({"uncertain": [{**door, "probability": 0.2}, patient],
          "joint": [{"facts": [door, patient], "outcomes": [{"values": [True, True], "probability": 1}]}]},
         "has probabilities of its own and a joint table"),
        ({"uncertain": [door, patient], "joint": [{"facts": [door, patient], "outcomes": [
            {"values": [True, True], "probability": 0.5}, {"values": [False, True], "probability": 0.4}]}]},
         "the probabilities add up to 0.9, not 1"),
        ({"uncertain": [door, patient], "joint": [{"facts": [door, patient], "outcomes": [
            {"values": [True, 2], "probability": 1}]}]}, "gives patient-present(Room203) a value it cannot take"),
        ({"uncertain": [door, patient], "joint": [{"facts": [door], "outcomes": []}]}, "two or more"),
        ({"uncertain": [door], "joint": [{"facts": [door, door], "outcomes": [
            {"values": [True, False], "probability": 1}]}]}, "joint[0].facts[1]: Room202.door_locked is listed twice"),
    ]
    for document, message in cases:
        bad.write_text(json.dumps(document, indent=1))
        status, _, err = run(capsys, "check", str(mission), "--uncertain", str(bad), "-q")
        assert status == 2 and message in err and "joint.json:" in err, (message, err)
    # a good table: the lock and the patient move together (a night-shift lock-up with the patient out)
    bad.write_text(json.dumps({"uncertain": [door, patient], "joint": [{"facts": [door, patient], "outcomes": [
        {"values": [False, True], "probability": 0.6}, {"values": [True, False], "probability": 0.4}]}]}))
    status, out, _ = run(capsys, "explain", str(mission), "--uncertain", str(bad), "-q")
    assert status == 0 and "most likely decomposition now: valid with probability 0.6" in out


def test_an_uncertainty_file_over_the_input_limit_is_refused(mission, capsys, tmp_path):
    big = tmp_path / "big.json"
    big.write_text(json.dumps({"uncertain": [{"entity": "Room202", "attribute": "door_locked"}], "pad": "x" * 2_000_000}))
    status, _, err = run(capsys, "count", str(mission), "--uncertain", str(big), "--max-input-mb", "1", "-q")
    assert status == 2 and "over the input limit of 1 MB" in err


def test_the_example_with_a_fact_the_goal_model_reads(mission, capsys, tmp_path):
    """What docs/guide.md and examples/README.md show of knowledge/uncertain-orders.json."""
    orders = str(mission / "knowledge" / "uncertain-orders.json")
    assert run(capsys, "count", str(mission), "--uncertain", orders, "-q")[:2] == (0, "8\n")
    status, out, _ = run(capsys, "explain", str(mission), "--uncertain", orders, "-q")
    assert status == 0 and "most likely decomposition now: valid with probability 0.312" in out
    assert "sensing patient-present(Room203) first raises it to 0.52" in out
    assert "sensing dose_due(Room204) first raises it to 0.48" in out
    plan = tmp_path / "plan.json"
    assert run(capsys, "decompose", str(mission), "--uncertain", orders, "--most-likely", "-o", str(plan), "-q")[0] == 0
    status, _, err = run(capsys, "validate", str(mission), str(plan))
    assert status == 0 and "Room204.dose_due = False" in err


def hospital_copy(tmp_path: Path, query: str | None = None, first_record: str = "",
                  fields: dict[str, str] | None = None) -> Path:
    """The hospital mission in ``tmp_path``, its query's condition replaced, a record written
    first in the world, and a field added to every room (by name: text)."""
    folder = tmp_path / "hospital"
    shutil.copytree(HOSPITAL, folder)
    gm = next((folder / "gm").iterdir())
    if query is not None:
        gm.write_text(gm.read_text().replace("r.needs_disinfection)", f"{query})"))
    world = folder / "knowledge" / "world_db.xml"
    text = world.read_text().replace("<world_db>", f"<world_db>{first_record}", 1)
    for room, value in (fields or {}).items():
        text = text.replace(f"<name>{room}</name>", f"<name>{room}</name><dose>{value}</dose>", 1)
    world.write_text(text)
    return folder


def test_numbers_the_goal_model_reads_are_written_into_each_world_exactly(tmp_path, capsys):
    """A dose compared by a query, uncertain between 1234567 and 1234568: each world's file says
    its value to the digit (a rounded 1.23457e+06 made the two worlds one), and so do the output's
    world and needs."""
    folder = hospital_copy(tmp_path, "r.dose > 1234567",
                           fields={"Room101": "1234568", "Room102": "1234568", "Room103": "0", "Room104": "1234568"})
    assert run(capsys, "count", str(folder), "-q")[:2] == (0, "36\n")
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "dose", "distribution": {"1234567": 0.7, "1234568": 0.3}}]})
    assert run(capsys, "count", str(folder), "--uncertain", str(u), "-q")[:2] == (0, "48\n")
    assert run(capsys, "count", str(folder), "--uncertain", str(u), "-q", "--robust")[:2] == (0, "0\n")
    plan = tmp_path / "plan.json"
    assert run(capsys, "decompose", str(folder), "--uncertain", str(u), "--most-likely", "-o", str(plan), "-q")[0] == 0
    section = json.loads(plan.read_text())["mission_decomposition_uncertainty"]
    assert section["world"] == [{"entity": "Room101", "attribute": "dose", "value": "1234567"}]
    assert section["decompositions"][0]["needs"] == ["dose(Room101) = 1234567"]
    assert section["uncertain_facts"][0]["values"] == ["1234567", "1234568"]
    status, _, err = run(capsys, "validate", str(folder), str(plan))
    assert status == 0 and "Room101.dose = 1234567" in err


def test_a_nested_copy_of_an_entity_does_not_take_its_value_alone(tmp_path, capsys):
    """A note that names Room101, written before Room101's own record: the query reads the
    record, so each world must give the record the value, not the first element named Room101."""
    note = "<Note><name>handover</name><about><Room><name>Room101</name></Room></about></Note>"
    folder = hospital_copy(tmp_path, first_record=note)
    assert run(capsys, "count", str(folder), "-q")[:2] == (0, "36\n")
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection", "probability": 0.3}]})
    assert run(capsys, "count", str(folder), "--uncertain", str(u), "-q")[:2] == (0, "48\n")  # as without the note
    assert run(capsys, "count", str(folder), "--uncertain", str(u), "-q", "--robust")[:2] == (0, "0\n")


def test_the_kind_of_a_fact_the_goal_model_reads_is_checked(tmp_path, capsys):
    """Numbers for a boolean the goal model reads, a probability for a number it compares, and
    numbers for an attribute the configuration maps to a predicate: each refused, located."""
    folder = hospital_copy(tmp_path, "r.needs_disinfection && r.door_open && r.dose > 5",
                           fields={"Room101": "9", "Room102": "9", "Room103": "9", "Room104": "9"})
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection", "values": [0, 1]},
        {"entity": "Room102", "attribute": "dose", "probability": 0.5},
        {"entity": "Room104", "attribute": "door_open", "distribution": {"0": 0.5, "1": 0.5}}]})
    status, _, err = run(capsys, "check", str(folder), "--uncertain", str(u))
    assert status == 2 and "3 problems found" in err, err
    assert f"{u}:1:" in err and "Room101.needs_disinfection: goal G2 reads needs_disinfection" in err
    assert "as a boolean: give \"probability\"" in err
    assert "Room102.dose: goal G2 reads dose" in err and "as a number: give its possible \"values\"" in err
    assert "Room104.door_open is the predicate door-open: give \"probability\"" in err
    good = write_json(tmp_path / "good.json", {"uncertain": [
        {"entity": "Room102", "attribute": "dose", "values": [0, 9]},
        {"entity": "Room104", "attribute": "door_open", "probability": 0.5}]})
    assert run(capsys, "check", str(folder), "--uncertain", str(good), "-q")[0] == 0


def test_a_value_of_probability_0_is_no_scenario_beside_facts_without_probabilities(tmp_path, capsys):
    """Room101 certainly needs disinfection (probability 1), and whether Room102 does and Room104's
    door are unknown (no probabilities): the worlds where Room101 needs none cannot happen, so the
    answers are those of the other two facts alone.  Likewise for a fact the domain reads: Room102's door closed for sure."""
    door = {"entity": "Room104", "attribute": "door_open"}
    needs = {"entity": "Room102", "attribute": "needs_disinfection"}
    alone = write_json(tmp_path / "alone.json", {"uncertain": [needs, door]})
    certain = write_json(tmp_path / "certain.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection", "probability": 1.0}, needs, door]})
    occupied = {"entity": "Room102", "attribute": "occupied"}
    alone_102 = write_json(tmp_path / "alone102.json", {"uncertain": [occupied]})
    closed = write_json(tmp_path / "closed.json", {"uncertain": [
        {"entity": "Room102", "attribute": "door_open", "probability": 0.0}, occupied]})
    for expected, given in ((alone, certain), (alone_102, closed)):
        for kind in ("--possible", "--robust"):
            want = run(capsys, "count", str(HOSPITAL), "--uncertain", str(expected), "-q", kind)
            got = run(capsys, "count", str(HOSPITAL), "--uncertain", str(given), "-q", kind)
            assert want[0] == got[0] == 0 and want[1] == got[1], (given.name, kind, want[1], got[1])
    status, _, err = run(capsys, "count", str(HOSPITAL), "--uncertain", str(certain))
    assert status == 0 and "expanded in 2 worlds" in err, err


def test_xml_output_is_refused_before_any_warning_about_its_suffix(tmp_path, capsys):
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection", "probability": 0.3}]})
    status, _, err = run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "--most-likely",
                         "-o", str(tmp_path / "x.xml"))
    assert status == 2 and "write JSON" in err and "warning" not in err, err
    assert not (tmp_path / "x.xml").exists()


def test_a_mission_with_no_task_in_any_world_has_no_decomposition(tmp_path, capsys):
    """A query that matches nothing in the only world that can happen: no decomposition, as
    when the world is known (count 0), and each command says so instead of failing."""
    folder = hospital_copy(tmp_path, "r.dose > 5")  # no room has a dose
    assert run(capsys, "count", str(folder), "-q")[:2] == (0, "0\n")
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "dose", "distribution": {"0": 1.0, "9": 0.0}}]})
    status, out, err = run(capsys, "count", str(folder), "--uncertain", str(u))
    assert (status, out) == (0, "0\n") and "expanded in 1 world of the 1 fact" in err, err
    assert "no decomposition when dose(Room101) = 0: no entity of the world matched the queries" in err
    assert run(capsys, "count", str(folder), "--uncertain", str(u), "--robust", "-q")[:2] == (0, "0\n")
    assert run(capsys, "explain", str(folder), "--uncertain", str(u), "-q")[0] == 3
    for option in ("--robust", "--most-likely"):
        status, _, err = run(capsys, "decompose", str(folder), "--uncertain", str(u), option, "-o",
                             str(tmp_path / "x.json"))
        assert status == 3 and "no mission decomposition is valid" in err and "Traceback" not in err, err
        assert not (tmp_path / "x.json").exists()


def test_equal_probabilities_tie_as_written_and_the_cheaper_plan_wins(tmp_path, capsys):
    """Entering Room202 through its door is valid with probability 0.95 (unlocked), with the
    nurse's badge with 0.08 + 0.87 (a lock state above 0), which in floating point is
    0.9500000000000001: equal as written, so the tie goes to the cheaper plan, the door's (two
    actions, not three)."""
    folder, hddl = with_function(tmp_path, "lock_state", "lockstate")
    domain = hddl.read_text()
    badge = domain.index("(:method enter-with-nurse-badge")
    hddl.write_text(domain[:badge] + domain[badge:].replace("(door-locked ?rm)", "(> (lockstate ?rm) 0)", 1))
    world = folder / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace("</name>", "</name><lock_state>1</lock_state>"))
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room202", "attribute": "door_locked", "probability": 0.05},
        {"entity": "Room202", "attribute": "lock_state", "distribution": {"0": 0.05, "1": 0.08, "2": 0.87}}]})
    plan = tmp_path / "plan.json"
    assert run(capsys, "decompose", str(folder), "--uncertain", str(u), "--most-likely", "-o", str(plan), "-q")[0] == 0
    written = json.loads(plan.read_text())
    assert written["mission_decomposition_uncertainty"]["decompositions"][0]["probability"] == "0.95"
    chosen = [written["tasks"][k] for k in written["mission_decompositions"][0]]
    room202 = next(t for t in chosen if t["locations"] == "Room202" and t["name"] == "EnterRoom")
    assert [a["name"] for a in room202["decomposition"].values()] == ["navigate", "pass-door"], room202


def test_counts_exit_status_follows_the_worlds_not_the_world_as_written(tmp_path, capsys):
    """No room needs disinfection but perhaps Room101, which is occupied: the world where it does
    has tasks and no valid decomposition, so count exits 3 (as decompose would), whatever the
    world file says of the uncertain fact."""
    for written in ("False", "True"):
        folder = hospital_copy(tmp_path / written)
        world = folder / "knowledge" / "world_db.xml"
        text = world.read_text().replace("<needs_disinfection>True</needs_disinfection>",
                                         "<needs_disinfection>False</needs_disinfection>")
        first = text.index("<name>Room101</name>")
        head, tail = text[:first], text[first:]
        tail = tail.replace("<needs_disinfection>False</needs_disinfection>",
                            f"<needs_disinfection>{written}</needs_disinfection>", 1)
        world.write_text(head + tail.replace("<occupied>False</occupied>", "<occupied>True</occupied>", 1))
        u = write_json(tmp_path / f"u-{written}.json", {"uncertain": [
            {"entity": "Room101", "attribute": "needs_disinfection", "probability": 0.5}]})
        assert run(capsys, "count", str(folder), "--uncertain", str(u), "-q")[:2] == (3, "0\n"), written


def test_odd_values_in_the_uncertainty_file_are_located_once(tmp_path, capsys):
    """A number too large for a float, the unique id as an attribute, an entry given twice (one
    problem, not two), a robot's attribute, true against 1 in a joint table, a distribution key
    that only Python reads as a number, and a huge probability quoted short."""
    huge = "1" + "0" * 400
    text = ('{"uncertain": [\n'
            f'{{"entity": "Room202", "attribute": "door_locked", "values": [0, {huge}]}},\n'
            '{"entity": "Room202", "attribute": "name", "probability": 0.5},\n'
            '{"entity": "Room203", "attribute": "patient_present"},\n'
            '{"entity": "Room203", "attribute": "patient_present"},\n'
            '{"entity": "Room201", "attribute": "stock", "distribution": {"1_0": 0.5, "2": 0.5}},\n'
            f'{{"entity": "Room204", "attribute": "door_locked", "probability": {huge}}}\n'
            '],\n"joint": [{"facts": [{"entity": "Room203", "attribute": "patient_present"}, '
            '{"entity": "Room205", "attribute": "door_locked"}], "outcomes": [{"values": [true, true], "probability": 0.5}, '
            f'{{"values": [1, 1], "probability": 0.5}}, {{"values": [true, {huge}], "probability": 0}}]}}]}}')
    bad = tmp_path / "bad.json"
    bad.write_text(text)
    status, _, err = run(capsys, "check", str(EXAMPLE), "--uncertain", str(bad))
    assert status == 2 and "Traceback" not in err, err
    assert f"{bad}:2:" in err and "uncertain[0].values[1]: expected a number of at most 1e+15 either way, not 1000000000000000000000000000000000000..." in err
    assert f"{bad}:3:" in err and "Room202.name: name is the unique id that names the entity" in err
    assert err.count("Room203.patient_present is already uncertain") == 1
    assert f"{bad}:6:" in err and "'1_0' is not a number" in err
    assert f"{bad}:7:" in err and "expected a probability between 0 and 1, not 1000000000000000000000000000000000000..." in err
    assert "joint[0].outcomes[2]: expected" in err  # the huge number: not a value
    table = write_json(tmp_path / "t.json", {"uncertain": [{"entity": "Room203", "attribute": "patient_present"},
                                                           {"entity": "Room202", "attribute": "door_locked"}],
                                             "joint": [{"facts": [{"entity": "Room203", "attribute": "patient_present"},
                                                                  {"entity": "Room202", "attribute": "door_locked"}],
                                                        "outcomes": [{"values": [True, True], "probability": 0.5},
                                                                     {"values": [1, 1], "probability": 0.5}]}]})
    status, _, err = run(capsys, "check", str(EXAMPLE), "--uncertain", str(table))
    assert status == 2 and "listed twice" not in err and "a value it cannot take" in err, err
    robot = write_json(tmp_path / "r.json", {"uncertain": [{"entity": "Room101", "attribute": "is_loaded"}]})
    status, _, err = run(capsys, "check", str(HOSPITAL), "--uncertain", str(robot))
    assert status == 2 and "maps is_loaded only for robots" in err and "did you mean" not in err, err


def test_commands_that_read_the_world_as_written_say_so(mission, capsys, tmp_path):
    """The configuration names an uncertainty file: validate, export-hddl and graph read the world
    as written and say so; graph --from-output of an output expanded in a world says that one."""
    plain = tmp_path / "plain.json"
    assert run(capsys, "decompose", str(mission), "--as-written", "-o", str(plain), "-q")[0] == 0
    said = "this command does not read the uncertainty file"
    assert said in run(capsys, "validate", str(mission), str(plain))[2]
    assert said in run(capsys, "export-hddl", str(mission), "-o", str(tmp_path / "d.hddl"))[2]
    assert said in run(capsys, "graph", str(mission), "--view", "decomposition", "--from-output", str(plain), "-o",
                       str(tmp_path / "p.dot"))[2]
    plan = tmp_path / "plan.json"
    orders = str(mission / "knowledge" / "uncertain-orders.json")
    assert run(capsys, "decompose", str(mission), "--uncertain", orders, "--most-likely", "-o", str(plan), "-q")[0] == 0
    status, _, err = run(capsys, "graph", str(mission), "--view", "decomposition", "--from-output", str(plan), "-o",
                         str(tmp_path / "w.dot"))
    assert status == 0 and said not in err and f"drawn in the world {plan} was expanded in" in err


def test_a_joint_table_lists_only_the_scenarios_that_can_happen(tmp_path, capsys, monkeypatch):
    """One sensor for the whole ward: every door locked and every patient away, or none, over 8
    rooms (16 facts, 2 scenarios of 65,536).  Only the scenarios that can happen are listed, so
    the answer is exact far below the listing limit, where listing every combination of the
    facts would have given bounds."""
    from mutrose_cp.solve import uncertain
    folder = tmp_path / "ward"
    shutil.copytree(EXAMPLE, folder)
    rooms = [f"R{i}" for i in range(8)]
    (folder / "knowledge" / "world_db.xml").write_text("<world_db>" + "".join(
        f"<Room><name>{r}</name><dose_due>True</dose_due><door_locked>False</door_locked>"
        f"<patient_present>True</patient_present><is_served>False</is_served></Room>" for r in rooms) + "</world_db>")
    facts = [{"entity": r, "attribute": a} for r in rooms for a in ("door_locked", "patient_present")]
    write_json(folder / "knowledge" / "uncertain.json", {"uncertain": facts, "joint": [{"facts": facts, "outcomes": [
        {"values": [True] * 16, "probability": 0.5}, {"values": [False] * 16, "probability": 0.5}]}]})
    monkeypatch.setattr(uncertain, "MAX_PAIRS", 100)
    status, out, err = run(capsys, "count", str(folder))
    assert (status, out) == (0, "2\n") and "bounds" not in err, err
    assert run(capsys, "count", str(folder), "--robust", "-q")[:2] == (0, "0\n")
    plan = tmp_path / "plan.json"
    assert run(capsys, "decompose", str(folder), "--most-likely", "-o", str(plan), "-q")[0] == 0
    assert json.loads(plan.read_text())["mission_decomposition_uncertainty"]["decompositions"][0]["probability"] == "0.5"


def test_names_past_ascii_are_read_back_from_either_json_style(tmp_path, capsys):
    """The original's JSON style writes each byte of a UTF-8 name as \\u00XX: validate and graph
    read Zimmer_ü202 back as written in the world, in the tasks and in the world section; the
    standard style's RoomÃ© (characters that are also the bytes of é) stays as written."""
    folder = tmp_path / "station"
    shutil.copytree(EXAMPLE, folder)
    for name in ("world_db.xml", "uncertain.json"):
        path = folder / "knowledge" / name
        text = path.read_text(encoding="utf-8").replace("Room202", "Zimmer_ü202")
        path.write_text(text.replace("Room201", "RoomÃ©"), encoding="utf-8")  # whose bytes look escaped
    u = write_json(tmp_path / "u.json", {"uncertain": [{"entity": "Zimmer_ü202", "attribute": "dose_due",
                                                         "probability": 0.9}]})
    for style in ("boost", "standard"):
        plan = tmp_path / f"{style}.json"
        assert run(capsys, "decompose", str(folder), "--uncertain", str(u), "--most-likely", "--json-style", style,
                   "-o", str(plan), "-q")[0] == 0
        assert ("Zimmer_\\u00C3\\u00BC202" in plan.read_text()) == (style == "boost")
        status, out, err = run(capsys, "validate", str(folder), str(plan))
        assert status == 0 and "Zimmer_ü202.dose_due = True" in err, out + err
        assert run(capsys, "graph", str(folder), "--view", "decomposition", "--from-output", str(plan), "-o",
                   str(tmp_path / f"{style}.dot"), "-q")[0] == 0


def test_options_that_cannot_say_what_they_assume_are_refused(tmp_path, capsys):
    """--explain explains a known world, and iHTN files cannot name the world a mission was
    expanded in: with uncertain facts, each is refused before anything is written."""
    u = write_json(tmp_path / "u.json", {"uncertain": [
        {"entity": "Room101", "attribute": "needs_disinfection", "probability": 0.3}]})
    status, _, err = run(capsys, "decompose", str(HOSPITAL), "--uncertain", str(u), "--most-likely", "--ihtn",
                         str(tmp_path / "ihtn"))
    assert status == 2 and "iHTN files cannot name" in err and not (tmp_path / "ihtn").exists()
    status, _, err = run(capsys, "decompose", str(EXAMPLE), "--explain", "-o", str(tmp_path / "x.json"))
    assert status == 2 and "mutrose-cp explain says which facts to sense" in err and not (tmp_path / "x.json").exists()


def test_a_world_number_beyond_the_model_is_refused_by_name(tmp_path, capsys):
    """A stock of 10^300 written out in digits, which a precondition reads: the CP-SAT model
    would overflow its 64-bit integers, so it is refused naming the function; the exploratory
    decomposer reads it, and a time in milliseconds is within the model's numbers."""
    folder, hddl = with_function(tmp_path, "stock", "doses")
    domain = hddl.read_text()
    hddl.write_text(domain.replace("(not (door-locked ?rm))", "(not (door-locked ?rm))\n            (> (doses ?rm) 0)", 1))
    world = folder / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace("<name>Room201</name>", f"<name>Room201</name><stock>{10**300}</stock>"))
    status, _, err = run(capsys, "count", str(folder), "--as-written")
    assert status == 2 and "doses(Room201) starts at 1e+300 in the world, beyond the numbers" in err, err
    assert run(capsys, "decompose", str(folder), "--as-written", "--algorithm", "exploratory", "-q", "-o",
               str(tmp_path / "x.json"))[0] == 0
    world.write_text(world.read_text().replace(f"{10**300}", "1718000000000"))  # a time in ms: within
    assert run(capsys, "count", str(folder), "--as-written", "-q")[0] == 0


def test_values_alike_in_thousandths_are_one_value(tmp_path, capsys):
    """Numbers are told apart in thousandths, so 0 and 0.0001 would be one scenario counted
    twice: refused, located, in values and distributions alike; and a distribution's key is held
    to the same limit as a value."""
    bad = write_json(tmp_path / "close.json", {"uncertain": [
        {"entity": "Room201", "attribute": "stock", "values": [0, 0.0001]},
        {"entity": "Room202", "attribute": "stock", "distribution": {"1": 0.5, "1.0004": 0.5}},
        {"entity": "Room203", "attribute": "stock", "distribution": {"1e20": 0.5, "2": 0.5}}]})
    status, _, err = run(capsys, "check", str(EXAMPLE), "--uncertain", str(bad))
    assert status == 2 and "uncertain[0].values: a value is listed twice (values are told apart in thousandths)" in err
    assert "uncertain[1].distribution.1.0004: the value 1.0004 is given twice" in err
    # a key past the numbers the decomposer computes with, as a value of "values" is
    assert "uncertain[2].distribution.1e20: expected a number of at most 1e+15 either way, not '1e20'" in err
