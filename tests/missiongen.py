"""Random but valid MutRoSe missions for differential testing (hypothesis strategies).

``missions()`` draws a :class:`MissionSpec`: a small HDDL domain, a goal model, a configuration
and a world, all consistent with each other, so that ``Mission.load`` accepts it.  ``write``
renders the four files into a directory; ``load_mission`` writes them to a temporary directory
and loads them.

Shapes.  ``missions()`` mixes several *shapes* (3/8 ``basic``, 1/8 each of the
others); ``missions(shape=...)`` draws only one of them (``SHAPES`` lists them; the strategies
``basic_missions()``, ``long_sequences()``, ``contradictory_missions()``,
``unique_branch_missions()``, ``nested_forall_missions()`` and ``tasks_beside_goals()`` are the
same as ``missions(shape=...)``).  ``MissionSpec.shape`` records the shape of a drawn mission.

* ``basic``: the general shape below.
* ``long_sequence``: 10-15 GM tasks under one flat ``;`` annotation (of the forAll goal, or of
  its subgoal beside one more task), directly or through means-end goals (sometimes one plain
  Achieve goal and one condition context among them), in one selected room.  The domain
  (``_toggle_domain``) sets, unsets and requires one room predicate ``P``: ``TaskA`` sets it,
  ``TaskB`` unsets it, ``TaskC`` checks it, each in a variant that always applies, splits on
  ``P``, has a guard, or has two methods that may both apply; every task occurs at least once.
  So the order in which effects are applied matters (``AT10_1`` sorts before ``AT2_1`` as a
  string).  At most two decompositions per task; their product is capped by
  ``LONG_PRODUCT_CAP`` (tasks whose every method sets or unsets ``P`` do not count).  One in
  five also gets the contradictory/duplicate preconditions of the next shape.
* ``contradictory``: a basic mission in which some method of a used task has a
  self-contradictory precondition (``(and (sealed ?rm) (not (sealed ?rm)))``, a robot literal
  and its negation, or ``(= (level ?rm) 0)`` with ``(= (level ?rm) 1)``) and some method has a
  duplicate precondition (the same literal twice, or the precondition of its first action).
* ``unique_branch``: one selected room and a chain of single-child goals above one task
  (sometimes with a sibling goal whose false condition context removes it from the Task Graph),
  so that the Task Graph is unique-branch (spec semantics.md §5.5, §7.7); the domain favours
  numeric (``level``) method preconditions (methods split on the level, level tests).
* ``nested_forall``: below the room forAll, a second Query goal
  ``world_db->select(i:Item | i.name in current_room.items)`` (sometimes ``&& !i.is_<q>``),
  then optionally a room task, and a second forAll goal over
  ``current_items`` (``current_item : Item``), whose subtree contains plain Achieve goals
  (``GoalType Achieve`` with conditions over ``current_room`` / ``current_item``) and tasks over
  the item (``TaskI (?r ?rm ?it)``, ``Params: current_item``); items are top-level ``Item``
  records with boolean ``is_ready`` (``is_tagged``) attributes, rooms list them in ``<items>``
  (0-2 each, possibly shared between rooms; at most ``NESTED_MAX_INSTANCES`` task instances and
  ``PRODUCT_CAP`` combinations of decompositions).
* ``tasks_beside_goals``: a goal with a ``;`` annotation over 3-4 children mixing direct tasks
  and subgoals (``[G4;AT2;G5]``; flat, or nested with ``;`` at the top), at the forAll goal or
  one level below; at most 8 task instances and ``PRODUCT_CAP`` combinations.

Shape of a basic mission (sizes are kept small so that the exploratory algorithm, which combines
decompositions explicitly, stays fast: at most ``MAX_TASK_INSTANCES`` task instances after the
forAll expansion and at most ``MAX_PATHS`` decompositions per abstract task)::

    G1 Root [G2;G3]
    ├─ G2 Query: world_db->select(r:Room | r.active)        (or an empty condition: every room)
    └─ G3 Achieve: rooms->forAll(current_room | <cond>)    <cond>: empty, current_room.is_<p>,
       └─ random goal tree: AND / OR refinements,           !current_room.is_<p> or a level test
          annotations with ;  #  FALLBACK(..) (flat or nested, OR goals only # or none),
          means-end goals, tasks directly under operators, optional Group=False /
          Divisible=False, condition contexts and plain Achieve goals;
          every task has Location: current_room

    HDDL: types room, Bot - robot; 2-4 predicates over ?rm (room, mapped to world attributes) and
    ?r (robot, non-ground); one function (level ?rm); 1-3 abstract tasks (?r - Bot ?rm - room)
    with 1-3 methods each: method preconditions over predicates and (> (level ?rm) 0) /
    (= (level ?rm) N), ordered or unordered subtasks (actions, or an earlier abstract task);
    actions with literal preconditions/effects and (increase|decrease (level ?rm) 1).

    World: 1-3 rooms with random active flag, boolean attributes (True / False / missing, i.e.
    unknown) and a numeric level (0-2 or missing); configuration maps every attribute to its
    predicate (attribute -> predicate) and level to the function (attribute -> function).
"""
from __future__ import annotations

import dataclasses
import json
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Callable, Iterator, Union

from hypothesis import HealthCheck, given, seed, settings
from hypothesis import strategies as st

MAX_TASK_INSTANCES = 6  # GM tasks x selected rooms (basic shape)
MAX_PATHS = 4  # decomposition paths of one abstract task (upper bound, before filtering)
MAX_DEPTH = 3  # goal levels below the forAll goal
LONG_PRODUCT_CAP = 64  # long sequences: product of the decomposition counts of all instances
NESTED_MAX_INSTANCES = 8  # nested forAll: task instances over all rooms and items
PRODUCT_CAP = 1024  # nested forAll, tasks beside goals: product of the decomposition counts of all instances

ROOM_PREDICATES = ("clean", "sealed", "lit", "checked")
ROBOT_PREDICATES = ("charged", "loaded")
ITEM_PREDICATES = ("ready", "tagged")
TASK_NAMES = ("TaskA", "TaskB", "TaskC")  # letters only: the GM reads the first run of letters
ITEM_TASK = "TaskI"  # the abstract task over an item (nested_forall shape)

SHAPES = ("basic", "long_sequence", "contradictory", "unique_branch", "nested_forall", "tasks_beside_goals")


# ---------------------------------------------------------------------------------------------
# The mission model


@dataclass(frozen=True)
class Lit:
    """A boolean literal ``(pred ?var)``; ``var`` is ``?rm`` (room), ``?r`` (robot) or ``?it``
    (item)."""

    pred: str
    var: str
    positive: bool = True

    def hddl(self) -> str:
        atom = f"({self.pred} {self.var})"
        return atom if self.positive else f"(not {atom})"


@dataclass(frozen=True)
class Cmp:
    """A numeric precondition ``(op (level ?rm) value)``, op ``>`` or ``=``."""

    op: str
    value: int

    def hddl(self) -> str:
        return f"({self.op} (level ?rm) {self.value})"


@dataclass(frozen=True)
class Change:
    """A numeric effect ``(increase|decrease (level ?rm) amount)``."""

    kind: str
    amount: int = 1

    def hddl(self) -> str:
        return f"({self.kind} (level ?rm) {self.amount})"


@dataclass(frozen=True)
class Action:
    name: str
    pre: tuple[Union[Lit, Cmp], ...] = ()
    eff: tuple[Union[Lit, Change], ...] = ()
    item: bool = False  # parameters (?r ?rm ?it) instead of (?r ?rm)


@dataclass(frozen=True)
class Method:
    name: str
    pre: tuple[Union[Lit, Cmp], ...] = ()
    subtasks: tuple[str, ...] = ()  # action or abstract task names, called with (?r ?rm [?it])
    ordered: bool = True


@dataclass(frozen=True)
class Task:
    name: str
    methods: tuple[Method, ...]
    item: bool = False  # parameters (?r ?rm ?it) instead of (?r ?rm)


@dataclass(frozen=True)
class Room:
    name: str
    active: bool = True
    facts: tuple[tuple[str, Union[bool, None]], ...] = ()  # predicate -> value (None: missing)
    level: Union[int, None] = 0
    items: Union[tuple[str, ...], None] = None  # names of Item records (<items>), None: no field


@dataclass(frozen=True)
class Item:
    name: str
    facts: tuple[tuple[str, Union[bool, None]], ...] = ()  # item predicate -> value (None: missing)


@dataclass(frozen=True)
class TaskNode:
    """A goal-model task (``AT<k>: <task>``, ``Location: current_room``; a task over an item
    also gets ``Params: current_item``)."""

    task: str


@dataclass(frozen=True)
class QueryNode:
    """The item Query goal: ``current_items`` := the items of ``current_room`` (a GOAL leaf)."""


