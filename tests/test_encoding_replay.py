"""Replaying a class leader's records for the other stamped copies gives the full encoding.

``Encoder(..., replay=True)`` (the default) encodes one copy of each class in full and replays
its records for the others (``solve.replay``); it must build exactly the model that
``replay=False`` builds: the same variables with the same names, the same records in the same
order, and the same maps from the Task Graph to literals, in the same order.

* random missions from ``missiongen.repeated_rooms`` (a seeded run checks that copies are really
  replayed on a fair share of them);
* the vital-signs, delivery and pickup benchmark worlds, where every copy but a class's first
  is replayed, and vital signs has several classes (rooms whose patients differ in the world);
* the world changes that must split a class or stop the replay: an initial fact, an atom that a
  task outside the copies writes, an achieve condition that reads another copy's patient.
"""
from __future__ import annotations

import re
import sys
from pathlib import Path

import pytest
from hypothesis import HealthCheck, event, given, settings

from mutrose_cp.model.state_tests import FactTest
from mutrose_cp.mission import Mission
from mutrose_cp.solve import encoding, replay
from mutrose_cp.solve.encoding import AFTER, Encoder, Encoding
from mutrose_cp.solve.replay import TASK_RULES
from mutrose_cp.solve.semantics import achieve_tests

from conftest import ROOT, require_reference
from missiongen import MissionSpec, load_mission, repeated_rooms, seeded_draws

sys.path.insert(0, str(ROOT / "benchmarks"))
from generate import generate  # noqa: E402


def _encode(m: Mission, replaying: bool) -> tuple[Encoding, tuple[int, int]]:
    enc = Encoder(m.task_graph, m.constraints, m.domain, m.goal_model, m.config, m.initial_state, replay=replaying)
    return enc.encode(), enc.replayed


def _replayed(m: Mission) -> tuple[int, int]:
    """Asserts that the replaying encoder builds the full encoding's model; returns how many
    copies replayed a leader's task rules, and how many classes led them."""
    full, _ = _encode(m, replaying=False)
    made, replayer = _encode(m, replaying=True)
    a, b = made.model, full.model
    assert len(a.names) == len(b.names)
    assert [a.name(v) for v in range(len(a.names))] == [b.name(v) for v in range(len(b.names))]
    assert a.ints == b.ints
    assert len(a.records) == len(b.records)
    for i, (x, y) in enumerate(zip(a.records, b.records)):
        assert x == y, f"record {i}: {x} != {y}"
    for mine, theirs in ((made.decomposition_lit, full.decomposition_lit), (made.task_lit, full.task_lit),
                         (made.or_choice_lit, full.or_choice_lit)):
        assert list(mine.items()) == list(theirs.items())
    assert made.tasks == full.tasks
    return replayer


@settings(max_examples=60, deadline=None, suppress_health_check=list(HealthCheck))
@given(repeated_rooms())
def test_replayed_encoding_is_the_full_encoding_on_random_missions(spec: MissionSpec) -> None:
    try:
        m = load_mission(spec)
        m.task_graph
    except Exception as e:  # a drawn mission the expansion refuses has nothing to encode
        event(f"refused: {type(e).__name__}")
        return
    followers, _ = _replayed(m)
    event("replayed" if followers else "encoded in full")


def test_copies_are_replayed_on_random_missions() -> None:
    """The property above is not vacuous: copies are replayed on a fair share of the draws."""
    used = seeded_draws(2, 60, "task_graph", lambda m: _replayed(m)[0] > 0)
    assert len(used) >= 20
    assert sum(used) >= len(used) // 8, (sum(used), len(used))


@pytest.mark.parametrize("family,n", [("vital-signs", 40), ("delivery", 12), ("pickup", 12)])
def test_benchmark_worlds_are_replayed(tmp_path: Path, family: str, n: int) -> None:
    require_reference()
    m = Mission.load(*generate(family, n, tmp_path))
    followers, classes = _replayed(m)
    assert followers >= n - 3 - classes, (followers, classes)
    if family == "vital-signs":
        assert classes > 1, "the rooms' patients differ: more than one class"


def _vital_signs(tmp_path: Path, rooms: int, edit_world=None) -> Mission:
    hddl, gm, cfg = generate("vital-signs", rooms, tmp_path)
    if edit_world is not None:
        world = tmp_path / f"vital-signs-{rooms}.xml"
        world.write_text(edit_world(world.read_text(encoding="utf-8")), encoding="utf-8")
    return Mission.load(hddl, gm, cfg)


def _followers_and_classes(tmp_path: Path, edit_world=None) -> tuple[int, int]:
    return _replayed(_vital_signs(tmp_path, 12, edit_world=edit_world))


