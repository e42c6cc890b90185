"""Pictures of a mission: Graphviz DOT text for three views, and rendering to a file.

* :func:`goal_model_dot` - the goal model expanded against the world: the runtime annotation
  tree with goals (their text, queries, forAll, contexts, Group/Divisible), the operators
  ``;`` / ``#`` / ``FALLBACK`` / OR, one branch per forAll element, and the task instances.
* :func:`task_graph_dot` - the (minimal) Task Graph: operator, goal, task and decomposition
  vertices; AND, OR, context-dependency (CD) and execution-constraint (EC) edges.
* :func:`decomposition_dot` - one valid mission decomposition: the chosen task decompositions
  with their actions, and the SEQ / FB / EC constraints among them.
* :func:`render` - write DOT text as ``.dot``, or as ``.svg`` / ``.png`` / ``.pdf`` through the
  Graphviz ``dot`` program; without Graphviz the DOT file is written and a notice returned.

The DOT text is generated here (no Graphviz Python binding is needed) and is deterministic: the
same mission gives the same bytes.
"""
from __future__ import annotations

import os
import shutil
import subprocess
import textwrap
from contextlib import contextmanager
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Iterator, Mapping, Sequence

from ..pipeline.annotation_tree import GOAL, OPERATOR, TASK, RatNode
from ..pipeline.constraints import EC, FB, SEQ
from ..errors import MissionError, NoDecompositionError
from ..model.task_graph import DecompositionVertex, EdgeKind, GoalVertex, OperatorVertex, ScopeVertex, TaskVertex
from .files import atomic_writer
from ..solve import decomposers

if TYPE_CHECKING:  # pragma: no cover
    from ..pipeline.constraints import Constraint
    from ..model.task_instances import TaskInstance
    from ..model.decomposition_paths import Step
    from ..pipeline.stages import MissionStages
    from ..model import ForAll, GMNode
    from ..model.task_graph import Edge, TaskGraph, Vertex

__all__ = [
    "RenderError",
    "RenderResult",
    "decomposition_dot",
    "goal_model_dot",
    "nth_decomposition",
    "render",
    "task_graph_dot",
    "view_dot",
    "VIEWS",
]

VIEWS = ("goal-model", "task-graph", "decomposition")

WRAP = 36  # characters per label line for goal texts
FONT = "Helvetica"

# colours (fill, border)
GOAL_COLOURS = ("#dae8fc", "#6c8ebf")
QUERY_COLOURS = ("#fff2cc", "#d6b656")
FORALL_COLOURS = ("#e1d5e7", "#9673a6")
TASK_COLOURS = ("#d5e8d4", "#82b366")
DECOMPOSITION_COLOURS = ("#f5f5f5", "#666666")
INSTANCE_COLOURS = ("#ffffff", "#9673a6")
OPERATOR_COLOURS = ("#ffffff", "#333333")
CD_COLOUR = "#d62728"
EC_COLOUR = "#1f5fbf"
FB_COLOUR = "#e07000"


# ---------------------------------------------------------------------------------------------
# A small DOT writer


def _quote(text: str) -> str:
    """A DOT double-quoted string (backslashes and quotes escaped, newlines as ``\\n``)."""
    return '"' + text.replace("\\", "\\\\").replace('"', '\\"').replace("\n", "\\n") + '"'


def _label(lines: Iterable[str]) -> str:
    """A centred multi-line label."""
    return "\n".join(lines)


class _Escaped(str):
    """A label already in DOT escape syntax (e.g. with ``\\l`` left-justified lines)."""


def _left_label(centred: Iterable[str], left: Iterable[str]) -> _Escaped:
    """Centred heading lines followed by left-justified lines."""
    def esc(t: str) -> str:
        return _quote(t)[1:-1]
    out = "\\n".join(esc(t) for t in centred)
    left = list(left)
    if left:
        out += "\\n" + "".join(esc(t) + "\\l" for t in left)
    return _Escaped(out)