@dataclass(frozen=True)
class GoalNode:
    """A goal; ``annotation`` is None (no brackets) or an expression over child positions:
    an ``int`` (the i-th child, left to right) or ``(op, left, right)`` with op ``;``, ``#`` or
    ``FALLBACK``, or ``("flat", op)`` for ``c1 op c2 op ...`` over all children.  With
    ``forall`` set (the condition, possibly empty) the goal is the item forAll
    ``current_items->forAll(current_item | <forall>)``."""

    children: tuple["Node", ...]
    refinement: str = "and"  # "and" | "or"
    annotation: object = None
    group: bool = True
    divisible: bool = True
    condition: Union[str, None] = None  # condition context, e.g. "current_room.is_clean"
    achieve: Union[str, None] = None  # plain achieve condition (GoalType Achieve)
    forall: Union[str, None] = None  # item forAll condition (nested_forall shape)


Node = Union[TaskNode, GoalNode, QueryNode]


@dataclass(frozen=True)
class MissionSpec:
    room_predicates: tuple[str, ...]
    robot_predicates: tuple[str, ...]
    actions: tuple[Action, ...]
    tasks: tuple[Task, ...]
    rooms: tuple[Room, ...]
    query_active: bool  # select(r:Room | r.active) or select(r:Room | ) (every room)
    forall_condition: str  # the part after '|' of the forAll ("" for none)
    tree: GoalNode  # the forAll goal's refinement (G3 itself)
    item_predicates: tuple[str, ...] = ()  # non-empty: items exist (type item, Item records)
    items: tuple[Item, ...] = ()
    item_select: str = ""  # extra condition of the item query, e.g. "!i.is_ready"
    shape: str = "basic"

    # -- derived ---------------------------------------------------------------------------------
    @property
    def selected_rooms(self) -> list[Room]:
        return [r for r in self.rooms if r.active or not self.query_active]

    @property
    def uses_items(self) -> bool:
        return bool(self.item_predicates)

    def gm_task_count(self) -> int:
        return _count_tasks(self.tree)

    def selected_items(self, room: Room) -> list[Item]:
        """The records the item query selects for ``room`` (document order)."""
        by_name = {i.name: i for i in self.items}
        wanted = set(room.items or ())
        out = [i for i in self.items if i.name in wanted]
        if self.item_select.startswith("!i."):  # !i.is_<p>: the attribute exists and is not true
            pred = self.item_select[len("!i.is_"):]
            out = [i for i in out if dict(i.facts).get(pred) is False]
        return [by_name[i.name] for i in out]

    def instance_count(self) -> int:
        return sum(_count_instances(self.tree, len(self.selected_items(r))) for r in self.selected_rooms)

    def task_bounds(self) -> dict[str, int]:
        """An upper bound of the decomposition paths of every abstract task."""
        return _task_bounds(self.tasks)

    def instance_names(self) -> list[str]:
        """The abstract task of every task instance (in no particular order)."""
        out: list[str] = []
        for r in self.selected_rooms:
            _collect_instances(self.tree, len(self.selected_items(r)), 1, out)
        return out

    def path_product(self, free: frozenset[str] | set[str] = frozenset()) -> int:
        """Upper bound of the number of combinations of decompositions of all task instances
        (tasks in ``free`` count as one decomposition)."""
        bounds = self.task_bounds()
        bounds.update({t: 1 for t in free})
        n = 1
        for name in self.instance_names():
            n *= bounds.get(name, 1)
        return n

    def task_nodes(self) -> list[TaskNode]:
        """The GM tasks in id order (AT1, AT2, ...)."""
        return list(_task_nodes(self.tree))

    # -- rendering -------------------------------------------------------------------------------
    def texts(self, world_path: str = "knowledge/world_db.xml") -> dict[str, str]:
        return {
            "hddl": render_hddl(self),
            "gm": render_gm(self),
            "config": render_config(self, world_path),
            "world": render_world(self),
        }

    def write(self, directory: str | Path) -> tuple[Path, Path, Path]:
        """Write ``hddl/ gm/ configuration/ knowledge/`` into ``directory`` (the configuration
        names the world file by its absolute path); returns (hddl, gm, configuration)."""
        root = Path(directory)
        files = {
            "hddl": root / "hddl" / "domain.hddl",
            "gm": root / "gm" / "gm.json",
            "config": root / "configuration" / "configuration.json",
            "world": root / "knowledge" / "world_db.xml",
        }
        texts = self.texts(str(files["world"].resolve()))
        for key, path in files.items():
            path.parent.mkdir(parents=True, exist_ok=True)
            path.write_text(texts[key])
        return files["hddl"], files["gm"], files["config"]

    def dump(self) -> str:
        """All four files, for failure reports and regression cases."""
        t = self.texts()
        return "\n".join(f"----- {k} -----\n{v}" for k, v in t.items())

    def summary(self) -> str:
        return (f"MissionSpec(shape={self.shape}, rooms={len(self.rooms)}, selected={len(self.selected_rooms)}, "
                f"gm_tasks={self.gm_task_count()}, instances={self.instance_count()}, tasks={len(self.tasks)}, "
                f"actions={len(self.actions)}, annotation={render_tree_outline(self.tree)!r}, "
                f"forall={self.forall_condition!r})")


def _count_tasks(node: Node) -> int:
    if isinstance(node, TaskNode):
        return 1
    if isinstance(node, QueryNode):
        return 0
    return sum(_count_tasks(c) for c in node.children)


def _count_instances(node: Node, n_items: int) -> int:
    if isinstance(node, TaskNode):
        return 1
    if isinstance(node, QueryNode):
        return 0
    inner = sum(_count_instances(c, n_items) for c in node.children)
    return inner * n_items if node.forall is not None else inner


def _collect_instances(node: Node, n_items: int, times: int, out: list[str]) -> None:
    if isinstance(node, TaskNode):
        out.extend([node.task] * times)
    elif isinstance(node, GoalNode):
        k = times * n_items if node.forall is not None else times
        for c in node.children:
            _collect_instances(c, n_items, k, out)


def _task_nodes(node: Node) -> Iterator[TaskNode]:
    """GM tasks in depth-first, left-to-right order: the order of their ids."""
    if isinstance(node, TaskNode):
        yield node
    elif isinstance(node, GoalNode):
        for c in node.children:
            yield from _task_nodes(c)


def goal_nodes(node: Node) -> Iterator[GoalNode]:
    """Every goal of the tree (pre-order), ``node`` included."""
    if isinstance(node, GoalNode):
        yield node
        for c in node.children:
            yield from goal_nodes(c)


def _task_bounds(tasks: tuple[Task, ...]) -> dict[str, int]:
    bounds: dict[str, int] = {}
    for t in tasks:  # a task only calls earlier ones
        bounds[t.name] = sum(_method_paths(m, bounds) for m in t.methods)
    return bounds


def load_mission(spec: MissionSpec):
    """Write ``spec`` to a temporary directory and ``Mission.load`` it (every input is read at
    load time, so the directory can go)."""
    from mutrose_cp.mission import Mission

    with tempfile.TemporaryDirectory(prefix="mutrose-gen-") as d:
        return Mission.load(*spec.write(d))


def seeded_draws(seed_value: int, examples: int, stage: str, check: Callable[[Any], bool]) -> list[bool]:
    """``check`` on each mission of ``examples`` seeded draws of :func:`repeated_rooms` that loads
    and reaches ``stage`` (a stage of ``Mission``, such as ``"expansion"``), in order: what it
    said of each.  A property test says what holds; this says that it was not vacuous."""
    said: list[bool] = []

    @seed(seed_value)
    @settings(max_examples=examples, deadline=None, database=None, suppress_health_check=list(HealthCheck))
    @given(repeated_rooms())
    def draw(spec: MissionSpec) -> None:
        try:
            m = load_mission(spec)
            getattr(m, stage)
        except Exception:
            return
        said.append(check(m))

    draw()
    return said


# ---------------------------------------------------------------------------------------------
# Rendering


def _attr(pred: str) -> str:
    return f"is_{pred}"


def _params(item: bool) -> str:
    return "(?r - Bot ?rm - room ?it - item)" if item else "(?r - Bot ?rm - room)"


def _args(item: bool) -> str:
    return "?r ?rm ?it" if item else "?r ?rm"