def test_an_initial_fact_makes_a_class_of_its_own(tmp_path: Path) -> None:
    """One patient whose vital signs are checked already: its room's achieve condition folds
    otherwise, so the room cannot replay another's records; it leads a class of its own."""
    require_reference()
    followers, classes = _followers_and_classes(tmp_path / "plain")

    def checked(text: str) -> str:
        edited = text.replace("<name>Patient7</name><infectious_disease>false</infectious_disease><diabetes>true</diabetes>"
                              "<post_surgical>false</post_surgical><available>true</available><checked>false</checked>",
                              "<name>Patient7</name><infectious_disease>false</infectious_disease><diabetes>true</diabetes>"
                              "<post_surgical>false</post_surgical><available>true</available><checked>true</checked>")
        assert edited != text
        return edited

    assert _followers_and_classes(tmp_path / "edited", checked) == (followers - 1, classes + 1)


def test_a_patient_in_two_rooms_is_not_replayed(tmp_path: Path) -> None:
    """A patient listed in two rooms: each room's decompositions write its atoms, so neither
    room's atoms have all their writers inside the room, and neither is replayed."""
    require_reference()
    followers, _ = _followers_and_classes(tmp_path / "plain")

    def shared(text: str) -> str:
        edited = re.sub(r"<patients>Patient13,Patient14</patients>", "<patients>Patient13,Patient11</patients>", text)
        assert edited != text
        return edited

    after, _ = _followers_and_classes(tmp_path / "edited", shared)
    assert after < followers - 1, (after, followers)


def test_patients_shared_along_the_rooms_are_not_replayed(tmp_path: Path) -> None:
    """Each room's second patient is the next room's first: every room shares atoms with its
    neighbours in the same way, but an atom with a writer outside the copy is never replayed."""
    require_reference()
    followers, _ = _followers_and_classes(tmp_path / "plain")

    def along(text: str) -> str:
        for i in range(12):
            text = text.replace(f"<patients>Patient{2 * i + 1},Patient{2 * i + 2}</patients>",
                                f"<patients>Patient{2 * i + 1},Patient{2 * i + 3}</patients>")
        return text

    after, _ = _followers_and_classes(tmp_path / "edited", along)
    assert after < followers // 2, (after, followers)


def test_two_patients_of_one_name_are_not_replayed(tmp_path: Path) -> None:
    """Two patient records named alike in one room: its copy's values repeat where the others'
    do not (its two patients' atoms are one), so it is no renaming of them."""
    require_reference()
    followers, _ = _followers_and_classes(tmp_path / "plain")

    def twins(text: str) -> str:
        edited = text.replace("<Patient><name>Patient14</name>", "<Patient><name>Patient13</name>")
        edited = edited.replace("<patients>Patient13,Patient14</patients>", "<patients>Patient13</patients>")
        assert edited != text
        return edited

    m = _vital_signs(tmp_path / "edited", 12, edit_world=twins)
    assert any(len(c) == 12 for c in m.task_graph.stamped_copies), "the twins' room is stamped as the others"
    after, _ = _replayed(m)
    assert after < followers, (after, followers)


class _ReadsFirst(Encoder):
    """An encoder that reads one copy's atom before the task rules, as a reader outside the
    copies that comes first would (an achieve condition above them, say)."""

    atom: tuple[str, tuple[str, ...]] = ("checked", ("Patient13",))

    def _each(self, phase, vertices, encode):  # type: ignore[no-untyped-def]
        if phase == TASK_RULES:
            writers = self.bool_writers[self.atom]
            self._bool_holds(self.atom, True, writers, (AFTER, self.atom, writers[-1][0], None))
        super()._each(phase, vertices, encode)


def test_a_chain_read_outside_the_copy_first_is_not_replayed(tmp_path: Path) -> None:
    """The copy whose atom another run read first finds that chain in place: it is encoded in
    full, and the model is the full encoding's."""
    require_reference()
    m = _vital_signs(tmp_path, 12)
    models = []
    for replaying in (False, True):
        enc = _ReadsFirst(m.task_graph, m.constraints, m.domain, m.goal_model, m.config, m.initial_state, replay=replaying)
        models.append(enc.encode().model)
    full, made = models
    assert [full.name(v) for v in range(len(full.names))] == [made.name(v) for v in range(len(made.names))]
    assert full.records == made.records


def test_achieve_conditions_are_compared_not_assumed(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """One room's achieve condition read otherwise than its bindings suggest (here: forced to
    the opposite polarity): that room is encoded in full, and the model is the full encoding's."""
    require_reference()
    m = _vital_signs(tmp_path, 12)
    odd = next(c for region in m.task_graph.stamped_copies for c in region if c.start != c.source)

    def tests(tg, v, gm, config):  # type: ignore[no-untyped-def]
        found = achieve_tests(tg, v, gm, config)
        if odd.start <= v < odd.start + odd.size:
            found = [(goal, _negated(test)) for goal, test in found]
        return found

    monkeypatch.setattr(encoding, "achieve_tests", tests)
    monkeypatch.setattr(replay, "achieve_tests", tests)
    followers, _ = _replayed(m)
    assert followers > 0


def _negated(test):  # type: ignore[no-untyped-def]
    if isinstance(test, FactTest):
        return FactTest(test.predicate, test.args, not test.positive)
    return type(test)(tuple(_negated(p) for p in test.parts))
