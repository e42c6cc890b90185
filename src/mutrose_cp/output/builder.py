"""Output in the original MutRoSe schema (spec ``output.md`` §2 and §4).

The JSON is written exactly as Boost.PropertyTree writes it (every scalar a string, empty lists
as ``""``, ``\\/`` escapes, 4-space layout), because a simulator and other tools already read
these files.  Files are streamed to a temporary file and renamed into place, so a failed run
never leaves a half-written output.
"""
from __future__ import annotations

from dataclasses import dataclass
from typing import IO, Any, Callable, Iterable, Mapping, Sequence

from .boost_json import Tree, write_list, boost_json, write_boost_json
from .constraint_texts import constraint_texts
from ..pipeline.constraints import EC, SEQ, Constraint
from .copy_blocks import CopyBlocks
from .entry_templates import EntryTemplates, actions_tree, argument_values, pred_tree, robots_tree
from ..model import Configuration, Domain, InitialState
from ..model.task_graph import Decomposition, SplitListing, TaskGraph
from .predicates import PrintedPredicate, PredicatePrinter


__all__ = ["OutputBuilder", "OutputModel", "SplitListing", "Tree", "boost_json", "write_boost_json"]






# ---------------------------------------------------------------------------------------------
# The output document


@dataclass
class OutputModel:
    """Everything the writers need, with keys already assigned."""

    tg: TaskGraph
    constraints: Sequence[Constraint]
    decompositions: Iterable[list[int]]  # valid mission decompositions (vertex indices)
    domain: Domain
    config: Configuration
    state: InitialState
    space: Mapping[str, Any] | None = None  # optional mission_decomposition_space section
    # optional mission_decomposition_uncertainty section, made once the listing is written
    # (its argument: the standard JSON style)
    uncertainty: Callable[[bool], Mapping[str, Any]] | None = None


