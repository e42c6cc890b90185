"""Goal model reader: piStar/GODA JSON (spec ``goal-model.md``).

Builds the tree with the original's child order (children left to right by ``x``), reads every
custom property, and parses the embedded expressions.  Problems are collected per node so that
``check`` can report all of them; each is located by file and goal/task id.
"""
from __future__ import annotations

import json
import math
import os
import re
from dataclasses import dataclass, field
from typing import Any, Callable, TypeVar

from ..errors import MissionError, Problem, closest
from ..model.goal_model import Context, GMNode, GoalModel, RobotNumber, VarDecl
from .expressions import FORALL_HINT, SELECT_HINT, parse_condition, parse_forall, parse_node_text, parse_select
from .text import decode_utf8, parse_json, read_bytes

# ---------------------------------------------------------------------------------------------
# Reader

ISTAR_GOAL = "istar.Goal"
ISTAR_TASK = "istar.Task"
OR_REFINEMENT = "istar.OrRefinementLink"

GOAL_TYPES = ("Perform", "Achieve", "Query")

#: customProperties keys the original accepts (case-sensitive); anything else is an error.
KNOWN_PROPERTIES = frozenset(
    {
        "Description",
        "GoalType",
        "Controls",
        "Monitors",
        "CreationCondition",
        "AchieveCondition",
        "QueriedProperty",
        "Group",
        "Divisible",
        "Location",
        "Params",
        "RobotNumber",
    }
)

_GOAL_ID = re.compile(r"G[0-9]+")
_TASK_ID = re.compile(r"[AT]{2}[0-9]+")  # the original's class: TA1 would match too
_TASK_NAME = re.compile(r"[a-zA-Z]+")
# The original's character classes, including the C++ ``A-z`` range that also admits
# ``[\]^_` `` (which is why ``current_room`` is one name).
_VAR_NAME = re.compile(r"[a-zA-Z][a-zA-z0-9]*")
_VAR_TYPE = re.compile(r"[a-zA-z0-9]+([(][a-zA-z]+[)])?")
_ROBOTS_RANGE = re.compile(r"\[(\d+),(\d+)\]", re.ASCII)
_ROBOTS_FIXED = re.compile(r"\d+", re.ASCII)

_T = TypeVar("_T")


def load_goal_model(path: str | os.PathLike[str]) -> GoalModel:
    """Read and parse a goal model file (any extension; the examples use ``.txt``).

    Raises :class:`MissionError` located at the path when the file is missing or unreadable,
    at ``file:line:col`` for invalid JSON, and with every node/link problem otherwise.
    """
    source = os.fspath(path)
    data = read_bytes(source, "goal model")
    return parse_goal_model(decode_utf8(data, source, "goal model"), source)


def parse_goal_model(text: str, source: str) -> GoalModel:
    """Parse piStar/GODA JSON text (``source`` names it in messages) into a :class:`GoalModel`.

    All problems of all nodes and links are collected and raised together as one
    :class:`MissionError`; each is located as ``<source>: goal G3`` / ``task AT1`` /
    ``node <piStar id>`` / ``link <piStar id>``.
    """
    return _Reader(source).read(parse_json(text, source))


def _scalar_text(value: Any) -> str | None:
    """A JSON scalar as the text the original's property-tree parser would give (None: not a scalar)."""
    if isinstance(value, str):
        return value
    if isinstance(value, bool):
        return "true" if value else "false"
    if isinstance(value, (int, float)):
        return json.dumps(value)
    if value is None:
        return "null"
    return None


def _number(value: Any) -> float | None:
    """A coordinate: a finite JSON number, or a numeric string (the original reads every scalar
    as text).  Non-finite values are refused because coordinates are sort keys."""
    if isinstance(value, bool) or not isinstance(value, (int, float, str)):
        return None
    try:
        number = float(value)
    except ValueError:
        return None
    return number if math.isfinite(number) else None


def _flag(value: str | None) -> tuple[bool, bool]:
    """``Group``/``Divisible``: (value, recognised).  ``True``/``False`` in any case, else True."""
    if value is None:
        return True, True
    lowered = value.lower()
    if lowered in ("true", "false"):
        return lowered == "true", True
    return True, False