def render_hddl(spec: MissionSpec) -> str:
    item_callee = {a.name for a in spec.actions if a.item} | {t.name for t in spec.tasks if t.item}
    out = ["; generated by tests/missiongen.py", "(define (domain generated)", "    (:types", "        room - object"]
    if spec.uses_items:
        out.append("        item - object")
    out += ["        Bot - robot", "    )", "    (:predicates"]
    out += [f"        ({p} ?rm - room)" for p in spec.room_predicates]
    out += [f"        ({p} ?it - item)" for p in spec.item_predicates]
    out += [f"        ({p} ?r - robot)" for p in spec.robot_predicates]
    out += ["    )", "    (:functions (level ?rm - room))", "    (:capabilities work)", ""]
    for t in spec.tasks:
        out.append(f"    (:task {t.name} :parameters {_params(t.item)})")
        for m in t.methods:
            out += [f"    (:method {m.name}", f"        :parameters {_params(t.item)}",
                    f"        :task ({t.name} {_args(t.item)})"]
            if m.pre:
                out.append(f"        :precondition (and {' '.join(c.hddl() for c in m.pre)})")
            if m.ordered:
                calls = " ".join(f"({s} {_args(s in item_callee)})" for s in m.subtasks)
                out.append(f"        :ordered-subtasks (and {calls})")
            else:
                calls = " ".join(f"(s{i} ({s} {_args(s in item_callee)}))" for i, s in enumerate(m.subtasks))
                out.append(f"        :subtasks (and {calls})")
            out.append("    )")
        out.append("")
    for a in spec.actions:
        pre = f"(and {' '.join(c.hddl() for c in a.pre)})" if a.pre else "()"
        eff = f"(and {' '.join(e.hddl() for e in a.eff)})" if a.eff else "()"
        out += [f"    (:action {a.name}", f"        :parameters {_params(a.item)}",
                "        :required-capabilities (work)", f"        :precondition {pre}",
                f"        :effect {eff}", "    )"]
    out.append(")")
    return "\n".join(out) + "\n"


def render_world(spec: MissionSpec) -> str:
    out = ['<?xml version="1.0" encoding="utf-8"?>', "<world_db>"]
    for r in spec.rooms:
        out += ["    <Room>", f"        <name>{r.name}</name>", f"        <active>{r.active}</active>"]
        for pred, value in r.facts:
            if value is not None:
                out.append(f"        <{_attr(pred)}>{value}</{_attr(pred)}>")
        if r.level is not None:
            out.append(f"        <level>{r.level}</level>")
        if r.items is not None:
            out.append(f"        <items>{','.join(r.items)}</items>")
        out.append("    </Room>")
    for i in spec.items:
        out += ["    <Item>", f"        <name>{i.name}</name>"]
        for pred, value in i.facts:
            if value is not None:
                out.append(f"        <{_attr(pred)}>{value}</{_attr(pred)}>")
        out.append("    </Item>")
    out.append("</world_db>")
    return "\n".join(out) + "\n"


def render_config(spec: MissionSpec, world_path: str) -> str:
    task_of = {t.name: t for t in spec.tasks}
    sem = [{"type": "attribute", "name": _attr(p), "relates_to": "Room", "belongs_to": "world_db",
            "mapped_type": "predicate", "map": {"pred": p, "arg_sorts": ["room"]}} for p in spec.room_predicates]
    sem.append({"type": "attribute", "name": "level", "relates_to": "Room", "belongs_to": "world_db",
                "mapped_type": "function", "map": {"pred": "level", "arg_sorts": ["room"]}})
    sem += [{"type": "attribute", "name": _attr(p), "relates_to": "Item", "belongs_to": "world_db",
             "mapped_type": "predicate", "map": {"pred": p, "arg_sorts": ["item"]}} for p in spec.item_predicates]
    sem += [{"type": "attribute", "name": _attr(p), "relates_to": "robot", "belongs_to": "robots_db",
             "mapped_type": "predicate", "map": {"pred": p, "arg_sorts": ["robot"]}} for p in spec.robot_predicates]
    var_mapping = []
    for k, node in enumerate(spec.task_nodes()):
        m = [{"gm_var": "current_room", "hddl_var": "?rm"}]
        if task_of[node.task].item:
            m.append({"gm_var": "current_item", "hddl_var": "?it"})
        var_mapping.append({"task_id": f"AT{k + 1}", "map": m})
    type_mapping = [{"hddl_type": "room", "ocl_type": "Room"}]
    if spec.uses_items:
        type_mapping.append({"hddl_type": "item", "ocl_type": "Item"})
    config = {
        "world_db": {"type": "file", "file_type": "xml", "path": world_path, "xml_root": "world_db",
                     "unique_id": "name"},
        "output": {"output_type": "file", "file_path": "output/mission.json", "file_type": "json"},
        "location_types": ["Room"],
        "type_mapping": type_mapping,
        "var_mapping": var_mapping,
        "semantic_mapping": sem,
    }
    return json.dumps(config, indent=4) + "\n"


def _gm_task_ids(spec: MissionSpec) -> list[str]:
    return [f"AT{i + 1}" for i in range(spec.gm_task_count())]


def _render_annotation(expr, ids: list[str]) -> str:
    if isinstance(expr, int):
        return ids[expr]
    if expr[0] == "flat":
        op = expr[1]
        if op == "FALLBACK":
            text = ids[0]
            for i in ids[1:]:
                text = f"FALLBACK({text},{i})"
            return text
        return op.join(ids)
    op, left, right = expr
    lt, rt = _render_annotation(left, ids), _render_annotation(right, ids)
    if op == "FALLBACK":
        return f"FALLBACK({lt},{rt})"
    wrap = lambda e, t: t if isinstance(e, int) else f"({t})"  # noqa: E731
    return f"{wrap(left, lt)}{op}{wrap(right, rt)}"


def render_tree_outline(node: Node) -> str:
    """A compact one-line picture of the tree (for summaries)."""
    if isinstance(node, TaskNode):
        return node.task
    if isinstance(node, QueryNode):
        return "Q"
    inner = ",".join(render_tree_outline(c) for c in node.children)
    tag = "OR" if node.refinement == "or" else "AND"
    ann = "" if node.annotation is None else f"{node.annotation}"
    flags = ("" if node.group else "!G") + ("" if node.divisible else "!D") + ("C" if node.condition else "") \
        + ("A" if node.achieve else "") + ("F" if node.forall is not None else "")
    return f"{tag}{flags}{ann}({inner})"


ITEM_QUERY = "world_db->select(i:Item | i.name in current_room.items{extra})"


def render_gm(spec: MissionSpec) -> str:
    nodes: list[dict] = []
    links: list[dict] = []
    counters = {"goal": 0, "task": 0, "x": 0, "uid": 0}
    item_tasks = {t.name for t in spec.tasks if t.item}

    def uid() -> str:
        counters["uid"] += 1
        return f"00000000-0000-4000-8000-{counters['uid']:012d}"

    def next_x() -> int:
        counters["x"] += 1
        return 120 + 110 * (counters["x"] - 1)

    def add_goal(text_words: str, depth: int, props: dict) -> tuple[str, str, dict]:
        counters["goal"] += 1
        gid = f"G{counters['goal']}"
        node = {"id": uid(), "text": f"{gid}: {text_words}", "type": "istar.Goal", "x": next_x(),
                "y": 60 + 110 * depth, "customProperties": {"Description": "", **props}}
        nodes.append(node)
        return gid, node["id"], node

    def link(child_uid: str, parent_uid: str, kind: str) -> None:
        links.append({"id": uid(), "type": "istar.OrRefinementLink" if kind == "or" else "istar.AndRefinementLink",
                      "source": child_uid, "target": parent_uid})

    def add_children(goal: GoalNode, node: dict, node_uid: str, depth: int) -> None:
        ids = []
        for child in goal.children:
            if isinstance(child, TaskNode):
                counters["task"] += 1
                tid = f"AT{counters['task']}"
                props = {"Description": "", "Location": "current_room"}
                if child.task in item_tasks:
                    props["Params"] = "current_item"
                tnode = {"id": uid(), "text": f"{tid}: {child.task}", "type": "istar.Task", "x": next_x(),
                         "y": 60 + 110 * (depth + 1), "customProperties": props}
                nodes.append(tnode)
                link(tnode["id"], node_uid, goal.refinement)
                ids.append(tid)
            elif isinstance(child, QueryNode):
                extra = f" && {spec.item_select}" if spec.item_select else ""
                cid, cuid, _ = add_goal("Items Are Listed", depth + 1, {
                    "GoalType": "Query", "Monitors": "current_room", "Controls": "current_items : Sequence(Item)",
                    "QueriedProperty": ITEM_QUERY.format(extra=extra)})
                link(cuid, node_uid, goal.refinement)
                ids.append(cid)
            else:
                words = "Every Item Is Handled" if child.forall is not None else "Subgoal"
                cid, cuid, cnode = add_goal(words, depth + 1, goal_props(child))
                link(cuid, node_uid, goal.refinement)
                ids.append(cid)
                add_children(child, cnode, cuid, depth + 1)
        if goal.annotation is not None and len(goal.children) >= 2:
            node["text"] += f" [{_render_annotation(goal.annotation, ids)}]"

    def goal_props(goal: GoalNode) -> dict:
        if goal.forall is not None:
            props: dict = {"GoalType": "Achieve", "Monitors": "current_items", "Controls": "current_item : Item",
                           "AchieveCondition": f"current_items->forAll(current_item | {goal.forall})"}
        else:
            props = {"Monitors": "current_room"}
        if not goal.group:
            props["Group"] = "False"
        if not goal.divisible:
            props["Divisible"] = "False"
        if goal.condition:
            props["CreationCondition"] = f'assertion condition "{goal.condition}"'
        if goal.achieve:
            props["GoalType"] = "Achieve"
            props["AchieveCondition"] = goal.achieve
        return props

    _, root_uid, _ = add_goal("Root [G2;G3]", 0, {})
    query = "world_db->select(r:Room | r.active)" if spec.query_active else "world_db->select(r:Room | )"
    _, q_uid, _ = add_goal("Rooms Are Listed", 1, {"GoalType": "Query", "Controls": "rooms : Sequence(Room)",
                                                    "QueriedProperty": query})
    tree = spec.tree
    fa_props = {"GoalType": "Achieve", "Monitors": "rooms : Sequence(Room)", "Controls": "current_room : Room",
                "AchieveCondition": f"rooms->forAll(current_room | {spec.forall_condition})"}
    if not tree.group:
        fa_props["Group"] = "False"
    if not tree.divisible:
        fa_props["Divisible"] = "False"
    _, fa_uid, fa_node = add_goal("Every Room Is Handled", 1, fa_props)
    link(q_uid, root_uid, "and")
    link(fa_uid, root_uid, "and")
    add_children(tree, fa_node, fa_uid, 1)
    gm = {
        "actors": [{"id": uid(), "text": "Generated Mission", "type": "istar.Actor", "x": 40, "y": 20,
                    "customProperties": {"Description": ""}, "nodes": nodes}],
        "orphans": [], "dependencies": [], "links": links, "display": {}, "tool": "pistar.2.0.0",
        "istar": "2.0", "saveDate": "Sat, 22 Nov 2025 12:00:00 GMT",
        "diagram": {"width": 120 + 110 * counters["x"], "height": 700, "customProperties": {"Description": ""}},
    }
    return json.dumps(gm, indent=2) + "\n"


