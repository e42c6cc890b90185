"""The original tool's console reports: ``-p`` (pretty print) and ``-v`` (verbose trace).

``-p`` prints three blocks on stdout (spec ``output.md`` §5), which the VS Code plug-in shows to
its user: "GENERATED TASK INSTANCES" (every task decomposition with its abstract task,
capabilities, location, arguments and actions), "MISSION CONSTRAINTS" (the counts, and the lists
as ``[a ; b]``, ``[a EC b]``, ``[a FB b]``, five to a line) and "POSSIBLE MISSION
DECOMPOSITIONS" (each valid mission decomposition, one task decomposition a line, in the
original's words).  ``-v`` prints the pipeline's intermediate results, stage by stage.

The console is informative (the files are the contract): the texts follow the original where
its wording is known and are documented in ``docs/deviations.md`` where it is not.
"""
from __future__ import annotations

from typing import IO, Iterable, Sequence

from .constraints import EC, FB, SEQ, Constraint, ConstraintKind
from .expansion import TaskInstance
from .model import Domain, InitialState
from .model.task_graph import Decomposition, TaskGraph

RULE = "--------------------------------------"
CLOSING_RULE = "-" * 109
PER_LINE = 5  # constraints printed on one line
_SYMBOL = {SEQ: ";", EC: "EC", FB: "FB"}
_KIND_NAMES = ((SEQ, "sequential"), (EC, "execution"), (FB, "fallback"))


def _heading(title: str) -> str:
    return f"{RULE} {title} {RULE}"


def _listed(values: Sequence[str]) -> str:
    return "[" + ", ".join(values) + "]"


def _capabilities(dec: Decomposition) -> list[str]:
    """The capabilities the decomposition's actions require, as a sorted set (as the original)."""
    return sorted({c for step in dec.path.steps for c in step.capabilities})


def _location(instance: TaskInstance) -> str:
    loc = instance.location
    if isinstance(loc, tuple):
        return f"at locations {_listed(loc)}"
    return f"at location [{loc or ''}]"


def _summary_line(dec: Decomposition) -> str:
    """``Task [AT1_1|1] with required capability [c] at location [Room3]``, the original's
    wording for a task decomposition of a mission decomposition."""
    caps = _capabilities(dec)
    text = f"Task [{dec.id}] "
    if caps:
        text += f"with required {'capabilities' if len(caps) > 1 else 'capability'} {_listed(caps)} "
    return text + _location(dec.instance)


def _value(value: str | tuple[str, ...]) -> str:
    return _listed(value) if isinstance(value, tuple) else value


def _arguments(dec: Decomposition, domain: Domain) -> str:
    """The abstract task's parameters with their types and, where the goal model binds them,
    their values: ``?r - robot, ?rm - room = RoomA``."""
    binding = dec.instance.binding
    parts = []
    for p in domain.task_by_name[dec.instance.name].parameters:
        parts.append(f"{p.name} - {p.type}" + (f" = {_value(binding[p.name])}" if p.name in binding else ""))
    return ", ".join(parts) if parts else "none"


def print_task_instances(tg: TaskGraph, domain: Domain, out: IO[str]) -> None:
    """The "GENERATED TASK INSTANCES" block: every task decomposition of the Task Graph."""
    print(_heading("GENERATED TASK INSTANCES"), file=out)
    for i, vertex in enumerate(tg.decompositions()):
        dec = vertex.decomposition
        if i:
            print(file=out)
        print(f"{_summary_line(dec)}: {dec.instance.name}", file=out)
        print(f"    Arguments: {_arguments(dec, domain)}", file=out)
        actions = ", ".join(f"{s.name}({' '.join(s.args)})" for s in dec.path.actions)
        print(f"    Actions: {actions or 'none'}", file=out)
    print(CLOSING_RULE, file=out)


def _constraint_lines(label: str, texts: list[str]) -> Iterable[str]:
    """``Label: [a] AND [b] AND ...``, five constraints to a line."""
    for start in range(0, len(texts), PER_LINE):
        chunk = " AND ".join(texts[start:start + PER_LINE])
        more = " AND" if start + PER_LINE < len(texts) else ""
        yield (f"{label}: " if start == 0 else "    ") + chunk + more


