"""The checks of one mission decomposition (docs/validate.md, "What is checked", 1 to 7).

:meth:`DecompositionChecker.check` takes the chosen task keys of one *part* of a mission
decomposition (a component of :mod:`.components`: tasks that can affect each other's checks) and
the task instances of that part, and returns the violations found there:

* tasks and choices: no instance decomposed twice, every instance outside OR branches chosen,
  one branch per OR goal instance;
* the SEQ and FB constraints between the chosen tasks admit an order;
* each task's actions are a decomposition of its task by the domain's methods, and replayed
  from the state it starts in (the initial world changed by the chosen tasks that the
  constraints or a ``;`` put before it, without the alternatives a fallback replaces) every
  method and action precondition holds; parallel tasks never set a fact both ways;
* creation conditions hold where their tasks start, achieve and forAll conditions after the
  goal's tasks (per copy of the goal); one start value of each function the world does not give
  meets every comparison on it;
* execution-constrained tasks have compatible robot numbers.
"""
from __future__ import annotations

import itertools
from typing import Callable

import networkx as nx

from ..io.decomposition_output import DecompositionOutput, OutputTask, RobotsNum
from ..model import Condition, Domain, GMNode, GoalModel, InitialState
from .conditions import GoalConditions, show_condition, variables
from .goal_relations import GoalRelations, Place
from .htn_match import Matcher
from .numbers import AtomKey, StartTests, StartValues
from .replay import StepReplay, Values, show_literal, task_values
from .state import State, TaskEffects
from .steps import Step

Found = list[tuple[str, str]]  # (task or goal, message)
BindingKey = tuple[tuple[str, tuple[str, ...]], ...]


def after_condition(goal: GMNode) -> tuple[Condition | None, str | None]:
    """The condition that must hold after a goal's tasks, and the variable its copies are told
    apart by (a forAll's iteration variable)."""
    if goal.forall is not None and goal.forall.condition is not None:
        return goal.forall.condition, goal.forall.iteration
    return goal.achieve_condition, None


def show_robots(r: RobotsNum) -> str:
    return str(r.min) if r.fixed else f"[{r.min},{r.max}]"


def robots_compatible(ra: RobotsNum, rb: RobotsNum) -> bool:
    return max(ra.min, rb.min) <= min(ra.max, rb.max) and not (ra.fixed and rb.fixed and ra.min != rb.min)


class _Run:
    """What one check of a part keeps while it runs."""

    def __init__(self, keys: list[str]) -> None:
        self.keys = keys
        self.chosen = set(keys)
        self.replays: dict[str, TaskEffects | None] = {}
        self.entry: dict[str, State] = {}
        self.start = StartValues()
        self.places: dict[Place, list[str]] | None = None
        self.found: Found = []


