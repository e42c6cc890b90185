"""The XML form of an output (output.md §4): several top-level elements and no single root,
``task<i>`` keys, empty lists left out.

The document is read as a stream (a pull parser, fed a block at a time): each task, constraint,
action and mission decomposition is read when its element ends and then dropped, so that the
memory holds what was read, not the document's tree (the XML of 200,000 decompositions runs to
150 MB, and its tree to several GB).
"""
from __future__ import annotations

import re
import sys
from typing import Iterator

from lxml import etree

from ...errors import MissionError, Problem, located
from ..tolerant_xml import source_line
from .fields import flag, require_sections, robots
from .records import Capabilities, DecompositionOutput, OutputAction, OutputConstraint, OutputPredicate, OutputTask

_DECLARATION = re.compile(rb"^\s*(?:\xef\xbb\xbf)?\s*<\?xml[^>]*\?>")
BLOCK = 1 << 20  # bytes fed to the parser at a time


def _texts(el: etree._Element | None) -> list[str]:
    return [] if el is None else [(c.text or "").strip() for c in el if isinstance(c.tag, str)]


def _predicates(el: etree._Element | None) -> tuple[OutputPredicate, ...]:
    if el is None:
        return ()
    return tuple(OutputPredicate((p.text or "").strip(), p.get("vars", ""), p.get("var_types", ""))
                 for p in el if isinstance(p.tag, str))


def _flag(t: etree._Element, field: str, problems: list[tuple[str, str]]) -> bool | None:
    text = t.findtext(field)
    if text is None:
        problems.append((field, "is missing"))
        return None
    value = flag(text)
    if value is None:
        problems.append((field, f"is neither True nor False: {text!r}"))
    return value


def _task(t: etree._Element, source: str) -> OutputTask:
    tid, name = t.findtext("id"), t.findtext("name")
    if tid is None or name is None:
        raise MissionError(Problem(located(source, source_line(t)), f"task element <{t.tag}> needs <id> and <name>"))
    problems: list[tuple[str, str]] = []
    arguments = tuple(((a.findtext("name") or "").strip(), (a.findtext("type") or "").strip(),
                       (a.findtext("value") or "").strip()) for a in t.findall("arguments/*"))
    rn = t.find("robots_num")
    robot_number = None
    if rn is None:
        problems.append(("robots_num", "is missing"))
    else:
        robot_number = robots({k: rn.get(k) for k in ("fixed", "num", "min", "max") if rn.get(k) is not None})
        if robot_number is None:
            problems.append(("robots_num", f"is not a robot number: {sorted(rn.items())!r}"))
    actions = tuple(OutputAction(n, None) for n in _texts(t.find("decomposition")))
    return OutputTask(sys.intern(str(t.tag)), tid.strip(), name.strip(), arguments, robot_number, actions,
                      tuple(v for v in _texts(t.find("locations")) if v), f"line {source_line(t)}",
                      tuple((p, v) for p, _, v in arguments), _predicates(t.find("preconditions")),
                      _predicates(t.find("effects")), tuple(_texts(t.find("triggering_events"))),
                      _flag(t, "group", problems), _flag(t, "divisible", problems), tuple(problems))


def _constraint(c: etree._Element, source: str) -> OutputConstraint:
    ends = _texts(c.find("task_instances"))
    if len(ends) != 2:
        raise MissionError(Problem(located(source, source_line(c)), "a constraint needs two task instances"))
    kind = (c.findtext("type") or "").strip()
    if kind == "EC" and c.find("group") is None and c.find("divisible") is None:
        kind = "FB"  # a fallback constraint, as in the JSON form
    group, divisible = (None if c.find(name) is None else flag(c.findtext(name)) for name in ("group", "divisible"))
    return OutputConstraint(kind, ends[0], ends[1], f"line {source_line(c)}", group, divisible)


def _action(a: etree._Element) -> tuple[str, Capabilities]:
    caps = a.find("capabilities")
    return a.findtext("name", "").strip(), None if caps is None else tuple(_texts(caps))


class _Reading:
    """What the stream has given so far, by top-level section."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.sections: set[str] = set()
        self.tasks: dict[str, OutputTask] = {}
        self.constraints: list[OutputConstraint] = []
        self.listing: list[tuple[str, ...]] = []
        self.actions: list[tuple[str, Capabilities]] | None = None

    def ended(self, el: object) -> None:
        """An element has ended: an entry of a section is read (and dropped, with what came
        before it), a section is noted."""
        if not isinstance(el, etree._Element) or not isinstance(el.tag, str):
            return
        parent = el.getparent()
        if parent is None:
            return  # the root around the sections
        above = parent.getparent()
        if above is None:
            self.sections.add(el.tag)
            if el.tag == "actions" and self.actions is None:
                self.actions = []
        elif above.getparent() is None:
            self._entry(str(parent.tag), el)
            el.clear()
            while el.getprevious() is not None:
                del parent[0]

    def _entry(self, section: str, el: etree._Element) -> None:
        if section == "tasks":
            task = _task(el, self.source)
            self.tasks[task.key] = task
        elif section == "constraints":
            self.constraints.append(_constraint(el, self.source))
        elif section == "mission_decompositions":
            self.listing.append(tuple(sys.intern(k) for k in _texts(el.find("tasks"))))
        elif section == "actions":
            self.actions = self.actions if self.actions is not None else []
            self.actions.append(_action(el))


def _blocks(data: bytes) -> Iterator[bytes]:
    """The document inside one root element (on line 1, so that lines stay right)."""
    yield b"<output>"
    declaration = _DECLARATION.match(data)
    for start in range(declaration.end() if declaration else 0, len(data), BLOCK):
        yield data[start:start + BLOCK]
    yield b"</output>"


def read_xml(data: bytes, source: str) -> DecompositionOutput:
    parser = etree.XMLPullParser(events=("end",), resolve_entities=False, no_network=True, load_dtd=False,
                                 huge_tree=False)
    reading = _Reading(source)
    try:
        for block in _blocks(data):
            parser.feed(block)
            for _, el in parser.read_events():
                reading.ended(el)
        parser.close()
        for _, el in parser.read_events():
            reading.ended(el)
    except etree.XMLSyntaxError as exc:
        line, col = exc.position if exc.position else (None, None)
        raise MissionError(Problem(located(source, line, col), f"XML syntax error in the output: {exc.msg}")) from None
    require_sections(reading.sections, source, "XML elements")
    return DecompositionOutput(source, reading.tasks, tuple(reading.constraints), tuple(reading.listing), "xml",
                               None if reading.actions is None else tuple(reading.actions))
