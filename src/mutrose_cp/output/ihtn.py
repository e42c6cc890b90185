"""iHTN export (spec ``output.md`` §6): one hierarchical plan per ordering of each valid mission
decomposition, read by execution tools (a VS Code plug-in, a mission-control demo).

Agents follow the rule of the reference iHTN files (§6.3): bound non-location values are
agents; unbound robot parameters become anonymous robots ``r1, r2, ...``, shared with
execution-constrained partners.
"""
from __future__ import annotations

import fcntl
import os
import re
import shutil
import signal
import tempfile
from pathlib import Path
from typing import Callable, Collection, Iterator

from ..pipeline.constraints import EC, FB, SEQ
from ..errors import MissionError
from ..model.decomposition_paths import TreeNode
from ..model.task_graph import Decomposition
from .builder import OutputModel
from .boost_json import Tree, write_boost_json
from .files import write_failure


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

    def _decomposition(self, d: int) -> Decomposition:
        return self.model.tg.decomposition(d).decomposition

    def _assign(self, d: int, partners: set[int]) -> None:
        """The agents of decomposition vertex ``d``: its bound non-location values, and a robot
        per unbound robot parameter, shared with an execution-constrained partner assigned
        before it where there is one, else a fresh anonymous robot."""
        dec = self._decomposition(d)
        values, agents, unbound = self._bound(dec)
        robots = self._shared_robots(unbound, partners)
        for name, _t in unbound:
            if name not in robots or not robots[name]:
                robots[name] = [self._fresh(name, dec)]
            agents.update(robots[name])
        self.robot_agents[d] = robots
        self.values[d] = values
        self.agents[d] = agents
        self.all |= agents

    def _bound(self, dec: Decomposition) -> tuple[dict[str, str], set[str], list[tuple[str, str]]]:
        """(parameter -> bound single value, the agents among those values, the unbound
        parameters with their types).  A bound collection is skipped if it is of a location
        type and refused otherwise; an unbound parameter must be a robot."""
        task = self.domain.task_by_name[dec.instance.name]
        bound = {v.hddl_param: v for v in dec.instance.parameters}  # the last entry wins
        agents: set[str] = set()
        values: dict[str, str] = {}
        unbound: list[tuple[str, str]] = []
        for p in task.parameters:
            pv = bound.get(p.name)
            if pv is None:
                if p.type not in self.domain.robot_sorts:
                    raise MissionError(f"Variable {p.name} of HDDL type {p.type} is not grounded. iHTN generation "
                                       "does not support non-ground variables that are not robot-related")
                unbound.append((p.name, p.type))
            elif isinstance(pv.value, tuple):
                if not self._is_location_type(p.type):
                    raise MissionError("Agent-related type container is not supported for iHTN generation "
                                       f"(parameter {p.name} of {dec.id} holds a collection)")
            else:
                values[p.name] = pv.value
                if not self._is_location_type(p.type):
                    agents.add(pv.value)
        return values, agents, unbound

    def _shared_robots(self, unbound: list[tuple[str, str]], partners: set[int]) -> dict[str, list[str]]:
        """Robots taken over from the execution-constrained partners already assigned (§6.3):
        a single robot parameter gets the first partner's first robot, a single robot team
        the first robot of every partner, several parameters the first partner's robots in
        order."""
        robots: dict[str, list[str]] = {}
        earlier = sorted(e for e in partners if e in self.robot_agents)
        if not earlier or not unbound:
            return robots
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
        return robots

    def _question_agents(self, e: int) -> list[str]:
        """The robots already given to decomposition vertex ``e``, in parameter order."""
        task = self.domain.task_by_name[self._decomposition(e).instance.name]
        out = []
        for p in task.parameters:
            out.extend(self.robot_agents[e].get(p.name, []))
        return out

    def show(self, names: set[str]) -> list[str]:
        return [self.display.get(n, n) for n in sorted(names)]

    def of_args(self, d: int, args: tuple[str, ...]) -> set[str]:
        """Agents among the values of ``args`` (renamed parameters of a tree node)."""
        out: set[str] = set()
        task = self.domain.task_by_name[self._decomposition(d).instance.name]
        types = {p.name: p.type for p in task.parameters}
        for a in args:
            if a in self.robot_agents[d]:
                out.update(self.robot_agents[d][a])
            elif a in self.values[d] and not self._is_location_type(types[a]):
                out.add(self.values[d][a])
        return out


IhtnNodes = dict[str, dict[str, Tree]]  # node key ("0", "1", ...) -> the node's fields


