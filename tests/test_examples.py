"""The bundled example missions check, decompose, and give the numbers their design implies.

Every expected number below is derived by hand from the mission files (see the comments), not
copied from a run, so a change of behaviour in the decomposer shows up here.
"""
from __future__ import annotations

import itertools
import json
from collections import Counter
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
MODELS = ROOT / "models"

EXAMPLE_DIRS = sorted(p for p in EXAMPLES.iterdir() if (p / "configuration").is_dir())


ALGORITHMS = ("cpsat", "exploratory")


def decompose(folder: Path, tmp_path: Path, algorithm: str | None = None) -> dict:
    out = tmp_path / "mission.json"
    extra = ["--algorithm", algorithm] if algorithm else []
    assert main(["decompose", str(folder), "-o", str(out), "-q", *extra]) == 0
    return json.loads(out.read_text())


def instance_ids(output: dict) -> set[str]:
    """Task instances present in the output: the decomposition ids without their ``|n``."""
    return {t["id"].split("|")[0] for t in output["tasks"].values()}


def constraint_kinds(output: dict) -> Counter:
    """SEQ, EC with group/divisible (execution constraints) and FB (fallbacks: EC without flags)."""
    kinds: Counter = Counter()
    for c in output["constraints"] or []:
        if c["type"] == "EC" and "group" not in c:
            kinds["FB"] += 1
        else:
            kinds[c["type"]] += 1
    return kinds


def decomposition_sets(output: dict) -> set[frozenset[str]]:
    ids = {key: t["id"] for key, t in output["tasks"].items()}
    return {frozenset(ids[k] for k in vmd) for vmd in output["mission_decompositions"] or []}


def test_example_folders_are_found():
    assert {"hospital-disinfection", "item-delivery"} <= {p.name for p in EXAMPLE_DIRS}


@pytest.mark.parametrize("folder", EXAMPLE_DIRS, ids=lambda p: p.name)
def test_example_checks(folder: Path):
    assert main(["check", str(folder), "-q"]) == 0


@pytest.mark.parametrize("folder", EXAMPLE_DIRS, ids=lambda p: p.name)
def test_example_decomposes(folder: Path, tmp_path: Path):
    output = decompose(folder, tmp_path)
    assert output["tasks"] and output["mission_decompositions"]


@pytest.mark.parametrize(("folder", "count"), [(EXAMPLES / "hospital-disinfection", 36),
                                               (EXAMPLES / "item-delivery", 8),
                                               # 2 x 2: Room202 entered either way, Room203's dose given either way
                                               (EXAMPLES / "medication-round", 4)], ids=lambda v: getattr(v, "name", v))
def test_example_count(folder: Path, count: int, capsys):
    assert main(["count", str(folder), "-q"]) == 0
    assert capsys.readouterr().out.split() == [str(count)]