# ---------------------------------------------------------------------------------------------
# Strategies: the domain


def _atoms(room_preds: tuple[str, ...], robot_preds: tuple[str, ...],
           item_preds: tuple[str, ...] = ()) -> list[tuple[str, str]]:
    return [(p, "?rm") for p in room_preds] + [(p, "?r") for p in robot_preds] + [(p, "?it") for p in item_preds]


def _literals(room_preds: tuple[str, ...], robot_preds: tuple[str, ...], sizes: tuple[int, ...],
              positive_bias: bool = False, item_preds: tuple[str, ...] = ()):
    """Lists of literals on distinct atoms; the size is drawn from ``sizes`` (shrinks to the
    first); with ``positive_bias`` three out of four literals are positive."""
    polarity = st.sampled_from([True, True, True, False]) if positive_bias else st.booleans()
    atoms = _atoms(room_preds, robot_preds, item_preds)

    @st.composite
    def draw_list(draw):
        n = min(draw(st.sampled_from(sizes)), len(atoms))
        chosen = draw(st.permutations(atoms))[:n]  # distinct atoms, no filtering
        return [Lit(p, v, draw(polarity)) for p, v in chosen]

    return draw_list()


NUMERIC_PRECONDITIONS = (Cmp(">", 0), Cmp("=", 1), Cmp("=", 0), Cmp(">", 1))


@st.composite
def _action(draw, name: str, room_preds, robot_preds, item_preds: tuple[str, ...] = (),
            numeric: bool = False) -> Action:
    """An action over (?r ?rm), or over (?r ?rm ?it) when ``item_preds`` are given."""
    pre = draw(_literals(room_preds, robot_preds, (0, 0, 0, 1, 1), item_preds=item_preds))
    eff: list = draw(_literals(room_preds, robot_preds, (1, 0, 1, 2), positive_bias=True, item_preds=item_preds))
    change = draw(st.sampled_from([None, None, "increase", "decrease"]))
    if change:
        eff.append(Change(change))
    # occasionally a numeric action precondition too (not often: below an assumed method
    # precondition (> (level ?rm) N) a second level test fails, which prunes the path)
    if draw(st.integers(0, 7)) == 0:
        pre.append(draw(st.sampled_from(NUMERIC_PRECONDITIONS)))
    return Action(name, tuple(pre), tuple(eff), item=bool(item_preds))


def _method_paths(m: Method, bounds: dict[str, int]) -> int:
    n = 1 if m.ordered or len(m.subtasks) < 2 else 2  # unordered pair: two orderings
    for s in m.subtasks:
        n *= bounds.get(s, 1)
    return n


@st.composite
def _method_precondition(draw, switch: Lit, room_preds, robot_preds, numeric: bool = False,
                         item_preds: tuple[str, ...] = ()) -> list:
    """A method precondition: none, the task's switch literal or its negation (so that methods
    complement each other, as in real domains), random literals, or a numeric test."""
    kind = draw(st.sampled_from([4, 5, 4, 5, 0, 1, 3]) if numeric else st.integers(-1, 5))
    if kind <= 0:
        return []
    if kind == 1:
        return [switch]
    if kind == 2:
        return [Lit(switch.pred, switch.var, not switch.positive)]
    if kind == 3:
        return draw(_literals(room_preds, robot_preds, (1, 1, 2), item_preds=item_preds))
    if kind == 4:
        return [draw(st.sampled_from(NUMERIC_PRECONDITIONS))]
    return draw(_literals(room_preds, robot_preds, (1,), item_preds=item_preds)) + \
        [draw(st.sampled_from(NUMERIC_PRECONDITIONS))]


@st.composite
def _task(draw, name: str, actions: tuple[Action, ...], earlier: tuple[Task, ...], bounds: dict[str, int],
          room_preds, robot_preds, *, max_paths: int = MAX_PATHS, numeric: bool = False,
          switch: Union[Lit, None] = None, forced: Union[str, None] = None,
          item_preds: tuple[str, ...] = ()) -> Task:
    """An abstract task with 1-3 methods and at most ``max_paths`` decomposition paths; a task
    over an item when ``item_preds`` are given (it may call every action and earlier task, the
    others only room actions and earlier room tasks).  ``forced``: an action that the first
    method calls."""
    item = bool(item_preds)
    n_methods = min(max_paths, draw(st.sampled_from([2, 3, 1]) if numeric else st.integers(1, 3)))
    if switch is None:
        switch = draw(_literals(room_preds, (), (1,)))[0]
    # 0: independent preconditions; 1: the methods split on a room fact (switch / not switch),
    # 2: on the level ((> 0), (= 0), (= 1)) - so that some method fits most world states
    if n_methods < 2:
        scheme = 0
    else:
        scheme = draw(st.sampled_from([2, 2, 2, 1]) if numeric else st.integers(0, 2))
    split = ([switch], [Lit(switch.pred, switch.var, not switch.positive)]) if scheme == 1 else (
        [Cmp(">", 0)], [Cmp("=", 0)], [Cmp("=", 1)])
    room_actions = [a.name for a in actions if not a.item]
    callees = [a.name for a in actions if item or not a.item] + [t.name for t in earlier if item or not t.item]
    methods = []
    budget = max_paths
    for k in range(n_methods):
        remaining_methods = n_methods - k - 1
        if scheme and k < len(split):
            pre = list(split[k])
            if draw(st.integers(0, 3)) == 0:
                pre += draw(_literals(room_preds, robot_preds, (1,), item_preds=item_preds))
        else:
            pre = draw(_method_precondition(switch, room_preds, robot_preds, numeric, item_preds))
        subtasks = draw(st.lists(st.sampled_from(callees), min_size=1, max_size=2))
        if k == 0 and forced is not None and forced not in subtasks:
            subtasks[draw(st.integers(0, len(subtasks) - 1))] = forced
        ordered = draw(st.integers(0, 3)) != 0
        m = Method(f"m{name[-1]}{k}", tuple(pre), tuple(subtasks), ordered)
        # keep the number of decomposition paths small: simplify the method until it fits
        if _method_paths(m, bounds) > budget - remaining_methods:
            m = Method(m.name, m.pre, tuple(s if s not in bounds else room_actions[0] for s in m.subtasks), True)
        methods.append(m)
        budget -= _method_paths(m, bounds)
    return Task(name, tuple(methods), item)


@dataclass(frozen=True)
class _Domain:
    room_preds: tuple[str, ...]
    robot_preds: tuple[str, ...]
    item_preds: tuple[str, ...]
    actions: tuple[Action, ...]
    tasks: tuple[Task, ...]
    toggle: Union[str, None] = None  # the predicate that toggle actions set, unset and require

    @property
    def room_task_names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.tasks if not t.item)

    @property
    def task_names(self) -> tuple[str, ...]:
        return tuple(t.name for t in self.tasks)