def _tree_json(nodes: IhtnNodes, node: TreeNode, parent: str, d: int, agents: _Agents,
               location: set[str]) -> str:
    key = str(len(nodes))
    entry: dict[str, Tree] = {"name": node.name, "type": node.kind, "parent": parent}
    nodes[key] = entry
    if node.kind == "action":
        values = agents.values[d]
        loc = next((values[a] for a in node.args if a in values and values[a] in location), None)
        entry["locations"] = [loc] if loc else ""
    entry["agents"] = agents.show(agents.of_args(d, node.args))
    entry["children"] = [_tree_json(nodes, c, key, d, agents, location) for c in node.children]
    return key


IHTN_MAX = 10_000  # default limit on the number of files one export may write
IHTN_FILE = re.compile(r"ihtn_[0-9]+\.json")  # the only files an export ever replaces or removes


def _constraint_index(model: OutputModel) -> tuple[dict[int, set[int]], dict[int, set[int]]]:
    succ: dict[int, set[int]] = {}
    ec: dict[int, set[int]] = {}
    for c in model.constraints:
        if c.kind in (SEQ, FB):
            succ.setdefault(c.first, set()).add(c.second)
        elif c.kind == EC:
            ec.setdefault(c.first, set()).add(c.second)
            ec.setdefault(c.second, set()).add(c.first)
    return succ, ec


class CountTooCostly(Exception):
    """Counting the orderings exactly would take more than the allowed work."""


def count_orderings(members: list[int], succ: dict[int, set[int]], cap: int, budget: int | None = None) -> int:
    """How many total orders of ``members`` respect ``succ`` (the iHTN files of one mission
    decomposition), counted over the sets of tasks already placed; stops at ``cap``.  With a
    ``budget``, more sets than that raise :class:`CountTooCostly`."""
    index = {m: i for i, m in enumerate(members)}
    after = [sum(1 << index[t] for t in succ.get(m, ()) if t in index) for m in members]
    full = (1 << len(members)) - 1
    memo: dict[int, int] = {full: 1}

    def count(placed: int) -> int:
        if placed in memo:
            return memo[placed]
        if budget is not None and len(memo) > budget:
            raise CountTooCostly
        total = 0
        for i in range(len(members)):
            if not placed >> i & 1 and not after[i] & placed:
                total += count(placed | 1 << i)
                if total >= cap:
                    break
        memo[placed] = total = min(total, cap)
        return total

    return count(0)


def _listed(model: OutputModel) -> Collection[list[int]]:
    """The mission decompositions of an export: a collection, since an export reads them more
    than once (to count the files, then to write them)."""
    decompositions = model.decompositions
    if not isinstance(decompositions, Collection):
        raise TypeError("an iHTN export needs the mission decompositions as a list, not a stream")
    return decompositions


def ihtn_file_count(model: OutputModel, one_per_decomposition: bool, cap: int, budget: int | None = None) -> int:
    """The number of files an export writes (at most ``cap``, which means "at least ``cap``");
    with a ``budget`` of counting work per decomposition, :class:`CountTooCostly` beyond it."""
    if one_per_decomposition:
        return min(len(_listed(model)), cap)
    succ, _ = _constraint_index(model)
    total = 0
    for md in _listed(model):
        members = set(md)
        total += count_orderings(list(md), {d: succ.get(d, set()) & members for d in md}, cap - total, budget)
        if total >= cap:
            return cap
    return total


DEFAULT_MAX_FILES = 10_000  # an export of more files is refused before anything is written


REMEDIES = ("write the first ordering of each with --ihtn-orderings one, list fewer decompositions (--limit K, "
            "--optimize), or raise --ihtn-max")  # the options of ``mutrose-cp decompose``


def refuse_oversized_export(model: OutputModel, one_per_decomposition: bool, maximum: int, folder: str,
                            remedies: str = REMEDIES) -> int:
    """The number of files the export will write; a :class:`MissionError` (located at
    ``folder``) when that is more than ``maximum``, saying how many and what to do instead
    (``remedies``: the options of the command that asked)."""
    files = ihtn_file_count(model, one_per_decomposition, maximum + 1)
    if files > maximum:
        raise MissionError(f"the iHTN export would write {_how_many_files(model, one_per_decomposition, maximum)}, "
                           f"over --ihtn-max {maximum}; one file is written per ordering of each listed "
                           f"decomposition: {remedies}", folder)
    return files


def _how_many_files(model: OutputModel, one: bool, limit: int) -> str:
    """How many files a refused export would write, as exactly as a second of work tells."""
    try:
        return f"{ihtn_file_count(model, one, 10**18, budget=20_000):,} files"
    except CountTooCostly:
        pass
    first = _listed(model)
    members = next(iter(first))
    succ, _ = _constraint_index(model)
    local = {d: succ.get(d, set()) & set(members) for d in members}
    try:
        alone = count_orderings(list(members), local, 10**18, budget=500_000)
    except CountTooCostly:
        return f"more than {limit:,} files"
    return f"at least {alone:,} files (the first listed decomposition alone has that many orderings)"


