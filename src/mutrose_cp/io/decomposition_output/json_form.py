"""The JSON form of an output (output.md §2): the original's (``""`` for an empty list, the
strings ``"True"``/``"False"``) and the standard style (``[]``, numbers and booleans).

The document is read member by member.  ``mission_decompositions``, which may list hundreds of
thousands of decompositions, is decoded one decomposition at a time, each kept as a tuple of
interned task keys (a pointer per key, where the decoded lists would cost a string each); the
other sections are decoded whole.
"""
from __future__ import annotations

import json
import re
import sys
from typing import Any

from ...errors import MissionError, Problem
from ..text import json_depth_problem, json_syntax_problem, parse_json
from .fields import as_list, flag, require_sections, robots
from .records import Capabilities, DecompositionOutput, OutputAction, OutputConstraint, OutputPredicate, OutputTask

_SPACE = re.compile(r"[ \t\n\r]*")
_ESCAPED_BYTE = re.compile(r"\\u00[89a-fA-F][0-9a-fA-F]")  # a byte past ASCII, as the original escapes it
_DECODER = json.JSONDecoder()
LISTING = "mission_decompositions"


class _Document:
    """A JSON text read from its top-level object, with errors located as ``json.loads`` would
    locate them."""

    def __init__(self, text: str, source: str) -> None:
        self.text = text
        self.source = source
        # the original's style escapes every byte past ASCII, so its file is ASCII throughout;
        # the standard style writes UTF-8 as it is, and its strings are read as they are.  A
        # file with no escaped byte at all (most) is read without walking its values again
        self.escaped_bytes = text.isascii() and _ESCAPED_BYTE.search(text) is not None

    def error(self, message: str, pos: int) -> MissionError:
        return MissionError(json_syntax_problem(json.JSONDecodeError(message, self.text, pos), self.text, self.source))

    def skip(self, pos: int) -> int:
        match = _SPACE.match(self.text, pos)
        return match.end() if match else pos

    def expect(self, pos: int, char: str, message: str) -> int:
        if self.text[pos:pos + 1] != char:
            raise self.error(message, pos)
        return self.skip(pos + 1)

    def next_item(self, pos: int, close: str, trailing: str) -> int:
        """Past the ``,`` after an item of an object or array, at the next item; or at the
        closing bracket ``close`` (a comma right before it is an error, ``trailing``)."""
        pos = self.skip(pos)
        if self.text[pos:pos + 1] == ",":
            pos = self.skip(pos + 1)
            if self.text[pos:pos + 1] == close:
                raise self.error(trailing, pos)
        elif self.text[pos:pos + 1] != close:
            raise self.error("Expecting ',' delimiter", pos)
        return pos

    def value(self, pos: int) -> tuple[Any, int]:
        try:
            value, end = _DECODER.raw_decode(self.text, pos)
            return (_utf8_text(value) if self.escaped_bytes else value), end
        except json.JSONDecodeError as err:
            raise MissionError(json_syntax_problem(err, self.text, self.source)) from None
        except RecursionError:
            raise MissionError(json_depth_problem(self.text, self.source)) from None

    def members(self) -> dict[str, Any]:
        """The top-level object's members (a repeated key keeps its last value, as in
        ``json.loads``); the listing of decompositions is read as :meth:`listing` reads it."""
        pos = self.skip(0)
        if self.text[pos:pos + 1] != "{":
            parse_json(self.text, self.source)  # a syntax error is reported as such
            raise MissionError(Problem(self.source, "expected a JSON object with tasks, constraints and "
                                                    "mission_decompositions"))
        members: dict[str, Any] = {}
        pos = self.skip(pos + 1)
        while self.text[pos:pos + 1] != "}":
            if self.text[pos:pos + 1] != '"':
                raise self.error("Expecting property name enclosed in double quotes", pos)
            key, pos = self.value(pos)
            pos = self.expect(self.skip(pos), ":", "Expecting ':' delimiter")
            listing = key == LISTING and self.text[pos:pos + 1] == "["
            members[key], pos = self.listing(pos) if listing else self.value(pos)
            pos = self.next_item(pos, "}", "Expecting property name enclosed in double quotes")
        end = self.skip(pos + 1)
        if end != len(self.text):
            raise self.error("Extra data", end)
        return members

    def listing(self, pos: int) -> tuple[tuple[tuple[str, ...], ...], int]:
        """The array of mission decompositions at ``pos``, one decomposition at a time."""
        out: list[tuple[str, ...]] = []
        pos = self.skip(pos + 1)
        while self.text[pos:pos + 1] != "]":
            element, pos = self.value(pos)
            out.append(decomposition_keys(element, len(out), self.source))
            pos = self.next_item(pos, "]", "Expecting value")
        return tuple(out), pos + 1