@st.composite
def _domain(draw, *, toggle: bool = False, numeric: bool = False, items: bool = False,
            max_paths: int = MAX_PATHS) -> _Domain:
    """Predicates, actions and abstract tasks.

    ``toggle``: one room predicate ``P`` gets actions ``setP`` / ``unsetP`` / ``needP`` /
    ``neednotP``; three tasks, ``TaskA``'s first method calls ``setP``, ``TaskB``'s ``unsetP``
    and ``TaskC``'s ``needP`` or ``neednotP``.  ``numeric``: more level tests in method and
    action preconditions.  ``items``: item predicates, item actions and the item task ``TaskI``."""
    room_preds = tuple(draw(st.lists(st.sampled_from(ROOM_PREDICATES), min_size=1, max_size=3, unique=True)))
    toggled = None
    if toggle:
        toggled = draw(st.sampled_from(ROOM_PREDICATES))
        room_preds = (toggled,) + tuple(p for p in room_preds if p != toggled)[:1]
    robot_preds = tuple(draw(st.lists(st.sampled_from(ROBOT_PREDICATES), min_size=max(0, 2 - len(room_preds)),
                                      max_size=min(2, 4 - len(room_preds)), unique=True)))
    item_preds = tuple(draw(st.lists(st.sampled_from(ITEM_PREDICATES), min_size=1, max_size=2, unique=True))) \
        if items else ()
    n_actions = draw(st.integers(1, 2 if toggle else 4))
    actions_list: list[Action] = []
    for i in range(n_actions):
        act = draw(_action(f"act{i}", room_preds, robot_preds, numeric=numeric))
        # sometimes undo a room effect of an earlier action: parallel conflicts, set/unset chains
        undoable = [e for prev in actions_list for e in prev.eff if isinstance(e, Lit) and e.var == "?rm"]
        if undoable and draw(st.integers(0, 1)) == 0:
            e = draw(st.sampled_from(undoable))
            if all(not (isinstance(x, Lit) and x.pred == e.pred and x.var == e.var) for x in act.eff):
                act = Action(act.name, act.pre, act.eff + (Lit(e.pred, e.var, not e.positive),))
        actions_list.append(act)
    forced: dict[str, str] = {}
    if toggled:
        p = toggled
        on, off = Lit(p, "?rm"), Lit(p, "?rm", False)
        level = lambda kind: (Change(kind),) if draw(st.integers(0, 2)) == 0 else ()  # noqa: E731
        others = [q for q in room_preds if q != p]
        side = (Lit(others[0], "?rm", draw(st.booleans())),) if others and draw(st.booleans()) else ()
        actions_list += [Action(f"set{p}", (), (on,) + level("increase")),
                         Action(f"unset{p}", (), (off,) + level("decrease")),
                         Action(f"need{p}", (on,), side),
                         Action(f"neednot{p}", (off,), ())]
        forced = {"TaskA": f"set{p}", "TaskB": f"unset{p}", "TaskC": draw(st.sampled_from([f"need{p}", f"neednot{p}"]))}
    for i in range(draw(st.integers(1, 2)) if items else 0):
        actions_list.append(draw(_action(f"iact{i}", room_preds, robot_preds, item_preds, numeric)))
    actions = tuple(actions_list)
    n_tasks = 3 if toggle else draw(st.integers(1, len(TASK_NAMES)))
    tasks: list[Task] = []
    bounds: dict[str, int] = {}
    switch = Lit(toggled, "?rm", draw(st.booleans())) if toggled else None
    for name in TASK_NAMES[:n_tasks]:
        t = draw(_task(name, actions, tuple(tasks), bounds, room_preds, robot_preds, max_paths=max_paths,
                       numeric=numeric, switch=switch, forced=forced.get(name)))
        tasks.append(t)
        bounds[name] = sum(_method_paths(m, bounds) for m in t.methods)
    if items:
        item_actions = [a.name for a in actions if a.item]
        t = draw(_task(ITEM_TASK, actions, tuple(tasks), bounds, room_preds, robot_preds, max_paths=max_paths,
                       numeric=numeric, forced=draw(st.sampled_from(item_actions)), item_preds=item_preds))
        tasks.append(t)
    return _Domain(room_preds, robot_preds, item_preds, actions, tuple(tasks), toggled)


def _simplified(task: Task, action: str, actions: set[str]) -> Task:
    """``task`` with only its first method, totally ordered and calling actions only: one path."""
    m = task.methods[0]
    return Task(task.name, (Method(m.name, m.pre, tuple(s if s in actions else action for s in m.subtasks), True),),
                task.item)


def _capped(spec: MissionSpec, cap: int, free: set[str] = frozenset()) -> MissionSpec:
    """Simplify the most used abstract tasks until the decompositions of all task instances
    combine in at most ``cap`` ways (keeps the exploratory algorithm fast); tasks in ``free``
    count as one decomposition (they do not multiply the combinations)."""
    action_names = {a.name for a in spec.actions}
    fallback = next(a.name for a in spec.actions if not a.item)
    while spec.path_product(free) > cap:
        bounds = spec.task_bounds()
        bounds.update({t: 1 for t in free})
        uses = spec.instance_names()
        candidates = [t for t in spec.tasks
                      if bounds[t.name] > 1 or any(s not in action_names for s in t.methods[0].subtasks)]
        if not candidates:
            break
        worst = max(candidates, key=lambda t: (uses.count(t.name) * bounds[t.name], t.name))
        tasks = tuple(_simplified(t, fallback, action_names) if t.name == worst.name else t for t in spec.tasks)
        spec = dataclasses.replace(spec, tasks=tasks)
    return spec


# ---------------------------------------------------------------------------------------------
# Strategies: contradictory and duplicate preconditions


@st.composite
def _with_odd_preconditions(draw, spec: MissionSpec) -> MissionSpec:
    """Give a method of a used task a self-contradictory precondition and a method of a used task
    a duplicate precondition.  A contradictory method is usually added beside the task's other
    methods (so that the task keeps a decomposition) and sometimes replaces a method's
    precondition part."""
    used = {n.task for n in spec.task_nodes()}
    tasks = list(spec.tasks)
    action_of = {a.name: a for a in spec.actions}

    def pick_used() -> int:
        return draw(st.sampled_from([i for i, t in enumerate(tasks) if t.name in used]))

    # contradiction
    i = pick_used()
    t = tasks[i]
    kind = draw(st.integers(0, 3))
    if kind == 1 and spec.robot_predicates:
        q = draw(st.sampled_from(spec.robot_predicates))
        pair: tuple = (Lit(q, "?r"), Lit(q, "?r", False))
    elif kind == 2:
        pair = draw(st.sampled_from([(Cmp("=", 0), Cmp("=", 1)), (Cmp("=", 1), Cmp("=", 2))]))
    elif kind == 3 and t.item:
        q = draw(st.sampled_from(spec.item_predicates))
        pair = (Lit(q, "?it"), Lit(q, "?it", False))
    else:
        q = draw(st.sampled_from(spec.room_predicates))
        pair = (Lit(q, "?rm"), Lit(q, "?rm", False))
    if draw(st.booleans()):
        pair = pair[::-1]
    if len(t.methods) == 1 or draw(st.integers(0, 2)) != 0:  # a new method beside the others
        base = t.methods[draw(st.integers(0, len(t.methods) - 1))]
        odd = Method(f"m{t.name[-1]}{len(t.methods)}", pair, base.subtasks, True)
        at = draw(st.integers(0, len(t.methods)))
        methods = t.methods[:at] + (odd,) + t.methods[at:]
        # method names follow the position (the name does not matter, the order does)
        tasks[i] = Task(t.name, methods, t.item)
    else:
        k = draw(st.integers(0, len(t.methods) - 1))
        m = t.methods[k]
        at = draw(st.integers(0, len(m.pre)))
        pre = m.pre[:at] + pair[:1] + m.pre[at:] + pair[1:]
        tasks[i] = Task(t.name, t.methods[:k] + (dataclasses.replace(m, pre=pre),) + t.methods[k + 1:], t.item)
    # duplicate
    i = pick_used()
    t = tasks[i]
    k = draw(st.integers(0, len(t.methods) - 1))
    m = t.methods[k]
    first = action_of.get(m.subtasks[0]) if m.subtasks else None
    kind = draw(st.integers(0, 2))
    if kind == 0 and first is not None and first.pre:
        dup: tuple = (draw(st.sampled_from(first.pre)),)  # the first action requires it too
    elif kind == 1 and m.pre:
        dup = (draw(st.sampled_from(m.pre)),)
    else:
        c = draw(st.sampled_from([Lit(draw(st.sampled_from(spec.room_predicates)), "?rm", draw(st.booleans())),
                                  Cmp(">", 0)]))
        dup = (c, c)
    tasks[i] = Task(t.name, t.methods[:k] + (dataclasses.replace(m, pre=m.pre + dup),) + t.methods[k + 1:], t.item)
    return dataclasses.replace(spec, tasks=tuple(tasks))


def contradictory_methods(spec: MissionSpec) -> list[tuple[str, str]]:
    """(task, method) pairs whose precondition requires a fact and its negation or two values of
    one function."""
    out = []
    for t in spec.tasks:
        for m in t.methods:
            lits = {(c.pred, c.var, c.positive) for c in m.pre if isinstance(c, Lit)}
            values = {c.value for c in m.pre if isinstance(c, Cmp) and c.op == "="}
            if any((p, v, not pos) in lits for p, v, pos in lits) or len(values) > 1:
                out.append((t.name, m.name))
    return out