class _Dot:
    """Collects nodes, edges and clusters, in insertion order, and prints them as DOT.

    Statements are indented by their nesting: one level in the graph, one more inside each
    :meth:`cluster`."""

    def __init__(self, name: str, graph: Mapping[str, str], node: Mapping[str, str],
                 edge: Mapping[str, str]) -> None:
        self.name = name
        self.defaults = (("graph", graph), ("node", node), ("edge", edge))
        self.body: list[str] = []
        self.ids: set[str] = set()
        self.indent = 1

    @staticmethod
    def _attrs(attrs: Mapping[str, object]) -> str:
        parts = []
        for k, v in attrs.items():
            if v is None:
                continue
            if isinstance(v, bool):
                v = "true" if v else "false"
            parts.append(f'{k}="{v}"' if isinstance(v, _Escaped) else f"{k}={_quote(str(v))}")
        return f" [{', '.join(parts)}]" if parts else ""

    def unique(self, wanted: str) -> str:
        """``wanted``, or ``wanted~2``, ``wanted~3``... if it is already a node id."""
        node_id, k = wanted, 1
        while node_id in self.ids:
            k += 1
            node_id = f"{wanted}~{k}"
        self.ids.add(node_id)
        return node_id

    def node(self, node_id: str, **attrs: object) -> None:
        self.raw(_quote(node_id) + self._attrs(attrs) + ";")

    def edge(self, a: str, b: str, **attrs: object) -> None:
        self.raw(f"{_quote(a)} -> {_quote(b)}" + self._attrs(attrs) + ";")

    def raw(self, line: str) -> None:
        self.body.append("    " * self.indent + line)

    @contextmanager
    def cluster(self, name: str, label: str, colour: str) -> Iterator[None]:
        """A ``subgraph cluster_...`` drawn as a dashed rounded box: the statements made inside
        the ``with`` block are its members."""
        self.raw(f"subgraph {_quote(name)} {{")
        self.indent += 1
        self.raw(f'label={_quote(label)}; style="rounded,dashed"; color="{colour}";')
        yield
        self.indent -= 1
        self.raw("}")

    def text(self) -> str:
        out = [f"digraph {_quote(self.name)} {{"]
        for kind, attrs in self.defaults:
            if attrs:
                out.append(f"    {kind}{self._attrs(attrs)};")
        out.extend(self.body)
        out.append("}")
        return "\n".join(out) + "\n"


def _new_graph(name: str, rankdir: str, title: str | None = None, **graph: str) -> _Dot:
    if rankdir not in ("TB", "LR", "BT", "RL"):
        raise ValueError(f"rankdir must be TB, LR, BT or RL, not {rankdir!r}")
    attrs = {"rankdir": rankdir, "fontname": FONT, "fontsize": "12", **graph}
    if title:
        attrs.update({"label": title, "labelloc": "t", "labeljust": "l"})
    return _Dot(
        name,
        attrs,
        {"fontname": FONT, "fontsize": "10"},
        {"fontname": FONT, "fontsize": "9", "arrowsize": "0.6"},
    )


def _filled(colours: tuple[str, str], style: str = "filled") -> dict[str, str]:
    return {"style": style, "fillcolor": colours[0], "color": colours[1]}


def _wrap(text: str, width: int = WRAP) -> list[str]:
    """Lines of at most ``width`` characters; a short last word stays on the line before."""
    lines = textwrap.wrap(text, width, break_long_words=False, break_on_hyphens=False) or [""]
    if len(lines) > 1 and len(lines[-1]) <= 10 and len(lines[-2]) + 1 + len(lines[-1]) <= width + 10:
        lines[-2:] = [lines[-2] + " " + lines[-1]]
    return lines


def _value(v: object) -> str:
    """A variable or parameter value: a record id, or ``[a, b]`` for a collection."""
    if isinstance(v, tuple):
        return "[" + ", ".join(v) + "]"
    return str(v) if v != "" else '""'


# ---------------------------------------------------------------------------------------------
# Shared label helpers


def _goal_title(node: "GMNode") -> str:
    """The goal's text without its runtime annotation: ``G4: Room Is Made Safe ...``."""
    text = " ".join(node.text.split())
    if text.endswith("]") and "[" in text:
        text = text[: text.rfind("[")].rstrip()
    return text


def _robots(inst: "TaskInstance") -> str | None:
    r = inst.robot_number
    if r.fixed:
        return None if r.min == 1 else f"robots: {r.min}"
    return f"robots: {r.min}..{r.max}"


