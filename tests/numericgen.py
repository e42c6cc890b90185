"""Numeric missions and a brute-force reference for them (docs/numbers.md).

The mission generator (:mod:`missiongen`) draws structure: operators, contexts, facts.  This
module draws the numbers: one function ``level`` per room, known as an integer, known as a
decimal, or not given by the world; methods and actions that compare it (``=``, ``>``) and change
it (increase and decrease by 1 or 2) across the tasks of a sequence; forAll conditions on it with
every goal-model operator; recursions with steps 1 and 2 and base cases ``=`` and ``>``.

:func:`brute_force` is the reference: it knows nothing of paths, Task Graphs or encodings.  For
every room and every start value of its level (the world's, or each of a fine grid when the world
is silent), it runs the tasks of the sequence in order, trying every method of every task on
concrete values, and keeps the runs whose preconditions and forAll condition hold.  A recursion
runs while its guard holds (MutRoSe's reading: the recursive method is repeated while its
precondition holds, then a base method ends it), from the world's value.

Two limits of the decomposers are left out of the draws, and stated in docs/numbers.md: a
recursion over a value the world does not give is unrolled once (not simulated), and a base case
``(= f c)`` is only found for ``c`` equal to the guard's bound.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass
from fractions import Fraction
from typing import Iterator, Union

from hypothesis import strategies as st

from missiongen import Action, Change, Cmp, GoalNode, Method, MissionSpec, Room, Task, TaskNode

SHAPES = ("sequence", "recursion")
LEVELS = (None, 0, 1, 2, 3, 4, 6, 4.0, 2.5, 1.5)
BOUNDS = (0, 1, 2, 3, 1.5)
CONDITION_OPS = ("=", ">", ">=", "<", "<=", "<>")
GRID = tuple(Fraction(k, 4) for k in range(-40, 61))  # start values tried when the world is silent

ACTIONS = {
    "report": Action("report"),
    "bump": Action("bump", eff=(Change("increase"),)),
    "bump-two": Action("bump-two", eff=(Change("increase", 2),)),
    "pick": Action("pick", eff=(Change("decrease"),)),
    "pick-two": Action("pick-two", eff=(Change("decrease", 2),)),
}


# ---------------------------------------------------------------------------------------------
# Strategies


@st.composite
def _comparisons(draw, most: int, bounds: tuple[float, ...] = BOUNDS) -> tuple[Cmp, ...]:
    return tuple(Cmp(draw(st.sampled_from(("=", ">"))), draw(st.sampled_from(bounds)))
                 for _ in range(draw(st.integers(0, most))))


@st.composite
def _action(draw, name: str, bounds: tuple[float, ...]) -> Action:
    """One of the numeric actions, with up to one comparison of its own."""
    base = ACTIONS[draw(st.sampled_from(sorted(ACTIONS)))]
    return Action(name, pre=draw(_comparisons(1, bounds)), eff=base.eff)


@st.composite
def _sequence(draw, integral: bool = False) -> MissionSpec:
    """Tasks of a sequence comparing and changing the level; ``integral``: one room with a known
    integer level and integer bounds, the missions the original reads most often without
    stopping (it aborts where a partial decomposition cannot go on, fix 2)."""
    bounds = tuple(b for b in BOUNDS if isinstance(b, int) or not integral)
    n_actions = draw(st.integers(2, 4))
    actions = tuple(draw(_action(f"act{i}", bounds)) for i in range(n_actions))
    names = [a.name for a in actions]
    tasks = []
    for t in range(draw(st.integers(1, 3))):
        methods = tuple(Method(f"m{t}-{k}", draw(_comparisons(2, bounds)),
                               tuple(draw(st.lists(st.sampled_from(names), min_size=1, max_size=2))))
                        for k in range(draw(st.integers(1, 2))))
        tasks.append(Task(f"Task{'ABC'[t]}", methods))
    order = draw(st.lists(st.sampled_from([t.name for t in tasks]), min_size=1, max_size=4))
    tree = GoalNode(tuple(TaskNode(n) for n in order), annotation=("flat", ";") if len(order) > 1 else None)
    if integral:
        room = Room("Room1", True, (), draw(st.sampled_from([lv for lv in LEVELS if isinstance(lv, int)])))
        return MissionSpec((), (), actions, tuple(tasks), (room,), True, "", tree, shape="numeric-integral")
    return _numeric_spec(draw, tuple(tasks), actions, tree, known_only=False)


@st.composite
def _recursion(draw) -> MissionSpec:
    step = draw(st.sampled_from(("pick", "pick-two")))
    guard = draw(st.sampled_from((0, 1, 2)))
    base = draw(st.sampled_from((Cmp("=", guard), Cmp(">", max(guard - 1, 0)), Cmp(">", 0))))
    base_action = draw(st.sampled_from(("pick", "report")))
    actions = tuple(ACTIONS[n] for n in sorted({step, base_action, "report"}))
    pick = Task("PickObject", (Method("pick-multiple", (Cmp(">", guard),), (step, "PickObject")),
                               Method("pick-base", (base,), (base_action,))))
    after = draw(st.sampled_from(((), ("Check",))))
    check = Task("Check", (Method("check", draw(_comparisons(1)), ("report",)),))
    order = ("PickObject", *after)
    tree = GoalNode(tuple(TaskNode(n) for n in order), annotation=("flat", ";") if after else None)
    return _numeric_spec(draw, (pick, check), actions, tree, known_only=True, shape="recursion")


def _numeric_spec(draw, tasks: tuple[Task, ...], actions: tuple[Action, ...], tree: GoalNode, *,
                  known_only: bool, shape: str = "sequence") -> MissionSpec:
    levels = [lv for lv in LEVELS if lv is not None or not known_only]
    rooms = tuple(Room(f"Room{i + 1}", True, (), draw(st.sampled_from(levels))) for i in range(draw(st.integers(1, 2))))
    condition = ""
    if draw(st.booleans()):
        condition = f"current_room.level {draw(st.sampled_from(CONDITION_OPS))} {draw(st.sampled_from(BOUNDS))}"
    return MissionSpec((), (), actions, tasks, rooms, True, condition, tree, shape=f"numeric-{shape}")


def numeric_missions(shape: Union[str, None] = None) -> st.SearchStrategy[MissionSpec]:
    """Numeric missions of one shape of ``SHAPES`` (or ``integral``, see :func:`_sequence`), or of
    either."""
    if shape is None:
        return st.sampled_from(SHAPES).flatmap(numeric_missions)
    if shape == "integral":
        return _sequence(integral=True)
    return {"sequence": _sequence, "recursion": _recursion}[shape]()


# ---------------------------------------------------------------------------------------------
# The brute-force reference

Signature = frozenset[tuple[str, tuple[str, ...]]]  # (task instance id, its actions)


def _holds(value: Fraction, op: str, bound: Fraction) -> bool:
    return {"=": value == bound, "<>": value != bound, ">": value > bound, "<": value < bound,
            ">=": value >= bound, "<=": value <= bound}[op]


def _number(x: float | int) -> Fraction:
    return Fraction(str(x))


def _change(value: Fraction, action: Action) -> Fraction:
    for e in action.eff:
        if isinstance(e, Change):
            value += e.amount if e.kind == "increase" else -e.amount
    return value


def _meets(value: Fraction, pre: tuple) -> bool:
    return all(_holds(value, c.op, _number(c.value)) for c in pre if isinstance(c, Cmp))


@dataclass
class _Runner:
    spec: MissionSpec

    def __post_init__(self) -> None:
        self.tasks = {t.name: t for t in self.spec.tasks}
        self.actions = {a.name: a for a in self.spec.actions}

    def task(self, name: str, value: Fraction, depth: int = 0) -> Iterator[tuple[tuple[str, ...], Fraction]]:
        """Every run of task ``name`` from ``value``: its actions and the value after.  Inside a
        recursion (depth > 0) the recursive method is taken while its guard holds."""
        task = self.tasks[name]
        methods = task.methods
        if depth > 0:
            recursive = [m for m in methods if name in m.subtasks and _meets(value, m.pre)]
            if recursive:
                methods = tuple(recursive)
        if depth > 40:
            return
        for m in methods:
            if _meets(value, m.pre):
                yield from self._subtasks(m.subtasks, value, depth + (name in m.subtasks), name)

    def _subtasks(self, names: tuple[str, ...], value: Fraction, depth: int,
                  caller: str) -> Iterator[tuple[tuple[str, ...], Fraction]]:
        if not names:
            yield (), value
            return
        head, rest = names[0], names[1:]
        if head in self.actions:
            action = self.actions[head]
            if not _meets(value, action.pre):
                return
            for tail, after in self._subtasks(rest, _change(value, action), depth, caller):
                yield (head, *tail), after
            return
        for steps, mid in self.task(head, value, depth if head == caller else 0):
            for tail, after in self._subtasks(rest, mid, depth, caller):
                yield (*steps, *tail), after

    def room(self, index: int, start: Fraction) -> set[tuple[tuple[str, ...], ...]]:
        """The valid runs of the sequence for one room from ``start``: the actions of each task."""
        order = [n.task for n in self.spec.task_nodes()]
        runs: list[tuple[tuple[tuple[str, ...], ...], Fraction]] = [((), start)]
        for name in order:
            runs = [(done + (steps,), after) for done, value in runs for steps, after in self.task(name, value)]
        condition = self.spec.forall_condition
        if condition:
            _, op, bound = condition.split()
            runs = [r for r in runs if _holds(r[1], op, _number(float(bound)))]
        return {done for done, _ in runs}


def brute_force(spec: MissionSpec) -> set[Signature]:
    """The valid mission decompositions of ``spec`` (a flat sequence below a forAll over rooms),
    each as the set of (task instance id, actions) it runs."""
    runner = _Runner(spec)
    per_room = []
    for r, room in enumerate(spec.selected_rooms):
        starts = GRID if room.level is None else (_number(room.level),)
        runs: set[tuple[tuple[str, ...], ...]] = set()
        for start in starts:
            runs |= runner.room(r, start)
        per_room.append({frozenset((f"AT{k + 1}_{r + 1}", steps) for k, steps in enumerate(run)) for run in runs})
    return {frozenset().union(*combo) for combo in itertools.product(*per_room)}


def _actions_of(task: dict) -> list[str]:
    return [a["name"] for a in (task["decomposition"] or {}).values()]


def decomposition_actions(document: dict) -> dict[str, list[str]]:
    """An output file's task decompositions: id (``AT1_1|2``) -> its action names."""
    return {t["id"]: _actions_of(t) for t in document["tasks"].values()}


def valid_decompositions(document: dict) -> set[frozenset[str]]:
    """An output file's valid mission decompositions, as sets of decomposition ids."""
    ids = {key: task["id"] for key, task in document["tasks"].items()}
    return {frozenset(ids[k] for k in md) for md in document["mission_decompositions"]}


def signatures(document: dict) -> set[Signature]:
    """The valid mission decompositions of an output file, as :func:`brute_force` gives them."""
    tasks = document["tasks"]
    return {frozenset((tasks[k]["id"].split("|")[0], tuple(_actions_of(tasks[k]))) for k in md)
            for md in document["mission_decompositions"]}
