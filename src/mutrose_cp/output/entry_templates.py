"""Task entries of the Boost JSON output, formatted once per template.

The forAll instances of a large mission give task entries that are equal up to renaming: the same
abstract task, decomposition path and printed predicates, with another room and other patients.
Most of an entry depends on the task or the path alone (its name, arguments, actions) and is
formatted once.  The printed preconditions and effects depend on the values too: they are
grounded with placeholders (one per distinct value, so that equal values stay equal), printed and
formatted once per template, and each instance puts its own values into the slots.

A template is keyed by everything printing reads besides the values' names: the task, the path,
which parameter holds which slot, and the sorts each value belongs to (an attribute mapping is
chosen by sort).  A value that is also a constant of the path is kept as itself.  The first
instance of every template is formatted both ways and compared; a template that would not give
the same bytes (which no known input does) is not used.
"""
from __future__ import annotations

import re
from typing import TYPE_CHECKING, Callable, Hashable, Mapping

from .boost_json import escape_json, boost_json
from ..errors import MissionError
from ..pipeline.htn import ground_path

if TYPE_CHECKING:
    from ..model.task_instances import Value
    from ..model.decomposition_paths import DecompositionPath, Step
    from ..model.task_instances import TaskInstance
    from ..model import AbstractTask, Domain, RobotNumber
    from ..model.task_graph import Decomposition
    from .predicates import PredicatePrinter, PrintedPredicate

PAD = " " * 12  # a task entry's members, inside "tasks" at indent 8
_SLOT_MARK = "\x1f"  # placeholders are "\x1f<k>\x1f": a control character no name contains
_SLOT = re.compile(r"\\u001F(\d+)\\u001F")  # ... as Boost escapes it


def _member(key: str, text: str) -> str:
    return f'{PAD}"{key}": {text}'


def pred_tree(p: PrintedPredicate) -> dict[str, str]:
    """A printed predicate as the entry lists it."""
    return {"predicate": p.text, "vars": p.args[-1] if p.args else "", "var_types": p.sorts[-1] if p.sorts else ""}


def robots_tree(rn: RobotNumber) -> dict[str, str]:
    """An entry's ``robots_num``."""
    return ({"fixed": "True", "num": str(rn.min)} if rn.fixed
            else {"fixed": "False", "min": str(rn.min), "max": str(rn.max)})


def actions_tree(path: DecompositionPath) -> dict[str, dict[str, str]]:
    """An entry's ``decomposition``: the path's actions, ``a0``, ``a1``..."""
    return {f"a{i}": {"name": s.name, "arguments": " ".join(s.args)} for i, s in enumerate(path.actions)}


def argument_values(task: AbstractTask, inst: TaskInstance) -> dict[str, str]:
    """Each parameter of the HDDL task with the instance's value: a collection as ``[a,b]``,
    an unbound parameter empty."""
    values: dict[str, str] = {p.name: "" for p in task.parameters}
    for pv in inst.parameters:
        if pv.hddl_param in values:
            values[pv.hddl_param] = "[" + ",".join(pv.value) + "]" if isinstance(pv.value, tuple) else pv.value
    return values


def predicate_members(printed: tuple[list[PrintedPredicate], list[PrintedPredicate]]) -> str:
    """The ``preconditions`` and ``effects`` members of an entry."""
    pre, eff = printed
    return (_member("preconditions", boost_json([pred_tree(p) for p in pre], 12)) + ",\n"
            + _member("effects", boost_json([pred_tree(e) for e in eff], 12)))


class Template:
    """Formatted text with slots: ``parts[0] + v[slots[0]] + parts[1] + ...``."""

    def __init__(self, text: str) -> None:
        pieces = _SLOT.split(text)
        self.parts = pieces[0::2]
        self.slots = [int(k) for k in pieces[1::2]]

    def fill(self, escaped: list[str]) -> str:
        parts, out = self.parts, [self.parts[0]]
        for i, k in enumerate(self.slots, start=1):
            out.append(escaped[k])
            out.append(parts[i])
        return "".join(out)