def print_constraints(tg: TaskGraph, constraints: Sequence[Constraint], out: IO[str]) -> None:
    """The "MISSION CONSTRAINTS" block: per kind, the count and the list."""
    print(_heading("MISSION CONSTRAINTS"), file=out)
    by_kind: dict[ConstraintKind, list[str]] = {kind: [] for kind, _ in _KIND_NAMES}
    for c in constraints:
        if c.kind in by_kind:
            first, second = tg.decomposition(c.first).decomposition.id, tg.decomposition(c.second).decomposition.id
            by_kind[c.kind].append(f"[{first} {_SYMBOL[c.kind]} {second}]")
    for i, (kind, name) in enumerate(_KIND_NAMES):
        if i:
            print(file=out)
        texts = by_kind[kind]
        print(f"Number of {name} constraints: {len(texts)}", file=out)
        for line in _constraint_lines(f"{name.capitalize()} constraints", texts):
            print(line, file=out)
    print(CLOSING_RULE, file=out)


def print_mission_decompositions(tg: TaskGraph, decompositions: Sequence[Sequence[int]], out: IO[str]) -> None:
    """The "POSSIBLE MISSION DECOMPOSITIONS" block, in the original's words: one task
    decomposition a line, joined by ``AND``, a blank line between mission decompositions."""
    print(_heading("POSSIBLE MISSION DECOMPOSITIONS"), file=out)
    for m, md in enumerate(decompositions):
        if m:
            print(file=out)
        for i, d in enumerate(md):
            print(_summary_line(tg.decomposition(d).decomposition) + (" AND" if i < len(md) - 1 else ""), file=out)
    print(CLOSING_RULE, file=out)


# ---------------------------------------------------------------------------------------------
# -v: the verbose trace


def _section(title: str, out: IO[str]) -> None:
    print(f"\n==== {title}", file=out)


def print_inputs(domain: Domain, paths: dict[str, str], out: IO[str]) -> None:
    """The four files read, and the size of the domain."""
    _section("inputs", out)
    for what, path in paths.items():
        print(f"{what}: {path}", file=out)
    print(f"domain {domain.name}: {len(domain.tasks)} abstract tasks, {len(domain.actions)} actions, "
          f"{len(domain.methods)} methods", file=out)


def print_expansion(annotation: str, instances: Sequence[TaskInstance], out: IO[str]) -> None:
    """The runtime annotation of the expanded goal model and the task instances."""
    _section("runtime annotation", out)
    print(annotation, file=out)
    _section(f"task instances ({len(instances)})", out)
    for inst in instances:
        values = ", ".join(f"{p.hddl_param} = {_value(p.value)}" for p in inst.parameters)
        robots = (str(inst.robot_number.min) if inst.robot_number.fixed
                  else f"{inst.robot_number.min}..{inst.robot_number.max}")
        print(f"{inst.id}: {inst.name} ({values or 'no parameters'}) {_location(inst)}, robots {robots}", file=out)


def print_decomposition_paths(tg: TaskGraph, out: IO[str]) -> None:
    """The HTN decomposition paths of the abstract tasks the mission uses."""
    _section("decomposition paths", out)
    seen: set[tuple[str, int]] = set()
    for vertex in tg.decompositions():
        dec = vertex.decomposition
        if (dec.instance.name, dec.number) in seen:
            continue
        seen.add((dec.instance.name, dec.number))
        steps = " -> ".join(s.name for s in dec.path.actions) or "(no action)"
        print(f"{dec.instance.name} path {dec.number}: {steps}", file=out)


def print_world_state(state: InitialState, out: IO[str]) -> None:
    """The initial world state: its facts and function values."""
    _section(f"initial world state ({len(state.literals)} facts, {len(state.functions)} function values)", out)
    for lit in state.literals:
        print(str(lit), file=out)
    for (name, args), value in state.functions:
        print(f"{name}({', '.join(args)}) = {value}", file=out)


def print_task_graph(tg: TaskGraph, out: IO[str]) -> None:
    """The Task Graph's vertices with their parents, and its edges."""
    _section(f"task graph ({len(tg.vertices)} vertices)", out)
    for v in tg.vertices:
        print(f"{v.index}: {v.kind} {v.content} (parent {v.parent})", file=out)
    for e in tg.edges():
        print(f"{e.source} -> {e.target} {e.kind}", file=out)


def print_trace_decompositions(tg: TaskGraph, decompositions: Sequence[Sequence[int]], out: IO[str]) -> None:
    """The valid mission decompositions as chains of task decomposition ids."""
    _section(f"valid mission decompositions ({len(decompositions)})", out)
    for md in decompositions:
        print(" -> ".join(tg.decomposition(d).decomposition.id for d in md), file=out)