def write_ihtns(model: OutputModel, folder: Path, progress: Callable[[int], None] | None = None, *,
                one_per_decomposition: bool = False, owned: bool = False) -> int:
    """Write ``ihtn_<n>.json`` files into ``folder``, all or nothing.

    The files are built in a temporary folder beside ``folder`` and then moved in under a lock,
    with SIGINT and SIGTERM held back for those few renames; old ``ihtn_<n>.json`` files that
    the new export does not replace are removed.  No other file of ``folder`` is touched,
    unless the folder is ``owned`` (the drop-in's ``./ihtn``, which the original empties): then
    every other entry goes too.  Two concurrent exports leave the whole result of one of them.
    A failed or interrupted export leaves no folder it created; a write error (a full disk) is
    located at ``folder``."""
    if folder.exists() and not folder.is_dir():
        raise MissionError("cannot write the iHTN files: it is a file; give a folder", str(folder))
    created = not folder.exists()
    try:
        folder.mkdir(parents=True, exist_ok=True)
        return _export(model, folder, progress, one_per_decomposition, owned)
    except BaseException as err:
        if created:
            _remove_if_empty(folder)
        if isinstance(err, OSError):
            raise write_failure(folder, err) from None
        raise


def _remove_if_empty(folder: Path) -> None:
    try:
        folder.rmdir()
    except OSError:  # a concurrent export filled it
        pass


def _export(model: OutputModel, folder: Path, progress: Callable[[int], None] | None,
            one_per_decomposition: bool, owned: bool) -> int:
    """Stage the files beside ``folder``, then swap them in (see :func:`write_ihtns`)."""
    succ, ec = _constraint_index(model)
    staging = Path(tempfile.mkdtemp(prefix=f".{folder.name}.", suffix=".tmp", dir=folder.parent))
    try:
        count = 0
        for md in _listed(model):
            agents = _Agents(model, list(md), ec)
            member_set = set(md)
            local = {d: succ.get(d, set()) & member_set for d in md}
            for order in _orderings(list(md), local):
                count += 1
                with open(staging / f"ihtn_{count}.json", "w", encoding="utf-8", newline="") as fh:
                    write_boost_json(_ihtn_nodes(model, order, agents), fh)
                    fh.write("\n")
                if progress is not None:
                    progress(count)
                if one_per_decomposition:
                    break
        _swap_in(staging, folder, count, owned)
    finally:
        shutil.rmtree(staging, ignore_errors=True)
    return count


def _ihtn_nodes(model: OutputModel, order: list[int], agents: _Agents) -> IhtnNodes:
    """The nodes of one iHTN file: a ROOT task and its ROOT_M method, whose children are the
    task trees of the decompositions in ``order``, numbered depth-first."""
    nodes: IhtnNodes = {}
    nodes["0"] = {"name": "ROOT", "type": "task", "parent": "-1", "agents": agents.show(agents.all),
                  "children": ["1"]}
    children: list[str] = []
    nodes["1"] = {"name": "ROOT_M", "type": "method", "parent": "0", "agents": agents.show(agents.all),
                  "children": children}
    for d in order:
        dec = model.tg.decomposition(d).decomposition
        loc = dec.instance.location
        location = set(loc) if isinstance(loc, tuple) else ({loc} if loc else set())
        children.append(_tree_json(nodes, dec.path.tree, "1", d, agents, location))
    return nodes


def _swap_in(staging: Path, folder: Path, count: int, owned: bool) -> None:
    """Move the staged files into ``folder`` and drop its other ``ihtn_<n>.json`` files (every
    other entry of an ``owned`` folder)."""
    lock = os.open(folder, os.O_RDONLY)  # the folder itself is the lock: nothing is left behind
    try:
        fcntl.flock(lock, fcntl.LOCK_EX)
        held = signal.pthread_sigmask(signal.SIG_BLOCK, {signal.SIGINT, signal.SIGTERM})
        try:
            for n in range(1, count + 1):
                os.replace(staging / f"ihtn_{n}.json", folder / f"ihtn_{n}.json")
            for old in folder.iterdir():
                if IHTN_FILE.fullmatch(old.name) and int(old.name[5:-5]) <= count:
                    continue  # just written
                if owned and old.is_dir() and not old.is_symlink():
                    shutil.rmtree(old)
                elif owned or IHTN_FILE.fullmatch(old.name):
                    old.unlink()
        finally:
            signal.pthread_sigmask(signal.SIG_SETMASK, held)
    finally:
        os.close(lock)  # releases the lock