class EntryTemplates:
    """Formats task entries, sharing the work between the instances of a template."""

    def __init__(self, domain: Domain, printer: PredicatePrinter, sorts: Mapping[str, frozenset[str]]) -> None:
        self.domain = domain
        self.printer = printer
        self.sorts = sorts
        self._heads: dict[str, str] = {}
        self._actions: dict[int, tuple[DecompositionPath, str, frozenset[str], int]] = {}
        self._same_steps: dict[tuple[Step, ...], int] = {}  # a path expanded per instance (recursion)
        self._small: dict[Hashable, str] = {}
        self._sort_of: dict[str, tuple[str, ...]] = {}
        self._predicates: dict[Hashable, Template | None] = {}

    # -- parts that depend on the task or the path only ----------------------------------------
    def _head(self, name: str) -> str:
        """The ``name`` and ``arguments`` members."""
        head = self._heads.get(name)
        if head is None:
            task = self.domain.task_by_name[name]
            head = self._heads[name] = (_member("name", escape_json(name)) + ",\n" + _member(
                "arguments", boost_json({p.name: p.type for p in task.parameters}, 12)))
        return head

    def _path(self, path: DecompositionPath) -> tuple[str, frozenset[str], int]:
        """The ``decomposition`` member, the constants the path's steps name, and the path's key
        in templates: paths with the same steps share it (recursive methods give each instance a
        path of its own, mostly with the same steps)."""
        known = self._actions.get(id(path))
        if known is None:
            actions = actions_tree(path)
            same = self._same_steps.setdefault(path.steps, id(path))
            known = self._actions[id(path)] = (path, _member("decomposition", boost_json(actions, 12)), path.constants,
                                               same)
        return known[1], known[2], known[3]

    def _cached(self, key: Hashable, make: Callable[[], str]) -> str:
        text = self._small.get(key)
        if text is None:
            text = self._small[key] = make()
        return text

    def _robots(self, rn: RobotNumber) -> str:
        return _member("robots_num", boost_json(robots_tree(rn), 12))

    # -- the printed predicates, per template --------------------------------------------------
    def sorts_of(self, value: str) -> tuple[str, ...]:
        known = self._sort_of.get(value)
        if known is None:
            known = self._sort_of[value] = tuple(s for s, members in self.sorts.items() if value in members)
        return known

    def _predicate_slots(self, dec: Decomposition, constants: frozenset[str],
                         path_key: int) -> tuple[Hashable, list[str], dict[str, Value]]:
        """The template key of ``dec``'s predicates, the values in its slots (in slot order) and
        the binding with a placeholder for each of them."""
        values: list[str] = []
        slot: dict[str, int] = {}
        symbolic: dict[str, Value] = {}
        shape: list[Hashable] = []

        def placeholder(v: str) -> str:
            if v in constants or v.startswith("?"):  # printing tells a "?" value from a value
                shape.append(("constant", v))
                return v
            k = slot.get(v)
            if k is None:
                k = slot[v] = len(values)
                values.append(v)
                shape.append(self.sorts_of(v))
            shape.append(k)
            return f"{_SLOT_MARK}{k}{_SLOT_MARK}"

        for param, value in dec.instance.binding.items():
            shape.append(param)
            if isinstance(value, tuple):
                shape.append(len(value))
                symbolic[param] = tuple(placeholder(v) for v in value)
            else:
                symbolic[param] = placeholder(value)
        return (dec.instance.name, path_key, tuple(shape)), values, symbolic

    def _predicates_text(self, dec: Decomposition, constants: frozenset[str], path_key: int) -> str:
        key, values, symbolic = self._predicate_slots(dec, constants, path_key)
        escaped = [escape_json(v)[1:-1] for v in values]
        if key in self._predicates:
            template = self._predicates[key]
            return template.fill(escaped) if template is not None else predicate_members(self.printer.printed(dec))
        direct = predicate_members(self.printer.printed(dec))
        self._predicates[key] = self._template(dec, symbolic, values, escaped, direct)
        return direct

    def _template(self, dec: Decomposition, symbolic: dict[str, Value], values: list[str], escaped: list[str],
                  direct: str) -> Template | None:
        """The template of ``dec``'s key, if it gives ``direct`` back for ``dec`` itself."""
        real = {f"{_SLOT_MARK}{k}{_SLOT_MARK}": v for k, v in enumerate(values)}
        try:
            printed = self.printer.printed(dec, ground_path(dec.path, symbolic), real)
        except MissionError:  # a placeholder in an error: the direct path reports it
            return None
        template = Template(predicate_members(printed))
        return template if template.fill(escaped) == direct else None

    # -- an entry -----------------------------------------------------------------------------
    def entry(self, dec: Decomposition, group: bool, divisible: bool) -> str:
        """The task entry of ``dec`` at indent 8, as ``boost_json`` of ``OutputBuilder.task_entry``."""
        inst = dec.instance
        values = argument_values(self.domain.task_by_name[inst.name], inst)
        loc = inst.location
        decomposition, constants, path_key = self._path(dec.path)
        return self._members(dec, group, divisible, escape_json(dec.id), boost_json(values, 12),
                             boost_json(list(loc) if isinstance(loc, tuple) else (loc or ""), 12),
                             self._predicates_text(dec, constants, path_key), decomposition)

    def slotted_entry(self, dec: Decomposition, group: bool, divisible: bool,
                      slot: Callable[[str, str], int]) -> str | None:
        """The task entry of ``dec`` with a slot (``_SLOT`` in the text) for its id and for each
        value, numbered by ``slot(kind, name)`` (kind "id" or "value"); None when its printed
        predicates have no template.  An empty value stays empty, as a path's constants and "?"
        values stay themselves in the printed predicates (``copy_blocks`` checks them)."""
        inst = dec.instance
        decomposition, constants, path_key = self._path(dec.path)
        key, values, _ = self._predicate_slots(dec, constants, path_key)
        if key not in self._predicates:
            self._predicates_text(dec, constants, path_key)  # makes the template and checks it
        template = self._predicates[key]
        if template is None:
            return None

        def mark(v: str) -> str:
            return f"{_SLOT_MARK}{slot('value', v)}{_SLOT_MARK}" if v else ""

        arguments: dict[str, str] = {p.name: "" for p in self.domain.task_by_name[inst.name].parameters}
        for pv in inst.parameters:
            if pv.hddl_param in arguments:
                value = pv.value
                arguments[pv.hddl_param] = ("[" + ",".join(mark(v) for v in value) + "]" if isinstance(value, tuple)
                                            else mark(value))
        loc = inst.location
        locations = [mark(v) for v in loc] if isinstance(loc, tuple) else mark(loc or "")
        predicates = template.fill([slot_text(slot("value", v)) for v in values])
        return self._members(dec, group, divisible, f'"{slot_text(slot("id", dec.id))}"', boost_json(arguments, 12),
                             boost_json(locations, 12), predicates, decomposition)

    def _members(self, dec: Decomposition, group: bool, divisible: bool, id_text: str, values: str, locations: str,
                 predicates: str, decomposition: str) -> str:
        inst = dec.instance
        members = (
            _member("id", id_text),
            self._head(inst.name),
            _member("arguments_values", values),
            _member("locations", locations),
            self._cached(("robots", inst.robot_number), lambda: self._robots(inst.robot_number)),
            predicates,
            self._cached(("events", inst.triggering_events), lambda: _member(
                "triggering_events", boost_json(list(inst.triggering_events), 12))),
            decomposition,
            self._cached(("flags", group, divisible), lambda: _member("group", f'"{group}"') + ",\n"
                         + _member("divisible", f'"{divisible}"')),
        )
        return "{\n" + ",\n".join(members) + "\n        }"


def slot_text(k: int) -> str:
    """Slot ``k`` as it stands in formatted (escaped) text."""
    return f"\\u001F{k}\\u001F"