def parse_var_decls(value: str) -> tuple[VarDecl, ...]:
    """``Controls``/``Monitors``: comma separated ``name : Type`` (spec §4.1).

    Raises ValueError ``Invalid variable declaration <piece> in GM.`` for a piece without a name.
    """
    value = value.strip()
    if not value:
        return ()
    decls: list[VarDecl] = []
    for piece in value.split(","):
        left, _, right = piece.partition(":")
        name = _VAR_NAME.search(left)
        if name is None:
            raise ValueError(f"Invalid variable declaration {piece} in GM.")
        words = right.split()
        type_match = _VAR_TYPE.search(words[0]) if words else None
        decls.append(VarDecl(name.group(), type_match.group() if type_match else ""))
    return tuple(decls)


def parse_robot_number(value: str) -> RobotNumber:
    """``RobotNumber`` (already trimmed): ``n`` or ``[n1,n2]`` with no inner spaces (spec §4).

    Raises ValueError ``Invalid declaration of robot number: <text>``.
    """
    if (m := _ROBOTS_RANGE.fullmatch(value)) is not None:
        low, high = int(m[1]), int(m[2])
        if high == 0:
            raise ValueError(f"Invalid declaration of robot number: {value} (a task needs at least one robot)")
        if low > high:
            raise ValueError(
                f"Invalid declaration of robot number: {value} (lower bound greater than upper bound)"
            )
        return RobotNumber(low, high, fixed=False)
    if _ROBOTS_FIXED.fullmatch(value) is not None:
        if int(value) == 0:
            raise ValueError(f"Invalid declaration of robot number: {value} (a task needs at least one robot)")
        return RobotNumber(int(value), int(value), fixed=True)
    raise ValueError(f"Invalid declaration of robot number: {value}")


#: How to fix the values rejected with the original's messages, by message prefix.
HINTS = {
    "Invalid declaration of robot number": "Write a number of robots such as 2, or a range such as "
    "[2,4], with no spaces.",
    "Invalid variable declaration": "Declare variables as name : Type separated by commas, e.g. "
    "rooms : Sequence(Room), current_room : Room.",
    "Invalid forAll statement": FORALL_HINT,
    "Invalid select statement": SELECT_HINT,
}


def _hint_for(message: str) -> str:
    return next((hint for prefix, hint in HINTS.items() if message.startswith(prefix)), "")


def parse_params(value: str) -> tuple[str, ...]:
    """``Params``: comma separated variable names, each trimmed; empty pieces are dropped."""
    return tuple(p for p in (piece.strip() for piece in value.split(",")) if p)


def _property_hint(key: str) -> str:
    """How to fix an unknown custom property: the closest known key, and the list."""
    by_lower = {k.lower(): k for k in KNOWN_PROPERTIES}
    close = closest(key.lower(), by_lower, cutoff=0.6)
    known = ", ".join(sorted(KNOWN_PROPERTIES))
    if close:
        return f"Did you mean {by_lower[close]}? Keys are case-sensitive; the known keys are {known}."
    return f"Remove it or use one of the known (case-sensitive) keys: {known}."


def _node_id(kind: str | None, text: str | None) -> str:
    """The goal (``G3``) or task (``AT1``) id at the start of a node's text; "" when absent."""
    if not kind or text is None:
        return ""
    head = text.split(":", 1)[0]
    id_match = (_GOAL_ID if kind == "goal" else _TASK_ID).search(head)
    return id_match.group() if id_match else ""


def _node_where(kind: str | None, node_id: str, uid: str | None, index: int) -> str:
    """How problems name a node: by its id, else its piStar id, else its position."""
    if node_id:
        return f"{kind} {node_id}"
    if uid is not None:
        return f"node {uid}"
    return f"node #{index + 1}"


@dataclass
class _Draft:
    """A node as read, before the tree fields (children/parent/or_decomposed) are known."""

    index: int  # position in the file's node list
    uid: str
    id: str
    kind: str
    x: float
    where: str
    fields: dict[str, Any] = field(default_factory=dict)


@dataclass
class _Link:
    id: str
    type: str
    child: int  # index into the drafts list
    parent: int