def decomposition_keys(element: Any, i: int, source: str) -> tuple[str, ...]:
    """One mission decomposition: a list of task keys (``""`` for none, a string for one)."""
    keys = [element] if isinstance(element, str) and element else as_list(element)
    if keys is None or not all(type(k) is str for k in keys):
        raise MissionError(Problem(f"{source}: {LISTING}[{i}]", "expected a list of task keys"))
    return tuple(sys.intern(k) for k in keys)


class _JsonTask:
    """One entry of ``tasks``, read field by field; what cannot be read becomes a problem."""

    def __init__(self, key: str, t: dict[str, Any], source: str) -> None:
        self.key = key
        self.t = t
        self.where = f"tasks.{key}"
        self.problems: list[tuple[str, str]] = []
        if not isinstance(t.get("id"), str) or not isinstance(t.get("name"), str):
            raise MissionError(Problem(f"{source}: {self.where}", "expected a task object with string fields id and name"))

    def absent(self, field: str) -> bool:
        if field not in self.t:
            self.problems.append((field, "is missing"))
            return True
        return False

    def object(self, field: str) -> dict[str, Any] | None:
        if self.absent(field):
            return None
        value = self.t[field]
        if value == "":
            return {}
        if not isinstance(value, dict):
            self.problems.append((field, f"is not an object: {value!r}"))
            return None
        return value

    def items(self, field: str) -> list[Any] | None:
        if self.absent(field):
            return None
        items = as_list(self.t[field])
        if items is None:
            self.problems.append((field, f"is not a list: {self.t[field]!r}"))
        return items

    def predicates(self, field: str) -> tuple[OutputPredicate, ...] | None:
        items = self.items(field)
        if items is None:
            return None
        out = []
        for p in items:
            if not isinstance(p, dict) or "predicate" not in p:
                self.problems.append((field, f"has an entry that is not a predicate object: {p!r}"))
                return None
            out.append(OutputPredicate(str(p["predicate"]), str(p.get("vars", "")), str(p.get("var_types", ""))))
        return tuple(out)

    def actions(self) -> tuple[OutputAction, ...]:
        out = []
        for a in (self.object("decomposition") or {}).values():
            if not isinstance(a, dict) or "name" not in a:
                self.problems.append(("decomposition", f"has an action that is not an object with a name: {a!r}"))
                continue
            args = a.get("arguments")
            if args is None:
                self.problems.append(("decomposition", f"action {a['name']} has no arguments"))
            out.append(OutputAction(str(a["name"]), tuple(str(args).split()) if args is not None else None))
        return tuple(out)

    def locations(self) -> tuple[str, ...]:
        if self.absent("locations"):
            return ()
        value = self.t["locations"]
        if isinstance(value, list):
            return tuple(str(v) for v in value)
        return (str(value),) if value != "" else ()

    def flag(self, field: str) -> bool | None:
        if self.absent(field):
            return None
        value = flag(self.t[field])
        if value is None:
            self.problems.append((field, f"is neither True nor False: {self.t[field]!r}"))
        return value

    def read(self) -> OutputTask:
        t = self.t
        types = self.object("arguments")
        values = self.object("arguments_values")
        arguments = tuple((str(p), str(ty), str((values or {}).get(p, ""))) for p, ty in (types or {}).items())
        robot_number = None if self.absent("robots_num") else robots(t["robots_num"])
        if robot_number is None and "robots_num" in t:
            self.problems.append(("robots_num", f"is not a robot number: {t['robots_num']!r}"))
        events = self.items("triggering_events")
        return OutputTask(
            sys.intern(self.key), t["id"], t["name"], arguments, robot_number, self.actions(), self.locations(),
            self.where, None if values is None else tuple((str(p), str(v)) for p, v in values.items()),
            self.predicates("preconditions"), self.predicates("effects"),
            None if events is None else tuple(str(e) for e in events),
            self.flag("group"), self.flag("divisible"), tuple(self.problems))


