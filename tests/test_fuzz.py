"""Property tests: every reader either returns its model or raises a located ``MissionError``.

Each parser is fed mutated versions of the real example files (characters or bytes deleted,
inserted or replaced at random positions, truncations) and random text over an alphabet that
looks like its grammar.  Any exception other than :class:`~mutrose_cp.errors.MissionError` fails
the property: bad input must end in a message, never in a traceback.  One end-to-end property
runs ``check`` and ``decompose`` on example missions whose world was mutated (booleans flipped,
fields and records deleted): the exit status is 0, 2 or 3 and no traceback is printed.

The default run is short (about 150 examples per property).  ``HYPOTHESIS_PROFILE=nightly``
runs ten times more; the settings objects live in this file (the shared conftest is not
touched).
"""
from __future__ import annotations

import contextlib
import io
import json
import os
import random
import shutil
import tempfile
from pathlib import Path

from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st
from lxml import etree

from mutrose_cp.cli.program import main
from mutrose_cp.errors import MissionError
from mutrose_cp.io.config import load_configuration, parse_configuration_json, parse_configuration_xml
from mutrose_cp.io.expressions import parse_condition, parse_forall, parse_node_text, parse_select
from mutrose_cp.io.goal_model import load_goal_model, parse_goal_model
from mutrose_cp.io.hddl import load_domain, parse_domain
from mutrose_cp.io.knowledge import load_knowledge
from mutrose_cp.model import (
    AnnotationLeaf,
    AnnotationOp,
    Atom,
    BoolOp,
    Configuration,
    Domain,
    ForAll,
    GoalModel,
    Select,
    WorldKnowledge,
)

ROOT = Path(__file__).resolve().parent.parent
EXAMPLES = ROOT / "examples"
EXAMPLE_DIRS = sorted(p for p in EXAMPLES.iterdir() if (p / "configuration").is_dir())

NIGHTLY = os.environ.get("HYPOTHESIS_PROFILE") == "nightly"
SCALE = 10 if NIGHTLY else 1

_HEALTH = [HealthCheck.too_slow, HealthCheck.data_too_large, HealthCheck.filter_too_much]
PARSER_SETTINGS = settings(max_examples=150 * SCALE, deadline=None, suppress_health_check=_HEALTH)
EXPRESSION_SETTINGS = settings(max_examples=200 * SCALE, deadline=None, suppress_health_check=_HEALTH)
END_TO_END_SETTINGS = settings(max_examples=25 * SCALE, deadline=None, suppress_health_check=_HEALTH)


def _example_files(pattern: str) -> list[tuple[str, str]]:
    """(name, text) of every example file matching ``pattern`` (relative to a mission folder)."""
    out = []
    for folder in EXAMPLE_DIRS:
        for path in sorted(folder.glob(pattern)):
            out.append((f"{folder.name}/{path.relative_to(folder)}", path.read_text(encoding="utf-8")))
    return out


HDDL_FILES = _example_files("hddl/*.hddl")
GM_FILES = _example_files("gm/*.json")
CONFIG_FILES = _example_files("configuration/*.json")
WORLD_FILES = _example_files("knowledge/*.xml")


