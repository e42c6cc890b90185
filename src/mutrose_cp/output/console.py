"""The original tool's console reports: ``-p`` (pretty print) and ``-v`` (verbose trace).

``-p`` is what the VS Code plug-in shows its user, so it is printed as the original prints it,
byte for byte (the original's exact text for the reference missions is in the corpus,
``console/``): three blocks on stdout, "GENERATED TASK INSTANCES" (every task decomposition of
the Task Graph with its abstract task, capabilities, location, arguments and actions), "MISSION
CONSTRAINTS" (per kind the count and the list, five to a line) and "POSSIBLE MISSION
DECOMPOSITIONS" (each valid mission decomposition as a numbered ``MISSION n`` block of task
decompositions); docs/cli.md ("What -p prints") gives the rules.  ``-v`` prints the pipeline's
intermediate results, stage by stage, in mutrose-cp's words (the original's trace prints internal
structures; spec ``output.md`` §5), its constraints as ``-p``'s block.  What the original's lexers
echo around them is :mod:`.lexer_echo`'s.
"""
from __future__ import annotations

from typing import IO, Callable, Iterator, Sequence

from ..pipeline.constraints import EC, FB, SEQ, Constraint, ConstraintKind
from ..model.task_instances import TaskInstance, Value
from ..model import Domain, InitialState
from ..model.task_graph import Decomposition, TaskGraph

WIDTH = 109  # the original's rules are this wide
CLOSING_RULE = "-" * WIDTH
MISSION_RULE = "@" * 39  # either side of "MISSION n"
MISSION_CLOSING = "@" * 89
PER_LINE = 5  # constraints printed on one line
AND = "AND"  # between the task decompositions of a mission decomposition
# (kind, symbol, the count's wording, the list's heading), in the order printed
_KINDS = ((SEQ, ";", "Number of Sequential Mission Constraints", "Sequential Constraints:"),
          (EC, "EC", "Number of execution constraints", "Execution Constraints:"),
          (FB, "FB", "Number of fallback constraints", "Fallback Constraints:"))


def heading(title: str) -> str:
    """``---- TITLE ----``, as wide as the closing rule (the left side one dash shorter when
    the title leaves an odd number)."""
    left = (WIDTH - len(title) - 2) // 2
    return "-" * left + f" {title} " + "-" * (WIDTH - len(title) - 2 - left)


def _capabilities(dec: Decomposition) -> str:
    """``with required capability [c] `` (or ``capabilities [a, b] ``): the capabilities the
    path's actions require, as a sorted set, or nothing when they require none."""
    caps = sorted({c for step in dec.path.steps for c in step.capabilities})
    if not caps:
        return ""
    return f"with required {'capabilities' if len(caps) > 1 else 'capability'} [{', '.join(caps)}] "


def _location(instance: TaskInstance) -> str:
    """``at location [Room]``; a task without a location has an empty list of them, which the
    original prints as ``at locations []``."""
    loc = instance.location
    if isinstance(loc, tuple):
        return f"at locations [{', '.join(loc)}]"
    if loc is None:
        return "at locations []"
    return f"at location [{loc}]"


def instance_value(value: Value) -> str:
    """A value as "GENERATED TASK INSTANCES" prints it.  The original loses a collection's
    closing parenthesis there unless it has one element: ``(A)``, ``(A,B,`` (every element
    followed by a comma), ``(`` when empty."""
    if not isinstance(value, tuple):
        return value
    return f"({value[0]})" if len(value) == 1 else "(" + "".join(v + "," for v in value)


def decomposition_value(value: Value) -> str:
    """A value as "POSSIBLE MISSION DECOMPOSITIONS" prints it: ``(A,B)``, ``(`` when empty."""
    if not isinstance(value, tuple):
        return value
    return "(" + ",".join(value) + ")" if value else "("


def _arguments(dec: Decomposition, value_text: Callable[[Value], str]) -> str:
    """The abstract task's parameters, ``?p=value`` for every entry of the instance's variable
    mapping that binds it (a parameter mapped twice, by ``Location`` and ``Params``, is printed
    twice, as the original does), the bare name when none does: ``?r,?n=Nurse1``.  The names
    are the root of the path's tree, the task's declared parameters; an empty value (a query
    that matched nothing) binds nothing."""
    parts: list[str] = []
    for name in dec.path.tree.args:
        values = [p.value for p in dec.instance.parameters if p.hddl_param == name and p.value != ""]
        parts.extend([f"{name}={value_text(v)}" for v in values] or [name])
    return ",".join(parts)


