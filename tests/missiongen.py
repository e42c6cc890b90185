"""Random but valid MutRoSe missions for differential testing (hypothesis strategies).

``missions()`` draws a :class:`MissionSpec`: a small HDDL domain, a goal model, a configuration
and a world, all consistent with each other, so that ``Mission.load`` accepts it.  ``write``
renders the four files into a directory; ``load_mission`` writes them to a temporary directory
and loads them.

Shape of a drawn mission (sizes are kept small so that the exploratory algorithm, which combines
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

import json
import tempfile
from dataclasses import dataclass
from pathlib import Path
from typing import Union

from hypothesis import strategies as st

MAX_TASK_INSTANCES = 6  # GM tasks x selected rooms
MAX_PATHS = 4  # decomposition paths of one abstract task (upper bound, before filtering)
MAX_DEPTH = 3  # goal levels below the forAll goal

ROOM_PREDICATES = ("clean", "sealed", "lit", "checked")
ROBOT_PREDICATES = ("charged", "loaded")
TASK_NAMES = ("TaskA", "TaskB", "TaskC")  # letters only: the GM reads the first run of letters


# ---------------------------------------------------------------------------------------------
# The mission model


@dataclass(frozen=True)
class Lit:
    """A boolean literal ``(pred ?var)``; ``var`` is ``?rm`` (room) or ``?r`` (robot)."""

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


@dataclass(frozen=True)
class Method:
    name: str
    pre: tuple[Union[Lit, Cmp], ...] = ()
    subtasks: tuple[str, ...] = ()  # action or abstract task names, called with (?r ?rm)
    ordered: bool = True


@dataclass(frozen=True)
class Task:
    name: str
    methods: tuple[Method, ...]


@dataclass(frozen=True)
class Room:
    name: str
    active: bool = True
    facts: tuple[tuple[str, Union[bool, None]], ...] = ()  # predicate -> value (None: missing)
    level: Union[int, None] = 0


@dataclass(frozen=True)
class TaskNode:
    """A goal-model task (``AT<k>: <task>``, ``Location: current_room``)."""

    task: str


@dataclass(frozen=True)
class GoalNode:
    """A goal; ``annotation`` is None (no brackets) or an expression over child positions:
    an ``int`` (the i-th child, left to right) or ``(op, left, right)`` with op ``;``, ``#`` or
    ``FALLBACK``, or ``("flat", op)`` for ``c1 op c2 op ...`` over all children."""

    children: tuple["Node", ...]
    refinement: str = "and"  # "and" | "or"
    annotation: object = None
    group: bool = True
    divisible: bool = True
    condition: Union[str, None] = None  # condition context, e.g. "current_room.is_clean"
    achieve: Union[str, None] = None  # plain achieve condition (GoalType Achieve)


Node = Union[TaskNode, GoalNode]


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

    # -- derived ---------------------------------------------------------------------------------
    @property
    def selected_rooms(self) -> list[Room]:
        return [r for r in self.rooms if r.active or not self.query_active]

    def gm_task_count(self) -> int:
        return _count_tasks(self.tree)

    def instance_count(self) -> int:
        return self.gm_task_count() * len(self.selected_rooms)

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
        return (f"MissionSpec(rooms={len(self.rooms)}, selected={len(self.selected_rooms)}, "
                f"gm_tasks={self.gm_task_count()}, tasks={len(self.tasks)}, actions={len(self.actions)}, "
                f"annotation={render_tree_outline(self.tree)!r}, forall={self.forall_condition!r})")


def _count_tasks(node: Node) -> int:
    if isinstance(node, TaskNode):
        return 1
    return sum(_count_tasks(c) for c in node.children)


def load_mission(spec: MissionSpec):
    """Write ``spec`` to a temporary directory and ``Mission.load`` it (every input is read at
    load time, so the directory can go)."""
    from mutrose_cp.mission import Mission

    with tempfile.TemporaryDirectory(prefix="mutrose-gen-") as d:
        return Mission.load(*spec.write(d))


# ---------------------------------------------------------------------------------------------
# Rendering


def _attr(pred: str) -> str:
    return f"is_{pred}"


def render_hddl(spec: MissionSpec) -> str:
    out = ["; generated by tests/missiongen.py", "(define (domain generated)",
           "    (:types", "        room - object", "        Bot - robot", "    )", "    (:predicates"]
    out += [f"        ({p} ?rm - room)" for p in spec.room_predicates]
    out += [f"        ({p} ?r - robot)" for p in spec.robot_predicates]
    out += ["    )", "    (:functions (level ?rm - room))", "    (:capabilities work)", ""]
    for t in spec.tasks:
        out.append(f"    (:task {t.name} :parameters (?r - Bot ?rm - room))")
        for m in t.methods:
            out += [f"    (:method {m.name}", "        :parameters (?r - Bot ?rm - room)",
                    f"        :task ({t.name} ?r ?rm)"]
            if m.pre:
                out.append(f"        :precondition (and {' '.join(c.hddl() for c in m.pre)})")
            if m.ordered:
                calls = " ".join(f"({s} ?r ?rm)" for s in m.subtasks)
                out.append(f"        :ordered-subtasks (and {calls})")
            else:
                calls = " ".join(f"(s{i} ({s} ?r ?rm))" for i, s in enumerate(m.subtasks))
                out.append(f"        :subtasks (and {calls})")
            out.append("    )")
        out.append("")
    for a in spec.actions:
        pre = f"(and {' '.join(c.hddl() for c in a.pre)})" if a.pre else "()"
        eff = f"(and {' '.join(e.hddl() for e in a.eff)})" if a.eff else "()"
        out += [f"    (:action {a.name}", "        :parameters (?r - Bot ?rm - room)",
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
        out.append("    </Room>")
    out.append("</world_db>")
    return "\n".join(out) + "\n"


def render_config(spec: MissionSpec, world_path: str) -> str:
    gm_tasks = _gm_task_ids(spec)
    sem = [{"type": "attribute", "name": _attr(p), "relates_to": "Room", "belongs_to": "world_db",
            "mapped_type": "predicate", "map": {"pred": p, "arg_sorts": ["room"]}} for p in spec.room_predicates]
    sem.append({"type": "attribute", "name": "level", "relates_to": "Room", "belongs_to": "world_db",
                "mapped_type": "function", "map": {"pred": "level", "arg_sorts": ["room"]}})
    sem += [{"type": "attribute", "name": _attr(p), "relates_to": "robot", "belongs_to": "robots_db",
             "mapped_type": "predicate", "map": {"pred": p, "arg_sorts": ["robot"]}} for p in spec.robot_predicates]
    config = {
        "world_db": {"type": "file", "file_type": "xml", "path": world_path, "xml_root": "world_db",
                     "unique_id": "name"},
        "output": {"output_type": "file", "file_path": "output/mission.json", "file_type": "json"},
        "location_types": ["Room"],
        "type_mapping": [{"hddl_type": "room", "ocl_type": "Room"}],
        "var_mapping": [{"task_id": t, "map": [{"gm_var": "current_room", "hddl_var": "?rm"}]} for t in gm_tasks],
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
    inner = ",".join(render_tree_outline(c) for c in node.children)
    tag = "OR" if node.refinement == "or" else "AND"
    ann = "" if node.annotation is None else f"{node.annotation}"
    flags = ("" if node.group else "!G") + ("" if node.divisible else "!D") + ("C" if node.condition else "") \
        + ("A" if node.achieve else "")
    return f"{tag}{flags}{ann}({inner})"


def render_gm(spec: MissionSpec) -> str:
    nodes: list[dict] = []
    links: list[dict] = []
    counters = {"goal": 0, "task": 0, "x": 0, "uid": 0}

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
                tnode = {"id": uid(), "text": f"{tid}: {child.task}", "type": "istar.Task", "x": next_x(),
                         "y": 60 + 110 * (depth + 1),
                         "customProperties": {"Description": "", "Location": "current_room"}}
                nodes.append(tnode)
                link(tnode["id"], node_uid, goal.refinement)
                ids.append(tid)
            else:
                cid, cuid, cnode = add_goal("Subgoal", depth + 1, goal_props(child))
                link(cuid, node_uid, goal.refinement)
                ids.append(cid)
                add_children(child, cnode, cuid, depth + 1)
        if goal.annotation is not None and len(goal.children) >= 2:
            node["text"] += f" [{_render_annotation(goal.annotation, ids)}]"

    def goal_props(goal: GoalNode) -> dict:
        props: dict = {"Monitors": "current_room"}
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
# Strategies


def _atoms(room_preds: tuple[str, ...], robot_preds: tuple[str, ...]) -> list[tuple[str, str]]:
    return [(p, "?rm") for p in room_preds] + [(p, "?r") for p in robot_preds]


def _literals(room_preds: tuple[str, ...], robot_preds: tuple[str, ...], sizes: tuple[int, ...],
              positive_bias: bool = False):
    """Lists of literals on distinct atoms; the size is drawn from ``sizes`` (shrinks to the
    first); with ``positive_bias`` three out of four literals are positive."""
    polarity = st.sampled_from([True, True, True, False]) if positive_bias else st.booleans()
    atoms = _atoms(room_preds, robot_preds)

    @st.composite
    def draw_list(draw):
        n = min(draw(st.sampled_from(sizes)), len(atoms))
        chosen = draw(st.permutations(atoms))[:n]  # distinct atoms, no filtering
        return [Lit(p, v, draw(polarity)) for p, v in chosen]

    return draw_list()


NUMERIC_PRECONDITIONS = (Cmp(">", 0), Cmp("=", 1), Cmp("=", 0), Cmp(">", 1))


@st.composite
def _action(draw, name: str, room_preds, robot_preds) -> Action:
    pre = draw(_literals(room_preds, robot_preds, (0, 0, 0, 1, 1)))
    eff: list = draw(_literals(room_preds, robot_preds, (1, 0, 1, 2), positive_bias=True))
    change = draw(st.sampled_from([None, None, "increase", "decrease"]))
    if change:
        eff.append(Change(change))
    if draw(st.integers(0, 7)) == 0:  # occasionally a numeric action precondition too
        pre.append(draw(st.sampled_from(NUMERIC_PRECONDITIONS)))
    return Action(name, tuple(pre), tuple(eff))


def _method_paths(m: Method, bounds: dict[str, int]) -> int:
    n = 1 if m.ordered or len(m.subtasks) < 2 else 2  # unordered pair: two orderings
    for s in m.subtasks:
        n *= bounds.get(s, 1)
    return n


@st.composite
def _method_precondition(draw, switch: Lit, room_preds, robot_preds) -> list:
    """A method precondition: none, the task's switch literal or its negation (so that methods
    complement each other, as in real domains), random literals, or a numeric test."""
    kind = draw(st.integers(-1, 5))
    if kind <= 0:
        return []
    if kind == 1:
        return [switch]
    if kind == 2:
        return [Lit(switch.pred, switch.var, not switch.positive)]
    if kind == 3:
        return draw(_literals(room_preds, robot_preds, (1, 1, 2)))
    if kind == 4:
        return [draw(st.sampled_from(NUMERIC_PRECONDITIONS))]
    return draw(_literals(room_preds, robot_preds, (1,))) + [draw(st.sampled_from(NUMERIC_PRECONDITIONS))]


@st.composite
def _task(draw, name: str, actions: tuple[Action, ...], earlier: tuple[Task, ...], bounds: dict[str, int],
          room_preds, robot_preds) -> Task:
    n_methods = draw(st.integers(1, 3))
    switch = draw(_literals(room_preds, (), (1,)))[0]
    # 0: independent preconditions; 1: the methods split on a room fact (switch / not switch),
    # 2: on the level ((> 0), (= 0), (= 1)) - so that some method fits most world states
    scheme = draw(st.integers(0, 2)) if n_methods >= 2 else 0
    split = ([switch], [Lit(switch.pred, switch.var, not switch.positive)]) if scheme == 1 else (
        [Cmp(">", 0)], [Cmp("=", 0)], [Cmp("=", 1)])
    methods = []
    budget = MAX_PATHS
    for k in range(n_methods):
        remaining_methods = n_methods - k - 1
        if scheme and k < len(split):
            pre = list(split[k])
            if draw(st.integers(0, 3)) == 0:
                pre += draw(_literals(room_preds, robot_preds, (1,)))
        else:
            pre = draw(_method_precondition(switch, room_preds, robot_preds))
        callees = [a.name for a in actions] + [t.name for t in earlier]
        subtasks = draw(st.lists(st.sampled_from(callees), min_size=1, max_size=2))
        ordered = draw(st.integers(0, 3)) != 0
        m = Method(f"m{name[-1]}{k}", tuple(pre), tuple(subtasks), ordered)
        # keep the number of decomposition paths small: simplify the method until it fits
        if _method_paths(m, bounds) > budget - remaining_methods:
            m = Method(m.name, m.pre, tuple(s if s not in bounds else actions[0].name for s in m.subtasks), True)
        methods.append(m)
        budget -= _method_paths(m, bounds)
    return Task(name, tuple(methods))


@st.composite
def _annotation(draw, k: int, refinement: str):
    if refinement == "or":
        return draw(st.sampled_from([None, ("flat", "#")]))
    choice = draw(st.integers(0, 3))
    if choice == 0:
        return None
    if choice == 1 or k == 2:
        return ("flat", draw(st.sampled_from([";", "#", "FALLBACK"])))
    # a nested expression over the children, left to right
    def expr(lo: int, hi: int):
        if hi - lo == 1:
            return lo
        split = draw(st.integers(lo + 1, hi - 1))
        return (draw(st.sampled_from([";", "#", "FALLBACK"])), expr(lo, split), expr(split, hi))

    return expr(0, k)


@st.composite
def _goal(draw, budget: int, depth: int, task_names: tuple[str, ...], room_preds: tuple[str, ...],
          top: bool = False) -> GoalNode:
    """A goal with 1..3 children using at most ``budget`` GM tasks (at least one)."""
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
            child: Node = draw(_goal(child_budget, depth + 1, task_names, room_preds))
        else:
            child = TaskNode(draw(st.sampled_from(task_names)))
        children.append(child)
        used += _count_tasks(child)
    refinement = "or" if k >= 2 and draw(st.integers(0, 2)) == 0 else "and"
    annotation = draw(_annotation(k, refinement)) if k >= 2 else None
    flag = draw(st.integers(0, 11))
    group, divisible = (False, True) if flag == 0 else (True, False) if flag == 1 else (True, True)
    condition = achieve = None
    if not top:
        extra = draw(st.integers(0, 14))
        pred = draw(st.sampled_from(room_preds))
        if extra == 0:
            condition = f"current_room.{_attr(pred)}"
        elif extra == 1:
            condition = f"!current_room.{_attr(pred)}"
        elif extra == 2:
            achieve = f"current_room.{_attr(pred)}"
    return GoalNode(tuple(children), refinement, annotation, group, divisible, condition, achieve)


@st.composite
def missions(draw) -> MissionSpec:
    """A random, valid mission (see the module docstring for its shape)."""
    room_preds = tuple(draw(st.lists(st.sampled_from(ROOM_PREDICATES), min_size=1, max_size=3, unique=True)))
    robot_preds = tuple(draw(st.lists(st.sampled_from(ROBOT_PREDICATES), min_size=max(0, 2 - len(room_preds)),
                                      max_size=min(2, 4 - len(room_preds)), unique=True)))
    n_actions = draw(st.integers(1, 4))
    actions_list: list[Action] = []
    for i in range(n_actions):
        act = draw(_action(f"act{i}", room_preds, robot_preds))
        # sometimes undo a room effect of an earlier action: parallel conflicts, set/unset chains
        undoable = [e for prev in actions_list for e in prev.eff if isinstance(e, Lit) and e.var == "?rm"]
        if undoable and draw(st.integers(0, 1)) == 0:
            e = draw(st.sampled_from(undoable))
            if all(not (isinstance(x, Lit) and x.pred == e.pred and x.var == e.var) for x in act.eff):
                act = Action(act.name, act.pre, act.eff + (Lit(e.pred, e.var, not e.positive),))
        actions_list.append(act)
    actions = tuple(actions_list)
    n_tasks = draw(st.integers(1, len(TASK_NAMES)))
    tasks: list[Task] = []
    bounds: dict[str, int] = {}
    for name in TASK_NAMES[:n_tasks]:
        t = draw(_task(name, actions, tuple(tasks), bounds, room_preds, robot_preds))
        tasks.append(t)
        bounds[name] = sum(_method_paths(m, bounds) for m in t.methods)
    n_rooms = draw(st.integers(1, 3))
    rooms = []
    for i in range(n_rooms):
        active = draw(st.integers(0, 7)) != 7
        facts = tuple((p, draw(st.sampled_from([None, True, False, None]))) for p in room_preds)
        level = draw(st.sampled_from([1, 0, 2, None]))
        rooms.append(Room(f"Room{i + 1}", active, facts, level))
    query_active = draw(st.integers(0, 3)) != 0
    selected = [r for r in rooms if r.active or not query_active]
    budget = max(1, MAX_TASK_INSTANCES // max(1, len(selected)))
    tree = draw(_goal(budget, 0, tuple(t.name for t in tasks), room_preds, top=True))
    # forAll condition: empty, or a predicate that some action makes true (else any), or a level test
    set_true = [p for p in room_preds if any(isinstance(e, Lit) and e.var == "?rm" and e.positive and e.pred == p
                                               for a in actions for e in a.eff)]
    kind = draw(st.integers(0, 5))
    if kind <= 1:
        condition = ""
    elif kind <= 3:
        condition = f"current_room.{_attr(draw(st.sampled_from(set_true or list(room_preds))))}"
    elif kind == 4:
        condition = f"!current_room.{_attr(draw(st.sampled_from(room_preds)))}"
    else:
        condition = draw(st.sampled_from(["current_room.level > 0", "current_room.level = 1",
                                          "current_room.level = 0"]))
    return MissionSpec(room_preds, robot_preds, actions, tuple(tasks), tuple(rooms), query_active, condition, tree)


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
