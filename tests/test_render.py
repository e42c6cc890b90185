"""DOT views of a mission (``mutrose_cp.output.render``) and writing them to files.

The checks use examples/hospital-disinfection: 3 rooms, 21 task instances, 27 task
decompositions, 36 valid mission decompositions (see examples/README.md).  Rendering to pictures
is tested with a stand-in ``dot`` program, so Graphviz is not needed; one test uses the real
Graphviz when it is installed.
"""
from __future__ import annotations

import os
import re
import shutil
import stat
import sys
from pathlib import Path

import pytest

from mutrose_cp.output import render as render_module
from mutrose_cp.errors import MissionError, NoDecompositionError
from mutrose_cp.mission import Mission
from mutrose_cp.io.mission_files import find_mission_files
from mutrose_cp.output.render import (
    RenderError,
    decomposition_dot,
    goal_model_dot,
    nth_decomposition,
    render,
    task_graph_dot,
    view_dot,
)

ROOT = Path(__file__).resolve().parent.parent
HOSPITAL = ROOT / "examples" / "hospital-disinfection"
DELIVERY = ROOT / "examples" / "item-delivery"


def _load(folder: Path) -> Mission:
    return Mission.load(*find_mission_files(folder))


@pytest.fixture(scope="module")
def hospital() -> Mission:
    return _load(HOSPITAL)


def _node_ids(dot: str) -> list[str]:
    """Ids of the node statements (``"id" [shape=...]``)."""
    return re.findall(r'^\s*"([^"]+)" \[shape=', dot, flags=re.M)


def _edges(dot: str) -> list[tuple[str, str, str]]:
    """(from, to, attribute text) of every edge statement."""
    return [(a, b, attrs or "") for a, b, attrs in
            re.findall(r'^\s*"([^"]+)" -> "([^"]+)"(?: \[(.*)\])?;$', dot, flags=re.M)]


def _label_of(dot: str, node_id: str) -> str:
    m = re.search(r'^\s*"' + re.escape(node_id) + r'" \[.*?label="((?:[^"\\]|\\.)*)"', dot, flags=re.M)
    assert m, f"no node {node_id}"
    return m.group(1)


# ---------------------------------------------------------------------------------------------
# goal model


def test_goal_model_view(hospital: Mission) -> None:
    dot = goal_model_dot(hospital)
    assert dot.startswith('digraph "goal_model" {\n') and dot.endswith("}\n")
    ids = _node_ids(dot)
    assert len(ids) == len(set(ids))
    # the 21 task instances, by their ids, with task name and location
    tasks = [i for i in ids if re.fullmatch(r"AT\d+_\d+", i)]
    assert len(tasks) == 21
    assert _label_of(dot, "AT1_1") == r"AT1_1: ClearRoom\nat Room101"
    assert _label_of(dot, "AT5_3") == r"AT5_3: TeamDisinfection\nat Room104\nrobots: 2..3"
    # goals with their text (annotation stripped), query result, forAll, contexts and flags
    assert _label_of(dot, "G1").startswith("G1: Discharged Rooms Are Disinfected")
    assert "[G2;G3]" not in dot
    g2 = _label_of(dot, "G2")
    assert "Query: world_db->select(r:Room |" in g2 and "rooms = [Room101, Room102, Room104]" in g2
    assert "forAll current_room in rooms" in _label_of(dot, "G3.forall")
    for i, room in enumerate(("Room101", "Room102", "Room104"), start=1):
        assert _label_of(dot, f"G3_{i}") == rf"G3 instance {i}\ncurrent_room = {room}"
    assert 'trigger: \\"PatientDischarged\\"' in _label_of(dot, "G4_1")
    assert 'condition: \\"current_room.is_restocked\\"' in _label_of(dot, "G15_2")
    assert "Group=False" in _label_of(dot, "G5_3")
    # operators: ; # FALLBACK and OR (G8 is OR-refined: its edges are dashed)
    assert _label_of(dot, "G1.op") == ";"
    assert _label_of(dot, "G9_1.op") == "FALLBACK"
    assert _label_of(dot, "G13_1.op") == "#"
    assert _label_of(dot, "G8_1.op") == "OR"
    edges = {(a, b): attrs for a, b, attrs in _edges(dot)}
    assert edges[("G8_1.op", "G9_1")] == 'style="dashed"'
    assert edges[("G8_1.op", "G12_1")] == 'style="dashed"'
    assert edges[("G9_1.op", "G10_1")] == ""
    assert ("G3.forall", "G3_2") in edges and ("G12_2", "AT5_2") in edges


# ---------------------------------------------------------------------------------------------
# Task Graph