def duplicate_preconditions(spec: MissionSpec) -> list[tuple[str, str]]:
    """(task, method) pairs with a precondition written twice, or also required by the method's
    first action."""
    action_of = {a.name: a for a in spec.actions}
    out = []
    for t in spec.tasks:
        for m in t.methods:
            first = action_of.get(m.subtasks[0]) if m.subtasks else None
            if len(set(m.pre)) < len(m.pre) or (first is not None and set(m.pre) & set(first.pre)):
                out.append((t.name, m.name))
    return out


# ---------------------------------------------------------------------------------------------
# Strategies: goal trees


@st.composite
def _annotation(draw, k: int, refinement: str):
    if refinement == "or":
        return draw(st.sampled_from([None, ("flat", "#")]))
    choice = draw(st.integers(0, 3))
    if choice == 0:
        return None
    if choice == 1 or k == 2:
        return ("flat", draw(st.sampled_from([";", "#", "FALLBACK"])))
    return draw(_nested_expression(0, k))


@st.composite
def _nested_expression(draw, lo: int, hi: int, top_op: Union[str, None] = None):
    """A binary annotation expression over child positions lo..hi-1, left to right."""
    if hi - lo == 1:
        return lo
    split = draw(st.integers(lo + 1, hi - 1))
    op = top_op or draw(st.sampled_from([";", "#", "FALLBACK"]))
    return (op, draw(_nested_expression(lo, split)), draw(_nested_expression(split, hi)))


def _room_conditions(room_preds) -> tuple[str, ...]:
    return tuple(f"{neg}current_room.{_attr(p)}" for neg in ("", "!") for p in room_preds)


def _room_achieves(room_preds) -> tuple[str, ...]:
    return tuple(f"current_room.{_attr(p)}" for p in room_preds) + ("current_room.level > 0",)


def _item_conditions(item_preds) -> tuple[str, ...]:
    return tuple(f"{neg}current_item.{_attr(q)}" for neg in ("", "!") for q in item_preds)


def _flags(draw) -> tuple[bool, bool]:
    flag = draw(st.integers(0, 11))
    return (False, True) if flag == 0 else (True, False) if flag == 1 else (True, True)


@st.composite
def _goal(draw, budget: int, depth: int, task_names: tuple[str, ...], room_preds: tuple[str, ...],
          top: bool = False, *, conditions: Union[tuple[str, ...], None] = None,
          achieves: Union[tuple[str, ...], None] = None, extra_max: int = 14, achieve_slots: int = 1) -> GoalNode:
    """A goal with 1..3 children using at most ``budget`` GM tasks (at least one).  A non-top goal
    gets a condition context with probability 2/(extra_max+1) and a plain achieve condition with
    probability achieve_slots/(extra_max+1)."""
    conditions = conditions or _room_conditions(room_preds)
    achieves = achieves or _room_achieves(room_preds)
    max_children = min(3, budget) if depth < MAX_DEPTH else 1
    if top:  # the forAll goal: mostly an operator over two or three children
        k = min(max_children, draw(st.sampled_from([2, 3, 1])))
    else:
        k = draw(st.integers(1, max_children))
    children: list[Node] = []
    used = 0
    for i in range(k):
        child_budget = budget - used - (k - i - 1)
        if depth >= MAX_DEPTH - 1:
            nest = False
        elif k >= 2:
            nest = draw(st.integers(0, 3)) != 0  # mostly a subgoal (often a means-end goal)
        else:
            nest = draw(st.integers(0, 5)) == 0  # rarely a means-end goal over a subgoal
        if nest:
            child: Node = draw(_goal(child_budget, depth + 1, task_names, room_preds, conditions=conditions,
                                     achieves=achieves, extra_max=extra_max, achieve_slots=achieve_slots))
        else:
            child = TaskNode(draw(st.sampled_from(task_names)))
        children.append(child)
        used += _count_tasks(child)
    refinement = "or" if k >= 2 and draw(st.integers(0, 2)) == 0 else "and"
    annotation = draw(_annotation(k, refinement)) if k >= 2 else None
    group, divisible = _flags(draw)
    condition = achieve = None
    if not top:
        extra = draw(st.integers(0, extra_max))
        if extra <= 1:
            condition = draw(st.sampled_from(conditions))
        elif extra < 2 + achieve_slots:
            achieve = draw(st.sampled_from(achieves))
    return GoalNode(tuple(children), refinement, annotation, group, divisible, condition, achieve)


@st.composite
def _long_sequence_tree(draw, task_names: tuple[str, ...], forced: tuple[str, ...], room_preds) -> GoalNode:
    """10-15 GM tasks under one flat ``;``: direct tasks or means-end goals (sometimes one with a
    plain achieve condition and one with a condition context), every name of ``forced`` at least once; sometimes
    beside one more task under a parallel or sequential parent."""
    k = draw(st.integers(10, 15))
    names = [draw(st.sampled_from(task_names)) for _ in range(k)]
    for pos, name in zip(draw(st.permutations(range(k))), forced):
        names[pos] = name
    children: list[Node] = [TaskNode(name) if draw(st.integers(0, 3)) else GoalNode((TaskNode(name),))
                            for name in names]
    # at most one plain achieve goal and one condition context (each fails the whole sequence
    # or drops a task, so more would make most sequences trivial)
    if draw(st.integers(0, 2)) == 0:
        i = draw(st.integers(0, k - 1))
        children[i] = GoalNode((TaskNode(names[i]),), achieve=draw(st.sampled_from(_room_achieves(room_preds))))
    if draw(st.integers(0, 3)) == 0:
        i = draw(st.integers(0, k - 1))
        children[i] = GoalNode((TaskNode(names[i]),), condition=draw(st.sampled_from(_room_conditions(room_preds))))
    group, divisible = (True, True) if draw(st.integers(0, 3)) else _flags(draw)
    sequence = GoalNode(tuple(children), annotation=("flat", ";"), group=group, divisible=divisible)
    if draw(st.integers(0, 3)):
        return sequence
    other = TaskNode(draw(st.sampled_from(task_names)))
    pair = (sequence, other) if draw(st.booleans()) else (other, sequence)
    return GoalNode(pair, annotation=draw(st.sampled_from([("flat", ";"), ("flat", ";"), None, ("flat", "#")])))


@st.composite
def _chain_tree(draw, task_names: tuple[str, ...], room_preds) -> tuple[GoalNode, Union[tuple[str, bool], None]]:
    """One task below 0-3 single-child goals (some with a plain achieve condition or a condition
    context); sometimes a sibling goal on the left whose condition context is false (returned as
    (predicate, world value)) so that the Task Graph drops it: a unique-branch Task Graph."""
    node: Node = TaskNode(draw(st.sampled_from(task_names)))
    for _ in range(draw(st.integers(0, 3))):
        extra = draw(st.integers(0, 7))
        condition = draw(st.sampled_from(_room_conditions(room_preds))) if extra == 0 else None
        achieve = draw(st.sampled_from(_room_achieves(room_preds) + ("current_room.level = 1",))) \
            if extra in (1, 2) else None
        group, divisible = _flags(draw)
        node = GoalNode((node,), group=group, divisible=divisible, condition=condition, achieve=achieve)
    if draw(st.integers(0, 2)):
        return GoalNode((node,)), None
    p = draw(st.sampled_from(room_preds))
    positive = draw(st.booleans())
    sibling = GoalNode((TaskNode(draw(st.sampled_from(task_names))),),
                       condition=f"{'' if positive else '!'}current_room.{_attr(p)}")
    annotation = draw(st.sampled_from([None, ("flat", ";"), ("flat", "#"), ("flat", "FALLBACK")]))
    return GoalNode((sibling, node), annotation=annotation), (p, not positive)


@st.composite
def _with_achieve(draw, goal: GoalNode, achieves: tuple[str, ...]) -> GoalNode:
    """Usually put a plain Achieve goal into ``goal``'s subtree: an achieve goal over all of its
    children (an operator when there are several) or one child turned into / wrapped by one."""
    mode = draw(st.integers(0, 3))
    a = draw(st.sampled_from(achieves))
    if mode == 0:
        return goal
    if mode == 1:
        inner = GoalNode(goal.children, goal.refinement, goal.annotation, achieve=a)
        return dataclasses.replace(goal, children=(inner,), refinement="and", annotation=None)
    i = draw(st.integers(0, len(goal.children) - 1))
    c = goal.children[i]
    c = GoalNode((c,), achieve=a) if isinstance(c, TaskNode) else dataclasses.replace(c, achieve=a, condition=None)
    return dataclasses.replace(goal, children=goal.children[:i] + (c,) + goal.children[i + 1:])