def _task_lines(instance_id: str, inst: "TaskInstance | None") -> list[str]:
    """Label lines of a task instance: id and task, location, robot number."""
    lines = [f"{instance_id}: {inst.name}" if inst else instance_id]
    if inst is not None:
        if inst.location is not None:
            lines.append(f"at {_value(inst.location)}")
        robots = _robots(inst)
        if robots:
            lines.append(robots)
    return lines


def _goal_lines(node: "GMNode", var_maps: Mapping[str, object], forall_hub: bool = False) -> list[str]:
    """Label lines of a goal: its text and what the decomposer reads from its properties."""
    lines = _wrap(_goal_title(node))
    if node.query is not None:
        lines += _query_lines(node, var_maps)
    elif node.forall is not None:
        lines += _forall_lines(node.forall, var_maps, forall_hub)
    elif node.goal_type == "Achieve" and node.achieve_text:
        lines += _wrap(f"Achieve: {node.achieve_text}", WRAP + 10)
    if node.context is not None:
        lines += _wrap(f'{node.context.kind}: "{node.context.text}"', WRAP + 10)
    if not node.group:
        lines.append("Group=False")
    elif not node.divisible:
        lines.append("Divisible=False")
    return lines


def _bound_value(binding: object) -> object:
    """The value of a variable binding (a :class:`~mutrose_cp.pipeline.query.Binding` or a bare value)."""
    return getattr(binding, "value", binding)


def _query_lines(node: "GMNode", var_maps: Mapping[str, object]) -> list[str]:
    """A query goal's query, and the value it gave the variable it controls (when known here)."""
    assert node.query is not None
    lines = _wrap(f"Query: {node.query.text}", WRAP + 10)
    if node.controls:
        var = node.controls[0].name
        b = var_maps.get(var)
        if b is not None:
            lines += _wrap(f"{var} = {_value(_bound_value(b))}", WRAP + 10)
    return lines


def _forall_lines(fa: "ForAll", var_maps: Mapping[str, object], forall_hub: bool) -> list[str]:
    """A forAll goal's iteration, and for one copy (not the hub over all copies) the element it
    iterates over, or a note that the iterated collection is empty."""
    cond = f" | {fa.condition_text}" if fa.condition_text else ""
    lines = _wrap(f"forAll {fa.iteration} in {fa.iterated}{cond}", WRAP + 10)
    if not forall_hub:
        b = var_maps.get(fa.iteration)
        iterated = var_maps.get(fa.iterated)
        if b is not None:
            lines.append(f"{fa.iteration} = {_value(_bound_value(b))}")
        elif iterated is not None and getattr(iterated, "value", None) == ():
            lines.append(f"{fa.iterated} is empty: no instance")
    return lines


def _action_text(step: "Step", binding: Mapping[str, object]) -> str:
    args = ", ".join(_value(binding[a]) if a in binding else a for a in step.args)
    return f"{step.name}({args})"


# ---------------------------------------------------------------------------------------------
# Goal model view


def goal_model_dot(mission: "MissionStages", rankdir: str = "LR") -> str:
    """DOT text of the expanded goal model (the runtime annotation tree).

    Goals are rounded boxes labelled with their text (query goals in yellow, with the query and
    its result; forAll goals in purple with one branch per iterated element, labelled with the
    element); operators are small ellipses (``;`` sequence, ``#`` parallel, ``FALLBACK``,
    ``OR`` for an OR-refined goal, whose edges are dashed); task instances are green boxes with
    their instance id, HDDL task and location (grey and dashed when a false condition context
    removed them from the Task Graph).  Node ids: the task instance id (``AT1_2``),
    goal ids with their forAll position (``G4_2``), ``<goal>.op`` for a goal's operator and
    ``<goal>.forall`` for a forAll goal."""
    view = _GoalModelView(mission, rankdir)
    view.visit(mission.expansion.rat, None, False, "")
    return view.dot.text()


