"""An independent validator of decomposition outputs: the analogue of VAL for PDDL plans.

``validate`` takes the mission inputs and an output file (ours or the original tool's, JSON or
XML) and checks every listed mission decomposition against the inputs.  It uses the readers
(``io/``, the initial world state) and nothing of the decomposers: the method tree of each task
is rebuilt from the domain (:mod:`.htn_match`), the order of tasks is taken from the file's
constraints, and conditions are translated with the semantic mappings here.  So a mistake the
two decomposers share shows up as a violation.

The semantics checked (docs/validate.md):

* the tasks of a mission decomposition exist, one decomposition per task instance; every task
  instance outside OR branches is present; an OR goal has one chosen branch per instance;
* the SEQ and FB constraints between the chosen tasks admit an order (no cycle);
* each task's actions are a decomposition of the task by the domain's methods; replayed from the
  state the task starts in, every ground method and action precondition holds (an atom the world
  does not know is assumed on first use, so a decomposition contradicting itself fails);
* a task starts in the initial world changed by the tasks that the SEQ and FB constraints put
  before it (transitively, without the fallback alternatives it replaces), applied in the order
  the constraints give them (file order where they leave it open); tasks that meet under a
  parallel operator never set one fact both ways;
* condition contexts hold in the initial state or where their tasks start (an earlier task
  made them true); achieve conditions (for a ``forAll``, for every element) hold after the
  goal's tasks;
* execution-constrained tasks have compatible robot numbers.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass, field

import networkx as nx

from ..io.decomposition_output import DecompositionOutput, OutputTask, RobotsNum
from ..model import (
    Annotation,
    AnnotationLeaf,
    Atom,
    BoolOp,
    Comparison,
    Condition,
    Configuration,
    Domain,
    GMNode,
    GoalModel,
    InitialState,
    Literal,
    NumericEffect,
)
from .htn_match import Matcher, Step

AtomKey = tuple[str, tuple[str, ...]]
_BindingKey = tuple[tuple[str, tuple[str, ...]], ...]  # sorted (variable, values) pairs
EPSILON = 1e-9


@dataclass(frozen=True)
class Violation:
    """One reason a mission decomposition (or the file) is not valid, located."""

    decomposition: int | None  # index in mission_decompositions; None for the whole file
    task: str  # task id ("AT1_1|2") or goal id, "" when neither applies
    message: str

    def __str__(self) -> str:
        where = [] if self.decomposition is None else [f"decomposition {self.decomposition}"]
        if self.task:
            where.append(self.task)
        return f"{': '.join(where)}: {self.message}" if where else self.message


@dataclass
class Report:
    checked: int = 0  # mission decompositions checked
    violations: list[Violation] = field(default_factory=list)
    notes: list[str] = field(default_factory=list)  # what could not be checked, and why

    @property
    def valid(self) -> bool:
        return not self.violations


# ---------------------------------------------------------------------------------------------
# World states


class State:
    """Known facts and function values; an absent atom is unknown.  Of a function the world
    does not give, ``offsets`` holds what the increases and decreases so far added to it (it
    stays unknown until an assignment)."""

    def __init__(self, facts: dict[AtomKey, bool], values: dict[AtomKey, float],
                 offsets: dict[AtomKey, float] | None = None) -> None:
        self.facts = facts
        self.values = values
        self.offsets: dict[AtomKey, float] = offsets if offsets is not None else {}

    @classmethod
    def initial(cls, initial: InitialState) -> "State":
        return cls(initial.fact_map(), dict(initial.value_map()))

    def copy(self) -> "State":
        return State(dict(self.facts), dict(self.values), dict(self.offsets))


# What the tasks of one mission decomposition required of the start value of each function
# the world does not give: (op, bound on the start value, negated, who required it).  One
# start value must meet them all (_StartValues).
StartTests = dict[AtomKey, list[tuple[str, float, bool, str]]]


@dataclass
class _StartValues:
    """What one mission decomposition requires of the start values the world does not give:
    the achieve conditions' tests, and for each task the tests of each way its actions can be
    explained (methods that run the same actions may require different values).  One start
    value per function must meet the fixed tests and those of one explanation per task."""

    fixed: StartTests = field(default_factory=dict)
    tasks: list[tuple[str, list[StartTests]]] = field(default_factory=list)  # (task id, alternatives)

    def conflict(self) -> tuple[str, str] | None:
        """None when some choice of explanations leaves every function a value; else the first
        task (in execution order) that no choice gets past ("" for the achieve conditions
        alone), and the tests that exclude each other."""
        if not all(_some_value_meets(v) for v in self.fixed.values()):
            return "", self._excluding(self.fixed)
        reached = [0]
        if self._search(0, {key: list(v) for key, v in self.fixed.items()}, reached):
            return None
        k = min(reached[0], len(self.tasks) - 1)
        tests: StartTests = {key: list(v) for key, v in self.fixed.items()}
        for _, alternatives in self.tasks[:k + 1]:
            for key, more in alternatives[0].items():
                tests[key] = tests.get(key, []) + more
        return self.tasks[k][0], self._excluding(tests)

    def _search(self, k: int, tests: StartTests, reached: list[int]) -> bool:
        """Whether explanations from the ``k``-th task on can be chosen to fit ``tests``."""
        reached[0] = max(reached[0], k)
        if k == len(self.tasks):
            return True
        for alternative in self.tasks[k][1]:
            merged = {key: tests.get(key, []) + more for key, more in alternative.items()}
            if all(_some_value_meets(v) for v in merged.values()) and self._search(k + 1, {**tests, **merged}, reached):
                return True
        return False

    @staticmethod
    def _excluding(tests: StartTests) -> str:
        for key, found in tests.items():
            if not _some_value_meets(found):
                return f"{_first_conflict(found)}: no value of {key[0]}({', '.join(key[1])}) meets them all"
        return "the other tasks' comparisons on values the world does not give exclude each of its explanations"


@dataclass
class TaskEffects:
    """What a replayed task changed: final values of facts, numeric changes in order."""

    facts: dict[AtomKey, bool] = field(default_factory=dict)
    numeric: list[tuple[AtomKey, str, float]] = field(default_factory=list)

    def apply(self, state: State) -> None:
        state.facts.update(self.facts)
        for key, kind, amount in self.numeric:
            change = amount if kind == "increase" else -amount
            if kind == "assign":
                state.values[key] = amount
                state.offsets.pop(key, None)
            elif key in state.values:
                state.values[key] += change
            else:
                state.offsets[key] = state.offsets.get(key, 0.0) + change


def _some_value_meets(required: list[tuple[str, float, bool, str]]) -> bool:
    """Whether some number meets every (op, bound, negated) test.  The numbers that meet them
    are a union of intervals and points between the bounds, so trying each bound, a point
    between each two and one beyond each end decides it."""
    if not required:
        return True
    bounds = sorted({bound for _, bound, _, _ in required})
    candidates = bounds + [(a + b) / 2 for a, b in zip(bounds, bounds[1:])] + [bounds[0] - 1, bounds[-1] + 1]
    return any(all(_compare(x, op, bound) != negated for op, bound, negated, _ in required) for x in candidates)


def _first_conflict(required: list[tuple[str, float, bool, str]]) -> str:
    """Who required what, up to the first test no value meets together with the earlier ones."""
    for k in range(1, len(required) + 1):
        if not _some_value_meets(required[:k]):
            return "; ".join(who for *_, who in required[:k])
    return ""


def _compare(value: float, op: str, bound: float) -> bool:
    return {
        "=": lambda: abs(value - bound) < EPSILON,
        "<>": lambda: abs(value - bound) >= EPSILON,
        ">": lambda: value > bound,
        "<": lambda: value < bound,
        ">=": lambda: value >= bound - EPSILON,
        "<=": lambda: value <= bound + EPSILON,
    }[op]()


# ---------------------------------------------------------------------------------------------
# Grounding with a task's argument values


def _values(task: OutputTask) -> dict[str, tuple[str, ...]]:
    """Parameter -> ground values (a collection value ``[a,b]`` gives several)."""
    out: dict[str, tuple[str, ...]] = {}
    for name, _type, value in task.arguments:
        if not value:
            continue
        if value.startswith("[") and value.endswith("]"):
            out[name] = tuple(v.strip() for v in value[1:-1].split(",") if v.strip())
        else:
            out[name] = (value,)
    return out


def _groundings(args: tuple[str, ...], values: dict[str, tuple[str, ...]]) -> list[tuple[str, ...]]:
    """Every ground instance of ``args``; empty when some variable is unbound."""
    choices = []
    for a in args:
        if a.startswith("?"):
            if a not in values:
                return []
            choices.append(values[a])
        else:
            choices.append((a,))
    return [tuple(c) for c in itertools.product(*choices)]


# ---------------------------------------------------------------------------------------------
# Replay of one explanation of a task


class _StepReplay:
    """Replays the steps of one explanation of a task from the state where the task starts,
    over every grounding of their arguments: preconditions are checked against what the task
    changed so far, else the start state, else what it assumed (an atom nothing knows is
    assumed as first required); effects are recorded."""

    def __init__(self, values: dict[str, tuple[str, ...]], start: State, task: str) -> None:
        self.values = values
        self.start = start
        self.task = task
        self.changed = TaskEffects()
        self.facts: dict[AtomKey, bool] = {}  # changed facts
        self.assumed: dict[AtomKey, bool] = {}
        self.nums: dict[AtomKey, float | None] = {}  # function values known or changed here
        # a function nothing knows: what the steps required of its value where the mission
        # starts (op, bound, negated, who), and what they added to it since the task started
        self.required: StartTests = {}
        self.offset: dict[AtomKey, float] = {}
        self.failures: list[str] = []

    def step(self, step: Step) -> None:
        what = f"{step.kind} {step.name}"
        for c in step.preconditions:
            for g in _groundings(c.args, self.values):
                if isinstance(c, Literal):
                    self._literal(c, g, what, step.position)
                else:
                    self._comparison(c, g, what, step.position)
        for e in step.effects:
            for g in _groundings(e.args, self.values):
                self.facts[(e.predicate, g)] = e.positive
                self.changed.facts[(e.predicate, g)] = e.positive
        for n in step.numeric_effects:
            for g in _groundings(n.args, self.values):
                self._numeric_effect(n, (n.function, g))

    def _value(self, key: AtomKey) -> float | None:
        return self.nums[key] if key in self.nums else self.start.values.get(key)

    def _literal(self, c: Literal, g: tuple[str, ...], what: str, position: int) -> None:
        key = (c.predicate, g)
        known = self.facts.get(key, self.start.facts.get(key, self.assumed.get(key)))
        if known is None:
            self.assumed[key] = c.positive
        elif known != c.positive:
            self.failures.append(f"precondition {_show_literal(c.predicate, g, c.positive)} of {what} "
                                 f"(action {position + 1}) does not hold")

    def _comparison(self, c: Comparison, g: tuple[str, ...], what: str, position: int) -> None:
        """A numeric precondition; a value nothing knows may be anything that the task's
        preconditions on it allow together, and a required equality makes it known."""
        key = (c.function, g)
        value = self._value(key)
        if value is None:
            required = self.required.setdefault(key, [])
            shown = f"precondition {'not ' if c.negated else ''}{c.function}({', '.join(g)}) {c.op} {c.value:g}"
            start = self.start.offsets.get(key, 0.0) + self.offset.get(key, 0.0)
            required.append((c.op, float(c.value) - start, c.negated, f"{self.task}: {shown}"))
            if not _some_value_meets(required):
                self.failures.append(f"{shown} of {what} (action {position + 1}) cannot hold together "
                                     f"with the task's earlier preconditions on it (the world does not know it)")
            elif c.op == "=" and not c.negated:
                self.nums[key] = float(c.value)
            return
        if _compare(value, c.op, float(c.value)) == c.negated:
            self.failures.append(f"precondition {'not ' if c.negated else ''}{c.function}"
                                 f"({', '.join(g)}) {c.op} {c.value:g} of {what} (action "
                                 f"{position + 1}) does not hold: the value is {value:g}")

    def _numeric_effect(self, n: NumericEffect, key: AtomKey) -> None:
        """An assignment sets the value; an increase or decrease changes a known value only."""
        old = self._value(key)
        change = n.amount if n.kind == "increase" else -n.amount
        if n.kind == "assign":
            self.nums[key] = float(n.amount)
        elif old is not None:
            self.nums[key] = old + change
        else:
            self.offset[key] = self.offset.get(key, 0.0) + change
        self.changed.numeric.append((key, n.kind, float(n.amount)))


# ---------------------------------------------------------------------------------------------
# The validator


class _Validator:
    def __init__(self, domain: Domain, gm: GoalModel, config: Configuration, initial: InitialState,
                 output: DecompositionOutput) -> None:
        self.domain = domain
        self.gm = gm
        self.config = config
        self.out = output
        self.w0 = State.initial(initial)
        self.report = Report()
        self.order = {k: i for i, k in enumerate(output.tasks)}
        self.seq: nx.DiGraph[str] = nx.DiGraph()
        self.seq_fb: nx.DiGraph[str] = nx.DiGraph()
        self.seq.add_nodes_from(output.tasks)
        self.seq_fb.add_nodes_from(output.tasks)
        self.ec: list[tuple[str, str]] = []
        for c in output.constraints:
            missing = [k for k in (c.first, c.second) if k not in output.tasks]
            if missing:
                self._file(f"{c.where}: constraint names unknown task {missing[0]}")
                continue
            if c.kind == "SEQ":
                self.seq.add_edge(c.first, c.second)
                self.seq_fb.add_edge(c.first, c.second)
            elif c.kind == "FB":
                self.seq_fb.add_edge(c.first, c.second)
            elif c.kind == "EC":
                self.ec.append((c.first, c.second))
            else:
                self._file(f"{c.where}: unknown constraint type {c.kind!r}")
        self.var_types = {d.name: d.base_type for n in gm.nodes for d in (*n.controls, *n.monitors) if d.type}
        self.gm_task_path = {n.id: self._ancestors(n) for n in gm.nodes if n.kind == "task"}
        self.rank = self._execution_rank()
        self._replays: dict[str, tuple[TaskEffects, list[str]] | None] = {}
        self._start_values = _StartValues()  # of the mission decomposition being checked
        self._noted: set[str] = set()
        self._before: dict[str, set[str]] = {}  # per task, what the constraints put before it
        self._places_of: tuple[set[str] | None, dict[tuple[str, tuple[str, ...], int], list[str]]] = (None, {})
        self._levels_of: dict[str, list[tuple[str, int, int]]] = {}
        self._forall_depths: dict[str, int] = {}
        self._after: dict[str, set[str]] = {}

    def _execution_rank(self) -> dict[str, tuple[int, int]]:
        """A sort key that lists tasks in an order the SEQ and FB constraints allow (across tasks
        of other decompositions too), in file order where they leave the order open: effects
        are applied in this order, not in the order the file happens to list the tasks.  Tasks
        on a cycle (reported as such) keep their file order."""
        condensed = nx.condensation(self.seq_fb)
        scc_of = condensed.graph["mapping"]
        first = {c: min(self.order[k] for k in condensed.nodes[c]["members"]) for c in condensed}
        scc_rank = {c: r for r, c in enumerate(nx.lexicographical_topological_sort(condensed, key=first.__getitem__))}
        return {k: (scc_rank[scc_of[k]], self.order[k]) for k in self.out.tasks}

    # -- reporting -----------------------------------------------------------------------------
    def _file(self, message: str) -> None:
        self.report.violations.append(Violation(None, "", message))

    def _note(self, message: str) -> None:
        if message not in self._noted:
            self._noted.add(message)
            self.report.notes.append(message)

    def _ancestors(self, node: GMNode) -> list[GMNode]:
        out = []
        cur = node.parent
        while cur is not None:
            n = self.gm.node(cur)
            out.append(n)
            cur = n.parent
        return out

    # -- run -------------------------------------------------------------------------------------
    def run(self) -> Report:
        for i, md in enumerate(self.out.mission_decompositions):
            self.report.checked += 1
            self._decomposition(i, md)
        return self.report

    def _decomposition(self, i: int, md: tuple[str, ...]) -> None:
        bad = [k for k in md if k not in self.out.tasks]
        for k in bad:
            self.report.violations.append(Violation(i, k, "not a task of the file"))
        keys = [k for k in md if k in self.out.tasks]
        errors: list[Violation] = []
        self._structure(i, keys, errors)
        self._ordering(i, keys, errors)
        states = self._replay_all(i, keys, errors)
        self._conflicts(i, keys, errors)
        self._conditions(i, keys, states, errors)
        conflict = self._start_values.conflict()
        if conflict is not None:
            errors.append(Violation(i, conflict[0], "one start value of a function the world does not give must "
                                                    f"meet every comparison on it: {conflict[1]}"))
        self._robots(i, keys, errors)
        self.report.violations.extend(errors)

    # -- structure: instances, AND/OR choices ------------------------------------------------------
    def _structure(self, i: int, keys: list[str], errors: list[Violation]) -> None:
        tasks = [self.out.tasks[k] for k in keys]
        seen: dict[str, str] = {}
        for t in tasks:
            if t.instance in seen:
                errors.append(Violation(i, t.id, f"task instance {t.instance} is decomposed twice "
                                                 f"({seen[t.instance]} and {t.id})"))
            seen.setdefault(t.instance, t.id)
            if t.gm_task not in self.gm_task_path:
                errors.append(Violation(i, t.id, f"{t.gm_task} is not a task of the goal model"))
        chosen = set(seen)
        every = {t.instance: t for t in self.out.tasks.values()}
        for inst, t in every.items():
            path = self.gm_task_path.get(t.gm_task)
            if path is not None and not any(g.or_decomposed for g in path) and inst not in chosen:
                errors.append(Violation(i, inst, f"task instance {inst} is required (no OR goal above "
                                                 f"{t.gm_task}) but none of its decompositions is chosen"))
        for goal in self.gm.nodes:
            if goal.kind == "goal" and goal.or_decomposed:
                self._or_goal(i, goal, chosen, errors)

    def _branch_tasks(self, key: str) -> list[str]:
        node = self.gm.node(key)
        if node.kind == "task":
            return [node.id]
        return [t for c in node.children for t in self._branch_tasks(c)]

    def _or_goal(self, i: int, goal: GMNode, chosen: set[str], errors: list[Violation]) -> None:
        """One branch of an OR goal per instance (instances of one forAll element share their
        number): at most one, and at least one where the goal is required."""
        if self._or_branch_has_forall(goal):
            self._note(f"goal {goal.id}: an OR branch holds its own forAll; its choices per element "
                       "are not checked")
            return
        by_number: dict[str, set[str]] = {}
        for branch in goal.children:
            tasks = set(self._branch_tasks(branch))
            for inst in chosen:
                gm_task, _, number = inst.partition("_")
                if gm_task in tasks:
                    by_number.setdefault(number, set()).add(self.gm.node(branch).id)
        for number, branches in sorted(by_number.items()):
            if len(branches) > 1:
                errors.append(Violation(i, goal.id, f"OR goal {goal.id} has more than one chosen branch "
                                                    f"({', '.join(sorted(branches))}) for instance _{number}"))
        # at least one: for every instance that has tasks in the file in every branch (a branch
        # without tasks may be the one chosen) and that the decomposition needs
        for number, branches in sorted(self._branches_in_file(goal).items()):
            if number not in by_number and len(branches) == len(goal.children) and self._or_needed(goal, number, chosen):
                errors.append(Violation(i, goal.id, f"OR goal {goal.id} has no chosen branch for instance _{number}"))

    def _or_branch_has_forall(self, goal: GMNode) -> bool:
        """Whether some task below an OR goal is under a forAll between it and the goal: its
        instances per element are numbered beyond the OR goal's, which this check does not
        follow."""
        for branch in goal.children:
            for t in self._branch_tasks(branch):
                between = self.gm_task_path.get(t, [])[: self._depth_below(t, goal)]
                if any(n.forall is not None for n in between):
                    return True
        return False

    def _branches_in_file(self, goal: GMNode) -> dict[str, set[str]]:
        """Instance number -> the branches of an OR goal that have a task of that instance
        anywhere in the file (in any mission decomposition)."""
        present: dict[str, set[str]] = {}
        for branch in goal.children:
            tasks = set(self._branch_tasks(branch))
            for task in self.out.tasks.values():
                if task.gm_task in tasks:
                    present.setdefault(task.instance.partition("_")[2], set()).add(branch)
        return present

    def _or_needed(self, goal: GMNode, number: str, chosen: set[str]) -> bool:
        """Whether a decomposition must choose a branch of ``goal`` for instance ``number``: when
        no OR goal is above it, or when it chose a task of that instance in the branch of the
        nearest OR goal above that holds ``goal``."""
        below = goal
        for above in self._ancestors(goal):
            if above.or_decomposed:
                tasks = set(self._branch_tasks(below.key))
                return any(gm_task in tasks and n == number
                           for gm_task, _, n in (inst.partition("_") for inst in chosen))
            below = above
        return True

    def _depth_below(self, gm_task: str, goal: GMNode) -> int:
        path = self.gm_task_path.get(gm_task, [])
        for d, n in enumerate(path):
            if n.key == goal.key:
                return d
        return 0

    # -- how two tasks are related by the runtime annotations -------------------------------------
    def _relation(self, a: OutputTask, b: OutputTask) -> str:
        """The operator under which two tasks meet: ``;``, ``#``, ``FALLBACK`` or ``OR``."""
        return self._meeting(a, b)[0]

    def _sequenced_before(self, a: OutputTask, b: OutputTask) -> bool:
        """Whether ``a`` runs before ``b`` by a ``;`` of the goal model.  The constraints do not
        always say so: a subtree whose constraint list is empty (a one-child operator above a
        single task) gets no constraint with its siblings (semantics.md §6.1), and yet the
        tasks after it see its effects."""
        op, pos_a, pos_b = self._meeting(a, b)
        return op == ";" and pos_a < pos_b

    def _meeting(self, a: OutputTask, b: OutputTask) -> tuple[str, int, int]:
        """The operator under which two tasks meet (``;``, ``#``, ``FALLBACK`` or ``OR``), and the
        positions in its goal's annotation of the children that lead to them (-1, -1 where none).

        Read from the goal model alone: the lowest goal above both, and in its annotation the
        lowest operator over the two children that lead to them (annotation entries pair with
        children by position, as in the original).  Instances of different forAll elements
        meet under the forAll's parallel node."""
        if a.gm_task not in self.gm_task_path or b.gm_task not in self.gm_task_path:
            return "#", -1, -1
        up_a = [self.gm.node(a.gm_task)] + self.gm_task_path[a.gm_task]
        up_b = [self.gm.node(b.gm_task)] + self.gm_task_path[b.gm_task]
        keys_b = [n.key for n in up_b]
        depth_a = next(d for d, n in enumerate(up_a) if n.key in keys_b)
        meet = up_a[depth_a]
        # an instance number has one component per enclosing forAll, outermost first: the
        # forAlls at or above the meeting goal are the first components of both numbers
        common = self._forall_depth(meet)
        elements_a = a.instance.split("_")[1:1 + common]
        elements_b = b.instance.split("_")[1:1 + common]
        if elements_a != elements_b:
            return "#", -1, -1  # different elements of a forAll above both
        if depth_a == 0 or keys_b.index(meet.key) == 0:
            return "#", -1, -1
        if meet.or_decomposed:
            return "OR", -1, -1
        child_a, child_b = up_a[depth_a - 1].key, up_b[keys_b.index(meet.key) - 1].key
        if meet.annotation is None:
            return "#", -1, -1
        pos_a, pos_b = meet.children.index(child_a), meet.children.index(child_b)
        return _lowest_operator(meet.annotation, pos_a, pos_b) or "#", pos_a, pos_b

    # -- ordering ----------------------------------------------------------------------------------
    def _ordering(self, i: int, keys: list[str], errors: list[Violation]) -> None:
        sub = self.seq_fb.subgraph(keys)
        if not nx.is_directed_acyclic_graph(sub):
            cycle = nx.find_cycle(sub)
            errors.append(Violation(i, "", "the SEQ/FB constraints between its tasks form a cycle: "
                                           + " -> ".join(self.out.tasks[a].id for a, _ in cycle)))

    def _predecessors(self, key: str, chosen: set[str]) -> list[str]:
        """Chosen tasks that the SEQ and FB constraints, or the goal model's ``;``, put before
        ``key``, in execution order, without the alternatives a fallback replaces (they failed
        when ``key`` runs)."""
        task = self.out.tasks[key]
        before = self._ancestors_by_constraints(key) & chosen
        for p in self._sequence_candidates(task, chosen) - before - {key}:
            if self._sequenced_before(self.out.tasks[p], task):
                before |= {p} | (self._ancestors_by_constraints(p) & chosen)
        return sorted((p for p in before if self._relation(self.out.tasks[p], task) != "FALLBACK"),
                      key=self.rank.__getitem__)

    def _sequence_candidates(self, task: OutputTask, chosen: set[str]) -> set[str]:
        """The chosen tasks that may run before ``task`` by a ``;``: those in an earlier child of
        a goal above it, in the same copy of that goal (a quadratic search made ``validate``
        seven times slower at 50 vital-signs rooms)."""
        places = self._goal_places(chosen)
        out: set[str] = set()
        for goal, copy, position in self._places(task):
            for earlier in range(position):
                out.update(places.get((goal, copy, earlier), ()))
        return out

    def _goal_places(self, chosen: set[str]) -> dict[tuple[str, tuple[str, ...], int], list[str]]:
        """The chosen tasks by (goal above them, its copy, the goal's child leading to them), made
        once per decomposition (``chosen`` is one set object per decomposition, never changed)."""
        if self._places_of[0] is not chosen:
            places: dict[tuple[str, tuple[str, ...], int], list[str]] = {}
            for k in chosen:
                for place in self._places(self.out.tasks[k]):
                    places.setdefault(place, []).append(k)
            self._places_of = (chosen, places)
        return self._places_of[1]

    def _places(self, task: OutputTask) -> list[tuple[str, tuple[str, ...], int]]:
        """(goal, copy, child position) for every goal above ``task``; the copy of a goal is
        the task's first instance numbers, one per forAll at or above the goal."""
        elements = task.instance.split("_")[1:]
        return [(goal, tuple(elements[:copies]), position) for goal, copies, position in self._levels(task.gm_task)]

    def _levels(self, gm_task: str) -> list[tuple[str, int, int]]:
        """(goal, forAlls at or above it, position of the child leading down) for every goal
        above a goal-model task, once per task."""
        levels = self._levels_of.get(gm_task)
        if levels is None:
            levels = self._levels_of[gm_task] = []
            path = self.gm_task_path.get(gm_task, [])
            for below, goal in zip([self.gm.node(gm_task), *path] if path else [], path):
                if below.key in goal.children:
                    levels.append((goal.key, self._forall_depth(goal), goal.children.index(below.key)))
        return levels

    def _forall_depth(self, goal: GMNode) -> int:
        """The forAll goals at or above ``goal``: how many leading numbers of an instance id
        tell the copies of ``goal`` apart."""
        depth = self._forall_depths.get(goal.key)
        if depth is None:
            depth = self._forall_depths[goal.key] = sum(1 for n in [goal, *self._ancestors(goal)] if n.forall is not None)
        return depth

    def _ancestors_by_constraints(self, key: str) -> set[str]:
        if key not in self._before:
            self._before[key] = nx.ancestors(self.seq_fb, key)
        return self._before[key]

    def _state_before(self, keys: list[str], chosen: set[str]) -> State:
        """The initial state changed by every chosen predecessor of ``keys`` (and not by them)."""
        preds: set[str] = set()
        for k in keys:
            preds.update(self._predecessors(k, chosen))
        preds -= set(keys)
        state = self.w0.copy()
        for p in sorted(preds, key=self.rank.__getitem__):
            replay = self._replays.get(p)
            if replay is not None:
                replay[0].apply(state)
        return state

    # -- replay of each task ---------------------------------------------------------------------------
    def _replay_all(self, i: int, keys: list[str], errors: list[Violation]) -> dict[str, State]:
        chosen = set(keys)
        entry: dict[str, State] = {}
        self._replays = {}
        self._start_values = _StartValues()
        for k in sorted(keys, key=self.rank.__getitem__):
            start = self._state_before([k], chosen)
            entry[k] = start
            self._replays[k] = self._replay(i, self.out.tasks[k], start, errors)
        return entry

    def _replay(self, i: int, task: OutputTask, start: State, errors: list[Violation]) -> tuple[TaskEffects, list[str]] | None:
        if task.name not in self.domain.task_by_name:
            errors.append(Violation(i, task.id, f"{task.name} is not an abstract task of the domain"))
            return None
        root = [p.name for p in self.domain.task_by_name[task.name].parameters]
        explanations = Matcher(self.domain, root, task.actions).explain(task.name)
        if not explanations:
            listed = ", ".join(a.name for a in task.actions) or "no actions"
            errors.append(Violation(i, task.id, f"its actions ({listed}) are not a decomposition of {task.name} "
                                                "by the domain's methods"))
            return None
        values = _values(task)
        first_failure: list[str] | None = None
        chosen: TaskEffects | None = None
        alternatives: list[StartTests] = []
        for steps in explanations:
            effects, failures, required = self._run_steps(steps, values, start, task.id)
            if failures:
                first_failure = first_failure or failures
            elif chosen is None or effects == chosen:
                # the first explanation that runs fixes the effects; those with the same
                # effects differ only in what they require of unknown start values
                chosen = chosen or effects
                if required not in alternatives:
                    alternatives.append(required)
        if chosen is not None:
            if any(alternatives):
                self._start_values.tasks.append((task.id, alternatives))
            return chosen, []
        assert first_failure is not None
        for f in first_failure:
            errors.append(Violation(i, task.id, f))
        return None

    def _run_steps(self, steps: list[Step], values: dict[str, tuple[str, ...]], start: State,
                   task: str) -> tuple[TaskEffects, list[str], StartTests]:
        """Replay one explanation; unknown atoms are assumed when first required, and a
        function the world does not give must keep one start value for every task."""
        replay = _StepReplay(values, start, task)
        for step in steps:
            replay.step(step)
        return replay.changed, replay.failures, replay.required

    # -- parallel conflicts ------------------------------------------------------------------------
    def _conflicts(self, i: int, keys: list[str], errors: list[Violation]) -> None:
        """Only the pairs that set some fact both ways are examined (indexed by fact), so a
        decomposition of thousands of tasks is checked in time linear in its effects."""
        writers: dict[AtomKey, tuple[list[str], list[str]]] = {}
        for k in sorted(keys, key=self.order.__getitem__):
            replay = self._replays.get(k)
            if replay is not None:
                for atom, value in replay[0].facts.items():
                    writers.setdefault(atom, ([], []))[0 if value else 1].append(k)
        reported: set[tuple[str, str]] = set()
        for atom, (setting, clearing) in writers.items():
            for a, b in itertools.product(setting, clearing):
                a, b = sorted((a, b), key=self.order.__getitem__)
                if (a, b) in reported or self._relation(self.out.tasks[a], self.out.tasks[b]) != "#":
                    continue
                if b in self._descendants(a) or a in self._descendants(b):
                    continue  # ordered after all (a context dependency)
                reported.add((a, b))
                errors.append(Violation(i, self.out.tasks[a].id, f"parallel tasks {self.out.tasks[a].id} and "
                                        f"{self.out.tasks[b].id} set {_show_literal(atom[0], atom[1], True)} "
                                        "both true and false"))

    def _descendants(self, key: str) -> set[str]:
        """Tasks the SEQ and FB constraints put after ``key`` (the graph never changes)."""
        if key not in self._after:
            self._after[key] = nx.descendants(self.seq_fb, key)
        return self._after[key]

    # -- contexts and achieve conditions ---------------------------------------------------------
    def _binding(self, task: OutputTask) -> dict[str, tuple[str, ...]]:
        """Goal-model variables of a task, read back through its var_mapping."""
        values = _values(task)
        out: dict[str, tuple[str, ...]] = {}
        node = self.gm.by_id.get(task.gm_task)
        if node is not None and node.location and task.locations:
            out[node.location] = task.locations
        for vm in self.config.var_mapping:
            if vm.task_id == task.gm_task:
                for gm_var, hddl_var in vm.pairs:
                    if hddl_var in values:
                        out[gm_var] = values[hddl_var]
        return out

    def _conditions(self, i: int, keys: list[str], entry: dict[str, State], errors: list[Violation]) -> None:
        chosen = set(keys)
        tasks = [self.out.tasks[k] for k in keys]
        for goal in self.gm.nodes:
            if goal.kind != "goal":
                continue
            below = [t for t in tasks if any(a.key == goal.key for a in self.gm_task_path.get(t.gm_task, []))]
            if not below:
                continue
            if goal.context is not None and goal.context.kind == "condition" and goal.context.condition is not None:
                for t in below:
                    # a creation condition holds when the mission starts, or an earlier task
                    # makes it true before the goal's task starts
                    binding = self._binding(t)
                    if self._holds(goal.context.condition, binding, self.w0, goal) is not False:
                        continue
                    self._check(i, goal, "context condition", goal.context.condition, binding,
                                entry.get(t.key), t.id, errors)
            if goal.forall is not None and goal.forall.condition is not None:
                self._after_groups(i, goal, "forAll condition", goal.forall.condition, below, chosen, errors,
                                   group_by=goal.forall.iteration)
            elif goal.achieve_condition is not None:
                self._after_groups(i, goal, "achieve condition", goal.achieve_condition, below, chosen, errors)

    def _after_groups(self, i: int, goal: GMNode, what: str, cond: Condition, below: list[OutputTask],
                      chosen: set[str], errors: list[Violation], group_by: str | None = None) -> None:
        """Evaluate ``cond`` after the goal's tasks, once per copy of the goal (the forAll
        elements above it: the leading numbers of its tasks' instance ids) and binding of the
        condition's variables."""
        names = _variables(cond) | ({group_by} if group_by else set())
        depth = self._forall_depth(goal) - (goal.forall is not None)  # the forAlls above it
        groups: dict[tuple[tuple[str, ...], _BindingKey], list[OutputTask]] = {}
        unbound: list[OutputTask] = []
        # instance number -> the group of its tasks that bind the names
        numbers: dict[str, tuple[tuple[str, ...], _BindingKey]] = {}
        for t in below:
            b = self._binding(t)
            if not names <= b.keys():
                unbound.append(t)
                continue
            number = t.instance.partition("_")[2]
            key = (tuple(number.split("_")[:depth]), tuple(sorted((n, b[n]) for n in names)))
            groups.setdefault(key, []).append(t)
            numbers.setdefault(number, key)
        if not groups:
            self._note(f"goal {goal.id}: the {what} uses {', '.join(sorted(names))}, which no task binds "
                       "(Location or var_mapping): not checked")
            return
        for t in unbound:  # a task of the same forAll element (same instance number) joins its group
            joined = numbers.get(t.instance.partition("_")[2])
            if joined is not None:
                groups[joined].append(t)
        for key, members in groups.items():
            keys = [t.key for t in members]
            state = self._state_before(keys, chosen)
            for k in sorted(keys, key=self.rank.__getitem__):
                replay = self._replays.get(k)
                if replay is not None:
                    replay[0].apply(state)
            self._check(i, goal, what, cond, dict(key[1]), state, members[0].id, errors, after=True)

    def _check(self, i: int, goal: GMNode, what: str, cond: Condition, binding: dict[str, tuple[str, ...]],
               state: State | None, task: str, errors: list[Violation], after: bool = False) -> None:
        if state is None:
            return
        result = self._holds(cond, binding, state, goal, required=after)
        if result is False:
            moment = f"after the tasks of {goal.id}" if after else f"where {task} starts"
            bound = ", ".join(f"{k} = {','.join(v)}" for k, v in sorted(binding.items()) if k in _variables(cond))
            errors.append(Violation(i, goal.id, f"{what} of goal {goal.id} ({_show_condition(cond)}"
                                                f"{'; ' + bound if bound else ''}) does not hold {moment}"))

    def _holds(self, cond: Condition, binding: dict[str, tuple[str, ...]], state: State, goal: GMNode,
               required: bool = False) -> bool | None:
        """Open-world evaluation; None when an atom cannot be translated.  A comparison that
        is ``required`` (an achieve condition's conjunct) on a value the world does not give
        is a condition on its start value, which must agree with the others."""
        if isinstance(cond, BoolOp):
            parts = [self._holds(c, binding, state, goal, required and cond.op == "&&") for c in cond.children]
            if any(p is None for p in parts):
                return None
            return all(parts) if cond.op == "&&" else any(parts)
        return self._atom(cond, binding, state, goal, required)

    def _start_value_meets(self, key: AtomKey, op: str, bound: float, state: State, who: str) -> bool:
        """``op bound`` required of an unknown value: a test of its start value, which the
        decomposition's other tests must leave possible (checked once all are known)."""
        self._start_values.fixed.setdefault(key, []).append((op, bound - state.offsets.get(key, 0.0), False, who))
        return True

    def _atom(self, atom: Atom, binding: dict[str, tuple[str, ...]], state: State, goal: GMNode,
              required: bool = False) -> bool | None:
        relates = self.var_types.get(atom.variable, "")
        numeric = atom.op in ("=", "<>", ">", "<", ">=", "<=")
        for m in self.config.semantic_mapping:
            if (m.type == "attribute" and m.name == atom.attribute and m.relates_to == relates
                    and m.mapped_type == ("function" if numeric else "predicate")):
                values = binding.get(atom.variable, ())
                if numeric:
                    bound, op = float(atom.value), atom.op or "="
                    keys = [(m.pred, (v,)) for v in values]
                    return all(_compare(state.values[k], op, bound) if k in state.values
                               else not required or self._start_value_meets(k, op, bound, state,
                                                                            f"achieve condition of goal {goal.id}")
                               for k in keys)
                facts = [state.facts.get((m.pred, (v,))) for v in values]
                return all(f is None or f == (not atom.negated) for f in facts)
        self._note(f"goal {goal.id}: {atom.text} has no attribute mapping for type {relates or '?'}: not checked")
        return None

    # -- robots ----------------------------------------------------------------------------------------
    def _robots(self, i: int, keys: list[str], errors: list[Violation]) -> None:
        chosen = set(keys)
        for a, b in self.ec:
            if a in chosen and b in chosen:
                ra, rb = self.out.tasks[a].robots, self.out.tasks[b].robots
                if ra is None or rb is None:
                    continue
                if max(ra.min, rb.min) > min(ra.max, rb.max) or (ra.fixed and rb.fixed and ra.min != rb.min):
                    errors.append(Violation(i, self.out.tasks[a].id, f"execution-constrained with "
                                            f"{self.out.tasks[b].id}, but their robot numbers "
                                            f"({_show_robots(ra)} and {_show_robots(rb)}) are incompatible"))