@st.composite
def _nested_tree(draw, dom: _Domain) -> GoalNode:
    """[Q;(before);F;(after)]: the item query, the item forAll F (with plain achieve goals inside)
    and optionally a room task before or after it."""
    room_names = dom.room_task_names
    names = room_names + (ITEM_TASK,) * len(room_names)  # about half of the inner tasks are over the item
    achieves = _room_achieves(dom.room_preds) + _item_conditions(dom.item_preds) + (
        "current_room.level = 1", f"current_room.{_attr(dom.room_preds[0])} && current_item.{_attr(dom.item_preds[0])}")
    conditions = _room_conditions(dom.room_preds) + _item_conditions(dom.item_preds)
    inner = draw(_goal(draw(st.integers(1, 3)), 1, names, dom.room_preds, top=True, conditions=conditions,
                       achieves=achieves, extra_max=5, achieve_slots=2))
    # the item forAll itself iterates: its tasks must be over an item or a room
    inner = draw(_with_achieve(inner, achieves))
    forall = draw(st.sampled_from(("", "") + _item_conditions(dom.item_preds)))
    inner = dataclasses.replace(inner, forall=forall, condition=None, achieve=None)

    def room_part() -> Node:
        t = TaskNode(draw(st.sampled_from(room_names)))
        return t if draw(st.booleans()) else GoalNode((t,))

    before = [room_part()] if draw(st.integers(0, 2)) == 0 else []
    after = [room_part()] if draw(st.integers(0, 3)) == 0 else []
    annotation = draw(st.sampled_from([("flat", ";"), ("flat", ";"), ("flat", ";"), None, ("flat", "#"),
                                       ("flat", "FALLBACK")]))
    group, divisible = _flags(draw)
    return GoalNode((QueryNode(), *before, inner, *after), annotation=annotation, group=group, divisible=divisible)


@st.composite
def _beside_tree(draw, task_names: tuple[str, ...], room_preds, budget: int) -> GoalNode:
    """A goal with a ``;`` annotation over 3-4 children mixing direct tasks and subgoals, as the
    forAll goal or one level below it."""
    below = draw(st.integers(0, 2)) == 0 and budget >= 4
    own = budget - 1 if below else budget
    k = min(own, draw(st.integers(3, 4)))
    is_task = [draw(st.booleans()) for _ in range(k)]
    if all(is_task) or not any(is_task):
        is_task[draw(st.integers(0, k - 1))] = not is_task[0]
    children: list[Node] = []
    used = 0
    for i, direct in enumerate(is_task):
        if direct:
            child: Node = TaskNode(draw(st.sampled_from(task_names)))
        else:
            child = draw(_goal(own - used - (k - i - 1), 2 if below else 1, task_names, room_preds, extra_max=9))
        children.append(child)
        used += _count_tasks(child)
    annotation = ("flat", ";") if draw(st.integers(0, 3)) else draw(_nested_expression(0, k, ";"))
    group, divisible = (True, True) if draw(st.integers(0, 3)) else _flags(draw)
    mixed = GoalNode(tuple(children), annotation=annotation, group=group, divisible=divisible)
    if not below:
        return mixed
    other = TaskNode(draw(st.sampled_from(task_names)))
    pair = (mixed, other) if draw(st.booleans()) else (other, mixed)
    return GoalNode(pair, annotation=draw(st.sampled_from([None, ("flat", ";"), ("flat", "#"), ("flat", "FALLBACK")])))


def beside_goals(node: Node) -> list[GoalNode]:
    """Goals with a ``;`` annotation whose children mix direct tasks and subgoals."""
    return [g for g in goal_nodes(node)
            if g.annotation is not None and ";" in str(g.annotation)
            and any(isinstance(c, TaskNode) for c in g.children) and any(isinstance(c, GoalNode) for c in g.children)]


# ---------------------------------------------------------------------------------------------
# Strategies: the world


@st.composite
def _rooms(draw, room_preds, n_rooms: int) -> list[Room]:
    rooms = []
    for i in range(n_rooms):
        active = draw(st.integers(0, 7)) != 7
        facts = tuple((p, draw(st.sampled_from([None, True, False, None]))) for p in room_preds)
        level = draw(st.sampled_from([1, 0, 2, None]))
        rooms.append(Room(f"Room{i + 1}", active, facts, level))
    return rooms


@st.composite
def _one_selected_room(draw, room_preds) -> tuple[list[Room], bool]:
    """1-2 rooms of which the room query selects exactly one."""
    rooms = draw(_rooms(room_preds, draw(st.integers(1, 2))))
    if len(rooms) == 1:
        return rooms, draw(st.booleans()) and rooms[0].active
    chosen = draw(st.integers(0, 1))
    return [dataclasses.replace(r, active=(i == chosen)) for i, r in enumerate(rooms)], True


@st.composite
def _forall_condition(draw, room_preds, actions) -> str:
    """Empty, a predicate that some action makes true (else any), its negation or a level test."""
    set_true = [p for p in room_preds if any(isinstance(e, Lit) and e.var == "?rm" and e.positive and e.pred == p
                                               for a in actions for e in a.eff)]
    kind = draw(st.integers(0, 5))
    if kind <= 1:
        return ""
    if kind <= 3:
        return f"current_room.{_attr(draw(st.sampled_from(set_true or list(room_preds))))}"
    if kind == 4:
        return f"!current_room.{_attr(draw(st.sampled_from(room_preds)))}"
    return draw(st.sampled_from(["current_room.level > 0", "current_room.level = 1", "current_room.level = 0"]))


# ---------------------------------------------------------------------------------------------
# Strategies: missions


def _spec(dom: _Domain, rooms, query_active: bool, condition: str, tree: GoalNode, shape: str, **kw) -> MissionSpec:
    return MissionSpec(dom.room_preds, dom.robot_preds, dom.actions, dom.tasks, tuple(rooms), query_active,
                       condition, tree, item_predicates=dom.item_preds, shape=shape, **kw)