def test_task_graph_view(hospital: Mission) -> None:
    dot = task_graph_dot(hospital)
    tg = hospital.task_graph
    ids = _node_ids(dot)
    assert len(ids) == len(tg.vertices) == len(set(ids))
    decompositions = [i for i in ids if "|" in i]
    assert len(decompositions) == 27
    assert _label_of(dot, "AT3_2|2") == r"t12  AT3_2|2\nopen-door\nirradiate-room"
    assert 'fontsize="8"' in re.search(r'^\s*"AT3_2\|2" .*$', dot, flags=re.M).group(0)
    assert _label_of(dot, "v0") == r"#  G3\nforAll"
    assert _label_of(dot, "v2") == r";  G5\nGroup=False"
    assert _label_of(dot, "v7") == "OR  G8"
    assert _label_of(dot, "AT5_1") == r"AT5_1: TeamDisinfection\nat Room101\nrobots: 2..3"
    edges = {(a, b): attrs for a, b, attrs in _edges(dot)}
    # AND solid, OR dashed
    assert edges[("v1", "v2")] == "" and edges[("AT1_1", "AT1_1|1")] == ""
    assert edges[("v7", "v8")] == 'style="dashed"' and edges[("v7", "AT5_1")] == 'style="dashed"'
    # CD: red dotted, from the restocking decomposition to the reporting task
    cd = edges[("AT6_1|1", "AT7_1")]
    assert 'style="dotted"' in cd and 'color="#d62728"' in cd and 'constraint="false"' in cd
    assert sum('label="CD"' in a for a in edges.values()) == 3
    # EC: undirected, blue, drawn once per pair, with the flags
    ec = [(a, b, attrs) for a, b, attrs in _edges(dot) if "EC " in attrs]
    assert [(a, b) for a, b, _ in ec] == [("AT1_1", "AT2_1"), ("AT1_2", "AT2_2"), ("AT1_3", "AT2_3")]
    for _a, _b, attrs in ec:
        assert 'dir="none"' in attrs and 'color="#1f5fbf"' in attrs
        assert 'label="EC group=False divisible=True"' in attrs


# ---------------------------------------------------------------------------------------------
# one mission decomposition


def test_decomposition_view(hospital: Mission) -> None:
    dot = decomposition_dot(hospital, 0)
    chosen = [hospital.task_graph.vertices[d].content for d in list(hospital.decomposition_space())[0]]
    assert sorted(_node_ids(dot)) == sorted(chosen)
    assert len(chosen) == 18  # 3 rooms x (clear, dispose, UV + spray fallback, restock, report)
    assert "valid mission decomposition 0 (indices 0 to 35 of 36)" in dot
    label = _label_of(dot, "AT1_1|1")
    assert label == r"t0  AT1_1|1\nClearRoom at Room101\n1. strip-bed(?r, Room101)\l2. bag-waste(?r, Room101)\l"
    # Room102's door is closed: the UV robot opens it first
    assert r"1. open-door(?r, Room102)\l2. irradiate-room(?r, Room102)\l" in _label_of(dot, "AT3_2|2")
    edges = {(a, b): attrs for a, b, attrs in _edges(dot)}
    assert edges[("AT2_1|1", "AT3_1|1")] == 'label="SEQ"'
    assert edges[("AT6_1|1", "AT7_1|1")] == 'label="SEQ"'
    fb = edges[("AT3_1|1", "AT4_1|1")]
    assert 'label="FB"' in fb and 'style="dashed"' in fb
    # the clearing robot also disposes of the waste: SEQ and EC between the same pair
    pair = [attrs for a, b, attrs in _edges(dot) if (a, b) == ("AT1_1|1", "AT2_1|1")]
    assert pair[0] == 'label="SEQ"'
    assert 'dir="none"' in pair[1] and 'label="EC group=False divisible=True"' in pair[1]
    # every edge joins two chosen decompositions; one box per room
    assert all(a in chosen and b in chosen for a, b in edges)
    assert sorted(re.findall(r'label="(current_room = Room\d+)"', dot)) == [
        "current_room = Room101", "current_room = Room102", "current_room = Room104"]


def test_decomposition_index_follows_the_space_order(hospital: Mission) -> None:
    space = list(hospital.decomposition_space())
    assert len(space) == 36
    for i, members in enumerate(space):
        assert nth_decomposition(hospital, i) == members
    assert nth_decomposition(hospital, -1) == space[-1]
    # a team disinfection choice shows up in the picture
    team = next(i for i, members in enumerate(space)
                if any(hospital.task_graph.vertices[d].content.startswith("AT5_") for d in members))
    dot = decomposition_dot(hospital, team)
    assert "TeamDisinfection at Room" in dot and 'label="FB"' in dot


