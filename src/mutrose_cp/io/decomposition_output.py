"""Reader of decomposition outputs (spec ``output.md``), ours or the original tool's.

The validator checks an output file against the mission it claims to decompose, so it reads the
file the way other tools do: the JSON object of the original (``""`` for an empty list, the
strings ``"True"``/``"False"``) or its XML form (several top-level elements, no single root;
``task<i>`` keys).  Both become one :class:`DecompositionOutput`.
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import Any

from lxml import etree

from ..errors import MissionError, Problem, located
from .text import decode_utf8, parse_json, read_bytes
from .tolerant_xml import source_line


@dataclass(frozen=True)
class OutputAction:
    """One action of a task's decomposition; ``args`` is None when the file does not list them
    (the XML form names the actions only)."""

    name: str
    args: tuple[str, ...] | None


@dataclass(frozen=True)
class RobotsNum:
    fixed: bool
    min: int
    max: int


@dataclass(frozen=True)
class OutputTask:
    """A decomposition of a task instance as the file lists it."""

    key: str  # "t3" (JSON) or "task3" (XML)
    id: str  # "AT1_2|3"
    name: str  # the HDDL abstract task
    arguments: tuple[tuple[str, str, str], ...]  # (parameter, type, value); value "" if unbound
    robots: RobotsNum | None
    actions: tuple[OutputAction, ...]
    locations: tuple[str, ...] = ()  # the value of the task's Location variable

    @property
    def instance(self) -> str:
        """The task instance (``AT1_2``) of which this is one decomposition."""
        return self.id.split("|", 1)[0]

    @property
    def gm_task(self) -> str:
        """The goal-model task (``AT1``) the instance was generated from."""
        return self.instance.split("_", 1)[0]


@dataclass(frozen=True)
class OutputConstraint:
    kind: str  # "SEQ" | "FB" | "EC"
    first: str
    second: str
    where: str  # "constraints[4]"
    # an EC's flags as written; None where the file leaves one out
    group: bool | None = None
    divisible: bool | None = None


@dataclass(frozen=True)
class DecompositionOutput:
    source: str
    tasks: dict[str, OutputTask]  # by key, file order
    constraints: tuple[OutputConstraint, ...]
    mission_decompositions: tuple[tuple[str, ...], ...]


def load_decomposition_output(path: str) -> DecompositionOutput:
    """Read an output file; the format is told by its first character (``<`` is XML)."""
    data = read_bytes(path, "decomposition output")
    if data.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"<"):
        return _from_xml(data, path)
    text = decode_utf8(data, path, "decomposition output")
    doc = parse_json(text, path)
    if not isinstance(doc, dict):
        raise MissionError(Problem(path, "expected a JSON object with tasks, constraints and mission_decompositions"))
    return _from_json(doc, path)


# ---------------------------------------------------------------------------------------------
# JSON


def _list(value: Any) -> list[Any]:
    """The original writes ``""`` for an empty list."""
    if value in ("", None):
        return []
    if isinstance(value, dict):
        return list(value.values())
    if isinstance(value, list):
        return value
    return [value]


def _flag(value: Any) -> bool:
    return str(value).strip().lower() in ("true", "1")


def _robots(value: Any) -> RobotsNum | None:
    if not isinstance(value, dict):
        return None
    try:
        if _flag(value.get("fixed", "True")):
            n = int(value["num"])
            return RobotsNum(True, n, n)
        return RobotsNum(False, int(value["min"]), int(value["max"]))
    except (KeyError, TypeError, ValueError):
        return None


def _from_json(doc: dict[str, Any], source: str) -> DecompositionOutput:
    tasks: dict[str, OutputTask] = {}
    raw_tasks = doc.get("tasks") or {}
    if not isinstance(raw_tasks, dict):
        raise MissionError(Problem(f"{source}: tasks", "expected an object of tasks keyed t0, t1, ..."))
    for key, t in raw_tasks.items():
        where = f"{source}: tasks.{key}"
        if not isinstance(t, dict) or not isinstance(t.get("id"), str) or not isinstance(t.get("name"), str):
            raise MissionError(Problem(where, "expected a task object with string fields id and name"))
        raw_types, raw_values = t.get("arguments"), t.get("arguments_values")
        types: dict[str, Any] = raw_types if isinstance(raw_types, dict) else {}
        values: dict[str, Any] = raw_values if isinstance(raw_values, dict) else {}
        arguments = tuple((str(p), str(ty), str(values.get(p, ""))) for p, ty in types.items())
        actions = []
        for a in _list(t.get("decomposition")):
            if not isinstance(a, dict) or "name" not in a:
                raise MissionError(Problem(where, "expected decomposition actions with a name"))
            args = a.get("arguments")
            actions.append(OutputAction(str(a["name"]), tuple(str(args).split()) if args is not None else None))
        locations = tuple(str(v) for v in _list(t.get("locations")))
        tasks[key] = OutputTask(key, t["id"], t["name"], arguments, _robots(t.get("robots_num")), tuple(actions),
                                locations)
    constraints = []
    for i, c in enumerate(_list(doc.get("constraints"))):
        inst = c.get("task_instances") if isinstance(c, dict) else None
        if not isinstance(inst, dict) or "t0" not in inst or "t1" not in inst:
            raise MissionError(Problem(f"{source}: constraints[{i}]", "expected task_instances with t0 and t1"))
        kind = str(c.get("type"))
        if kind == "EC" and "group" not in c and "divisible" not in c:
            kind = "FB"  # the original writes a fallback constraint as an EC without group/divisible
        group, divisible = (_flag(c[flag]) if flag in c else None for flag in ("group", "divisible"))
        constraints.append(OutputConstraint(kind, str(inst["t0"]), str(inst["t1"]), f"constraints[{i}]", group,
                                            divisible))
    mds = tuple(tuple(str(k) for k in _list(md)) for md in _list(doc.get("mission_decompositions")))
    return DecompositionOutput(source, tasks, tuple(constraints), mds)


# ---------------------------------------------------------------------------------------------
# XML

_XML_DECLARATION = re.compile(rb"^\s*(?:\xef\xbb\xbf)?\s*<\?xml[^>]*\?>")


def _texts(el: etree._Element | None) -> list[str]:
    return [] if el is None else [(c.text or "").strip() for c in el if isinstance(c.tag, str)]


def _from_xml(data: bytes, source: str) -> DecompositionOutput:
    # the original writes several top-level elements: wrap them (on line 1, so lines stay right)
    body = _XML_DECLARATION.sub(b"", data, count=1)
    parser = etree.XMLParser(resolve_entities=False, no_network=True, load_dtd=False, huge_tree=False)
    try:
        root = etree.fromstring(b"<output>" + body + b"</output>", parser)
    except etree.XMLSyntaxError as exc:
        line, col = exc.position if exc.position else (None, None)
        raise MissionError(Problem(located(source, line, col), f"XML syntax error in the output: {exc.msg}")) from None
    tasks: dict[str, OutputTask] = {}
    for t in root.findall("tasks/*"):
        where = located(source, source_line(t))
        tid, name = t.findtext("id"), t.findtext("name")
        if tid is None or name is None:
            raise MissionError(Problem(where, f"task element <{t.tag}> needs <id> and <name>"))
        arguments = tuple(((a.findtext("name") or "").strip(), (a.findtext("type") or "").strip(),
                           (a.findtext("value") or "").strip()) for a in t.findall("arguments/*"))
        rn = t.find("robots_num")
        robots = None
        if rn is not None:
            robots = _robots({k: rn.get(k) for k in ("fixed", "num", "min", "max") if rn.get(k) is not None})
        actions = tuple(OutputAction(n, None) for n in _texts(t.find("decomposition")))
        tasks[t.tag] = OutputTask(t.tag, tid.strip(), name.strip(), arguments, robots, actions,
                                  tuple(v for v in _texts(t.find("locations")) if v))
    constraints = []
    for i, c in enumerate(root.findall("constraints/*")):
        ends = _texts(c.find("task_instances"))
        if len(ends) != 2:
            raise MissionError(Problem(located(source, source_line(c)), "a constraint needs two task instances"))
        kind = (c.findtext("type") or "").strip()
        if kind == "EC" and c.find("group") is None and c.find("divisible") is None:
            kind = "FB"  # a fallback constraint, as in the JSON form
        group, divisible = (None if c.find(flag) is None else _flag(c.findtext(flag)) for flag in ("group", "divisible"))
        constraints.append(OutputConstraint(kind, ends[0], ends[1], f"line {source_line(c)}", group, divisible))
    mds = tuple(tuple(_texts(d.find("tasks"))) for d in root.findall("mission_decompositions/*"))
    return DecompositionOutput(source, tasks, tuple(constraints), mds)