@st.composite
def _basic(draw) -> MissionSpec:
    dom = draw(_domain())
    rooms = draw(_rooms(dom.room_preds, draw(st.integers(1, 3))))
    query_active = draw(st.integers(0, 3)) != 0
    selected = [r for r in rooms if r.active or not query_active]
    budget = max(1, MAX_TASK_INSTANCES // max(1, len(selected)))
    tree = draw(_goal(budget, 0, dom.task_names, dom.room_preds, top=True))
    condition = draw(_forall_condition(dom.room_preds, dom.actions))
    return _spec(dom, rooms, query_active, condition, tree, "basic")


@st.composite
def _toggle_domain(draw) -> _Domain:
    """The long-sequence domain: ``setP`` / ``unsetP`` / ``needP`` / ``neednotP`` on one room
    predicate ``P`` and a side action; ``TaskA`` sets ``P``, ``TaskB`` unsets it and ``TaskC``
    checks it, each in one of a few variants: always applicable, split on ``P`` (exactly one
    method fits a known ``P``, and every method sets or unsets ``P``), guarded by a random
    precondition, or with two methods that may both fit."""
    p = draw(st.sampled_from(ROOM_PREDICATES))
    others = [q for q in ROOM_PREDICATES if q != p]
    room_preds = (p,) + tuple(draw(st.lists(st.sampled_from(others), max_size=1)))
    robot_preds = tuple(draw(st.lists(st.sampled_from(ROBOT_PREDICATES), max_size=1)))
    on, off = Lit(p, "?rm"), Lit(p, "?rm", False)
    change = lambda kind: (Change(kind),) if draw(st.integers(0, 3)) == 0 else ()  # noqa: E731
    side = tuple(Lit(q, "?rm", draw(st.booleans())) for q in room_preds[1:]) + \
        tuple(Lit(q, "?r", draw(st.booleans())) for q in robot_preds)
    sset, unset, need, neednot = f"set{p}", f"unset{p}", f"need{p}", f"neednot{p}"
    actions = (Action(sset, (), (on,) + change("increase")), Action(unset, (), (off,) + change("decrease")),
               Action(need, (on,), ()), Action(neednot, (off,), ()), Action("act0", (), side + change("increase")))
    guard = draw(st.sampled_from([Lit(q, "?rm", b) for q in room_preds[1:] for b in (True, False)]
                                 + [Lit(q, "?r", True) for q in robot_preds] + [Cmp(">", 0), Cmp("=", 1)]))

    def variants(name: str, does: str, needs: str) -> list[tuple[Method, ...]]:
        x = name[-1]
        return [
            (Method(f"m{x}0", (), (does,)),),
            (Method(f"m{x}0", (Lit(p, "?rm", does == unset),), (does,)),
             Method(f"m{x}1", (Lit(p, "?rm", does == sset),), ("act0", does))),
            (Method(f"m{x}0", (guard,), (does,)),),
            # both may fit (the second method even twice the same path)
            (Method(f"m{x}0", (), (does, needs) if draw(st.booleans()) else (needs,)), Method(f"m{x}1", (), (needs,))),
        ]

    a = variants("TaskA", sset, need)
    b = variants("TaskB", unset, neednot)
    check = draw(st.sampled_from([need, neednot]))
    fix = sset if check == need else unset
    c = [(Method("mC0", (), (check,)),),
         (Method("mC0", (on,), (need, unset)), Method("mC1", (off,), (neednot, sset))),
         (Method("mC0", (), (fix, check)), Method("mC1", (), (check,))),
         (Method("mC0", (guard,), (check,)),)]
    # weights: the always applicable and split variants are the common ones, so that a good part
    # of the sequences has a valid decomposition; a bare check (order dependent) is rarer
    weights = (0, 0, 1, 1, 1, 2, 3)
    tasks = (Task("TaskA", a[draw(st.sampled_from(weights))]), Task("TaskB", b[draw(st.sampled_from(weights))]),
             Task("TaskC", c[draw(st.sampled_from((1, 1, 1, 2, 2, 0, 3)))]))
    return _Domain(room_preds, robot_preds, (), actions, tasks, p)


def _settles(task: Task, actions: tuple[Action, ...], pred: str) -> bool:
    """Whether every method of ``task`` (a toggle-domain task) sets or unsets ``pred``: after it,
    ``pred`` is known and at most one method of a split task fits."""
    sets = {a.name for a in actions if any(isinstance(e, Lit) and e.pred == pred and e.var == "?rm" for e in a.eff)}
    return all(any(s in sets for s in m.subtasks) for m in task.methods)


@st.composite
def _long_sequence(draw) -> MissionSpec:
    dom = draw(_toggle_domain())
    rooms, query_active = draw(_one_selected_room(dom.room_preds))
    tree = draw(_long_sequence_tree(dom.task_names, ("TaskA", "TaskB", "TaskC"), dom.room_preds))
    condition = draw(_forall_condition(dom.room_preds, dom.actions))
    spec = _spec(dom, rooms, query_active, condition, tree, "long_sequence")
    if draw(st.integers(0, 4)) == 0:
        spec = draw(_with_odd_preconditions(spec))
    # tasks that always settle the toggled predicate branch at most once per decomposition
    settled = {t.name for t in spec.tasks if _settles(t, spec.actions, dom.toggle)}
    return _capped(spec, LONG_PRODUCT_CAP, free=settled)


@st.composite
def _contradictory(draw) -> MissionSpec:
    spec = draw(_basic())
    return dataclasses.replace(draw(_with_odd_preconditions(spec)), shape="contradictory")


@st.composite
def _unique_branch(draw) -> MissionSpec:
    dom = draw(_domain(numeric=True))
    rooms, query_active = draw(_one_selected_room(dom.room_preds))
    tree, pruned = draw(_chain_tree(dom.task_names, dom.room_preds))
    if pruned is not None:  # make the sibling's condition context false in the selected room
        p, value = pruned
        rooms = [dataclasses.replace(r, facts=tuple((q, value if q == p else v) for q, v in r.facts)) for r in rooms]
    condition = draw(_forall_condition(dom.room_preds, dom.actions))
    return _spec(dom, rooms, query_active, condition, tree, "unique_branch")


@st.composite
def _nested_forall(draw) -> MissionSpec:
    dom = draw(_domain(items=True, toggle=draw(st.integers(0, 2)) == 0))
    names = [f"Item{i + 1}" for i in range(draw(st.integers(1, 3)))]
    items = tuple(Item(n, tuple((q, draw(st.sampled_from([None, True, False]))) for q in dom.item_preds))
                  for n in names)
    rooms = draw(_rooms(dom.room_preds, draw(st.integers(1, 2))))
    rooms = [dataclasses.replace(r, items=tuple(draw(st.lists(st.sampled_from(names), unique=True, max_size=2,
                                                              min_size=draw(st.sampled_from([1, 1, 1, 0]))))))
             for r in rooms]
    query_active = draw(st.integers(0, 3)) != 0
    tree = draw(_nested_tree(dom))
    condition = draw(_forall_condition(dom.room_preds, dom.actions))
    select = draw(st.sampled_from(["", "", "", f"!i.{_attr(dom.item_preds[0])}"]))
    spec = _spec(dom, rooms, query_active, condition, tree, "nested_forall", items=items, item_select=select)
    # drop items from the fullest rooms until the instances stay few
    while spec.instance_count() > NESTED_MAX_INSTANCES or spec.path_product() > PRODUCT_CAP:
        fullest = max(spec.rooms, key=lambda r: (len(r.items or ()), r.name))
        if not fullest.items:
            break
        spec = dataclasses.replace(spec, rooms=tuple(dataclasses.replace(r, items=r.items[:-1]) if r is fullest else r
                                                     for r in spec.rooms))
    return spec


@st.composite
def _tasks_beside_goals(draw) -> MissionSpec:
    dom = draw(_domain(toggle=draw(st.booleans())))
    rooms = draw(_rooms(dom.room_preds, draw(st.integers(1, 2))))
    query_active = draw(st.integers(0, 3)) != 0
    selected = [r for r in rooms if r.active or not query_active]
    budget = max(3, 8 // max(1, len(selected)))
    tree = draw(_beside_tree(dom.task_names, dom.room_preds, budget))
    condition = draw(_forall_condition(dom.room_preds, dom.actions))
    return _capped(_spec(dom, rooms, query_active, condition, tree, "tasks_beside_goals"), PRODUCT_CAP)


_BY_SHAPE = {
    "basic": _basic,
    "long_sequence": _long_sequence,
    "contradictory": _contradictory,
    "unique_branch": _unique_branch,
    "nested_forall": _nested_forall,
    "tasks_beside_goals": _tasks_beside_goals,
}
_DEFAULT_MIX = ("basic",) * 3 + SHAPES[1:]  # 3/8 basic missions, 1/8 of each other shape


def missions(shape: Union[str, None] = None) -> st.SearchStrategy[MissionSpec]:
    """Random, valid missions: of the given shape (one of ``SHAPES``, see the module docstring),
    or by default a mix of all shapes (3/8 of them basic, 1/8 each of the others)."""
    if shape is None:
        return st.sampled_from(_DEFAULT_MIX).flatmap(missions)
    if shape not in _BY_SHAPE:
        raise ValueError(f"unknown mission shape {shape!r}; one of {', '.join(SHAPES)}")
    return _BY_SHAPE[shape]()


def basic_missions() -> st.SearchStrategy[MissionSpec]:
    return missions("basic")


def long_sequences() -> st.SearchStrategy[MissionSpec]:
    """10-15 tasks under one ``;`` that set, unset and require one room predicate."""
    return missions("long_sequence")


def contradictory_missions() -> st.SearchStrategy[MissionSpec]:
    """Self-contradictory and duplicate method preconditions."""
    return missions("contradictory")


def unique_branch_missions() -> st.SearchStrategy[MissionSpec]:
    """Unique-branch Task Graphs with numeric (level) preconditions."""
    return missions("unique_branch")


def nested_forall_missions() -> st.SearchStrategy[MissionSpec]:
    """A forAll over the items of each room, with plain Achieve goals inside."""
    return missions("nested_forall")


def tasks_beside_goals() -> st.SearchStrategy[MissionSpec]:
    """Direct tasks beside goals under a ``;`` annotation."""
    return missions("tasks_beside_goals")


# ---------------------------------------------------------------------------------------------
# Deterministic missions


def or_choices_mission(rooms: int = 8, alternatives: int = 3) -> MissionSpec:
    """``rooms`` rooms, each with an OR goal of ``alternatives`` task alternatives that are all
    valid (one method, no preconditions): exactly ``alternatives ** rooms`` decompositions."""
    actions = tuple(Action(f"act{i}", (), (Lit("clean", "?rm"),)) for i in range(alternatives))
    names = tuple(f"Task{chr(ord('A') + i)}" for i in range(alternatives))
    tasks = tuple(Task(n, (Method(f"m{n[-1]}0", (), (actions[i].name,)),)) for i, n in enumerate(names))
    choice = GoalNode(tuple(GoalNode((TaskNode(n),)) for n in names), "or", ("flat", "#"))
    tree = GoalNode((choice,))
    room_list = tuple(Room(f"Room{i + 1}", True, (("clean", False),), 0) for i in range(rooms))
    return MissionSpec(("clean",), ("charged",), actions, tasks, room_list, True, "current_room.is_clean", tree)


@st.composite
def repeated_rooms(draw) -> MissionSpec:
    """A random mission whose rooms are repeated under new names (identical copies), with one
    more room of its own now and then (a copy of another shape)."""
    spec = draw(missions())
    rooms = list(spec.rooms)
    for k in range(draw(st.integers(2, 5))):
        room = draw(st.sampled_from(spec.rooms))
        rooms.append(dataclasses.replace(room, name=f"Room{len(rooms) + 1}"))
    if draw(st.booleans()):
        facts = tuple((p, draw(st.sampled_from([None, True, False]))) for p, _ in spec.rooms[0].facts)
        rooms.append(dataclasses.replace(spec.rooms[0], name=f"Room{len(rooms) + 1}", facts=facts, active=True))
    return dataclasses.replace(spec, rooms=tuple(rooms))