class OutputBuilder:
    def __init__(self, model: OutputModel) -> None:
        self.m = model
        self.decs = model.tg.decompositions()
        self.key = model.tg.decomposition_keys
        self.printer = PredicatePrinter(model.domain, model.config, model.state)

    def actions(self) -> list[tuple[str, tuple[str, ...]]]:
        """Every action some decomposition uses, by name, with its capabilities; each path is
        read once (the decompositions of a forAll's copies share a few paths)."""
        paths = {id(d.decomposition.path): d.decomposition.path for d in self.decs}
        names = sorted({s.name for path in paths.values() for s in path.actions})
        return [(n, self.m.domain.action_by_name[n].capabilities) for n in names]

    def task_entry(self, dec: Decomposition, group: bool, divisible: bool) -> dict[str, Tree]:
        inst = dec.instance
        task = self.m.domain.task_by_name[inst.name]
        pre, eff = self.printer.printed(dec)
        loc = inst.location
        return {
            "id": dec.id,
            "name": inst.name,
            "arguments": {p.name: p.type for p in task.parameters},
            "arguments_values": argument_values(task, inst),
            "locations": list(loc) if isinstance(loc, tuple) else (loc or ""),
            "robots_num": robots_tree(inst.robot_number),
            "preconditions": [pred_tree(p) for p in pre],
            "effects": [pred_tree(p) for p in eff],
            "triggering_events": list(inst.triggering_events),
            "decomposition": actions_tree(dec.path),
            "group": str(group),
            "divisible": str(divisible),
        }

    def write_json(self, fh: IO[str]) -> None:
        """Stream the JSON document (mission decompositions may be many)."""
        self.write_json_head(fh)
        self.write_json_tail(fh)

    def write_json_head(self, fh: IO[str]) -> None:
        """The document up to its constraints: what the Task Graph alone decides."""
        fh.write("{\n    \"actions\": ")
        write_boost_json([{"name": n, "capabilities": caps[-1] if caps else ""} for n, caps in self.actions()], fh, 4)
        fh.write(",\n    \"tasks\": ")
        if self.decs:
            fh.write("{\n")
            last = len(self.decs) - 1
            templates = EntryTemplates(self.m.domain, self.printer, self.printer.sorts)
            blocks = CopyBlocks(self.m.tg, self.decs, self.key, templates)
            i = 0
            while i <= last:
                filled = blocks.entries(i)
                if filled is not None:  # a stamped copy's entries, filled in its source's
                    text, i = filled
                    fh.write(text)  # apart from its ending: adding it would copy the copy's text again
                    fh.write(",\n" if i <= last else "\n")
                    continue
                d = self.decs[i]
                entry = templates.entry(d.decomposition, d.group, d.divisible)
                fh.write(f'        "{self.key[d.index]}": {entry}' + (",\n" if i < last else "\n"))
                i += 1
            fh.write("    }")
        else:
            fh.write('""')
        fh.write(",\n    \"constraints\": ")
        write_list(fh, constraint_texts(self.m.constraints, self.key.__getitem__), 4)

    def write_json_tail(self, fh: IO[str]) -> None:
        """The rest of the document: the mission decompositions and the decomposition space."""
        fh.write(",\n    \"mission_decompositions\": ")
        first = True
        quoted = {i: f'            "{k}"' for i, k in self.key.items()}  # keys need no escaping
        decompositions = self.m.decompositions
        if isinstance(decompositions, SplitListing):
            head = ",\n".join(quoted[i] for i in decompositions.prefix)
            texts = (head + (",\n" if head and part else "") + ",\n".join(quoted[i] for i in part)
                     for part in decompositions.parts)
        else:
            texts = (",\n".join(quoted[i] for i in md) for md in decompositions)
        for text in texts:
            fh.write("[\n" if first else ",\n")
            first = False
            fh.write("        [\n" + text + "\n        ]" if text else '        ""')
        fh.write('""' if first else "\n    ]")
        if self.m.space is not None:
            fh.write(",\n    \"mission_decomposition_space\": ")
            write_boost_json(self.m.space, fh, 4)
        if self.m.uncertainty is not None:
            fh.write(",\n    \"mission_decomposition_uncertainty\": ")
            write_boost_json(self.m.uncertainty(False), fh, 4)
        fh.write("\n}\n")

    # -- XML -----------------------------------------------------------------------------------
    def write_xml(self, fh: IO[str]) -> None:
        """The original's XML: four sibling top-level elements after the declaration."""
        w = _XmlWriter(fh)
        fh.write('<?xml version="1.0" encoding="utf-8"?>\n')
        self._xml_actions(w)
        w.open("tasks", 0)
        for i, d in enumerate(self.decs):
            self._xml_task(w, i, d.decomposition, d.group, d.divisible)
        w.close("tasks", 0)
        self._xml_constraints(w)
        self._xml_mission_decompositions(w)

    def _xml_actions(self, w: "_XmlWriter") -> None:
        """Every action used by some decomposition, with its required capabilities."""
        w.open("actions", 0)
        for i, (name, caps) in enumerate(self.actions()):
            w.open(f"action{i}", 1)
            w.leaf("name", name, 2)
            if caps:
                w.open("capabilities", 2, {"number": str(len(caps))})
                for j, cap in enumerate(caps):
                    w.leaf(f"capability{j}", cap, 3)
                w.close("capabilities", 2)
            else:
                w.empty("capabilities", 2, {"number": "0"})
            w.close(f"action{i}", 1)
        w.close("actions", 0)

    def _xml_constraints(self, w: "_XmlWriter") -> None:
        """SEQ and EC constraints between task keys (written ``task<m>`` here, not ``t<m>``)."""
        if not self.m.constraints:
            w.empty("constraints", 0)
            return
        w.open("constraints", 0)
        for i, c in enumerate(self.m.constraints):
            w.open(f"constraint{i}", 1)
            w.leaf("type", "SEQ" if c.kind == SEQ else "EC", 2)
            w.open("task_instances", 2)
            w.leaf("id0", "task" + self.key[c.first][1:], 3)
            w.leaf("id1", "task" + self.key[c.second][1:], 3)
            w.close("task_instances", 2)
            if c.kind == EC:
                w.leaf("group", str(c.group), 2)
                w.leaf("divisible", str(c.divisible), 2)
            w.close(f"constraint{i}", 1)
        w.close("constraints", 0)

    def _xml_mission_decompositions(self, w: "_XmlWriter") -> None:
        """The valid mission decompositions, streamed: the element is opened on the first one,
        since the decompositions may be a generator whose emptiness is only known at the end."""
        first = True
        for i, md in enumerate(self.m.decompositions):
            if first:
                w.open("mission_decompositions", 0)
                first = False
            w.open(f"decomposition{i}", 1)
            w.open("tasks", 2)
            for j, v in enumerate(md):
                w.leaf(f"t{j}", "task" + self.key[v][1:], 3)
            w.close("tasks", 2)
            w.close(f"decomposition{i}", 1)
        if first:
            w.empty("mission_decompositions", 0)
        else:
            w.close("mission_decompositions", 0)

    def _xml_task(self, w: "_XmlWriter", i: int, dec: Decomposition, group: bool, divisible: bool) -> None:
        inst = dec.instance
        w.open(f"task{i}", 1)
        w.leaf("id", dec.id, 2)
        w.leaf("name", inst.name, 2)
        self._xml_arguments(w, dec)
        loc = inst.location
        w.leaves("locations", "t", list(loc) if isinstance(loc, tuple) else ([loc] if loc else []), 2)
        rn = inst.robot_number
        attrs = {"fixed": "True", "num": str(rn.min)} if rn.fixed else {"fixed": "False", "min": str(rn.min), "max": str(rn.max)}
        w.empty("robots_num", 2, attrs)
        pre, eff = self.printer.printed(dec)
        _xml_predicates(w, "preconditions", "prec", pre)
        _xml_predicates(w, "effects", "eff", eff)
        w.leaves("triggering_events", "event", inst.triggering_events, 2)
        w.leaves("decomposition", "action", [s.name for s in dec.path.actions], 2)
        w.leaf("group", str(group), 2)
        w.leaf("divisible", str(divisible), 2)
        w.close(f"task{i}", 1)

    def _xml_arguments(self, w: "_XmlWriter", dec: Decomposition) -> None:
        """Every parameter of the HDDL task with its value (a collection space-separated, an
        unbound parameter empty)."""
        inst = dec.instance
        task = self.m.domain.task_by_name[inst.name]
        w.open("arguments", 2)
        values: dict[str, str] = {p.name: "" for p in task.parameters}
        for pv in inst.parameters:
            if pv.hddl_param in values:
                values[pv.hddl_param] = " ".join(pv.value) if isinstance(pv.value, tuple) else pv.value
        for j, p in enumerate(task.parameters):
            w.open(f"arg{j}", 3)
            w.leaf("name", p.name, 4)
            w.leaf("type", p.type, 4)
            w.leaf("value", values[p.name], 4)
            w.close(f"arg{j}", 3)
        w.close("arguments", 2)


