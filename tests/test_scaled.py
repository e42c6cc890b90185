"""Missions larger than the reference corpus, from the benchmark generator: every entity of the
world produces its tasks, and both algorithms agree."""
from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest
from conftest import require_reference

from mutrose_cp.mission import Mission

sys.path.insert(0, str(Path(__file__).resolve().parent.parent / "benchmarks"))
from generate import generate  # noqa: E402


def _ids(mission: Mission, decompositions) -> set[frozenset[str]]:
    key = {d.index: d.content for d in mission.task_graph.decompositions()}
    return {frozenset(key[d] for d in md) for md in decompositions}


def test_vital_signs_with_several_occupied_rooms(tmp_path):
    require_reference()
    mission = Mission.load(*generate("vital-signs", 3, tmp_path))
    instances = {i.id for i in mission.expansion.instances}
    # every occupied room gets its room tasks, and every patient of it its patient tasks
    for room in (1, 2, 3):
        assert f"AT1_{room}" in instances
        for patient in (1, 2):
            assert f"AT2_{room}_{patient}" in instances and f"AT4_{room}_{patient}" in instances
    locations = {i.location for i in mission.expansion.instances if i.gm_task == "AT1"}
    assert locations == {"Room0", "Room1", "Room2"}
    space = mission.decomposition_space()
    assert _ids(mission, mission.exploratory()) == _ids(mission, space)
    assert space.count >= 1


@pytest.mark.parametrize("family,n,count", [("delivery", 4, 3 ** 4), ("pickup", 3, 4 ** 3)])
def test_food_logistics_counts(tmp_path, family, n, count):
    require_reference()
    mission = Mission.load(*generate(family, n, tmp_path))
    space = mission.decomposition_space()
    assert space.count == count
    assert _ids(mission, mission.exploratory()) == _ids(mission, space)


def _steps_to_encode(tmp_path: Path, n: int) -> int:
    """How many chain steps the encoder makes for the kitchen's state on a coupled sequence of n."""
    from unittest import mock

    from mutrose_cp.solve.encoding import Encoder

    hddl, gm, cfg = generate("coupled-sequence", n, tmp_path / str(n))
    mission = Mission.load(hddl, gm, cfg)
    with mock.patch.object(Encoder, "_bool_step", autospec=True, side_effect=Encoder._bool_step) as step:
        mission.encoding()
    return step.call_count


def test_a_long_sequence_is_encoded_in_linear_work(tmp_path):
    """Each task of a sequence tests the state its predecessors leave: the encoder must extend the
    fact's chain by the new writers only, not walk it from the start for every task (which made
    a sequence of 10,000 take minutes).  Counted in steps, not timed."""
    small, large = _steps_to_encode(tmp_path, 100), _steps_to_encode(tmp_path, 200)
    assert small > 0 and large <= 2.2 * small


def test_the_generator_says_where_the_corpus_it_needs_is(tmp_path):
    """The generator makes its worlds from the reference missions: without the corpus it says
    where it looked and how to point it elsewhere, and writes nothing."""
    script = Path(__file__).resolve().parent.parent / "benchmarks" / "generate.py"
    env = {**os.environ, "MUTROSE_REFERENCE": str(tmp_path / "nowhere")}
    result = subprocess.run([sys.executable, str(script), "vital-signs", "5", str(tmp_path / "out")],
                            capture_output=True, text=True, env=env, timeout=60)
    assert result.returncode == 2
    assert result.stderr.startswith(f"error: {tmp_path / 'nowhere'}/missions/vital-signs-monitoring: not found")
    assert "MUTROSE_REFERENCE" in result.stderr and "Traceback" not in result.stderr
    assert not (tmp_path / "out").exists()