def test_decomposition_index_out_of_range(hospital: Mission) -> None:
    with pytest.raises(MissionError) as err:
        decomposition_dot(hospital, 36)
    assert err.value.exit_code == 2
    assert "out of range" in str(err.value) and "36 valid" in str(err.value)
    with pytest.raises(MissionError):
        decomposition_dot(hospital, -37)


def test_decomposition_of_an_empty_mission(tmp_path: Path) -> None:
    mission_dir = tmp_path / "empty"
    shutil.copytree(DELIVERY, mission_dir, ignore=shutil.ignore_patterns("output"))
    world = mission_dir / "knowledge" / "world_db.xml"
    world.write_text(world.read_text().replace("<is_delivered>False", "<is_delivered>True"))
    mission = _load(mission_dir)
    assert "deliveries is empty: no instance" in goal_model_dot(mission)
    with pytest.raises(NoDecompositionError) as err:
        decomposition_dot(mission, 0)
    assert err.value.exit_code == 3


def test_item_delivery_views() -> None:
    mission = _load(DELIVERY)
    gm = goal_model_dot(mission)
    assert "pickup_point = CentralPharmacy" in gm and "destination = Laboratory" in gm
    tg = task_graph_dot(mission)
    assert 'label="EC group=False divisible=True"' in tg
    dec = decomposition_dot(mission, 7)
    assert "2. drop-item(?r, Delivery3, Laboratory)" in dec


# ---------------------------------------------------------------------------------------------
# determinism and options


def test_views_are_deterministic(hospital: Mission) -> None:
    again = _load(HOSPITAL)
    for view in ("goal-model", "task-graph", "decomposition"):
        first = view_dot(hospital, view, 5)
        assert first == view_dot(again, view, 5)
        assert first == view_dot(hospital, view, 5)
    assert view_dot(hospital, "decomposition", 5) == decomposition_dot(hospital, 5)


def test_rankdir(hospital: Mission) -> None:
    assert 'rankdir="TB"' in task_graph_dot(hospital, rankdir="TB")
    assert 'rankdir="LR"' in view_dot(hospital, "goal-model")
    with pytest.raises(ValueError):
        goal_model_dot(hospital, rankdir="sideways")
    with pytest.raises(ValueError):
        view_dot(hospital, "plan")


def test_labels_are_escaped() -> None:
    assert render_module._quote('say "hi" \\ there\nnow') == r'"say \"hi\" \\ there\nnow"'


# ---------------------------------------------------------------------------------------------
# writing files


@pytest.fixture
def no_graphviz(monkeypatch: pytest.MonkeyPatch, tmp_path: Path) -> None:
    """No ``dot`` anywhere: an empty PATH and ``shutil.which`` finding nothing."""
    empty = tmp_path / "empty-bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))
    monkeypatch.setattr(render_module.shutil, "which", lambda name, *a, **k: None)


def test_render_dot_needs_no_graphviz(hospital: Mission, tmp_path: Path, no_graphviz: None) -> None:
    text = task_graph_dot(hospital)
    result = render(text, tmp_path / "sub" / "tg.dot")
    assert result.rendered and result.message is None
    assert result.path == tmp_path / "sub" / "tg.dot"
    assert result.path.read_bytes() == text.encode("utf-8")
    assert render(text, tmp_path / "tg.gv").path.read_text() == text


def test_render_picture_without_graphviz(hospital: Mission, tmp_path: Path, no_graphviz: None) -> None:
    text = goal_model_dot(hospital)
    result = render(text, tmp_path / "gm.png")
    assert not result.rendered
    assert result.path == tmp_path / "gm.dot"
    assert result.path.read_text() == text
    assert not (tmp_path / "gm.png").exists()
    assert "apt-get install graphviz" in result.message
    assert str(tmp_path / "gm.dot") in result.message
    assert f"dot -Tpng {tmp_path / 'gm.dot'} -o {tmp_path / 'gm.png'}" in result.message


