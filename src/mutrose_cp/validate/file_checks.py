"""Checks of the output's ``tasks`` and ``constraints`` against what the mission implies.

Every task entry must be a decomposition of a task instance of the mission's Task Graph, every
such decomposition must have an entry, and each field must be the mission's: the id (the
instance from the goal-model task and its forAll elements, the number of one of the task's
decompositions), the HDDL task and its parameters, the parameter values, the location, the robot
number, the printed preconditions and effects, the trigger events, the actions with their
arguments, and the Group/Divisible flags.  The constraints must be exactly those the goal model
implies (:mod:`.constraint_rules`): none missing, none added, none reversed.  Each violation
names the task id (or the two tasks of a constraint) and the field or the constraint's place.
"""
from __future__ import annotations

from typing import Iterator

from ..io.decomposition_output import DecompositionOutput, OutputConstraint, OutputTask
from .constraint_rules import Decomposition
from .expected import ExpectedMission, Fields
from .report import Violation


def _text(value: str) -> str:
    return value if value else '""'


def _shown(field: str, value: object) -> str:
    """A field's value as a message shows it."""
    if isinstance(value, bool):
        return str(value)
    assert isinstance(value, tuple)
    if field == "robots_num":
        fixed, low, high = value
        return str(low) if fixed else f"[{low},{high}]"
    if not value:
        return "none"
    items: list[str] = []
    for v in value:
        if field == "arguments":
            items.append(f"{v[0]} - {v[1]}")
        elif field == "arguments_values":
            items.append(f"{v[0]} = {_text(v[1])}")
        elif field in ("preconditions", "effects"):
            items.append(f"{v[0]} (vars {_text(v[1])}, var_types {_text(v[2])})")
        elif isinstance(v, tuple):
            items.append(f"{v[0]}({' '.join(v[1])})")
        else:
            items.append(_text(v))
    return ", ".join(items) if field not in ("preconditions", "effects") else "; ".join(items)


class TaskChecks:
    """The ``tasks`` section against the mission's instances and decompositions."""

    def __init__(self, out: DecompositionOutput, expected: ExpectedMission) -> None:
        self.out = out
        self.expected = expected
        self.xml = out.format == "xml"
        self.ids: dict[str, Decomposition] = {}  # task key -> (instance, number) of a valid entry

    def run(self) -> list[Violation]:
        found: list[Violation] = []
        seen: dict[str, str] = {}
        for key, task in self.out.tasks.items():
            if task.id in seen:
                found.append(Violation(None, task.id, f"id ({task.where}): listed twice, also as {seen[task.id]}"))
            seen.setdefault(task.id, task.where)
            found.extend(Violation(None, task.id, f"{field} ({task.where}): {message}")
                         for field, message in task.problems)
            found.extend(self._task(key, task))
        for inst, n in self._missing(set(seen)):
            found.append(Violation(None, f"{inst}|{n}", f"tasks: the mission's decomposition {inst}|{n} "
                                                        f"({self.expected.instances[inst].name}) is missing"))
        return found

    def _missing(self, listed: set[str]) -> Iterator[Decomposition]:
        for inst, count in self.expected.counts.items():
            for n in range(1, count + 1):
                if f"{inst}|{n}" not in listed:
                    yield inst, n

    def _task(self, key: str, task: OutputTask) -> list[Violation]:
        inst_id, bar, number = task.id.partition("|")
        inst = self.expected.instances.get(inst_id)
        if inst is None:
            removed = " (its branch is removed: a creation condition is false and no task before it makes it " \
                      "true)" if inst_id in self.expected.generated else ""
            return [Violation(None, task.id, f"id ({task.where}): the mission has no task instance {inst_id}"
                                             f"{removed}")]
        count = self.expected.counts[inst_id]
        if not bar or not number.isdigit() or not 1 <= int(number) <= count:
            return [Violation(None, task.id, f"id ({task.where}): {number or 'no number'} names no decomposition "
                                             f"of {inst.name}, which has {count} (|1 to |{count})")]
        self.ids[key] = (inst_id, int(number))
        fields = self.expected.fields(inst, int(number), self.xml)
        return [Violation(None, task.id, f"{field} ({task.where}): is {_shown(field, given)}, the mission's is "
                                         f"{_shown(field, wanted)}")
                for field, given, wanted in self._fields(task, fields) if given != wanted]

    def _fields(self, task: OutputTask, f: Fields) -> Iterator[tuple[str, object, object]]:
        yield "name", (task.name,), (f.name,)
        yield "arguments", tuple((p, t) for p, t, _ in task.arguments), f.arguments
        if task.values is not None:
            yield "arguments_values", tuple(task.values), tuple(f.values.items())
        yield "locations", task.locations, f.locations
        if task.robots is not None:
            yield "robots_num", (task.robots.fixed, task.robots.min, task.robots.max), f.robots
        for field, given, wanted in (("preconditions", task.preconditions, f.preconditions),
                                     ("effects", task.effects, f.effects)):
            if given is not None:
                yield field, tuple((p.text, p.vars, p.var_types) for p in given), wanted
        if task.events is not None:
            yield "triggering_events", task.events, f.events
        if self.xml:
            yield "decomposition", tuple(a.name for a in task.actions), tuple(name for name, _ in f.actions)
        else:
            yield "decomposition", tuple((a.name, a.args or ()) for a in task.actions), f.actions
        for field, flag, wanted_flag in (("group", task.group, f.group), ("divisible", task.divisible, f.divisible)):
            if flag is not None:
                yield field, flag, wanted_flag