class _Reader:
    """One goal-model read: collects problems and warnings, builds the tree."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.problems: list[Problem] = []
        self.warnings: list[str] = []

    # -- reporting ------------------------------------------------------------------------------

    def _where(self, what: str) -> str:
        return f"{self.source}: {what}" if self.source else what

    def problem(self, what: str, message: str, hint: str = "") -> None:
        self.problems.append(Problem(self._where(what), message, hint))

    def warn(self, what: str, message: str) -> None:
        self.warnings.append(str(Problem(self._where(what), message)))

    def _raise_if_problems(self) -> None:
        if self.problems:
            raise MissionError(self.problems)

    def _attempt(self, what: str, prefix: str, parse: Callable[[], _T]) -> _T | None:
        """Run a property parser, turning its error into a located problem with advice on how to
        fix it (None on error)."""
        try:
            return parse()
        except MissionError as err:
            for p in err.problems:
                self.problem(what, f"{prefix}{p.message}", getattr(p, "hint", "") or _hint_for(p.message))
        except ValueError as err:
            self.problem(what, f"{prefix}{err}", _hint_for(str(err)))
        return None

    # -- top level ------------------------------------------------------------------------------

    def read(self, data: Any) -> GoalModel:
        top = self.source or "goal model"
        if not isinstance(data, dict):
            raise MissionError("the goal model must be a JSON object (piStar format)", self.source)
        raw_nodes = self._raw_nodes(data)
        raw_links = data.get("links")
        if not isinstance(raw_links, list):
            self.problem("links", "the goal model has no 'links' array")
            raw_links = []

        drafts = [d for i, raw in enumerate(raw_nodes or []) if (d := self._read_node(i, raw)) is not None]
        by_uid = self._index_by_uid(drafts)
        links = [k for i, raw in enumerate(raw_links) if (k := self._read_link(i, raw, by_uid)) is not None]
        self._raise_if_problems()
        if not drafts:
            raise MissionError("the goal model has no nodes", top)
        return self._build(drafts, links)

    def _raw_nodes(self, data: dict[str, Any]) -> Any:
        """The node list the original reads: it overwrites its node list for every actor that
        has one, so the last actor with nodes wins."""
        actors = data.get("actors")
        if not isinstance(actors, list) or not actors:
            self.problem("actors", "the goal model has no 'actors' array with an actor")
            actors = []
        raw_nodes: Any = None
        for actor in actors:
            if isinstance(actor, dict) and "nodes" in actor:
                raw_nodes = actor["nodes"]
        if len(actors) > 1:
            self.warn("actors", f"{len(actors)} actors: only the nodes of the last actor with nodes are used")
        if actors and not isinstance(raw_nodes, list):
            self.problem("actors", "no actor has a 'nodes' array")
        return raw_nodes

    def _index_by_uid(self, drafts: list[_Draft]) -> dict[str, int]:
        """piStar id -> position in ``drafts``, which links refer to; a reused id is a problem
        (the first node keeps it)."""
        by_uid: dict[str, int] = {}
        for position, draft in enumerate(drafts):
            if draft.uid in by_uid:
                other = drafts[by_uid[draft.uid]]
                self.problem(draft.where, f"duplicate piStar node id {draft.uid} (also used by {other.where})")
            else:
                by_uid[draft.uid] = position
        return by_uid

    # -- nodes ----------------------------------------------------------------------------------

    def _read_node(self, index: int, raw: Any) -> _Draft | None:
        if not isinstance(raw, dict):
            self.problem(f"node #{index + 1}", "a node must be a JSON object")
            return None
        uid = _scalar_text(raw["id"]) if "id" in raw else None
        text = _scalar_text(raw["text"]) if "text" in raw else None
        node_type = _scalar_text(raw["type"]) if "type" in raw else None
        kind = {ISTAR_GOAL: "goal", ISTAR_TASK: "task"}.get(node_type or "")
        node_id = _node_id(kind, text)
        where = _node_where(kind, node_id, uid, index)

        ok = self._check_node_keys(where, raw, {"id": uid, "text": text, "type": node_type})
        coordinates, numeric = self._coordinates(where, raw)
        props = self._custom_properties(where, raw)
        ok = ok and numeric and props is not None
        if node_type is not None and kind is None:
            self.problem(where, f"unsupported node type {node_type}: only {ISTAR_GOAL} and {ISTAR_TASK} are supported")
            ok = False
        if uid is None:
            return None
        # A draft is returned even for a broken node so that its links are not also reported as
        # dangling; the model is only built when no problem was found.
        fields: dict[str, Any] = {"text": text, "y": coordinates.get("y", 0.0)}
        draft = _Draft(index, uid, node_id, kind or "", coordinates.get("x", 0.0), where, fields)
        if not ok or text is None or kind is None or props is None:
            return draft
        if kind == "goal":
            if self._read_goal_text(where, text, node_id):
                fields["annotation"] = self._attempt(where, "", lambda: parse_node_text(text)[1])
        else:
            self._read_task_text(where, text, node_id, fields)
        self._read_properties(where, node_id, text, props, fields)
        return draft

    def _check_node_keys(self, where: str, raw: dict[str, Any], texts: dict[str, str | None]) -> bool:
        """Every key a node needs is present, and ``id``/``text``/``type`` (read into ``texts``)
        are scalars; False when a problem was reported."""
        ok = True
        missing = [k for k in ("id", "text", "type", "x", "y", "customProperties") if k not in raw]
        if missing:
            self.problem(where, "node is missing " + ", ".join(repr(k) for k in missing))
            ok = False
        for key, value in texts.items():
            if key in raw and value is None:
                self.problem(where, f"node {key!r} must be a string")
                ok = False
        return ok

    def _coordinates(self, where: str, raw: dict[str, Any]) -> tuple[dict[str, float], bool]:
        """``x`` and ``y`` as numbers (those present and numeric), and whether none was refused."""
        coordinates: dict[str, float] = {}
        ok = True
        for axis in ("x", "y"):
            if axis in raw:
                number = _number(raw[axis])
                if number is None:
                    self.problem(where, f"node {axis!r} must be a number, not {json.dumps(raw[axis])}")
                    ok = False
                else:
                    coordinates[axis] = number
        return coordinates, ok

    def _custom_properties(self, where: str, raw: dict[str, Any]) -> dict[str, str] | None:
        """``customProperties`` as texts, the way the original's property tree holds them;
        None when it is not an object or a value is not a scalar."""
        raw_props = raw.get("customProperties", {})
        if not isinstance(raw_props, dict):
            self.problem(where, "node 'customProperties' must be a JSON object")
            return None
        props: dict[str, str] = {}
        ok = True
        for key, value in raw_props.items():
            value_text = _scalar_text(value)
            if value_text is None:
                self.problem(where, f"custom property {key} must be a string")
                ok = False
            else:
                props[key] = value_text
        return props if ok else None

    def _read_goal_text(self, where: str, text: str, node_id: str) -> bool:
        if not node_id:
            self.problem(where, f"goal text must start with its id G<k> followed by ':' (text: {text})")
            return False
        try:
            name, _ = parse_node_text(text)
        except MissionError:
            return True  # reported with the annotation
        if name != node_id:
            self.problem(where, f"the text before ':' must be exactly the goal id {node_id}, not {name}")
            return False
        return True

    def _read_task_text(self, where: str, text: str, node_id: str, fields: dict[str, Any]) -> bool:
        if not node_id or ":" not in text:
            self.problem(where, f"task text must be 'AT<k>: <HDDLTaskName>' (text: {text})")
            return False
        name = _TASK_NAME.search(text.split(":", 1)[1])
        if name is None:
            self.problem(where, f"task text must name an HDDL abstract task after ':' (text: {text})")
            return False
        fields["task_name"] = name.group()
        return True

    def _read_properties(
        self, where: str, node_id: str, text: str, props: dict[str, str], fields: dict[str, Any]
    ) -> None:
        """Interpret every custom property (spec §4, §6–§8) into ``fields``; errors become problems.

        The properties are read in a fixed order (the order in which their problems are
        reported), whatever their order in the file."""
        for key in props:
            if key not in KNOWN_PROPERTIES:
                self.problem(where, f"Invalid property {key} in vertex {text}", _property_hint(key))

        goal_type = props.get("GoalType", "Perform")
        if goal_type not in GOAL_TYPES:
            self.warn(where, f"Invalid goal type on node [{node_id}]: [{goal_type}]. Defaulting to Perform type.")
        fields["goal_type"] = goal_type

        self._read_variables(where, props, fields)
        if "CreationCondition" in props:
            fields["context"] = self._read_context(where, props["CreationCondition"])
        if "AchieveCondition" in props:
            self._read_achieve_condition(where, props["AchieveCondition"], fields)
        # A Query goal without QueriedProperty fails like an empty one, as in the original.
        if goal_type == "Query" or "QueriedProperty" in props:
            queried = props.get("QueriedProperty", "")
            fields["query"] = self._attempt(where, "QueriedProperty: ", lambda: parse_select(queried))
        self._read_flags(where, props, fields)
        self._read_task_properties(where, props, fields)

    def _read_variables(self, where: str, props: dict[str, str], fields: dict[str, Any]) -> None:
        """``Controls`` and ``Monitors``: the variables a goal binds and reads."""
        for key, attr in (("Controls", "controls"), ("Monitors", "monitors")):
            if key in props:
                value = props[key]
                decls = self._attempt(where, f"{key}: ", lambda: parse_var_decls(value))
                fields[attr] = decls or ()

    def _read_achieve_condition(self, where: str, achieve: str, fields: dict[str, Any]) -> None:
        """``AchieveCondition``: a universal ``forAll`` (which makes the goal iterate) or a
        plain condition."""
        fields["achieve_text"] = achieve
        if "forAll" in achieve:
            fields["forall"] = self._attempt(where, "AchieveCondition: ", lambda: parse_forall(achieve))
        else:
            fields["achieve_condition"] = self._attempt(
                where, "AchieveCondition: ", lambda: parse_condition(achieve)
            )

    def _read_flags(self, where: str, props: dict[str, str], fields: dict[str, Any]) -> None:
        """``Group`` and ``Divisible``: True unless written False (an odd value is warned)."""
        for key, attr in (("Group", "group"), ("Divisible", "divisible")):
            flag, recognised = _flag(props.get(key))
            if not recognised:
                self.warn(where, f"{key} value {props[key]!r} is neither True nor False; using True")
            fields[attr] = flag

    def _read_task_properties(self, where: str, props: dict[str, str], fields: dict[str, Any]) -> None:
        """``Location``, ``Params`` and ``RobotNumber``: what an execution of the task needs."""
        if "Location" in props:
            fields["location"] = props["Location"].strip() or None
        if "Params" in props:
            fields["params"] = parse_params(props["Params"])
        robots = props.get("RobotNumber", "").strip()
        if robots:
            fields["robot_number"] = self._attempt(where, "", lambda: parse_robot_number(robots))

    def _read_context(self, where: str, value: str) -> Context | None:
        """``CreationCondition`` (spec §6): kind by substring, text between the first '"' and the
        last character of the value (which should be the closing '"')."""
        lowered = value.lower()
        kind = "trigger" if "trigger" in lowered else "condition" if "condition" in lowered else None
        if kind is None:
            if value.strip():
                self.warn(where, f"CreationCondition {value!r} is neither a trigger nor a condition; ignored")
            return None
        quote = value.find('"')
        inner = value[quote + 1 : len(value) - 1]
        if quote == -1 or quote == len(value) - 1 or not value.endswith('"'):
            self.warn(where, f'CreationCondition should read assertion {kind} "<text>"; read the text as {inner!r}')
        if kind == "trigger":
            return Context("trigger", inner)
        condition = self._attempt(where, "CreationCondition: ", lambda: parse_condition(inner))
        return Context("condition", inner, condition)

    # -- links and tree -------------------------------------------------------------------------

    def _read_link(self, index: int, raw: Any, by_uid: dict[str, int]) -> _Link | None:
        if not isinstance(raw, dict):
            self.problem(f"link #{index + 1}", "a link must be a JSON object")
            return None
        link_id = _scalar_text(raw.get("id")) if "id" in raw else None
        where = f"link {link_id}" if link_id is not None else f"link #{index + 1}"
        ends: dict[str, int] = {}
        ok = True
        for key in ("type", "source", "target"):
            value = _scalar_text(raw[key]) if key in raw else None
            if value is None:
                self.problem(where, f"link is missing a string {key!r}")
                ok = False
            elif key != "type":
                if value not in by_uid:
                    self.problem(where, f"link {key} {value} is not a node of the goal model")
                    ok = False
                else:
                    ends[key] = by_uid[value]
        if not ok:
            return None
        if ends["source"] == ends["target"]:
            self.problem(where, "link connects a node to itself")
            return None
        return _Link(link_id or f"#{index + 1}", str(raw["type"]), child=ends["source"], parent=ends["target"])

    def _build(self, drafts: list[_Draft], links: list[_Link]) -> GoalModel:
        """Child order, vertex order and DFS exactly as the original (spec §3)."""
        # Links sorted by the child's x (stable, so ties keep file order).
        links = sorted(links, key=lambda k: drafts[k.child].x)
        order = _vertex_order(len(drafts), links)
        rank = {v: r for r, v in enumerate(order)}
        tree = _Edges(links)
        for child, ps in tree.parents.items():
            if len(ps) > 1:
                names = ", ".join(drafts[p].id for p in ps)
                self.problem(drafts[child].where, f"node has more than one parent ({names})")
        roots = [v for v in order if v not in tree.parents]
        if not roots:
            self.problem("goal model", "no root: every node has a parent (the links form a cycle)")
        self._raise_if_problems()
        root = roots[0]
        dfs = self._depth_first(drafts, order, tree, root)
        keys = _unique_keys(drafts, order)
        nodes: list[GMNode] = []
        for v in order:
            d = drafts[v]
            children = sorted(tree.out_edges.get(v, []), key=rank.__getitem__)
            parent = tree.parents.get(v)
            nodes.append(
                GMNode(
                    uid=d.uid,
                    id=d.id,
                    kind=d.kind,
                    x=d.x,
                    children=tuple(keys[c] for c in children),
                    parent=keys[parent[0]] if parent else None,
                    key=keys[v],
                    or_decomposed=v in tree.or_decomposed,
                    **d.fields,
                )
            )
        return GoalModel(
            source=self.source,
            nodes=tuple(nodes),
            root=keys[root],
            dfs=tuple(keys[v] for v in dfs),
            warnings=tuple(self.warnings),
        )

    def _depth_first(self, drafts: list[_Draft], order: list[int], tree: _Edges, root: int) -> list[int]:
        """Depth-first from the root, children in sorted-link order, then (like boost's
        depth_first_search) from every vertex not reached yet, in vertex order; those are
        warned about, as nothing above them can ever run them."""
        dfs: list[int] = []
        visited: set[int] = set()
        for start in [root] + order:
            if start in visited:
                continue
            if start != root:
                self.warn(drafts[start].where, f"node is not reachable from the root {drafts[root].id}")
            stack = [start]
            while stack:
                v = stack.pop()
                if v in visited:
                    continue
                visited.add(v)
                dfs.append(v)
                stack.extend(reversed(tree.out_edges.get(v, [])))
        return dfs


class _Edges:
    """The refinement links as a graph over draft positions: parents and children of every
    node (in sorted-link order) and the nodes refined by an OR link."""

    def __init__(self, links: list[_Link]) -> None:
        self.parents: dict[int, list[int]] = {}
        self.out_edges: dict[int, list[int]] = {}
        self.or_decomposed: set[int] = set()
        for link in links:
            self.parents.setdefault(link.child, []).append(link.parent)
            self.out_edges.setdefault(link.parent, []).append(link.child)
            if link.type == OR_REFINEMENT:
                self.or_decomposed.add(link.parent)


def _vertex_order(count: int, links: list[_Link]) -> list[int]:
    """The original's vertex order: nodes in order of first appearance in the sorted links
    (parent before child); nodes in no link are not vertices of its graph, kept here last."""
    order: list[int] = []
    seen: set[int] = set()
    for link in links:
        for v in (link.parent, link.child):
            if v not in seen:
                seen.add(v)
                order.append(v)
    order.extend(i for i in range(count) if i not in seen)
    return order


def _unique_keys(drafts: list[_Draft], order: list[int]) -> dict[int, str]:
    """Each node's key: its id, or ``id#k`` for the k-th node (in vertex order) reusing it."""
    keys: dict[int, str] = {}
    seen_ids: dict[str, int] = {}
    for v in order:
        k = seen_ids[drafts[v].id] = seen_ids.get(drafts[v].id, 0) + 1
        keys[v] = drafts[v].id if k == 1 else f"{drafts[v].id}#{k}"
    return keys