class DecompositionChecker:
    """Everything the checks of a part need that does not depend on the decomposition."""

    def __init__(self, domain: Domain, gm: GoalModel, initial: InitialState, out: DecompositionOutput,
                 relations: GoalRelations, conditions: GoalConditions, note: Callable[[str], None]) -> None:
        self.domain, self.gm, self.out = domain, gm, out
        self.rel, self.cond, self.note = relations, conditions, note
        self.w0 = State.initial(initial)
        self.order = {k: i for i, k in enumerate(out.tasks)}
        self.seq_fb: nx.DiGraph[str] = nx.DiGraph()
        self.seq_fb.add_nodes_from(out.tasks)
        self.ec: list[tuple[str, str]] = []
        self.file_problems: Found = []  # (task, message): constraints the file's tasks cannot hold
        for c in out.constraints:
            self._constraint(c.kind, c.first, c.second, c.where)
        self.rank = self._execution_rank()
        self.acyclic = nx.is_directed_acyclic_graph(self.seq_fb)
        self._before: dict[str, set[str]] = {}
        self._after: dict[str, set[str]] = {}
        self._explained: dict[tuple[str, tuple[object, ...]], list[list[Step]] | None] = {}
        self._values: dict[str, Values] = {}
        self.xml = out.format == "xml"
        self.or_goals = [g for g in gm.nodes if g.kind == "goal" and g.or_decomposed]
        self.conditioned = [g for g in gm.nodes if g.kind == "goal" and (after_condition(g)[0] is not None or (
            g.context is not None and g.context.kind == "condition" and g.context.condition is not None))]
        self._present = {g.key: self._branches_in_file(g) for g in self.or_goals}
        self._clashes: dict[str, list[tuple[str, RobotsNum, RobotsNum]]] | None = None

    def _constraint(self, kind: str, first: str, second: str, where: str) -> None:
        missing = [k for k in (first, second) if k not in self.out.tasks]
        if missing:
            known = next((self.out.tasks[k].id for k in (first, second) if k in self.out.tasks), "")
            self.file_problems.append((known, f"{where}: constraint names unknown task {missing[0]}"))
            return
        a, b = self.out.tasks[first].id, self.out.tasks[second].id
        if kind in ("SEQ", "FB"):
            self.seq_fb.add_edge(first, second)
        elif kind == "EC":
            self.ec.append((first, second))
        else:
            self.file_problems.append((a, f"{where}: unknown constraint type {kind!r} between {a} and {b}"))

    def _execution_rank(self) -> dict[str, tuple[int, int]]:
        """A sort key that lists tasks in an order the SEQ and FB constraints allow, in file
        order where they leave it open (tasks on a cycle keep their file order)."""
        condensed = nx.condensation(self.seq_fb)
        scc_of = condensed.graph["mapping"]
        first = {c: min(self.order[k] for k in condensed.nodes[c]["members"]) for c in condensed}
        scc_rank = {c: r for r, c in enumerate(nx.lexicographical_topological_sort(condensed, key=first.__getitem__))}
        return {k: (scc_rank[scc_of[k]], self.order[k]) for k in self.out.tasks}

    # -- static per task ---------------------------------------------------------------------------
    def explanations(self, task: OutputTask) -> list[list[Step]] | None:
        """The ways the domain's methods produce the task's actions (None: no abstract task)."""
        key = (task.name, tuple((a.name, a.args) for a in task.actions))
        if key not in self._explained:
            if task.name not in self.domain.task_by_name:
                self._explained[key] = None
            else:
                root = [p.name for p in self.domain.task_by_name[task.name].parameters]
                self._explained[key] = Matcher(self.domain, root, task.actions).explain(task.name)
        return self._explained[key]

    def values(self, task: OutputTask) -> Values:
        if task.key not in self._values:
            self._values[task.key] = task_values(task, self.xml)
        return self._values[task.key]

    def ancestors_by_constraints(self, key: str) -> set[str]:
        if key not in self._before:
            self._before[key] = nx.ancestors(self.seq_fb, key)
        return self._before[key]

    def descendants(self, key: str) -> set[str]:
        if key not in self._after:
            self._after[key] = nx.descendants(self.seq_fb, key)
        return self._after[key]

    # -- a part --------------------------------------------------------------------------------------
    def check(self, keys: list[str], scope: set[str]) -> Found:
        """The violations of the chosen ``keys`` of one part whose task instances are ``scope``."""
        run = _Run(keys)
        self._structure(run, scope)
        if not self.acyclic:
            self._ordering(run)
        self._replay_all(run)
        self._conflicts(run)
        self._conditions(run)
        conflict = run.start.conflict()
        if conflict is not None:
            run.found.append((conflict[0], "one start value of a function the world does not give must meet "
                                           f"every comparison on it: {conflict[1]}"))
        self._robots(run)
        return run.found

    # -- structure: instances, AND/OR choices ------------------------------------------------------
    def _structure(self, run: _Run, scope: set[str]) -> None:
        seen: dict[str, str] = {}
        for t in (self.out.tasks[k] for k in run.keys):
            if t.instance in seen:
                run.found.append((t.id, f"task instance {t.instance} is decomposed twice ({seen[t.instance]} and "
                                        f"{t.id})"))
            seen.setdefault(t.instance, t.id)
            if t.gm_task not in self.rel.task_path:
                run.found.append((t.id, f"{t.gm_task} is not a task of the goal model"))
        chosen = set(seen)
        for inst in sorted(scope - chosen):
            gm_task = inst.partition("_")[0]
            path = self.rel.task_path.get(gm_task)
            if path is not None and not any(g.or_decomposed for g in path):
                run.found.append((inst, f"task instance {inst} is required (no OR goal above {gm_task}) but none of "
                                        "its decompositions is chosen"))
        for goal in self.or_goals:
            self._or_goal(run, goal, chosen, scope)

    def _or_goal(self, run: _Run, goal: GMNode, chosen: set[str], scope: set[str]) -> None:
        """One branch of an OR goal per instance (instances of one forAll element share their
        number): at most one, and at least one where the goal is required."""
        present = self._present[goal.key]
        if present is None:
            return
        by_number: dict[str, set[str]] = {}
        for branch in goal.children:
            tasks = set(self.rel.branch_tasks(branch))
            for inst in chosen:
                gm_task, _, number = inst.partition("_")
                if gm_task in tasks:
                    by_number.setdefault(number, set()).add(self.gm.node(branch).id)
        for number, branches in sorted(by_number.items()):
            if len(branches) > 1:
                run.found.append((goal.id, f"OR goal {goal.id} has more than one chosen branch "
                                           f"({', '.join(sorted(branches))}) for instance _{number}"))
        for number, (branches, instances) in sorted(present.items()):
            if number not in by_number and instances & scope and len(branches) == len(goal.children) \
                    and self._or_needed(goal, number, chosen):
                run.found.append((goal.id, f"OR goal {goal.id} has no chosen branch for instance _{number}"))

    def _branches_in_file(self, goal: GMNode) -> dict[str, tuple[set[str], set[str]]] | None:
        """Instance number -> the branches of an OR goal that have a task of that instance in the
        file, and those instances; None (noted) when a branch holds a forAll of its own: its
        instances are numbered beyond the OR goal's, which this check does not follow."""
        for branch in goal.children:
            for t in self.rel.branch_tasks(branch):
                if any(n.forall is not None for n in self.rel.task_path.get(t, [])[:self.rel.depth_below(t, goal)]):
                    self.note(f"goal {goal.id}: an OR branch holds its own forAll; its choices per element are not "
                              "checked")
                    return None
        present: dict[str, tuple[set[str], set[str]]] = {}
        for branch in goal.children:
            tasks = set(self.rel.branch_tasks(branch))
            for task in self.out.tasks.values():
                if task.gm_task in tasks:
                    entry = present.setdefault(task.instance.partition("_")[2], (set(), set()))
                    entry[0].add(branch)
                    entry[1].add(task.instance)
        return present

    def _or_needed(self, goal: GMNode, number: str, chosen: set[str]) -> bool:
        """Whether a decomposition must choose a branch of ``goal`` for instance ``number``: when
        no OR goal is above it, or when it chose a task of that instance in the branch of the
        nearest OR goal above that holds ``goal``."""
        below = goal
        for above in self.rel.ancestors(goal):
            if above.or_decomposed:
                tasks = set(self.rel.branch_tasks(below.key))
                return any(gm_task in tasks and n == number for gm_task, _, n in (i.partition("_") for i in chosen))
            below = above
        return True

    # -- ordering ----------------------------------------------------------------------------------
    def _ordering(self, run: _Run) -> None:
        sub = self.seq_fb.subgraph(run.keys)
        if not nx.is_directed_acyclic_graph(sub):
            cycle = nx.find_cycle(sub)
            run.found.append(("", "the SEQ/FB constraints between its tasks form a cycle: "
                                  + " -> ".join(self.out.tasks[a].id for a, _ in cycle)))

    def predecessors(self, key: str, run: _Run) -> list[str]:
        """Chosen tasks that the SEQ and FB constraints, or the goal model's ``;``, put before
        ``key``, in execution order, without the alternatives a fallback replaces."""
        task = self.out.tasks[key]
        before = self.ancestors_by_constraints(key) & run.chosen
        for p in self._sequence_candidates(task, run) - before - {key}:
            if self.rel.sequenced_before(self.out.tasks[p], task):
                before |= {p} | (self.ancestors_by_constraints(p) & run.chosen)
        return sorted((p for p in before if self.rel.relation(self.out.tasks[p], task) != "FALLBACK"),
                      key=self.rank.__getitem__)

    def _sequence_candidates(self, task: OutputTask, run: _Run) -> set[str]:
        """The chosen tasks in an earlier child of a goal above ``task``, in the same copy."""
        if run.places is None:
            run.places = {}
            for k in run.chosen:
                for place in self.rel.places(self.out.tasks[k]):
                    run.places.setdefault(place, []).append(k)
        out: set[str] = set()
        for goal, copy, position in self.rel.places(task):
            for earlier in range(position):
                out.update(run.places.get((goal, copy, earlier), ()))
        return out

    def state_before(self, keys: list[str], run: _Run) -> State:
        """The initial state changed by every chosen predecessor of ``keys`` (and not by them)."""
        preds: set[str] = set()
        for k in keys:
            preds.update(self.predecessors(k, run))
        preds -= set(keys)
        state = self.w0.copy()
        for p in sorted(preds, key=self.rank.__getitem__):
            effects = run.replays.get(p)
            if effects is not None:
                effects.apply(state)
        return state

    # -- replay of each task -----------------------------------------------------------------------
    def _replay_all(self, run: _Run) -> None:
        for k in sorted(run.keys, key=self.rank.__getitem__):
            start = self.state_before([k], run)
            run.entry[k] = start
            run.replays[k] = self._replay(run, self.out.tasks[k], start)

    def _replay(self, run: _Run, task: OutputTask, start: State) -> TaskEffects | None:
        explanations = self.explanations(task)
        if explanations is None:
            run.found.append((task.id, f"{task.name} is not an abstract task of the domain"))
            return None
        if not explanations:
            listed = ", ".join(a.name for a in task.actions) or "no actions"
            run.found.append((task.id, f"its actions ({listed}) are not a decomposition of {task.name} by the "
                                       "domain's methods"))
            return None
        first_failure: list[str] | None = None
        chosen: TaskEffects | None = None
        alternatives: list[StartTests] = []
        for steps in explanations:
            replay = StepReplay(self.values(task), start, task.id)
            for step in steps:
                replay.step(step)
            if replay.failures:
                first_failure = first_failure or replay.failures
            elif chosen is None or replay.changed == chosen:
                # the first explanation that runs fixes the effects; those with the same effects
                # differ only in what they require of unknown start values
                chosen = chosen or replay.changed
                if replay.required not in alternatives:
                    alternatives.append(replay.required)
        if chosen is not None:
            if any(alternatives):
                run.start.tasks.append((task.id, alternatives))
            return chosen
        run.found.extend((task.id, f) for f in first_failure or [])
        return None

    # -- parallel conflicts ------------------------------------------------------------------------
    def _conflicts(self, run: _Run) -> None:
        """Only the pairs that set some fact both ways are examined (indexed by fact)."""
        writers: dict[AtomKey, tuple[list[str], list[str]]] = {}
        for k in sorted(run.keys, key=self.order.__getitem__):
            effects = run.replays.get(k)
            if effects is not None:
                for atom, value in effects.facts.items():
                    writers.setdefault(atom, ([], []))[0 if value else 1].append(k)
        reported: set[tuple[str, str]] = set()
        for atom, (setting, clearing) in writers.items():
            for a, b in itertools.product(setting, clearing):
                a, b = sorted((a, b), key=self.order.__getitem__)
                if (a, b) in reported or not self._parallel(a, b):
                    continue
                reported.add((a, b))
                ta, tb = self.out.tasks[a], self.out.tasks[b]
                run.found.append((ta.id, f"parallel tasks {ta.id} and {tb.id} set "
                                         f"{show_literal(atom[0], atom[1], True)} both true and false"))

    def _parallel(self, a: str, b: str) -> bool:
        return self.rel.relation(self.out.tasks[a], self.out.tasks[b]) == "#" \
            and b not in self.descendants(a) and a not in self.descendants(b)

    # -- contexts and achieve conditions -----------------------------------------------------------
    def _conditions(self, run: _Run) -> None:
        tasks = [self.out.tasks[k] for k in run.keys]
        for goal in self.conditioned:
            below = [t for t in tasks if self.rel.below(t, goal)]
            if not below:
                continue
            ctx = goal.context
            if ctx is not None and ctx.kind == "condition" and ctx.condition is not None:
                self._creation(run, goal, ctx.condition, below)
            after, group_by = after_condition(goal)
            if after is not None:
                what = "forAll condition" if group_by else "achieve condition"
                self._after_groups(run, goal, what, after, below, group_by)

    def _creation(self, run: _Run, goal: GMNode, cond: Condition, below: list[OutputTask]) -> None:
        """A creation condition holds when the mission starts, or an earlier task makes it true
        before the goal's task starts."""
        for t in below:
            binding = self.cond.binding(t)
            if self.cond.holds(cond, binding, self.w0, goal) is not False:
                continue
            self._check(run, goal, "context condition", cond, binding, run.entry.get(t.key), t.id)

    def group_key(self, goal: GMNode, names: set[str], task: OutputTask) -> tuple[tuple[str, ...], BindingKey] | None:
        """The copy of ``goal`` a task's condition check belongs to: the forAll elements above the
        goal and the values the task binds to the condition's variables (None: it binds none)."""
        b = self.cond.binding(task)
        if not names <= b.keys():
            return None
        depth = self.rel.forall_depth(goal) - (goal.forall is not None)
        number = task.instance.partition("_")[2]
        return tuple(number.split("_")[:depth]), tuple(sorted((n, b[n]) for n in names))

    def _after_groups(self, run: _Run, goal: GMNode, what: str, cond: Condition, below: list[OutputTask],
                      group_by: str | None = None) -> None:
        """Evaluate ``cond`` after the goal's tasks, once per copy of the goal and binding of the
        condition's variables; a task that binds none joins the group of its forAll element."""
        names = variables(cond) | ({group_by} if group_by else set())
        groups: dict[tuple[tuple[str, ...], BindingKey], list[OutputTask]] = {}
        numbers: dict[str, tuple[tuple[str, ...], BindingKey]] = {}
        unbound: list[OutputTask] = []
        for t in below:
            key = self.group_key(goal, names, t)
            if key is None:
                unbound.append(t)
                continue
            groups.setdefault(key, []).append(t)
            numbers.setdefault(t.instance.partition("_")[2], key)
        if not groups:
            self.note(f"goal {goal.id}: the {what} uses {', '.join(sorted(names))}, which no task binds "
                      "(Location or var_mapping): not checked")
            return
        for t in unbound:
            joined = numbers.get(t.instance.partition("_")[2])
            if joined is not None:
                groups[joined].append(t)
        for key, members in groups.items():
            keys = [t.key for t in members]
            state = self.state_before(keys, run)
            for k in sorted(keys, key=self.rank.__getitem__):
                effects = run.replays.get(k)
                if effects is not None:
                    effects.apply(state)
            self._check(run, goal, what, cond, dict(key[1]), state, members[0].id, after=True)

    def _check(self, run: _Run, goal: GMNode, what: str, cond: Condition, binding: Values, state: State | None,
               task: str, after: bool = False) -> None:
        if state is None:
            return
        if self.cond.holds(cond, binding, state, goal, run.start if after else None) is False:
            moment = f"after the tasks of {goal.id}" if after else f"where {task} starts"
            bound = ", ".join(f"{k} = {','.join(v)}" for k, v in sorted(binding.items()) if k in variables(cond))
            run.found.append((goal.id, f"{what} of goal {goal.id} ({show_condition(cond)}"
                                       f"{'; ' + bound if bound else ''}) does not hold {moment}"))

    # -- robots ------------------------------------------------------------------------------------
    def _robots(self, run: _Run) -> None:
        """Only the pairs whose robot numbers do not fit can fail (indexed once by task)."""
        if self._clashes is None:
            self._clashes = {}
            for a, b in self.ec:
                ra, rb = self.out.tasks[a].robots, self.out.tasks[b].robots
                if ra is not None and rb is not None and not robots_compatible(ra, rb):
                    self._clashes.setdefault(a, []).append((b, ra, rb))
        for a in run.keys:
            for b, ra, rb in self._clashes.get(a, ()):
                if b in run.chosen:
                    run.found.append((self.out.tasks[a].id, f"execution-constrained with {self.out.tasks[b].id}, "
                                                            f"but their robot numbers ({show_robots(ra)} and "
                                                            f"{show_robots(rb)}) are incompatible"))