class _GoalModelView:
    """Draws the runtime annotation tree, one method per kind of node.  ``suffix`` carries the
    forAll position (``_2``, ``_2_1``) down the tree, so that the copies of a goal under
    different forAll elements get distinct node ids."""

    def __init__(self, mission: "MissionStages", rankdir: str) -> None:
        self.gm = mission.goal_model
        self.instances = {i.id: i for i in mission.expansion.instances}
        self.kept: set[str] | None
        try:
            self.kept = {v.content for v in mission.task_graph.tasks()}
        except MissionError:
            self.kept = None  # the Task Graph cannot be built: draw the expansion only
        self.dot = _new_graph("goal_model", rankdir, None, nodesep="0.15", ranksep="0.3")

    def goal_node(self, key: str, suffix: str, var_maps: Mapping[str, object], hub: bool = False) -> str:
        g = self.gm.node(key)
        colours = QUERY_COLOURS if g.query is not None else FORALL_COLOURS if g.forall is not None else GOAL_COLOURS
        node_id = self.dot.unique(f"{g.id}{suffix}" + (".forall" if hub else ""))
        self.dot.node(node_id, shape="box", label=_label(_goal_lines(g, var_maps, hub)),
                      **_filled(colours, "rounded,filled"))
        return node_id

    def op_node(self, op: RatNode, owner: str) -> str:
        symbol = "OR" if op.or_decomposition else op.content
        node_id = self.dot.unique(f"{owner}.op")
        self.dot.node(node_id, shape="ellipse", label=symbol, margin="0.04,0.02", height="0.3",
                      fontsize="11" if symbol in (";", "#") else "9", **_filled(OPERATOR_COLOURS))
        return node_id

    def link(self, parent: str | None, child: str, alternative: bool) -> None:
        """The edge from the parent's node (none at the root); dashed between OR alternatives."""
        if parent is not None:
            self.dot.edge(parent, child, style="dashed" if alternative else None)

    def visit(self, node: RatNode, parent: str | None, alternative: bool, suffix: str) -> None:
        if node.kind == TASK:
            self.task(node, parent, alternative)
        elif node.kind == GOAL:
            self.link(parent, self.goal_node(node.related_goal or node.content, suffix, node.var_maps), alternative)
        elif node.kind == OPERATOR and node.is_forall_dummy:
            self.forall(node, parent, alternative, suffix)
        elif node.kind == OPERATOR and node.inner:
            op = self.op_node(node, parent or "root")
            self.link(parent, op, alternative)
            self.children(node, op, suffix)
        else:
            self.refined_goal(node, parent, alternative, suffix)

    def children(self, node: RatNode, below: str, suffix: str) -> None:
        for c in node.children:
            self.visit(c, below, node.or_decomposition, suffix)

    def task(self, node: RatNode, parent: str | None, alternative: bool) -> None:
        """A task instance; greyed out when the Task Graph does not have it."""
        lines = _task_lines(node.content, self.instances.get(node.content))
        node_id = self.dot.unique(node.content)
        if self.kept is not None and node.content not in self.kept:
            # a false condition context that nothing enables removed this branch
            lines.append("removed: context is false")
            self.dot.node(node_id, shape="box", label=_label(lines), fontcolor="#666666",
                          **_filled(("#eeeeee", "#999999"), "filled,dashed"))
        else:
            self.dot.node(node_id, shape="box", label=_label(lines), **_filled(TASK_COLOURS))
        self.link(parent, node_id, alternative)

    def forall(self, node: RatNode, parent: str | None, alternative: bool, suffix: str) -> None:
        """A forAll goal: a hub node over one instance box per iterated element."""
        key = node.children[0].related_goal if node.children else None
        if key is None:
            return
        g = self.gm.node(key)
        hub = self.goal_node(key, suffix, node.var_maps, hub=True)
        self.link(parent, hub, alternative)
        it = g.forall.iteration if g.forall is not None else ""
        for i, copy in enumerate(node.children, start=1):
            self.forall_instance(g.id, hub, copy, i, it, f"{suffix}_{i}")

    def forall_instance(self, goal_id: str, hub: str, copy: RatNode, i: int, it: str, suffix: str) -> None:
        """Instance ``i`` of a forAll goal, labelled with its element, and its subtree."""
        b = copy.var_maps.get(it)
        inst_id = self.dot.unique(f"{goal_id}{suffix}")
        text = f"{it} = {_value(b.value)}" if b is not None else f"instance {i}"
        self.dot.node(inst_id, shape="box", label=f"{goal_id} instance {i}\n{text}",
                      **_filled(INSTANCE_COLOURS, "rounded,dashed"))
        self.dot.edge(hub, inst_id)
        below = inst_id
        if copy.kind == OPERATOR:
            below = self.op_node(copy, inst_id)
            self.dot.edge(inst_id, below)
        self.children(copy, below, suffix)

    def refined_goal(self, node: RatNode, parent: str | None, alternative: bool, suffix: str) -> None:
        """A means-end goal (one child) or a goal whose annotation is an operator."""
        gid = self.goal_node(node.related_goal or node.content, suffix, node.var_maps)
        self.link(parent, gid, alternative)
        below = gid
        if node.kind == OPERATOR:
            below = self.op_node(node, gid)
            self.dot.edge(gid, below)
        self.children(node, below, suffix)