# --------------------------------------------------------------------------------------------
# hospital-disinfection
#
# World: Room101 (door open), Room102 (door closed), Room104 (no door_open field: unknown) need
# disinfection; Room103 does not, so G2 selects 3 rooms and the forAll of G3 makes 3 copies of
# the G4 subtree (instance suffixes _1, _2, _3).
#
# Per room there are 7 GM tasks AT1..AT7 -> 3 * 7 = 21 task instances.  The output lists every
# HTN decomposition of each instance, valid or not: UVDisinfection and TeamDisinfection have two
# methods each, the other five tasks one -> 5 + 2 + 2 = 9 per room, 27 in total.
#
# Valid mission decompositions, per room (G8 is OR-refined):
#   * G9 = FALLBACK(UV, spray): both tasks are part of the decomposition.  UV has one valid method
#     when the door state is known (|1 "door open" for Room101, |2 "open the door first" for
#     Room102) and two for Room104, whose unknown door satisfies both method preconditions;
#     SprayDisinfection has one method.
#   * G12 = spray team: TeamDisinfection has two methods (fogging, spray-and-wipe), no world
#     preconditions other than "not occupied", so both are valid.
#   -> Room101: 1 + 2 = 3, Room102: 1 + 2 = 3, Room104: 2 + 2 = 4 alternatives; the rooms are
#      independent (`#` of the forAll), so 3 * 3 * 4 = 36 mission decompositions.
#
# Constraints per room (decomposition level):
#   * SEQ from G4 [G5;G8;G13] and G5 [G6;G7]: AT1->AT2 (1); AT2->AT3 (2 UV decompositions);
#     AT2->AT5 (2); AT3->AT6 (2), AT4->AT6 (1), AT5->AT6 (2); plus AT6->AT7 (1) because G15's
#     condition context (current_room.is_restocked, false initially) is enabled by AT6 in the
#     parallel sibling G14, which turns that parallel pair into a sequence.  AT2->AT4 is trimmed
#     (AT2 SEQ AT3 FB AT4) and AT3/AT4/AT5->AT7 are trimmed (via AT6).  -> 11 SEQ per room, 33.
#   * FALLBACK AT3 -> AT4: 2 UV decompositions x 1 spray -> 2 per room, 6 (printed as EC without
#     group/divisible).
#   * EC from the Group=False goal G5 between AT1 and AT2: 1 per room, 3, group False /
#     divisible True.  OR alternatives and forAll instances never get EC among themselves.

HOSPITAL = EXAMPLES / "hospital-disinfection"
ROOMS = {1: "Room101", 2: "Room102", 3: "Room104"}


@pytest.fixture(scope="module", params=ALGORITHMS)
def hospital(request, tmp_path_factory) -> dict:
    return decompose(HOSPITAL, tmp_path_factory.mktemp("hospital"), request.param)


def test_hospital_task_instances(hospital):
    expected = {f"AT{k}_{i}" for k in range(1, 8) for i in ROOMS}
    assert instance_ids(hospital) == expected
    assert len(expected) == 21
    assert len(hospital["tasks"]) == 27
    # the query skipped the occupied Room103; every instance is located in its room
    for t in hospital["tasks"].values():
        assert t["locations"] == ROOMS[int(t["id"].split("|")[0].split("_")[1])]
        assert t["triggering_events"] == ["PatientDischarged"]


def test_hospital_robot_numbers(hospital):
    for t in hospital["tasks"].values():
        if t["name"] == "TeamDisinfection":
            assert t["robots_num"] == {"fixed": "False", "min": "2", "max": "3"}
        else:
            assert t["robots_num"] == {"fixed": "True", "num": "1"}


def test_hospital_constraints(hospital):
    kinds = constraint_kinds(hospital)
    assert kinds == Counter({"SEQ": 33, "FB": 6, "EC": 3})
    keys = {t["id"]: k for k, t in hospital["tasks"].items()}
    pairs = {(c["type"], c["task_instances"]["t0"], c["task_instances"]["t1"], c.get("group"), c.get("divisible"))
             for c in hospital["constraints"]}
    for i in ROOMS:
        # non-group clearing: the same service robot bags and disposes of the waste
        assert ("EC", keys[f"AT1_{i}|1"], keys[f"AT2_{i}|1"], "False", "True") in pairs
        # fallback from each UV decomposition to manual spraying
        for n in (1, 2):
            assert ("EC", keys[f"AT3_{i}|{n}"], keys[f"AT4_{i}|1"], None, None) in pairs
        # context dependency: restocking before reporting the room ready
        assert ("SEQ", keys[f"AT6_{i}|1"], keys[f"AT7_{i}|1"], None, None) in pairs