def _constraint(i: int, c: Any, source: str) -> OutputConstraint:
    inst = c.get("task_instances") if isinstance(c, dict) else None
    if not isinstance(inst, dict) or "t0" not in inst or "t1" not in inst:
        raise MissionError(Problem(f"{source}: constraints[{i}]", "expected task_instances with t0 and t1"))
    kind = str(c.get("type"))
    if kind == "EC" and "group" not in c and "divisible" not in c:
        kind = "FB"  # the original writes a fallback constraint as an EC without group/divisible
    group, divisible = (flag(c[name]) if name in c else None for name in ("group", "divisible"))
    return OutputConstraint(kind, str(inst["t0"]), str(inst["t1"]), f"constraints[{i}]", group, divisible)


def _actions(value: Any) -> tuple[tuple[str, Capabilities], ...] | None:
    """The ``actions`` section; an entry that is a bare name, or an object without
    capabilities, gives none (None)."""
    items = as_list(value)
    if items is None or not all(isinstance(a, str) or (isinstance(a, dict) and "name" in a) for a in items):
        return None
    out: list[tuple[str, Capabilities]] = []
    for a in items:
        if isinstance(a, str) or "capabilities" not in a:
            out.append((str(a if isinstance(a, str) else a["name"]), None))
            continue
        caps = a["capabilities"]
        out.append((str(a["name"]), tuple(str(c) for c in caps) if isinstance(caps, list) else str(caps)))
    return tuple(out)


UNCERTAINTY = "mission_decomposition_uncertainty"


def _section(doc: dict[str, Any], key: str, source: str) -> list[Any]:
    items = as_list(doc[key])
    if items is None:
        raise MissionError(Problem(f"{source}: {key}", f"expected a list (or \"\"), not {type(doc[key]).__name__}"))
    return items


def _utf8_text(value: Any) -> Any:
    """``value`` with the original's escapes undone: its JSON style writes each byte of a
    UTF-8 name as ``\\u00XX`` (``Zimmer_ü202`` as ``Zimmer_\\u00C3\\u00BC202``), so a
    string of such characters that are the bytes of UTF-8 text is that text.  A string with
    a character past U+00FF, or whose bytes are not UTF-8, is as written.  Only for a file in
    ASCII throughout, as the original's style writes it (the standard style writes UTF-8)."""
    if isinstance(value, str):
        if value.isascii() or max(value) > "\u00ff":
            return value
        try:
            return value.encode("latin-1").decode("utf-8")
        except UnicodeDecodeError:
            return value
    if isinstance(value, dict):
        return {_utf8_text(k): _utf8_text(v) for k, v in value.items()}
    if isinstance(value, list):
        return [_utf8_text(v) for v in value]
    return value


def read_json(text: str, source: str) -> DecompositionOutput:
    doc = _Document(text, source).members()
    require_sections(set(doc), source, "JSON keys")
    raw_tasks = doc["tasks"] if doc["tasks"] != "" else {}
    if not isinstance(raw_tasks, dict):
        raise MissionError(Problem(f"{source}: tasks", "expected an object of tasks keyed t0, t1, ..."))
    tasks: dict[str, OutputTask] = {}
    for key, t in raw_tasks.items():
        if not isinstance(t, dict):
            raise MissionError(Problem(f"{source}: tasks.{key}", "expected a task object with string fields id and name"))
        task = _JsonTask(key, t, source).read()
        tasks[task.key] = task
    constraints = tuple(_constraint(i, c, source) for i, c in enumerate(_section(doc, "constraints", source)))
    listing = doc[LISTING]
    if not isinstance(listing, tuple):  # "" or an object: not read as it was decoded
        listing = tuple(decomposition_keys(md, i, source) for i, md in enumerate(_section(doc, LISTING, source)))
    return DecompositionOutput(source, tasks, constraints, listing, "json",
                               _actions(doc["actions"]) if "actions" in doc else None, _assumed_world(doc, source))


def _assumed_world(doc: dict[str, Any], source: str) -> tuple[tuple[str, str, str], ...]:
    """The world an output's tasks were expanded in, from its uncertainty section's ``world``
    (docs/formats/output.md): each entity's attribute and the value it was given."""
    section = doc.get(UNCERTAINTY)
    if not isinstance(section, dict) or "world" not in section:
        return ()
    items = section["world"]
    where = f"{source}: {UNCERTAINTY}.world"
    if not isinstance(items, list):
        raise MissionError(Problem(where, "expected a list of {entity, attribute, value}"))
    found = []
    for i, item in enumerate(items):
        if not isinstance(item, dict) or not all(isinstance(item.get(k), str) for k in ("entity", "attribute", "value")):
            raise MissionError(Problem(f"{where}[{i}]", "expected an object with strings entity, attribute and value"))
        found.append((item["entity"], item["attribute"], item["value"]))
    return tuple(found)