# ---------------------------------------------------------------------------------------------
# Task Graph view


def _flags_text(group: bool, divisible: bool) -> str:
    return f"group={group} divisible={divisible}"


def _constraining_flag(group: bool, divisible: bool) -> str:
    """How a goal constrains its tasks: ``Group=False`` or ``Divisible=False``."""
    return "Group=False" if not group else "Divisible=False"


# how the AND, OR and CD edges of the Task Graph are drawn (EC edges: see _task_graph_edge)
_EDGE_ATTRS: dict[EdgeKind, dict[str, object]] = {
    EdgeKind.AND: {},
    EdgeKind.OR: {"style": "dashed"},
    EdgeKind.CD: {"style": "dotted", "color": CD_COLOUR, "fontcolor": CD_COLOUR, "label": "CD",
                  "constraint": False, "penwidth": "1.5"},
}


def task_graph_dot(mission: "MissionStages", rankdir: str = "LR") -> str:
    """DOT text of the Task Graph (the minimal one the constraints and decompositions use).

    Operator vertices are ellipses (``;``, ``#``, ``FALLBACK``, ``OR`` when the children are
    alternatives, with the goal they come from), goal vertices rounded boxes, task vertices
    green boxes, decomposition vertices small grey boxes with their output key, id and actions.
    AND edges are solid, OR edges dashed, context-dependency (CD) edges red and dotted,
    execution constraints (EC) blue undirected lines labelled with their group/divisible flags.
    Node ids: ``v<index>`` for operator/goal vertices, the instance id for tasks (``AT1_2``),
    the decomposition id for decompositions (``AT1_2|1``)."""
    tg = mission.task_graph
    keys = tg.decomposition_keys  # the output's task keys
    dot = _new_graph("task_graph", rankdir, None, nodesep="0.12", ranksep="0.35")
    ids: dict[int, str] = {}
    for v in tg.vertices:
        if isinstance(v, (TaskVertex, DecompositionVertex)):
            ids[v.index] = dot.unique(v.content)
        else:
            ids[v.index] = dot.unique(f"v{v.index}")
    for v in tg.vertices:
        _task_graph_node(dot, ids[v.index], v, tg, keys)
    for edge in tg.edges():
        _task_graph_edge(dot, tg, ids, edge)
    return dot.text()


def _task_graph_node(dot: _Dot, nid: str, v: "Vertex", tg: "TaskGraph", keys: Mapping[int, str]) -> None:
    """One vertex of the Task Graph, drawn by its kind."""
    if isinstance(v, OperatorVertex):
        symbol = "OR" if tg.is_or(v.index) else v.content
        lines = [f"{symbol}  {v.goal or ''}".rstrip()]
        if v.forall:
            lines.append("forAll")
        elif v.achieve:
            lines.append("achieve")
        lines += _constraining_flags(v.group, v.divisible)
        dot.node(nid, shape="ellipse", label=_label(lines), margin="0.05,0.02", height="0.3",
                 **_filled(OPERATOR_COLOURS))
    elif isinstance(v, GoalVertex):
        lines = [v.content] + _constraining_flags(v.group, v.divisible)
        dot.node(nid, shape="box", label=_label(lines), **_filled(GOAL_COLOURS, "rounded,filled"))
    elif isinstance(v, TaskVertex):
        dot.node(nid, shape="box", label=_label(_task_lines(v.content, v.instance)), **_filled(TASK_COLOURS))
    else:
        lines = [f"{keys.get(v.index, '')}  {v.content}".strip()]
        actions = [s.name for s in v.decomposition.path.actions]
        lines += actions or ["(no action)"]
        dot.node(nid, shape="box", label=_label(lines), fontsize="8", margin="0.05,0.03", height="0.2",
                 **_filled(DECOMPOSITION_COLOURS))