def _xml_configuration(json_text: str) -> str:
    """The XML form (spec config-and-knowledge.md §3) of a JSON example configuration, so that
    the XML reader is fuzzed from a valid document as well."""
    data = json.loads(json_text)
    lines = ["<configuration>"]
    for section in ("world_db", "output"):
        lines.append(f"  <{section}>")
        lines += [f"    <{k}>{v}</{k}>" for k, v in data[section].items()]
        lines.append(f"  </{section}>")
    lines.append("  <location_types>")
    lines += [f"    <type>{t}</type>" for t in data["location_types"]]
    lines.append("  </location_type>")  # the lenient end tag of the shipped files
    lines.append("  <type_mapping>")
    for m in data["type_mapping"]:
        lines.append(
            f"    <mapping><hddl_type>{m['hddl_type']}</hddl_type><ocl_type>{m['ocl_type']}</ocl_type></mapping>"
        )
    lines.append("  </type_mapping>")
    lines.append("  <var_mapping>")
    for vm in data["var_mapping"]:
        maps = "".join(f'<map gm_var="{m["gm_var"]}" hddl_var="{m["hddl_var"]}"/>' for m in vm["map"])
        lines.append(f"    <mapping><task_id>{vm['task_id']}</task_id>{maps}</mapping>")
    lines.append("  </var_mapping>")
    lines.append("  <semantic_mapping>")
    for sm in data["semantic_mapping"]:
        fields = "".join(f"<{k}>{v}</{k}>" for k, v in sm.items() if k != "map")
        sorts = sm["map"]["arg_sorts"]
        lines.append(
            f"    <mapping>{fields}<map><pred>{sm['map']['pred']}</pred>"
            f"<arg_sorts number=\"{len(sorts)}\">{' '.join(sorts)}</arg_sorts></map></mapping>"
        )
    lines.append("  </semantic_mapping>")
    lines.append("</configuration>")
    return "\n".join(lines) + "\n"


XML_CONFIG_FILES = [(name.replace(".json", ".xml"), _xml_configuration(text)) for name, text in CONFIG_FILES]

# Alphabets that look like each grammar, so random text reaches deep into the parsers.
HDDL_ALPHABET = "()?-:; \n\tabcdefghijklmnopqrstuvwxyz0123456789.=<>" + "\x00é"
HDDL_WORDS = [
    "(define", "(domain", "d)", "(:types", "(:predicates", "(:functions", "(:task", "(:method",
    "(:action", ":parameters", ":task", ":precondition", ":effect", ":subtasks", ":ordered-subtasks",
    ":ordering", "(and", "(not", "(or", "(forall", "(increase", "(=", "(>", "?r", "?x", "- robot",
    "- robotteam", "- object", "robot", "t1", "(t1 <", "t2)", ")", "(", " ", "\n", "; c\n", "1", "1.5",
    ":capabilities", ":required-capabilities", "(:constants", "(:requirements", ":hierarchy",
]
JSON_ALPHABET = '{}[]:,"\\ \n0123456789.-+eEtrufalsn' + "GATx#;()|!&<>=é\x00"
JSON_WORDS = [
    "{", "}", "[", "]", ",", ":", '"', '"id"', '"text"', '"type"', '"x"', '"y"', '"nodes"', '"links"',
    '"actors"', '"customProperties"', '"istar.Goal"', '"istar.Task"', '"istar.OrRefinementLink"',
    '"istar.AndRefinementLink"', '"source"', '"target"', '"G1: a [G2;G3]"', '"AT1: T"', "null", "true",
    "1e999", "-0", '"GoalType"', '"Query"', '"Achieve"', '"Controls"', '"Monitors"', '"RobotNumber"',
    '"[2,1]"', '"world_db"', '"output"', '"semantic_mapping"', '"var_mapping"', '"map"', '"arg_sorts"',
    '"\\ud800"', '"type_mapping"', '"location_types"',
]
XML_ALPHABET = "<>/=\"' \n!?-[]&;#abcdefxyzNTRUEFALS0123456789" + "\x00é"
XML_WORDS = [
    "<", ">", "</", "/>", "<world_db>", "</world_db>", "<Room>", "</Room>", "<name>", "</name>",
    "<Location>", "</Location>", "True", "False", "<!DOCTYPE x [<!ENTITY a \"b\">]>", "&a;", "&amp;",
    "&#0;", "&#x110000;", "<![CDATA[", "]]>", "<!--", "-->", "<?xml version=\"1.0\"?>", "<?pi?>",
    "<configuration>", "</configuration>", "<mapping>", "<map gm_var=\"a\" hddl_var=\"?b\"/>",
    "<arg_sorts number=\"2\">", "<arg_sorts number=\"x\">", "encoding=\"latin-1\"",
]
EXPRESSION_ALPHABET = "abcxyzGAT0123456789 .,:;#|&!()[]\"<>=-_" + "é\t\n"
EXPRESSION_WORDS = [
    "world_db", "->select(", "->forAll(", "x", "x:Room", "x : Room", "|", "||", "&&", "!", "not ",
    "x.a", "x.a = \"R\"", "x.b in y.c", " in ", ">", "<", ">=", "<>", "=", "(", ")", "[", "]", ";", "#",
    "FALLBACK(", ",", "G1", "G2", "AT1", ": ", "Sequence(Room)", "5", "2.5",
]