def _leaves(annotation: Annotation) -> int:
    return 1 if isinstance(annotation, AnnotationLeaf) else sum(_leaves(c) for c in annotation.children)


def _lowest_operator(annotation: Annotation, a: int, b: int) -> str | None:
    """The operator of the smallest sub-expression holding leaf positions ``a`` and ``b``."""
    if isinstance(annotation, AnnotationLeaf):
        return None
    start = 0
    for child in annotation.children:
        n = _leaves(child)
        if start <= a < start + n and start <= b < start + n:
            return _lowest_operator(child, a - start, b - start)
        start += n
    return annotation.op


def _variables(cond: Condition) -> set[str]:
    if isinstance(cond, BoolOp):
        return set().union(*(_variables(c) for c in cond.children))
    return {cond.variable} if cond.variable else set()


def _show_literal(predicate: str, args: tuple[str, ...], positive: bool) -> str:
    atom = f"{predicate}({', '.join(args)})"
    return atom if positive else f"not {atom}"


def _show_condition(cond: Condition) -> str:
    if isinstance(cond, BoolOp):
        return f" {cond.op} ".join(_show_condition(c) for c in cond.children)
    return cond.text


def _show_robots(r: RobotsNum) -> str:
    return str(r.min) if r.fixed else f"[{r.min},{r.max}]"


def validate(domain: Domain, gm: GoalModel, config: Configuration, initial: InitialState,
             output: DecompositionOutput) -> Report:
    """Check every mission decomposition of ``output`` against the mission inputs."""
    return _Validator(domain, gm, config, initial, output).run()