def _constraining_flags(group: bool, divisible: bool) -> list[str]:
    """The label line of a vertex whose goal constrains its tasks; none for the default."""
    return [] if group and divisible else [_constraining_flag(group, divisible)]


def _task_graph_edge(dot: _Dot, tg: "TaskGraph", ids: Mapping[int, str], edge: "Edge") -> None:
    """One edge of the Task Graph; an EC edge, which the graph holds in both directions, is
    drawn once, from its lower vertex."""
    a, b = edge.source, edge.target
    if edge.kind != EdgeKind.EC:
        dot.edge(ids[a], ids[b], **_EDGE_ATTRS[edge.kind])
    elif not (tg.has_edge(b, a) and b < a):
        dot.edge(ids[a], ids[b], dir="none", color=EC_COLOUR, fontcolor=EC_COLOUR, constraint=False,
                 label="EC " + _flags_text(edge.group, edge.divisible),
                 penwidth="1.5")


# ---------------------------------------------------------------------------------------------
# One mission decomposition


def nth_decomposition(mission: "MissionStages", index: int) -> list[int]:
    """The decomposition vertices of valid mission decomposition ``index`` (0-based; negative
    counts from the end), in the order of ``list(Mission.decomposition_space())`` but computed
    directly from the components (mixed radix, last component fastest), so that any index of a
    huge space is cheap."""
    return _nth(mission, index)[0]


def _nth(mission: "MissionStages", index: int) -> tuple[list[int], int, int]:
    """(decomposition vertices, index >= 0, number of valid mission decompositions)."""
    if not mission.task_graph.tasks():
        raise NoDecompositionError("the mission has no task instances (no entity of the world matched its "
                                   "queries): no mission decomposition to draw", str(mission.goal_model.source))
    space = decomposers.decomposition_space(mission)
    total = space.count
    if total == 0:
        raise NoDecompositionError("no valid mission decomposition: nothing to draw",
                                   str(mission.goal_model.source))
    if not -total <= index < total:
        raise MissionError(f"decomposition index {index} is out of range: the mission has {total} valid "
                           f"mission decompositions (indices 0 to {total - 1})")
    if index < 0:
        index += total
    digits = []
    rest = index
    for c in reversed(space.components):
        rest, d = divmod(rest, c.count)
        digits.append(d)
    digits.reverse()
    parts = []
    for c, d in zip(space.components, digits):
        if c.solutions is not None:
            parts.append(c.solutions[d])
        elif c.layers is not None:
            parts.append(frozenset(c.layers.solution_at(d)))
        else:
            raise MissionError("a component of the decomposition space has too many solutions to list")
    decs = [space.var_to_dec[v] for p in parts for v in p] + list(space.fixed)
    return sorted(decs), index, total


def decomposition_dot(mission: "MissionStages", index: int = 0, rankdir: str = "LR",
                      chosen: Sequence[int] | None = None, source: str = "") -> str:
    """DOT text of valid mission decomposition ``index`` (0-based, in the order of
    ``list(Mission.decomposition_space())``; negative indices count from the end), or of the
    decomposition vertices ``chosen``, read from the file ``source``.

    Each chosen task decomposition is a box with its output key, id, task, location and numbered
    actions (parameters replaced by their values).  SEQ constraints are black arrows, FB
    (fallback: the second runs if the first fails) dashed orange arrows, EC (execution
    constraints) blue undirected lines with their flags.  When the Task Graph root is a forAll,
    the decompositions of each iterated element are grouped in a box labelled with the element.
    Node ids are the decomposition ids (``AT1_2|1``).

    Raises :class:`~mutrose_cp.errors.NoDecompositionError` (exit 3) if the mission has no valid
    decomposition and :class:`~mutrose_cp.errors.MissionError` (exit 2) for an index out of range."""
    tg = mission.task_graph
    if chosen is None:
        chosen, index, total = _nth(mission, index)
        title = f"valid mission decomposition {index} (indices 0 to {total - 1} of {total})"
    else:
        chosen = list(chosen)
        title = f"valid mission decomposition {index} of {Path(source).name}"
    keys = tg.decomposition_keys  # the output's task keys
    dot = _new_graph("mission_decomposition", rankdir, title, nodesep="0.25", ranksep="0.5")
    ids = {d: dot.unique(tg.vertices[d].content) for d in chosen}

    def node(d: int) -> None:
        _decomposition_node(dot, ids[d], tg.decomposition(d), keys.get(d, ""))

    groups = _forall_groups(tg, chosen)
    if groups is not None:
        it = _forall_iteration(mission)
        ordered = list(enumerate(sorted(groups.items(), key=lambda kv: kv[0]), start=1))
        if rankdir == "LR":
            ordered.reverse()  # dot stacks LR clusters bottom-up: emit the last first, so #1 is on top
        for n, (top_vertex, members) in ordered:
            top = tg.vertices[top_vertex]
            b = top.var_maps.get(it) if it and isinstance(top, ScopeVertex) else None
            label = f"{it} = {_value(b.value)}" if b is not None else f"forAll element {n}"
            with dot.cluster(f"cluster_{n}", label, FORALL_COLOURS[1]):
                for d in members:
                    node(d)
    else:
        for d in chosen:
            node(d)
    _constraint_edges(dot, mission.constraints, ids)
    return dot.text()