# ---------------------------------------------------------------------------------------------
# Mutation strategies


@st.composite
def mutated(draw, text: str, alphabet: str, words: list[str]) -> str:
    """``text`` with a few random edits: deletions, insertions and replacements (of characters
    or grammar words) at random positions, or a truncation."""
    chars = list(text)
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["delete", "insert", "replace", "insert_word", "truncate", "duplicate"]))
        pos = draw(st.integers(0, len(chars)))
        if kind == "delete":
            del chars[pos:pos + draw(st.integers(1, 8))]
        elif kind == "insert":
            chars[pos:pos] = draw(st.text(alphabet, min_size=1, max_size=4))
        elif kind == "replace":
            chars[pos:pos + 1] = draw(st.text(alphabet, min_size=1, max_size=2))
        elif kind == "insert_word":
            chars[pos:pos] = draw(st.sampled_from(words))
        elif kind == "duplicate":
            end = min(len(chars), pos + draw(st.integers(1, 40)))
            chars[pos:pos] = chars[pos:end]
        else:
            del chars[pos:]
    return "".join(chars)


@st.composite
def mutated_bytes(draw, data: bytes) -> bytes:
    """``data`` with a few byte-level edits (any byte value: invalid UTF-8, NULs, BOMs)."""
    out = bytearray(data)
    for _ in range(draw(st.integers(1, 4))):
        kind = draw(st.sampled_from(["delete", "insert", "replace", "truncate"]))
        pos = draw(st.integers(0, len(out)))
        if kind == "delete":
            del out[pos:pos + draw(st.integers(1, 8))]
        elif kind == "insert":
            out[pos:pos] = draw(st.one_of(st.binary(min_size=1, max_size=4),
                                          st.sampled_from([b"\xef\xbb\xbf", b"\xff\xfe", b"\x00", b"\xc3"])))
        elif kind == "replace":
            out[pos:pos + 1] = draw(st.binary(min_size=1, max_size=2))
        else:
            del out[pos:]
    return bytes(out)


def grammarish(alphabet: str, words: list[str], max_size: int = 30) -> st.SearchStrategy[str]:
    """Random text made of grammar words and single characters."""
    piece = st.one_of(st.sampled_from(words), st.text(alphabet, min_size=1, max_size=3))
    return st.lists(piece, max_size=max_size).map("".join)


def inputs_for(files: list[tuple[str, str]], alphabet: str, words: list[str]) -> st.SearchStrategy[tuple[str, str]]:
    """(name, text): a mutated example file, or grammar-ish random text."""
    mutations = st.sampled_from(files).flatmap(
        lambda f: mutated(f[1], alphabet, words).map(lambda t, n=f[0]: (n, t))
    )
    return st.one_of(mutations, mutations, grammarish(alphabet, words, 60).map(lambda t: ("random", t)))


def _only_mission_errors(call, *args):
    """Run ``call``; a MissionError is fine (its problems must be printable and non-empty), any
    other exception propagates and fails the property.  Returns the result or None."""
    try:
        return call(*args)
    except MissionError as err:
        assert err.problems, "a MissionError must carry at least one problem"
        for problem in err.problems:
            assert str(problem).strip()
        return None


# ---------------------------------------------------------------------------------------------
# Readers


def test_inputs_are_present():
    assert HDDL_FILES and GM_FILES and CONFIG_FILES and WORLD_FILES


