"""The planning domain: the HDDL abstract tasks, actions and methods the decomposer refines
goal-model tasks with (spec ``hddl.md``).

Produced by :mod:`mutrose_cp.io.hddl`; read by the world builder (types, constants), the HTN
decomposition (methods, actions) and the output (action signatures).  Every object is frozen:
a domain is read once and shared by every stage.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property


@dataclass(frozen=True)
class Parameter:
    """A typed variable ``?name - type`` (name includes the ``?``)."""

    name: str
    type: str


@dataclass(frozen=True, slots=True)
class Literal:
    """A boolean atom ``(pred a1 a2)`` or its negation; arguments are variables or constants."""

    predicate: str
    args: tuple[str, ...]
    positive: bool = True


@dataclass(frozen=True, slots=True)
class Comparison:
    """A numeric precondition ``(= (f a..) N)`` or ``(> (f a..) N)``.

    ``negated`` records ``(not (= ...))``; the original ignores it when evaluating (kept for
    fidelity and for the documented deviation)."""

    function: str
    args: tuple[str, ...]
    op: str  # "=" or ">"
    value: int | float
    negated: bool = False


@dataclass(frozen=True)
class NumericEffect:
    """``(increase|decrease|assign (f a..) N)`` with an integer amount."""

    kind: str  # "increase" | "decrease" | "assign"
    function: str
    args: tuple[str, ...]
    amount: int


Precondition = Literal | Comparison
"""One conjunct of an action's or method's precondition (HDDL ``:precondition``)."""


def show_precondition(c: Precondition) -> str:
    """A precondition as messages name it: ``not lit(RoomA)``, ``level(RoomA) = 1``."""
    if isinstance(c, Literal):
        return f"{'' if c.positive else 'not '}{c.predicate}({', '.join(c.args)})"
    return f"{c.function}({', '.join(c.args)}) {c.op} {c.value}"


@dataclass(frozen=True)
class Declaration:
    """A predicate or function declaration ``(name ?a - t1 ?b - t2)``; the position is where
    its name is written (not part of its identity)."""

    name: str
    parameters: tuple[Parameter, ...]
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)

    @property
    def sorts(self) -> tuple[str, ...]:
        """The parameters' types: what two declarations of one name must agree on."""
        return tuple(p.type for p in self.parameters)


@dataclass(frozen=True)
class AbstractTask:
    """A compound task ``(:task name :parameters (...))``; goal-model tasks name one."""

    name: str
    parameters: tuple[Parameter, ...]
    line: int = 0
    column: int = 0


@dataclass(frozen=True)
class Action:
    """A primitive task: what a robot executes, with the capabilities it needs."""

    name: str
    parameters: tuple[Parameter, ...]
    capabilities: tuple[str, ...] = ()
    preconditions: tuple[Precondition, ...] = ()  # flattened conjunction, declaration order
    effects: tuple[Literal, ...] = ()
    numeric_effects: tuple[NumericEffect, ...] = ()
    line: int = 0
    column: int = 0


GENERATED_SUBTASK_ID = "__t_id_"
"""Prefix of the ids given to subtasks written without one (``__t_id_<n>``, as the original)."""


@dataclass(frozen=True)
class Subtask:
    """One step of a method's task network; ``id`` is the declared id or ``__t_id_<n>``; the
    position is where the called task's name is written (not part of the step's identity)."""

    id: str
    task: str
    args: tuple[str, ...]
    line: int = field(default=0, compare=False)
    column: int = field(default=0, compare=False)

    @property
    def named(self) -> bool:
        """Whether the domain gave the step an id (``(s1 (task ...))``); generated ids start
        with ``__t_id_``, which no HDDL name can."""
        return not self.id.startswith(GENERATED_SUBTASK_ID)


@dataclass(frozen=True)
class Method:
    """A way to decompose the abstract task ``task`` into the ordered ``subtasks``."""

    name: str
    parameters: tuple[Parameter, ...]
    task: str
    task_args: tuple[str, ...]
    preconditions: tuple[Precondition, ...] = ()
    effects: tuple[Literal, ...] = ()
    numeric_effects: tuple[NumericEffect, ...] = ()
    subtasks: tuple[Subtask, ...] = ()
    # (before, after) pairs of subtask ids; for :ordered-subtasks the chain of consecutive ids
    ordering: tuple[tuple[str, str], ...] = ()
    ordered: bool = False  # declared with :ordered-subtasks / :ordered-tasks
    line: int = 0
    column: int = 0


@dataclass(frozen=True)
class TypeMention:
    """Where a sort is first used without being declared in ``:types`` (hddl.md §2.1: the
    decomposer, like PANDA, makes it a root type; standard HDDL readers reject it)."""

    name: str
    line: int
    column: int


@dataclass(frozen=True)
class Domain:
    """An HDDL domain as read, with indexes the decomposition looks things up by."""

    name: str
    source: str  # file name used in error locations
    # type -> parent (None when declared without parent); robot/robotteam are added as the
    # original does (subtypes of the parent of the first "- object" declaration, else roots)
    types: tuple[tuple[str, str | None], ...]
    constants: tuple[tuple[str, str], ...]  # (constant, type)
    predicates: tuple[Declaration, ...]
    functions: tuple[Declaration, ...]
    capabilities: tuple[str, ...]
    tasks: tuple[AbstractTask, ...]
    actions: tuple[Action, ...]
    methods: tuple[Method, ...]  # declaration order
    # sorts used (type parents, constants, predicate and function parameters) but not declared
    undeclared_types: tuple[TypeMention, ...] = field(default=(), compare=False)

    @cached_property
    def parent_of(self) -> dict[str, str | None]:
        """Type -> parent type (None for a root type)."""
        return dict(self.types)

    @cached_property
    def task_by_name(self) -> dict[str, AbstractTask]:
        return {t.name: t for t in self.tasks}

    @cached_property
    def action_by_name(self) -> dict[str, Action]:
        return {a.name: a for a in self.actions}

    def methods_of(self, task: str) -> tuple[Method, ...]:
        """Methods decomposing ``task`` in declaration order (defines decomposition numbering)."""
        return tuple(m for m in self.methods if m.task == task)

    @cached_property
    def robot_sorts(self) -> frozenset[str]:
        """``robot``, ``robotteam`` and the types declared *directly* below them (the
        original's "robot-related sorts"; deeper subtypes do not count)."""
        direct = {t for t, p in self.types if p in ("robot", "robotteam")}
        return frozenset({"robot", "robotteam"} | direct)

    def predicate_declarations(self, name: str) -> tuple[Declaration, ...]:
        """Every declaration of predicate ``name`` (a predicate may be declared more than once)."""
        return tuple(p for p in self.predicates if p.name == name)