def _decomposition_node(dot: _Dot, node_id: str, v: "DecompositionVertex", key: str) -> None:
    """A chosen task decomposition: key, id, task, location, robots and numbered actions."""
    inst = v.instance
    lines = [f"{key}  {v.content}".strip()]
    where = f" at {_value(inst.location)}" if inst.location is not None else ""
    lines.append(f"{inst.name}{where}")
    robots = _robots(inst)
    if robots:
        lines.append(robots)
    binding = inst.binding
    acts = [f"{i}. {_action_text(s, binding)}" for i, s in enumerate(v.decomposition.path.actions, 1)]
    dot.node(node_id, shape="box", label=_left_label(lines, acts), **_filled(TASK_COLOURS, "rounded,filled"))


def _forall_groups(tg: "TaskGraph", chosen: list[int]) -> dict[int, list[int]] | None:
    """The chosen decompositions by the child of the root they lie under, when the root is a
    forAll operator over several elements (one group per element); ``None`` otherwise, or when
    some decomposition is not below a child of the root."""
    root = tg.vertices[0] if tg.vertices else None
    if not (isinstance(root, OperatorVertex) and root.forall and not tg.unique_branch):
        return None
    top = {u: i for i, u in enumerate(tg.children(0))}
    groups: dict[int, list[int]] = {}
    for d in chosen:
        a = d
        while a != -1 and a not in top:
            a = tg.vertices[a].parent
        groups.setdefault(a, []).append(d)
    if not groups or any(g == -1 for g in groups):
        return None
    return groups


def _forall_iteration(mission: "MissionStages") -> str | None:
    """The iteration variable of the forAll goal at the root of the Task Graph, if known."""
    root = mission.task_graph.vertices[0]
    goal = mission.goal_model.node(root.goal) if isinstance(root, OperatorVertex) and root.goal else None
    return goal.forall.iteration if goal is not None and goal.forall is not None else None


def _constraint_edges(dot: _Dot, constraints: Iterable["Constraint"], ids: Mapping[int, str]) -> None:
    """The SEQ, FB and EC constraints among the drawn decompositions; an EC constraint, which
    is listed in both directions, is drawn once."""
    drawn: set[tuple[int, int]] = set()
    for c in constraints:
        if c.first not in ids or c.second not in ids:
            continue
        first, second = ids[c.first], ids[c.second]
        if c.kind == SEQ:
            dot.edge(first, second, label="SEQ")
        elif c.kind == FB:
            dot.edge(first, second, label="FB", style="dashed", color=FB_COLOUR, fontcolor=FB_COLOUR)
        elif c.kind == EC:
            pair = (min(c.first, c.second), max(c.first, c.second))
            if pair in drawn:
                continue
            drawn.add(pair)
            dot.edge(first, second, dir="none", color=EC_COLOUR, fontcolor=EC_COLOUR, constraint=False,
                     penwidth="1.5", label="EC " + _flags_text(c.group, c.divisible))


# ---------------------------------------------------------------------------------------------
# Rendering


class RenderError(MissionError):
    """The picture could not be written (unsupported file type, Graphviz failed)."""