@PARSER_SETTINGS
@given(inputs_for(HDDL_FILES, HDDL_ALPHABET, HDDL_WORDS))
def test_hddl_reader_never_crashes(case):
    name, text = case
    result = _only_mission_errors(parse_domain, text, name)
    assert result is None or isinstance(result, Domain)


@PARSER_SETTINGS
@given(inputs_for(GM_FILES, JSON_ALPHABET, JSON_WORDS))
def test_goal_model_reader_never_crashes(case):
    name, text = case
    result = _only_mission_errors(parse_goal_model, text, name)
    assert result is None or isinstance(result, GoalModel)


@PARSER_SETTINGS
@given(inputs_for(CONFIG_FILES, JSON_ALPHABET, JSON_WORDS))
def test_json_configuration_reader_never_crashes(case):
    name, text = case
    result = _only_mission_errors(parse_configuration_json, text, name)
    assert result is None or isinstance(result, Configuration)


@PARSER_SETTINGS
@given(inputs_for(XML_CONFIG_FILES, XML_ALPHABET, XML_WORDS), st.booleans())
def test_xml_configuration_reader_never_crashes(case, as_bytes):
    name, text = case
    data: bytes | str = text.encode("utf-8", "surrogatepass") if as_bytes else text
    result = _only_mission_errors(parse_configuration_xml, data, name)
    assert result is None or isinstance(result, Configuration)


@PARSER_SETTINGS
@given(
    inputs_for(WORLD_FILES, XML_ALPHABET, XML_WORDS),
    st.sampled_from(["world_db", None, "Room", "", "nothing"]),
    st.sampled_from(["name", "", "id"]),
)
def test_knowledge_reader_never_crashes(case, xml_root, unique_id):
    _name, text = case
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / "world_db.xml"
        path.write_bytes(text.encode("utf-8", "surrogatepass"))
        result = _only_mission_errors(load_knowledge, path, xml_root, unique_id)
    if result is not None:
        assert isinstance(result, WorldKnowledge)
        _ = result.records  # the record index must be buildable on whatever was accepted


FILE_READERS = {
    "hddl": (HDDL_FILES, "domain.hddl", load_domain, Domain),
    "gm": (GM_FILES, "gm.json", load_goal_model, GoalModel),
    "json configuration": (CONFIG_FILES, "configuration.json", load_configuration, Configuration),
    "xml configuration": (XML_CONFIG_FILES, "configuration.xml", load_configuration, Configuration),
    "world": (WORLD_FILES, "world_db.xml", lambda p: load_knowledge(p, "world_db"), WorldKnowledge),
}


@PARSER_SETTINGS
@given(
    st.sampled_from(sorted(FILE_READERS)).flatmap(
        lambda kind: st.tuples(
            st.just(kind),
            st.sampled_from(FILE_READERS[kind][0]).flatmap(lambda f: mutated_bytes(f[1].encode("utf-8"))),
        )
    )
)
def test_file_readers_never_crash_on_corrupt_bytes(case):
    """The ``load_*`` functions read files: any byte sequence (bad encodings included) gives a
    model or a MissionError."""
    kind, data = case
    _files, name, load, model = FILE_READERS[kind]
    with tempfile.TemporaryDirectory() as tmp:
        path = Path(tmp) / name
        path.write_bytes(data)
        result = _only_mission_errors(load, path)
    assert result is None or isinstance(result, model)


def _gm_expressions() -> list[tuple[str, str]]:
    """Every expression of the example goal models, by kind."""
    out: list[tuple[str, str]] = []
    for _name, text in GM_FILES:
        for actor in json.loads(text)["actors"]:
            for node in actor["nodes"]:
                out.append(("text", node["text"]))
                props = node.get("customProperties", {})
                if "QueriedProperty" in props:
                    out.append(("select", props["QueriedProperty"]))
                if "AchieveCondition" in props:
                    out.append(("forall", props["AchieveCondition"]))
                context = props.get("CreationCondition", "")
                if "condition" in context:
                    out.append(("condition", context.split('"')[1]))
    return out