def test_render_without_graphviz_on_path(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    empty = tmp_path / "bin"
    empty.mkdir()
    monkeypatch.setenv("PATH", str(empty))  # the real shutil.which finds no dot
    result = render("digraph g {}\n", tmp_path / "g.svg")
    assert not result.rendered and result.path == tmp_path / "g.dot"


def test_render_unsupported_suffix(tmp_path: Path) -> None:
    with pytest.raises(RenderError) as err:
        render("digraph g {}\n", tmp_path / "g.jpeg")
    assert err.value.exit_code == 2 and ".svg" in str(err.value)


def _fake_dot(tmp_path: Path, monkeypatch: pytest.MonkeyPatch, body: str) -> None:
    """Put a stand-in ``dot`` program first on PATH."""
    bin_dir = tmp_path / "fake-bin"
    bin_dir.mkdir()
    script = bin_dir / "dot"
    script.write_text(f"#!{sys.executable}\nimport sys\n{body}\n")
    script.chmod(script.stat().st_mode | stat.S_IXUSR | stat.S_IXGRP | stat.S_IXOTH)
    monkeypatch.setenv("PATH", str(bin_dir) + os.pathsep + os.environ.get("PATH", ""))


@pytest.mark.skipif(os.name == "nt", reason="uses an executable script as a stand-in for dot")
def test_render_runs_dot(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    # the stand-in prints its arguments and input as the "picture", which the render writes
    # to the target atomically (dot writes nothing itself)
    _fake_dot(tmp_path, monkeypatch,
              "args = sys.argv[1:]\n"
              "sys.stdout.write(' '.join(args) + '\\n' + sys.stdin.read())")
    result = render("digraph g { a -> b; }\n", tmp_path / "g.svg")
    assert result.rendered and result.message is None and result.path == tmp_path / "g.svg"
    assert result.path.read_text() == "-Tsvg\ndigraph g { a -> b; }\n"
    assert not (tmp_path / "g.dot").exists()


@pytest.mark.skipif(os.name == "nt", reason="uses an executable script as a stand-in for dot")
def test_render_reports_a_dot_failure(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    _fake_dot(tmp_path, monkeypatch, "sys.stderr.write('Error: syntax error in line 1\\n'); sys.exit(1)")
    with pytest.raises(RenderError) as err:
        render("digraph {", tmp_path / "g.png")
    assert "syntax error in line 1" in str(err.value)


@pytest.mark.skipif(shutil.which("dot") is None, reason="Graphviz is not installed")
def test_render_with_graphviz(hospital: Mission, tmp_path: Path) -> None:
    for name, text in (("gm", goal_model_dot(hospital)), ("tg", task_graph_dot(hospital)),
                       ("dec", decomposition_dot(hospital, 3))):
        svg = render(text, tmp_path / f"{name}.svg")
        assert svg.rendered and "<svg" in svg.path.read_text()
        png = render(text, tmp_path / f"{name}.png")
        assert png.path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


# ---------------------------------------------------------------------------------------------
# the mission of docs/guide.md (its numbers and pictures are quoted in the guide)


def test_guide_mission() -> None:
    mission = _load(ROOT / "docs" / "guide-mission")
    assert len(mission.expansion.instances) == 12
    assert len(mission.task_graph.decompositions()) == 17
    kinds = [c.kind for c in mission.constraints]
    assert (kinds.count("SEQ"), kinds.count("FB"), kinds.count("EC")) == (22, 0, 12)
    assert mission.decomposition_space().count == 8
    gm = goal_model_dot(mission)
    # Sample2 has no barcode label: the condition context of G10 removes the analyser branch
    assert _label_of(gm, "AT3_2") == r"AT3_2: AnalyseSample\nremoved: context is false"
    assert "removed" not in _label_of(gm, "AT3_1")
    dec = decomposition_dot(mission, 0)
    assert r"3. pick-sample(?r, Sample2, Ward2)\l" in _label_of(dec, "AT1_2|2")
    assert _label_of(dec, "AT4_2|1").startswith(r"t10  AT4_2|1\nManualAnalysis\nrobots: 2..3\n")


def test_dot_clusters_indent_their_members():
    dot = render_module._Dot("g", {}, {}, {})
    dot.node("a", shape="box")
    with dot.cluster("cluster_1", 'r = "x"', "#123456"):
        dot.node("b")
        dot.edge("a", "b", style=None, constraint=False)
    dot.edge("b", "a")
    assert dot.text() == ('digraph "g" {\n'
                          '    "a" [shape="box"];\n'
                          '    subgraph "cluster_1" {\n'
                          '        label="r = \\"x\\""; style="rounded,dashed"; color="#123456";\n'
                          '        "b";\n'
                          '        "a" -> "b" [constraint="false"];\n'
                          '    }\n'
                          '    "b" -> "a";\n'
                          '}\n')


def test_forall_clusters_when_the_root_has_task_children():
    """object-picking: the forAll at the Task Graph root refines directly into task instances,
    which carry no variable values: each element's box is labelled by its position."""
    from conftest import require_reference

    mission = _load(require_reference() / "missions" / "object-picking")
    dot = decomposition_dot(mission, 0)
    clusters = re.findall(r'subgraph "(cluster_\d)" \{\n\s+label="([^"]*)";.*\n\s+"([^"]+)" \[', dot)
    assert clusters == [("cluster_2", "forAll element 2", "AT1_1_2|1"), ("cluster_1", "forAll element 1", "AT1_1_1|1")]
