"""Fixes of plain bugs of the original decomposer (docs/deviations.md), each on a small variant
of the bundled item-delivery mission, checked with both algorithms."""
from __future__ import annotations

import shutil
from pathlib import Path


from mutrose_cp.cli import main
from mutrose_cp.errors import NoDecompositionError
from mutrose_cp.mission import Mission, find_mission_files

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"


def _variant(tmp_path: Path) -> Path:
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    return folder


def _edit(path: Path, old: str, new: str) -> None:
    text = path.read_text()
    assert old in text, f"{old!r} not in {path}"
    path.write_text(text.replace(old, new, 1))


def _both(folder: Path) -> tuple[set[frozenset[str]], set[frozenset[str]]]:
    """Valid mission decompositions (as sets of decomposition ids) by both algorithms."""
    mission = Mission.load(*find_mission_files(folder))
    ids = {d.index: d.content for d in mission.task_graph.decompositions()}
    try:
        exploratory = {frozenset(ids[d] for d in md) for md in mission.exploratory()}
    except NoDecompositionError:
        exploratory = set()
    space = mission.decomposition_space()
    cpsat = {frozenset(ids[d] for d in md) for md in space}
    assert space.count == len(cpsat)
    return exploratory, cpsat


def _hddl(folder: Path) -> Path:
    return next((folder / "hddl").glob("*.hddl"))


def test_impossible_or_alternative_is_dropped(tmp_path):
    """The original aborts the run when one OR alternative has no valid decomposition; the
    other alternative is still a valid way to achieve the goal."""
    folder = _variant(tmp_path)
    _edit(_hddl(folder), """    (:action request-loading
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :required-capabilities (communication)
        :precondition (and
""", """    (:action request-loading
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :required-capabilities (communication)
        :precondition (and
            (staffed ?src)
""")
    world = next((folder / "knowledge").glob("*.xml"))
    _edit(world, "<name>SupplyRoom</name>\n        <reachable>True</reachable>\n        <staffed>True</staffed>",
          "<name>SupplyRoom</name>\n        <reachable>True</reachable>\n        <staffed>False</staffed>")
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat
    # Delivery1 (from the staffed pharmacy) keeps both alternatives, Deliveries 2 and 3 (from the
    # unstaffed supply room) only the robot fetching from the shelf: 2 * 1 * 1
    assert len(cpsat) == 2
    assert all(not any(i.startswith(("AT3_2", "AT3_3")) for i in md) for md in cpsat)
    assert main(["decompose", str(folder), "--algorithm", "exploratory", "-q", "-o", str(tmp_path / "o.json")]) == 0


def test_forall_condition_checked_for_every_element(tmp_path, capsys):
    """The original checks a forAll condition only for the last element; here Delivery1 (handed
    to a person, whose action no longer marks it delivered) violates it while the last delivery
    satisfies it, so no mission decomposition achieves the goal."""
    folder = _variant(tmp_path)
    _edit(_hddl(folder), """            (not (delivered ?d))
        )
        :effect (and
            (delivered ?d)
        )
    )
    (:action drop-item""", """            (not (delivered ?d))
        )
        :effect ()
    )
    (:action drop-item""")
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat == set()
    assert main(["decompose", str(folder), "--algorithm", "exploratory", "-o", str(tmp_path / "o.json")]) == 3
    assert "achieve condition of goal G3" in capsys.readouterr().err
    assert main(["decompose", str(folder), "--explain", "-o", str(tmp_path / "o.json")]) == 3
    err = capsys.readouterr().err
    assert "achieve condition of goal G3" in err and "delivered(Delivery1)" in err


def test_nested_mixed_annotation(tmp_path):
    """`[(G5#G6);G7]` nests a parallel operator in a sequence; the original mis-pairs the
    children. The nested operator belongs to G4 and the mission decomposes as the flat one."""
    folder = _variant(tmp_path)
    gm = next((folder / "gm").glob("*"))
    _edit(gm, "G4: Current Delivery Is Completed [G5;G6;G7]", "G4: Current Delivery Is Completed [(G5#G6);G7]")
    mission = Mission.load(*find_mission_files(folder))
    assert "(G5#G6);" in mission.expansion.rat.render()
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat and len(cpsat) == 8


def test_alternatives_do_not_leak_effects(tmp_path):
    """With two valid decompositions of FetchItem, the original's mission decomposition for the
    second one also carries the first one's id and effects (marking the item delivered too
    early), which makes HandOver fail for both. Each decomposition now stands alone."""
    folder = _variant(tmp_path)
    _edit(_hddl(folder), """    (:method fetch-from-shelf""", """    (:method fetch-with-receipt
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :task (FetchItem ?r ?d ?src)
        :ordered-subtasks (and
            (navigate ?r ?src)
            (pick-and-sign ?r ?d ?src)
        )
    )
    (:action pick-and-sign
        :parameters (?r - DeliveryRobot ?d - delivery ?src - location)
        :required-capabilities (manipulation)
        :precondition (and (not (collected ?d)))
        :effect (and (collected ?d) (delivered ?d))
    )
    (:method fetch-from-shelf""")
    exploratory, cpsat = _both(folder)
    assert exploratory == cpsat
    assert len(cpsat) == 8  # as in the unmodified example: FetchItem|2 replaces the old FetchItem|1
    assert all(f"AT1_{k}|2" in md for md in cpsat for k in (1, 2, 3) if any(i.startswith(f"AT1_{k}") for i in md))
    assert not any(i.endswith("|1") and i.startswith("AT1_") for md in cpsat for i in md)