def _pair(a: Decomposition, b: Decomposition) -> str:
    return f"{a[0]}|{a[1]} and {b[0]}|{b[1]}"


class ConstraintChecks:
    """The ``constraints`` section against the constraints the goal model implies."""

    def __init__(self, out: DecompositionOutput, expected: ExpectedMission, ids: dict[str, Decomposition]) -> None:
        self.out = out
        self.expected = expected.constraints
        self.ids = ids

    def run(self) -> list[Violation]:
        found: list[Violation] = []
        ordered: set[tuple[Decomposition, Decomposition]] = set()
        execution: set[frozenset[Decomposition]] = set()
        for c in self.out.constraints:
            if c.kind not in ("SEQ", "FB", "EC") or c.first not in self.ids or c.second not in self.ids:
                continue  # a key that is no task, or a task the mission does not have: reported
            a, b = self.ids[c.first], self.ids[c.second]
            if c.kind == "EC":
                twice = frozenset((a, b)) in execution
                execution.add(frozenset((a, b)))
            else:
                twice = (a, b) in ordered
                ordered.add((a, b))
            if twice:
                found.append(Violation(None, f"{a[0]}|{a[1]}", f"{c.where}: {c.kind} {_pair(a, b)} is listed twice"))
                continue
            found.extend(self._listed(c, a, b))
        found.extend(self._missing(ordered, execution))
        return found

    def _listed(self, c: OutputConstraint, a: Decomposition, b: Decomposition) -> list[Violation]:
        where, task = c.where, f"{a[0]}|{a[1]}"
        if c.kind == "EC":
            flags = self.expected.execution.get(frozenset((a, b)))
            unread = [name for name, flag in (("group", c.group), ("divisible", c.divisible)) if flag is None]
            if unread:
                return [Violation(None, task, f"{where}: execution constraint between {_pair(a, b)}: {unread[0]} is "
                                              "missing or is neither True nor False")]
            written = (bool(c.group), bool(c.divisible))
            if flags is None:
                return [Violation(None, task, f"{where}: execution constraint between {_pair(a, b)}: the goal "
                                              "model's Group/Divisible flags imply none")]
            if flags != written:
                return [Violation(None, task, f"{where}: execution constraint between {_pair(a, b)} has group "
                                              f"{written[0]}, divisible {written[1]}; the goal model's are "
                                              f"group {flags[0]}, divisible {flags[1]}")]
            return []
        if c.group is not None or c.divisible is not None:
            return [Violation(None, task, f"{where}: {c.kind} {_pair(a, b)} has group/divisible flags, which only "
                                          "an execution constraint has")]
        kind = self.expected.ordered.get((a, b))
        if kind == c.kind:
            return []
        if kind is not None:
            return [Violation(None, task, f"{where}: {c.kind} {_pair(a, b)} should be {kind}")]
        if (b, a) in self.expected.ordered:
            return [Violation(None, task, f"{where}: {c.kind} {a[0]}|{a[1]} -> {b[0]}|{b[1]} is reversed: the goal "
                                          f"model puts {b[0]}|{b[1]} first ({self.expected.ordered[(b, a)]})")]
        return [Violation(None, task, f"{where}: {c.kind} {a[0]}|{a[1]} -> {b[0]}|{b[1]} is not implied by the "
                                      "goal model")]

    def _missing(self, ordered: set[tuple[Decomposition, Decomposition]],
                 execution: set[frozenset[Decomposition]]) -> list[Violation]:
        known = set(self.ids.values())
        found = [Violation(None, f"{a[0]}|{a[1]}", f"constraints: {kind} {a[0]}|{a[1]} -> {b[0]}|{b[1]} is missing "
                                                   "(the goal model implies it)")
                 for (a, b), kind in self.expected.ordered.items()
                 if (a, b) not in ordered and (b, a) not in ordered and a in known and b in known]
        for pair, (group, divisible) in self.expected.execution.items():
            if pair not in execution and pair <= known:
                a, b = sorted(pair)
                found.append(Violation(None, f"{a[0]}|{a[1]}", f"constraints: the execution constraint between "
                                       f"{_pair(a, b)} (group {group}, divisible {divisible}) is missing"))
        return found


def _capabilities(value: str | tuple[str, ...]) -> str:
    if isinstance(value, tuple):
        return ", ".join(value) or "none"
    return _text(value)


def check_actions(out: DecompositionOutput, expected: ExpectedMission) -> list[Violation]:
    """The ``actions`` section: every action of the mission's decompositions once, sorted by
    name, with its capabilities (JSON: the last one, or all in the standard style; XML: all)."""
    if out.actions is None:
        return [Violation(None, "", "actions: the section is missing or is no list of actions")]
    names = sorted({s.name for inst_id, count in expected.counts.items() for n in range(1, count + 1)
                    for s in expected.decomposition(expected.instances[inst_id], n).actions})
    given = [name for name, _ in out.actions]
    if given != names:
        return [Violation(None, "", f"actions: lists {', '.join(given) or 'none'}; the mission's decompositions "
                                    f"use {', '.join(names) or 'none'} (sorted by name)")]
    found = []
    for name, written in out.actions:
        if written is None:
            found.append(Violation(None, "", f"actions: {name} gives no capabilities (an entry is an object with "
                                             "the action's name and capabilities)"))
            continue
        caps = expected.domain.action_by_name[name].capabilities
        wanted = caps if isinstance(written, tuple) else (caps[-1] if caps else "")
        if written != wanted:
            found.append(Violation(None, "", f"actions: {name} has capabilities {_capabilities(written)}, the "
                                             f"domain's are {_capabilities(wanted)}"))
    return found
