"""Boost-compatible JSON output (``output.py``): string escaping at its boundaries, the layout of
keys and empty containers, and a whole run whose world names need escaping."""
from __future__ import annotations

import json
import shutil
from pathlib import Path

import pytest

from mutrose_cp.cli.program import main
from mutrose_cp.output.boost_json import boost_json, write_boost_json

EXAMPLE = Path(__file__).resolve().parent.parent / "examples" / "item-delivery"

NAMED = {'"': '\\"', "\\": "\\\\", "/": "\\/", "\b": "\\b", "\f": "\\f", "\n": "\\n", "\r": "\\r", "\t": "\\t"}
PRINTABLE = [chr(c) for c in range(0x20, 0x7F) if chr(c) not in NAMED]


@pytest.mark.parametrize("ch", PRINTABLE)
def test_printable_ascii_is_written_as_is(ch):
    """0x20 (space) to 0x7E (``~``) are kept, alone and next to a character that needs an escape."""
    assert boost_json(ch) == f'"{ch}"'
    assert boost_json(ch + "\n") == f'"{ch}\\n"'
    assert boost_json("\x01" + ch) == f'"\\u0001{ch}"'


def test_all_printable_ascii_in_one_string():
    text = "".join(PRINTABLE)
    assert boost_json(text) == f'"{text}"'
    assert boost_json(text + "/") == f'"{text}\\/"'


@pytest.mark.parametrize("ch, escaped", sorted(NAMED.items()))
def test_named_escapes(ch, escaped):
    """Quote, backslash and slash, and the five named control characters, alone, inside plain
    text and next to another escape."""
    assert boost_json(ch) == f'"{escaped}"'
    assert boost_json(f"a{ch}b") == f'"a{escaped}b"'
    assert boost_json(f"{ch}\x7f") == f'"{escaped}\\u007F"'


@pytest.mark.parametrize("code", [c for c in range(0x20) if chr(c) not in NAMED] + [0x7F])
def test_other_control_characters_are_hex_escaped(code):
    """Every other character below 0x20 (the boundary 0x1F included) and DEL (0x7F) become
    ``\\u00XX`` with upper-case hex digits."""
    assert boost_json(chr(code)) == f'"\\u00{code:02X}"'
    assert boost_json(f"x{chr(code)}y") == f'"x\\u00{code:02X}y"'


def test_boundaries_side_by_side():
    assert boost_json("\x1f \x7e\x7f") == '"\\u001F ~\\u007F"'


@pytest.mark.parametrize("text, escaped", [
    ("\x80", "\\u00C2\\u0080"),
    ("é", "\\u00C3\\u00A9"),
    ("€", "\\u00E2\\u0082\\u00AC"),
    ("Café/2", "Caf\\u00C3\\u00A9\\/2"),
])
def test_non_ascii_is_escaped_per_utf8_byte(text, escaped):
    """As Boost does: each UTF-8 byte of a non-ASCII character as its own ``\\u00XX``."""
    assert boost_json(text) == f'"{escaped}"'


def test_ascii_strings_are_valid_json():
    """Whatever ASCII a string holds, the output parses back to it."""
    text = "".join(chr(c) for c in range(0x80))
    assert json.loads(boost_json(text)) == text
    for c in range(0x80):
        assert json.loads(boost_json(chr(c))) == chr(c)


def test_keys_and_empty_containers():
    """Keys are escaped like values; empty lists and objects are written as ``""``."""
    tree = {"a/b": ["x\"y", [], {}], "c": {}, "d": {"e": "\t"}}
    assert boost_json(tree) == (
        '{\n'
        '    "a\\/b": [\n'
        '        "x\\"y",\n'
        '        "",\n'
        '        ""\n'
        '    ],\n'
        '    "c": "",\n'
        '    "d": {\n'
        '        "e": "\\t"\n'
        '    }\n'
        '}'
    )
    assert json.loads(boost_json(tree)) == {"a/b": ['x"y', "", ""], "c": "", "d": {"e": "\t"}}


def test_world_names_are_escaped_in_the_mission_output(tmp_path):
    """A location named ``Central"Ph/ar\\macy~é<DEL>`` in the world knowledge reaches the task
    entries of ``decompose`` escaped as Boost writes it, and the file is still valid JSON."""
    folder = tmp_path / "mission"
    shutil.copytree(EXAMPLE, folder, ignore=shutil.ignore_patterns("output"))
    world = folder / "knowledge" / "world_db.xml"
    text = world.read_text()
    assert "<name>CentralPharmacy</name>" in text
    world.write_text(text.replace("CentralPharmacy", 'Central"Ph/ar\\macy~é&#127;'))
    out = tmp_path / "out.json"
    assert main(["decompose", str(folder), "-q", "-o", str(out)]) == 0
    written = out.read_text(encoding="utf-8")
    escaped = 'Central\\"Ph\\/ar\\\\macy~\\u00C3\\u00A9\\u007F'
    assert f'            "locations": "{escaped}",\n' in written
    assert f'"predicate": "{escaped}.reachable",' in written
    assert written.isascii()
    tasks = json.loads(written)["tasks"]
    name = 'Central"Ph/ar\\macy~\u00c3\u00a9\x7f'  # the UTF-8 bytes of é, one escape each
    assert any(t["locations"] == name for t in tasks.values())


def test_xml_leaf_lists_are_left_out_when_empty():
    """``<locations>``, ``<triggering_events>``, ``<decomposition>``: one numbered leaf per text,
    and no element at all (not even an empty one) when there is nothing to list."""
    import io

    from mutrose_cp.output.builder import _XmlWriter

    fh = io.StringIO()
    w = _XmlWriter(fh)
    w.leaves("locations", "t", ["RoomA", "a<b"], 2)
    w.leaves("triggering_events", "event", (), 2)
    assert fh.getvalue() == ("        <locations>\n"
                             "            <t0>RoomA</t0>\n"
                             "            <t1>a&lt;b</t1>\n"
                             "        </locations>\n")


def test_a_large_document_is_written_while_it_is_serialized():
    """``write_boost_json`` streams: the same text as ``boost_json``, in several writes, for a
    document of more pieces than are gathered before a write (nested lists and dicts, empty
    members, the last member of each container without its comma)."""
    import io

    from mutrose_cp.output.boost_json import _FLUSH_PARTS

    tree = {"count": "3", "components": [{"count": str(i), "alternatives": [[f"t{i}", f"t{i + 1}"], []]}
                                         for i in range(_FLUSH_PARTS // 4)], "end": ""}
    writes: list[str] = []

    class Recorder(io.StringIO):
        def write(self, text: str) -> int:
            writes.append(text)
            return len(text)

    write_boost_json(tree, Recorder(), 4)
    assert "".join(writes) == boost_json(tree, 4)
    assert len(writes) > 2