def test_hospital_mission_decompositions(hospital):
    assert len(hospital["mission_decompositions"]) == 36
    common = lambda i: {f"AT1_{i}|1", f"AT2_{i}|1", f"AT6_{i}|1", f"AT7_{i}|1"}  # noqa: E731
    disinfection = {
        1: [{"AT3_1|1", "AT4_1|1"}, {"AT5_1|1"}, {"AT5_1|2"}],               # door open
        2: [{"AT3_2|2", "AT4_2|1"}, {"AT5_2|1"}, {"AT5_2|2"}],               # door closed
        3: [{"AT3_3|1", "AT4_3|1"}, {"AT3_3|2", "AT4_3|1"}, {"AT5_3|1"}, {"AT5_3|2"}],  # unknown
    }
    expected = {frozenset(set().union(*(common(i) | alt for i, alt in zip(ROOMS, choice))))
                for choice in itertools.product(*disinfection.values())}
    assert len(expected) == 36
    assert decomposition_sets(hospital) == expected


# --------------------------------------------------------------------------------------------
# item-delivery (models/delivery/delivery.hddl + delivery-gm.json)
#
# World: Delivery1..3 are pending, Delivery4 is already delivered -> the forAll of G3 makes
# n = 3 copies.  Per delivery there are 4 GM tasks (AT1 FetchItem, AT2 HandOver under the
# Group=False goal G8; AT3 ReceiveItem, AT4 HandOver under G11) -> 12 task instances.
# HandOver has two methods (to a person / into a drop box), the rest one -> 1 + 2 + 1 + 2 = 6
# decompositions per delivery, 18 in total.
#
# Valid mission decompositions: G7 is OR-refined with 2 alternatives (G8, G11).  In each,
# exactly one HandOver method is valid, chosen by the destination: WardA is staffed (hand to a
# person, |1), WardB and the Laboratory are unattended with a drop box (|2).  So each delivery
# contributes 2 alternatives and the count is 2^n = 8 (16 for four deliveries).
#
# Constraints per delivery: SEQ AT1->AT2 and AT3->AT4, each 1 x 2 decompositions -> 4, 12 in
# total; EC from Group=False G8 between AT1 and both HandOver decompositions of AT2 -> 2, 6 in
# total; no fallback.

DELIVERY = EXAMPLES / "item-delivery"
DESTINATION_METHOD = {1: 1, 2: 2, 3: 2}  # Delivery1 -> WardA (staffed), 2 -> WardB, 3 -> Laboratory


@pytest.fixture(scope="module", params=ALGORITHMS)
def delivery(request, tmp_path_factory) -> dict:
    return decompose(DELIVERY, tmp_path_factory.mktemp("delivery"), request.param)


def test_delivery_uses_the_reusable_models():
    assert (DELIVERY / "hddl" / "delivery.hddl").read_text() == (MODELS / "delivery" / "delivery.hddl").read_text()
    assert (DELIVERY / "gm" / "delivery-gm.json").read_text() == \
        (MODELS / "delivery" / "delivery-gm.json").read_text()


def test_delivery_task_instances(delivery):
    expected = {f"AT{k}_{i}" for k in range(1, 5) for i in (1, 2, 3)}
    assert instance_ids(delivery) == expected
    assert len(expected) == 12
    assert len(delivery["tasks"]) == 18
    for t in delivery["tasks"].values():
        i = int(t["id"].split("|")[0].split("_")[1])
        assert t["arguments_values"]["?d"] == f"Delivery{i}"


def test_delivery_constraints(delivery):
    assert constraint_kinds(delivery) == Counter({"SEQ": 12, "EC": 6})
    for c in delivery["constraints"]:
        if c["type"] == "EC":
            assert (c["group"], c["divisible"]) == ("False", "True")


def test_delivery_mission_decompositions(delivery):
    assert len(delivery["mission_decompositions"]) == 2 ** 3
    alternatives = {
        i: [{f"AT1_{i}|1", f"AT2_{i}|{m}"}, {f"AT3_{i}|1", f"AT4_{i}|{m}"}]
        for i, m in DESTINATION_METHOD.items()
    }
    expected = {frozenset(set().union(*choice)) for choice in itertools.product(*alternatives.values())}
    assert decomposition_sets(delivery) == expected
