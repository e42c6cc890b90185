"""iHTN export (spec ``output.md`` §6): one hierarchical plan per ordering of each valid mission
decomposition, read by execution tools (a VS Code plug-in, a mission-control demo).

Agents follow the rule of the reference iHTN files (§6.3): bound non-location values are
agents; unbound robot parameters become anonymous robots ``r1, r2, ...``, shared with
execution-constrained partners.
"""
from __future__ import annotations

from pathlib import Path
from typing import Iterator

from .constraints import EC, FB, SEQ
from .errors import MissionError
from .htn import TreeNode
from .output import OutputModel, write_boost_json
from .output_file import atomic_writer
from .taskgraph import Decomposition


def _orderings(members: list[int], succ: dict[int, set[int]]) -> Iterator[list[int]]:
    """Total orders of ``members`` respecting ``succ``, depth-first in mission order."""
    n = len(members)
    prefix: list[int] = []
    placed: set[int] = set()

    def extend() -> Iterator[list[int]]:
        if len(prefix) == n:
            yield list(prefix)
            return
        for x in members:
            if x in placed or succ.get(x, set()) & placed:
                continue
            prefix.append(x)
            placed.add(x)
            yield from extend()
            prefix.pop()
            placed.discard(x)

    return extend()


class _Agents:
    """Agent assignment for one mission decomposition."""

    def __init__(self, model: OutputModel, members: list[int], ec: dict[int, set[int]]) -> None:
        self.model = model
        self.domain = model.domain
        config = model.config
        self.location_hddl = {config.type_mapping[t] for t in config.location_types if t in config.type_mapping}
        self.locations = set(config.location_types)
        self.display: dict[str, str] = {}
        # per decomposition vertex: parameter -> agent internal names (unbound robots), and values
        self.robot_agents: dict[int, dict[str, list[str]]] = {}
        self.values: dict[int, dict[str, str]] = {}
        self.agents: dict[int, set[str]] = {}
        self.all: set[str] = set()
        for d in members:
            self._assign(d, ec.get(d, set()))

    def _is_location_type(self, hddl_type: str) -> bool:
        return hddl_type in self.location_hddl

    def _fresh(self, param: str, dec: Decomposition) -> str:
        name = f"{param}@{dec.id.lower()}"
        if name not in self.display:
            self.display[name] = f"r{len(self.display) + 1}"
        return name

    def _assign(self, d: int, partners: set[int]) -> None:
        dec = self.model.tg.vertices[d].decomposition
        task = self.domain.task_by_name[dec.instance.name]
        bound = {}
        for pv in dec.instance.parameters:
            bound[pv.hddl_param] = pv
        agents: set[str] = set()
        values: dict[str, str] = {}
        unbound: list[tuple[str, str]] = []
        for p in task.parameters:
            pv = bound.get(p.name)
            if pv is not None:
                if isinstance(pv.value, tuple):
                    if not self._is_location_type(p.type):
                        raise MissionError("Agent-related type container is not supported for iHTN generation "
                                           f"(parameter {p.name} of {dec.id} holds a collection)")
                    continue
                values[p.name] = pv.value
                if not self._is_location_type(p.type):
                    agents.add(pv.value)
            else:
                if p.type not in self.domain.robot_sorts:
                    raise MissionError(f"Variable {p.name} of HDDL type {p.type} is not grounded. iHTN generation "
                                       "does not support non-ground variables that are not robot-related")
                unbound.append((p.name, p.type))
        robots: dict[str, list[str]] = {}
        earlier = sorted(e for e in partners if e in self.robot_agents)
        if earlier and unbound:
            firsts = [self._question_agents(e) for e in earlier]
            if len(unbound) == 1 and unbound[0][1] != "robotteam":
                if firsts[0]:
                    robots[unbound[0][0]] = [firsts[0][0]]
            elif len(unbound) == 1:
                robots[unbound[0][0]] = [f[0] for f in firsts if f]
            else:
                available = firsts[0]
                for (name, _t), agent in zip(unbound, available):
                    robots[name] = [agent]
        for name, _t in unbound:
            if name not in robots or not robots[name]:
                robots[name] = [self._fresh(name, dec)]
            agents.update(robots[name])
        self.robot_agents[d] = robots
        self.values[d] = values
        self.agents[d] = agents
        self.all |= agents

    def _question_agents(self, e: int) -> list[str]:
        dec = self.model.tg.vertices[e].decomposition
        task = self.domain.task_by_name[dec.instance.name]
        out = []
        for p in task.parameters:
            out.extend(self.robot_agents[e].get(p.name, []))
        return out

    def show(self, names: set[str]) -> list[str]:
        return [self.display.get(n, n) for n in sorted(names)]

    def of_args(self, d: int, args: tuple[str, ...]) -> set[str]:
        """Agents among the values of ``args`` (renamed parameters of a tree node)."""
        out: set[str] = set()
        task = self.domain.task_by_name[self.model.tg.vertices[d].decomposition.instance.name]
        types = {p.name: p.type for p in task.parameters}
        for a in args:
            if a in self.robot_agents[d]:
                out.update(self.robot_agents[d][a])
            elif a in self.values[d] and not self._is_location_type(types[a]):
                out.add(self.values[d][a])
        return out


def _tree_json(nodes: dict[str, dict], node: TreeNode, parent: str, d: int, agents: _Agents,
               location: set[str]) -> str:
    key = str(len(nodes))
    entry: dict = {"name": node.name, "type": node.kind, "parent": parent}
    nodes[key] = entry
    if node.kind == "action":
        values = agents.values[d]
        loc = next((values[a] for a in node.args if a in values and values[a] in location), None)
        entry["locations"] = [loc] if loc else ""
    entry["agents"] = agents.show(agents.of_args(d, node.args))
    entry["children"] = [_tree_json(nodes, c, key, d, agents, location) for c in node.children]
    return key


IHTN_WARNING = 10_000


def write_ihtns(model: OutputModel, folder: Path, progress=None) -> int:
    """Write ``ihtn_<n>.json`` files into ``folder`` (old ``ihtn_*.json`` there are removed)."""
    tg = model.tg
    succ: dict[int, set[int]] = {}
    ec: dict[int, set[int]] = {}
    for c in model.constraints:
        if c.kind in (SEQ, FB):
            succ.setdefault(c.first, set()).add(c.second)
        elif c.kind == EC:
            ec.setdefault(c.first, set()).add(c.second)
            ec.setdefault(c.second, set()).add(c.first)
    folder.mkdir(parents=True, exist_ok=True)
    for old in folder.glob("ihtn_*.json"):
        old.unlink()
    count = 0
    for md in model.decompositions:
        agents = _Agents(model, list(md), ec)
        member_set = set(md)
        local = {d: succ.get(d, set()) & member_set for d in md}
        for order in _orderings(list(md), local):
            count += 1
            nodes: dict[str, dict] = {}
            root = {"name": "ROOT", "type": "task", "parent": "-1", "agents": agents.show(agents.all), "children": ["1"]}
            nodes["0"] = root
            rm = {"name": "ROOT_M", "type": "method", "parent": "0", "agents": agents.show(agents.all), "children": []}
            nodes["1"] = rm
            for d in order:
                dec = tg.vertices[d].decomposition
                loc = dec.instance.location
                location = set(loc) if isinstance(loc, tuple) else ({loc} if loc else set())
                rm["children"].append(_tree_json(nodes, dec.path.tree, "1", d, agents, location))
            with atomic_writer(folder / f"ihtn_{count}.json") as fh:
                write_boost_json(nodes, fh)
                fh.write("\n")
            if progress is not None:
                progress(count)
    return count