@dataclass(frozen=True)
class RenderResult:
    """What :func:`render` wrote.

    ``path`` is the file written: the requested one, or, when Graphviz is missing, the DOT file
    beside it (``graph.png`` -> ``graph.dot``).  ``message`` is ``None`` on success, else a
    notice for the user (the CLI prints it and still exits 0)."""

    path: Path
    rendered: bool
    message: str | None = None


DOT_SUFFIXES = (".dot", ".gv")
IMAGE_SUFFIXES = (".svg", ".png", ".pdf")
INSTALL_HINT = ("install Graphviz to render pictures (Debian/Ubuntu: apt-get install graphviz; "
                "macOS: brew install graphviz; https://graphviz.org/download/)")


def render_targets(path: str | os.PathLike[str]) -> list[Path]:
    """The files :func:`render` may write for ``path``: the file itself, or the ``.dot`` text
    beside it when Graphviz is missing (checked with the command's other outputs before any
    work)."""
    target = Path(path)
    if target.suffix.lower() in IMAGE_SUFFIXES and shutil.which("dot") is None:
        return [target.with_suffix(".dot")]
    return [target]


def render(dot_text: str, path: str | os.PathLike[str], *, timeout: float | None = 300) -> RenderResult:
    """Write ``dot_text`` to ``path``: as is for ``.dot``/``.gv``; for ``.svg``/``.png``/``.pdf``
    through the Graphviz ``dot`` program.  If ``dot`` is not on ``PATH``, the DOT text is written
    next to ``path`` with the suffix ``.dot`` and the result carries a message telling the user
    to install Graphviz.  Raises :class:`RenderError` for another suffix or if ``dot`` fails."""
    target = Path(path)
    suffix = target.suffix.lower()
    if suffix in DOT_SUFFIXES:
        _write(target, dot_text)
        return RenderResult(target, True)
    if suffix not in IMAGE_SUFFIXES:
        raise RenderError(f"cannot write a picture as {suffix or 'a file without suffix'}: use "
                          + ", ".join(DOT_SUFFIXES + IMAGE_SUFFIXES), str(target))
    exe = shutil.which("dot")
    if exe is None:
        fallback = target.with_suffix(".dot")
        _write(fallback, dot_text)
        return RenderResult(fallback, False,
                            f"Graphviz 'dot' was not found, so {target} was not drawn; the graph was written "
                            f"to {fallback} instead. To draw it, {INSTALL_HINT}, then run: "
                            f"dot -T{suffix[1:]} {fallback} -o {target}")
    try:  # the picture comes back on dot's stdout, and is written as any output (atomically)
        proc = subprocess.run([exe, f"-T{suffix[1:]}"], input=dot_text.encode("utf-8"),
                              capture_output=True, timeout=timeout, check=False)
    except subprocess.TimeoutExpired:
        raise RenderError(f"Graphviz took longer than {timeout:.0f} s; the graph is too large to draw "
                          "(write a .dot file instead)", str(target)) from None
    except OSError as err:
        raise RenderError(f"cannot run Graphviz dot: {err.strerror or err}", str(target)) from None
    if proc.returncode != 0:
        detail = proc.stderr.decode("utf-8", "replace").strip().splitlines()
        raise RenderError("Graphviz dot failed" + (f": {detail[-1]}" if detail else ""), str(target))
    with atomic_writer(target, "wb") as fh:
        fh.write(proc.stdout)
    return RenderResult(target, True)


def _write(path: Path, text: str) -> None:
    with atomic_writer(path, "wb") as fh:
        fh.write(text.encode("utf-8"))


def view_dot(mission: "MissionStages", view: str, index: int = 0, rankdir: str | None = None,
             chosen: Sequence[int] | None = None, source: str = "") -> str:
    """DOT text of one of :data:`VIEWS` (``goal-model``, ``task-graph``, ``decomposition``); the
    decomposition view draws ``chosen`` (read from ``source``) when given."""
    kw = {"rankdir": rankdir} if rankdir else {}
    if view == "goal-model":
        return goal_model_dot(mission, **kw)
    if view == "task-graph":
        return task_graph_dot(mission, **kw)
    if view == "decomposition":
        return decomposition_dot(mission, index, chosen=chosen, source=source, **kw)
    raise ValueError(f"unknown view {view!r}: one of {', '.join(VIEWS)}")