def task_lines(dec: Decomposition, value_text: Callable[[Value], str]) -> list[str]:
    """A task decomposition as the original prints it in both blocks (``value_text`` is the
    block's way of writing a value): its summary line (which ends in a space) and one
    ``\t-> action args`` line per action."""
    inst = dec.instance
    summary = (f"Task [{inst.name}] With ID [{dec.id}] {_capabilities(dec)}{_location(inst)} "
               f"with arguments [{_arguments(dec, value_text)}] decomposed into actions: ")
    return [summary, *("\t-> " + " ".join((step.name, *step.args)) for step in dec.path.actions)]


def print_task_instances(tg: TaskGraph, out: IO[str]) -> None:
    """The "GENERATED TASK INSTANCES" block: every task decomposition of the Task Graph, a
    blank line between two, and a blank line after the block."""
    lines = [heading("GENERATED TASK INSTANCES")]
    for i, vertex in enumerate(tg.decompositions()):
        if i:
            lines.append("")
        lines.extend(task_lines(vertex.decomposition, instance_value))
    lines += [CLOSING_RULE, ""]
    out.write("\n".join(lines) + "\n")


def constraint_lines(texts: Sequence[str]) -> Iterator[str]:
    """``[a] AND [b] AND ...``, five constraints to a line; a line that more constraints
    follow ends in ``AND `` (with its space, as the original writes it)."""
    for start in range(0, len(texts), PER_LINE):
        more = start + PER_LINE < len(texts)
        yield " AND ".join(texts[start:start + PER_LINE]) + (" AND " if more else "")


def print_constraints(tg: TaskGraph, constraints: Sequence[Constraint], out: IO[str]) -> None:
    """The "MISSION CONSTRAINTS" block: per kind the count, the heading and the list (nothing
    under the heading of an empty list), a blank line between kinds and after the block."""
    by_kind: dict[ConstraintKind, list[str]] = {kind: [] for kind, *_ in _KINDS}
    symbols = {kind: symbol for kind, symbol, *_ in _KINDS}
    for c in constraints:
        if c.kind in by_kind:
            first, second = tg.decomposition(c.first).decomposition.id, tg.decomposition(c.second).decomposition.id
            by_kind[c.kind].append(f"[{first} {symbols[c.kind]} {second}]")
    lines = [heading("MISSION CONSTRAINTS")]
    for i, (kind, _, count, title) in enumerate(_KINDS):
        if i:
            lines.append("")
        lines += [f"{count}: {len(by_kind[kind])}", title, *constraint_lines(by_kind[kind])]
    lines += [CLOSING_RULE, ""]
    out.write("\n".join(lines) + "\n")


def print_mission_decompositions(tg: TaskGraph, decompositions: Sequence[Sequence[int]], out: IO[str]) -> None:
    """The "POSSIBLE MISSION DECOMPOSITIONS" block: each valid mission decomposition between
    ``@@@ MISSION n @@@`` and a rule of ``@``, its task decompositions separated by ``AND``
    lines, a blank line between two and after the block.  A decomposition's text is built once
    (a mission has few task decompositions and may have many mission decompositions)."""
    texts: dict[int, str] = {}

    def text(d: int) -> str:
        if d not in texts:
            texts[d] = "\n".join(task_lines(tg.decomposition(d).decomposition, decomposition_value))
        return texts[d]

    out.write(heading("POSSIBLE MISSION DECOMPOSITIONS") + "\n")
    for m, md in enumerate(decompositions, 1):
        if m > 1:
            out.write("\n")
        body = f"\n{AND}\n".join(text(d) for d in md)
        out.write(f"{MISSION_RULE} MISSION {m} {MISSION_RULE}\n{body}\n{MISSION_CLOSING}\n")
    out.write(CLOSING_RULE + "\n\n")


# ---------------------------------------------------------------------------------------------
# -v: the verbose trace


def _trace_value(value: Value) -> str:
    """A value in the trace, a collection as ``[a, b]`` (the trace is mutrose-cp's own text)."""
    return "[" + ", ".join(value) + "]" if isinstance(value, tuple) else value


def _trace_location(instance: TaskInstance) -> str:
    """``at location [l]`` (empty without one), ``at locations [a, b]`` for a collection."""
    loc = instance.location
    if isinstance(loc, tuple):
        return f"at locations [{', '.join(loc)}]"
    return f"at location [{loc or ''}]"


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
        values = ", ".join(f"{p.hddl_param} = {_trace_value(p.value)}" for p in inst.parameters)
        robots = (str(inst.robot_number.min) if inst.robot_number.fixed
                  else f"{inst.robot_number.min}..{inst.robot_number.max}")
        print(f"{inst.id}: {inst.name} ({values or 'no parameters'}) {_trace_location(inst)}, robots {robots}", file=out)


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