GM_EXPRESSIONS = _gm_expressions()


def _expressions(kind: str) -> list[tuple[str, str]]:
    found = [(kind, t) for k, t in GM_EXPRESSIONS if k == kind]
    assert found, kind
    return found


@EXPRESSION_SETTINGS
@given(inputs_for(_expressions("condition") + _expressions("forall"), EXPRESSION_ALPHABET, EXPRESSION_WORDS))
def test_condition_parser_never_crashes(case):
    _kind, text = case
    result = _only_mission_errors(parse_condition, text)
    assert result is None or isinstance(result, (Atom, BoolOp))


@EXPRESSION_SETTINGS
@given(inputs_for(_expressions("select"), EXPRESSION_ALPHABET, EXPRESSION_WORDS))
def test_select_parser_never_crashes(case):
    _kind, text = case
    result = _only_mission_errors(parse_select, text)
    assert result is None or isinstance(result, Select)


@EXPRESSION_SETTINGS
@given(inputs_for(_expressions("forall"), EXPRESSION_ALPHABET, EXPRESSION_WORDS))
def test_forall_parser_never_crashes(case):
    _kind, text = case
    result = _only_mission_errors(parse_forall, text)
    assert result is None or isinstance(result, ForAll)


@EXPRESSION_SETTINGS
@given(inputs_for(_expressions("text"), EXPRESSION_ALPHABET, EXPRESSION_WORDS))
def test_node_text_parser_never_crashes(case):
    _kind, text = case
    result = _only_mission_errors(parse_node_text, text)
    if result is not None:
        name, annotation = result
        assert isinstance(name, str)
        assert annotation is None or isinstance(annotation, (AnnotationLeaf, AnnotationOp))


# ---------------------------------------------------------------------------------------------
# End to end: mutated worlds through check and decompose


@st.composite
def mutated_world(draw) -> tuple[Path, bytes]:
    """An example mission folder and a mutation of its world: booleans flipped, fields and
    records deleted, records duplicated."""
    folder = draw(st.sampled_from(EXAMPLE_DIRS))
    world = next((folder / "knowledge").glob("*.xml"))
    root = etree.fromstring(world.read_bytes())
    rng = random.Random(draw(st.integers(0, 2**32 - 1)))
    records = list(root.iterchildren(tag=etree.Element))
    flip_rate = draw(st.sampled_from([0.0, 0.1, 0.3, 1.0]))
    for record in records:
        for field in list(record.iterchildren(tag=etree.Element)):
            text = (field.text or "").strip()
            if text in ("True", "False") and rng.random() < flip_rate:
                field.text = "False" if text == "True" else "True"
            elif rng.random() < draw(st.sampled_from([0.0, 0.05])):
                record.remove(field)
    for record in records:
        roll = rng.random()
        if roll < draw(st.sampled_from([0.0, 0.2, 0.5])):
            root.remove(record)
        elif roll > 0.95:
            root.append(etree.fromstring(etree.tostring(record)))
    return folder, etree.tostring(root, xml_declaration=True, encoding="utf-8")


def _run_cli(argv: list[str]) -> tuple[int, str]:
    err = io.StringIO()
    with contextlib.redirect_stderr(err), contextlib.redirect_stdout(io.StringIO()):
        code = main(argv)
    return code, err.getvalue()


@END_TO_END_SETTINGS
@given(mutated_world())
def test_mutated_world_check_and_decompose(case):
    folder, world = case
    with tempfile.TemporaryDirectory() as tmp:
        mission = Path(tmp) / folder.name
        shutil.copytree(folder, mission)
        next((mission / "knowledge").glob("*.xml")).write_bytes(world)
        code, err = _run_cli(["check", str(mission)])
        assert code in (0, 2), err
        assert "Traceback" not in err
        code, err = _run_cli(["decompose", str(mission), "-q", "-o", str(Path(tmp) / "out.json")])
        assert code in (0, 2, 3), err
        assert "Traceback" not in err
        if code in (2, 3):
            assert err.startswith("error: "), err

