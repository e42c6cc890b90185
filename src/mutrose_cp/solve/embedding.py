"""Embedding: the whole space of valid mission decompositions as ONE CP-SAT model.

``Mission.decomposition_space()`` splits the boolean model into independent components and
solves each one on its own, which is the fast way to count or list decompositions.  An
application that *optimises over* the decompositions (a task allocator, a scheduler, a cost
model) needs the opposite: a single ``cp_model.CpModel`` that already contains every rule of a
valid decomposition, to which it adds its own variables and constraints, so that CP-SAT chooses
the decomposition *together with* its own decisions.  :class:`DecompositionModel` is that model
plus typed maps from the mission's names to CP-SAT literals.  The public names are re-exported
by :mod:`mutrose_cp.api`; see ``docs/api.md``.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

from ortools.sat.python import cp_model

from ..pipeline.constraints import Constraint, ConstraintKind
from ..model.task_instances import TaskInstance
from ..model import RobotNumber
from ..model.task_graph import ScopeVertex, TaskGraph, TaskVertex
from ..pipeline.stages import MissionStages
from . import decomposers
from .boolean_model import FALSE, TRUE, Lit
from .encoding import Encoding
from .native import cmh
from .proto import ProtoBuilder, negated
from .property_grounding import Grounded, ground
from ..model.properties import Property

#: A CP-SAT boolean literal: a ``BoolVar`` (or a constant ``IntVar`` of value 0/1) or its negation
#: (``IntVar`` and ``NotBooleanVariable`` share this base class).
CpLiteral = cmh.Literal

class ConstraintInfo(NamedTuple):
    """One mission constraint between two decompositions (ids like ``"AT1_1|1"``).

    ``kind`` is ``"SEQ"`` (``first`` before ``second``), ``"FB"`` (``second`` is the fallback of
    ``first``) or ``"EC"`` (execution constraint: with ``group=False`` both are executed by the
    same single robot; with ``group=True, divisible=False`` by the same team)."""

    kind: ConstraintKind
    first: str
    second: str
    group: bool
    divisible: bool


@dataclass(frozen=True)
class DecompositionInfo:
    """What an allocator needs to know about one decomposition."""

    id: str  # "AT1_1|2"
    task: str  # task instance id, "AT1_1"
    task_name: str  # HDDL abstract task, "HandOver"
    actions: tuple[str, ...]  # primitive action names, in order
    action_capabilities: tuple[tuple[str, ...], ...]  # required capabilities per action
    capabilities: frozenset[str]  # union over the actions: what a robot needs to execute it
    robot_number: RobotNumber  # fixed n (min == max, fixed) or a range [min, max]


def cp_literal(model: cp_model.CpModel, ref: int) -> CpLiteral:
    """The ``CpModel`` literal of proto literal ``ref`` (``-index - 1`` is a negation).

    Constants are proto variables too (one per value), so every literal of the maps, constant
    or not, behaves alike: ``Not()``, ``OnlyEnforceIf``, ``BooleanValue``."""
    if ref >= 0:
        return model.get_bool_var_from_proto_index(ref)
    return model.get_bool_var_from_proto_index(negated(ref)).negated()


@dataclass
class DecompositionModel:
    """The valid mission decompositions of a mission as one CP-SAT model, with named literals.

    Every solution of :attr:`model` (projected on :attr:`decomposition`) is exactly one valid
    mission decomposition, and every valid mission decomposition is a solution: enumerating
    the model gives the same set as ``mission.decomposition_space()``.  Auxiliary variables are
    defined by equivalences, so each decomposition is one solution.

    The model is deliberately *not* split into components and carries no objective: it exists so
    that allocation, scheduling or cost optimisers can add their own variables and constraints to
    the same ``CpModel`` and let CP-SAT choose the decomposition jointly with their decisions
    (``examples/allocation.py`` assigns robots, schedules and minimises the makespan).  Constant
    literals (facts fixed by the world, tasks that are always active) are mapped to real CP-SAT
    constants, so all map values can be used uniformly.

    Maps (keys are the names used in the mission output):

    * :attr:`decomposition`: decomposition id (``"AT1_1|2"``) -> literal "this decomposition is
      chosen";
    * :attr:`task`: task instance id (``"AT1_1"``) -> literal "this task instance is executed"
      (exactly one of its decompositions is chosen iff it is);
    * :attr:`or_choice`: ``(OR goal, child)`` -> literal "the OR goal is achieved through this
      child".  The OR goal is its goal id (``"G7"``), suffixed with its forAll indices like task
      instance ids (``"G7_2"`` for the copy made for the second element) when the goal sits under
      a forAll; the child is its goal id (``"G8"``) or, when the child is directly a task,
      the task instance id (``"AT5_1"``);
    * :attr:`constraints`: the mission constraints between decompositions (:class:`ConstraintInfo`);
    * :attr:`decompositions_info`: decomposition id -> :class:`DecompositionInfo`.
    """

    model: cp_model.CpModel
    decomposition: dict[str, CpLiteral]
    task: dict[str, CpLiteral]
    or_choice: dict[tuple[str, str], CpLiteral]
    constraints: list[ConstraintInfo]
    decompositions_info: dict[str, DecompositionInfo]
    true: CpLiteral  # the shared constant 1 (``false`` is the constant 0)
    false: CpLiteral
    mission: MissionStages = field(repr=False)
    #: the solver-neutral boolean model the CP-SAT model was built from (for relaxations)
    encoding: Encoding = field(repr=False)
    builder: ProtoBuilder = field(repr=False)

    # ------------------------------------------------------------------------------------------
    @classmethod
    def build(cls, mission: MissionStages, model: cp_model.CpModel | None = None) -> "DecompositionModel":
        """Encode ``mission`` and post the whole decomposition space to ``model`` (a new
        ``CpModel`` unless one is given, e.g. to combine it with existing variables)."""
        tg = mission.task_graph
        enc = decomposers.encoding(mission)
        model = model if model is not None else cp_model.CpModel()
        builder = ProtoBuilder(enc.model, model.proto)
        for r in enc.model.records:
            builder.post(r)

        made: dict[int, CpLiteral] = {}  # one object per literal: `dm.task[t] is dm.true` for constants

        def lit(l: Lit) -> CpLiteral:
            ref = builder.lit(l)
            if ref not in made:
                made[ref] = cp_literal(model, ref)
            return made[ref]

        decomposition: dict[str, CpLiteral] = {}
        info: dict[str, DecompositionInfo] = {}
        for v in tg.decompositions():
            dec = v.decomposition
            assert dec is not None
            # a decomposition the encoder never reached cannot be chosen
            decomposition[dec.id] = lit(enc.decomposition_lit.get(v.index, FALSE))
            acts = dec.path.actions
            info[dec.id] = DecompositionInfo(
                id=dec.id,
                task=dec.instance.id,
                task_name=dec.instance.name,
                actions=tuple(a.name for a in acts),
                action_capabilities=tuple(tuple(a.capabilities) for a in acts),
                capabilities=frozenset(c for a in acts for c in a.capabilities),
                robot_number=dec.instance.robot_number,
            )
        task: dict[str, CpLiteral] = {}
        for t in tg.tasks():
            task[t.content] = lit(enc.task_lit.get(t.index, FALSE))
        or_choice = {key: lit(enc.or_choice_lit[vc]) for vc, key in _or_keys(mission, tg, enc).items()}
        constraints = [_constraint_info(tg, c) for c in mission.constraints]
        return cls(model, decomposition, task, or_choice, constraints, info, lit(TRUE), lit(FALSE),
                   mission, enc, builder)

    # ------------------------------------------------------------------------------------------
    def solution(self, solver: cp_model.CpSolver) -> list[str]:
        """The chosen decomposition ids after ``solver.Solve(self.model)`` found a solution, in
        Task Graph order (the order of the mission output)."""
        return [d for d, lit in self.decomposition.items() if solver.BooleanValue(lit)]

    def chosen_or(self, solver: cp_model.CpSolver) -> dict[str, str]:
        """OR goal -> chosen child, for the OR goals that are active in the solution."""
        return {goal: child for (goal, child), lit in self.or_choice.items() if solver.BooleanValue(lit)}

    def add_property(self, prop: Property, holds: bool = True) -> CpLiteral:
        """Post ``prop``'s formula (its quantifier aside) to the model: every solution then
        satisfies it (``holds``) or violates it (``holds=False``), so that an allocator can
        require or forbid a property.  Returns the literal "the formula holds";
        :meth:`property_literal` gives it without posting anything, e.g. to weigh it in an
        objective."""
        literal = self.property_literal(prop)
        self.model.add_bool_and([literal if holds else literal.Not()])
        return literal

    def property_literal(self, prop: Property) -> CpLiteral:
        """A literal equal to "the solution satisfies ``prop``'s formula" (``solve/verify.py``
        grounds it; ``uses`` and ``before`` atoms)."""
        grounded = ground(prop, self.mission.task_graph, self.mission.domain, self.mission.constraints,
                          self.mission.initial_state)
        by_vertex = {v.index: self.decomposition[v.decomposition.id] for v in self.mission.task_graph.decompositions()
                     if v.decomposition is not None}
        atoms = [self._any_of([by_vertex[v] for v in sorted(chosen)]) for chosen in grounded.atoms]
        return self._formula_literal(grounded.formula, atoms)

    def _any_of(self, literals: list[CpLiteral]) -> CpLiteral:
        if not literals:
            return self.false
        any_literal = self.model.new_bool_var("")
        self.model.add_max_equality(any_literal, literals)
        return any_literal

    def _formula_literal(self, formula: Grounded, atoms: list[CpLiteral]) -> CpLiteral:
        if isinstance(formula, int):
            return atoms[formula]
        op, operands = formula
        literals = [self._formula_literal(f, atoms) for f in operands]
        if op == "not":
            return literals[0].Not()
        result = self.model.new_bool_var("")
        if op == "and":
            self.model.add_min_equality(result, literals or [self.true])
        else:
            self.model.add_max_equality(result, literals or [self.false])
        return result

    def forbid(self, decompositions: list[str]) -> None:
        """Convenience: exclude every solution that chooses all of ``decompositions``."""
        self.model.add_bool_or([self.decomposition[d].Not() for d in decompositions])


# ----------------------------------------------------------------------------------------------


def _constraint_info(tg: TaskGraph, c: Constraint) -> ConstraintInfo:
    return ConstraintInfo(c.kind, tg.vertices[c.first].content, tg.vertices[c.second].content,
                          c.group, c.divisible)


def _forall_depth(mission: MissionStages, goal_key: str) -> int:
    """How many forAll goals are above ``goal_key`` in the goal model (itself included)."""
    gm = mission.goal_model
    depth = 0
    key: str | None = goal_key
    seen: set[str] = set()
    while key and key not in seen:
        seen.add(key)
        try:
            node = gm.node(key)
        except KeyError:
            break
        if node.forall is not None:
            depth += 1
        key = node.parent
    return depth


def _or_keys(mission: MissionStages, tg: TaskGraph, enc: Encoding) -> dict[tuple[int, int], tuple[str, str]]:
    """(OR vertex, child vertex) -> (OR goal name with forAll suffix, child label)."""
    out: dict[tuple[int, int], tuple[str, str]] = {}
    used: set[tuple[str, str]] = set()
    for (v, c) in enc.or_choice_lit:
        vx, cx = tg.vertices[v], tg.vertices[c]
        goal = (vx.goal if isinstance(vx, ScopeVertex) else None) or vx.content
        k = _forall_depth(mission, goal)
        goal_name = goal
        if k:
            inst = _first_task_below(tg, v)
            if inst is not None:  # the task's forAll indices, outermost first: "AT1_2_1" -> 2, 1
                parts = inst.id[len(inst.gm_task):].split("_")[1:]
                goal_name = goal + "".join(f"_{p}" for p in parts[:k])
        child = (cx.goal if isinstance(cx, ScopeVertex) else None) or cx.content
        key = (goal_name, child)
        if key in used:  # defensive: never merge two choices (should not happen)
            key = (f"{goal_name}@{v}", child)
        used.add(key)
        out[(v, c)] = key
    return out


def _first_task_below(tg: TaskGraph, v: int) -> TaskInstance | None:
    stack = [v]
    while stack:
        u = stack.pop()
        vertex = tg.vertices[u]
        if isinstance(vertex, TaskVertex):
            return vertex.instance
        stack.extend(reversed(tg.children(u)))
    return None