def _xml_predicates(w: "_XmlWriter", tag: str, prefix: str, preds: list[PrintedPredicate]) -> None:
    """Printed predicates as ``<prec0 vars=".." var_types="..">text</prec0>``; nothing if none."""
    if preds:
        w.open(tag, 2)
        for j, pred in enumerate(preds):
            w.leaf(f"{prefix}{j}", pred.text, 3, {"vars": ",".join(pred.args), "var_types": ",".join(pred.sorts)})
        w.close(tag, 2)


def _xml_escape(s: str) -> str:
    return (s.replace("&", "&amp;").replace("<", "&lt;").replace(">", "&gt;")
            .replace('"', "&quot;").replace("'", "&apos;"))


class _XmlWriter:
    """Boost ``write_xml`` layout with a 4-space indent."""

    def __init__(self, fh: IO[str]) -> None:
        self.fh = fh

    @staticmethod
    def _attrs(attrs: Mapping[str, str] | None) -> str:
        return "".join(f' {k}="{_xml_escape(v)}"' for k, v in (attrs or {}).items())

    def open(self, tag: str, level: int, attrs: Mapping[str, str] | None = None) -> None:
        self.fh.write(f"{'    ' * level}<{tag}{self._attrs(attrs)}>\n")

    def close(self, tag: str, level: int) -> None:
        self.fh.write(f"{'    ' * level}</{tag}>\n")

    def empty(self, tag: str, level: int, attrs: Mapping[str, str] | None = None) -> None:
        self.fh.write(f"{'    ' * level}<{tag}{self._attrs(attrs)}/>\n")

    def leaf(self, tag: str, text: str, level: int, attrs: Mapping[str, str] | None = None) -> None:
        if text == "":
            self.empty(tag, level, attrs)
        else:
            self.fh.write(f"{'    ' * level}<{tag}{self._attrs(attrs)}>{_xml_escape(text)}</{tag}>\n")

    def leaves(self, tag: str, prefix: str, texts: Sequence[str], level: int) -> None:
        """``<tag>`` holding ``<prefix0>``, ``<prefix1>``... one leaf per text; nothing at all
        (not even an empty element) when there is no text, as the original writes it."""
        if not texts:
            return
        self.open(tag, level)
        for j, text in enumerate(texts):
            self.leaf(f"{prefix}{j}", text, level + 1)
        self.close(tag, level)


