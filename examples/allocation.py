"""Choose a mission decomposition *together with* a robot allocation and a schedule.

    python examples/allocation.py [MISSION_DIR] [--config NAME] [--robots N] [--time-limit S]
                                  [--durations action|unit] [--fleet FLEET.json] [--deliveries N]
                                  [--workers N] [--seed N] [--deterministic-limit T] [--log]

The decomposition space comes from ``mission.decomposition_model()``: one CP-SAT model whose
solutions are exactly the valid mission decompositions (``mutrose_cp.api``).  This script adds
its own variables to that same model:

* a fleet of robots, each with a set of capabilities (``--fleet`` or a generated one);
* ``assign[d, r]``: robot ``r`` executes decomposition ``d``.  Only robots that have every
  capability required by the actions of ``d`` are candidates; a robot is assigned only when
  ``d`` is chosen, and a chosen ``d`` gets as many robots as its RobotNumber says (fixed ``n`` or
  a range ``[a, b]``);
* execution constraints: ``EC`` with ``group=False`` (the same single robot executes both) and
  ``group=True, divisible=False`` (the same team) force equal assignments when both are chosen;
* time: ``start[d]``, ``end[d] = start[d] + duration[d] * chosen[d]``, ``end(first) <=
  start(second)`` for every SEQ (and FB: the fallback is scheduled after its primary, the
  worst case); a decomposition that is not chosen takes no time and only passes precedences on;
* one optional interval per (decomposition, candidate robot), ``AddNoOverlap`` per robot;
* objective: minimise the makespan (plus a redundant load constraint per robot, which gives
  CP-SAT's own bound the energy argument).

Then it computes a lower bound on the makespan from the LP relaxation of the same problem
(continuous assignments ``x[d,r]`` in [0, 1], decomposition choice relaxed through the linear
relaxation of the boolean decomposition model, robot loads ``sum_d dur_d x[d,r] <= M``, start
times along precedence chains, chains along the goal model's operators) with Clarabel, and
prints the CP-SAT objective, CP-SAT's own bound, the LP bound and the gaps.  ``main()`` returns an :class:`AllocationResult` (used by the tests).
"""
from __future__ import annotations

import argparse
import json
import math
import shutil
import sys
import tempfile
import time
from dataclasses import dataclass, field
from pathlib import Path
from xml.etree import ElementTree

from ortools.sat.python import cp_model

from mutrose_cp.api import DecompositionModel, Mission, find_mission_files

ROOT = Path(__file__).resolve().parent
DEFAULT_MISSION = ROOT / "item-delivery"

#: Per-action durations (time units) for ``--durations action``; other actions take
#: ``DEFAULT_ACTION_DURATION``.  A ``--fleet`` file may override them (``"durations"``).
ACTION_DURATIONS = {
    "navigate": 4, "navto": 4,  # driving dominates
    "pick-item": 2, "request-loading": 3, "give-item": 1, "drop-item": 1,  # item-delivery
    "wait-for-food": 3, "wait-for-human-to-fetch": 2,  # food-logistics
}
DEFAULT_ACTION_DURATION = 2


# ----------------------------------------------------------------------------------------------
# Fleet and durations


@dataclass(frozen=True)
class Robot:
    name: str
    capabilities: frozenset[str]


def default_fleet(dm: DecompositionModel, n: int) -> list[Robot]:
    """``n`` robots with deterministic, heterogeneous capability sets.

    Capabilities that every decomposition with requirements needs (e.g. ``navigation``) are
    given to all robots; of the others, robot ``i`` lacks capability ``i mod (k+1)`` (so every
    (k+1)-th robot has them all)."""
    required = [info.capabilities for info in dm.decompositions_info.values() if info.capabilities]
    all_caps = sorted(set().union(*required)) if required else []
    core = set.intersection(*(set(r) for r in required)) if required else set()
    optional = [c for c in all_caps if c not in core]
    robots = []
    for i in range(n):
        k = i % (len(optional) + 1)
        lacks = {optional[k]} if k < len(optional) else set()
        robots.append(Robot(f"r{i + 1}", frozenset(c for c in all_caps if c not in lacks)))
    return robots


def load_fleet(path: str | Path) -> tuple[list[Robot], dict[str, int]]:
    """A fleet file: ``{"robots": {"r1": ["navigation", ...], ...}, "durations": {"navigate": 3}}``."""
    data = json.loads(Path(path).read_text())
    robots = [Robot(name, frozenset(caps)) for name, caps in data["robots"].items()]
    return robots, {k: int(v) for k, v in data.get("durations", {}).items()}


def decomposition_durations(dm: DecompositionModel, mode: str = "action",
                            table: dict[str, int] | None = None) -> dict[str, int]:
    """Duration of each decomposition: the sum of its actions' durations (``unit``: 1 per
    action), at least 1."""
    table = {**ACTION_DURATIONS, **(table or {})}
    out = {}
    for d, info in dm.decompositions_info.items():
        if mode == "unit":
            total = len(info.actions)
        else:
            total = sum(table.get(a, DEFAULT_ACTION_DURATION) for a in info.actions)
        out[d] = max(1, total)
    return out


# ----------------------------------------------------------------------------------------------
# The joint CP-SAT model


@dataclass
class AllocationModel:
    dm: DecompositionModel
    robots: list[Robot]
    durations: dict[str, int]
    candidates: dict[str, list[str]]  # decomposition -> robots that can execute it
    assign: dict[tuple[str, str], cp_model.IntVar] = field(default_factory=dict)
    start: dict[str, cp_model.IntVar] = field(default_factory=dict)
    end: dict[str, cp_model.IntVar] = field(default_factory=dict)
    makespan: cp_model.IntVar | None = None


def candidates_of(dm: DecompositionModel, robots: list[Robot]) -> dict[str, list[str]]:
    return {d: [r.name for r in robots if info.capabilities <= r.capabilities]
            for d, info in dm.decompositions_info.items()}


def precedences(dm: DecompositionModel) -> list[tuple[str, str]]:
    """(first, second) pairs that must not overlap in time: SEQ, and FB (worst case)."""
    return [(c.first, c.second) for c in dm.constraints if c.kind in ("SEQ", "FB")]


def same_robots(dm: DecompositionModel) -> list[tuple[str, str]]:
    """EC pairs whose robots must be identical when both are chosen."""
    return [(c.first, c.second) for c in dm.constraints
            if c.kind == "EC" and (not c.group or not c.divisible)]


def add_allocation(dm: DecompositionModel, robots: list[Robot], durations: dict[str, int],
                   redundant: bool = True) -> AllocationModel:
    """Add assignment, scheduling and makespan variables to ``dm.model`` (see module docstring).

    ``redundant`` adds the load of every robot, ``sum_d dur_d assign[d,r] <= makespan``: implied
    by the no-overlap constraints, but it gives CP-SAT's linear relaxation the energy argument
    that its bound otherwise misses on larger instances."""
    m = dm.model
    cand = candidates_of(dm, robots)
    am = AllocationModel(dm, robots, durations, cand)
    horizon = sum(durations.values())
    for d, chosen in dm.decomposition.items():
        rn = dm.decompositions_info[d].robot_number
        dur = durations[d]
        s = m.NewIntVar(0, horizon, f"start[{d}]")
        e = m.NewIntVar(0, horizon, f"end[{d}]")
        m.Add(e == s + dur * chosen)
        am.start[d], am.end[d] = s, e
        lits = []
        for r in cand[d]:
            a = m.NewBoolVar(f"assign[{d},{r}]")
            m.AddImplication(a, chosen)
            am.assign[(d, r)] = a
            lits.append(a)
        if len(lits) < rn.min:  # not enough capable robots: this decomposition cannot be chosen
            m.AddBoolOr([chosen.Not()])
            continue
        m.Add(sum(lits) >= rn.min).OnlyEnforceIf(chosen)
        m.Add(sum(lits) <= rn.max)
    for first, second in precedences(dm):
        m.Add(am.end[first] <= am.start[second])
    for d1, d2 in same_robots(dm):
        both = [dm.decomposition[d1], dm.decomposition[d2]]
        for r in sorted(set(cand[d1]) | set(cand[d2])):
            a1 = am.assign.get((d1, r), dm.false)
            a2 = am.assign.get((d2, r), dm.false)
            m.Add(a1 == a2).OnlyEnforceIf(both)
    for robot in robots:
        intervals = [m.NewOptionalFixedSizeIntervalVar(am.start[d], durations[d], am.assign[(d, robot.name)],
                                                       f"busy[{d},{robot.name}]")
                     for d in dm.decomposition if (d, robot.name) in am.assign]
        if len(intervals) > 1:
            m.AddNoOverlap(intervals)
    am.makespan = m.NewIntVar(0, horizon, "makespan")
    m.AddMaxEquality(am.makespan, list(am.end.values()))
    if redundant:
        for robot in robots:
            load = [durations[d] * am.assign[(d, robot.name)] for d in dm.decomposition if (d, robot.name) in am.assign]
            if load:
                m.Add(sum(load) <= am.makespan)
    m.Minimize(am.makespan)
    return am


# ----------------------------------------------------------------------------------------------
# LP relaxation (Clarabel)


class _Lp:
    """Rows ``sum coef*var (<=|==) rhs`` over named continuous variables."""

    def __init__(self) -> None:
        self.index: dict[object, int] = {}
        self.le: list[tuple[dict[int, float], float]] = []
        self.eq: list[tuple[dict[int, float], float]] = []

    def var(self, key, lo: float | None = 0.0, hi: float | None = None) -> int:
        if key not in self.index:
            self.index[key] = len(self.index)
            j = self.index[key]
            if lo is not None:
                self.le.append(({j: -1.0}, -lo))
            if hi is not None:
                self.le.append(({j: 1.0}, hi))
        return self.index[key]

    @staticmethod
    def _lin(terms) -> tuple[dict[int, float], float]:
        """terms: (coef, expr) with expr = (dict, const)."""
        row: dict[int, float] = {}
        const = 0.0
        for coef, (lin, c) in terms:
            const += coef * c
            for j, v in lin.items():
                row[j] = row.get(j, 0.0) + coef * v
        return row, const

    def add_le(self, terms, rhs: float = 0.0) -> None:  # sum terms <= rhs
        row, const = self._lin(terms)
        self.le.append((row, rhs - const))

    def add_eq(self, terms, rhs: float = 0.0) -> None:
        row, const = self._lin(terms)
        self.eq.append((row, rhs - const))


def lp_bound(dm: DecompositionModel, robots: list[Robot], durations: dict[str, int],
             structure: bool = True) -> dict:
    """Lower bound on the makespan from the LP relaxation, solved with Clarabel.

    Variables in [0, 1]: the boolean variables of the decomposition model (its clauses,
    exactly-one choices, AND/OR definitions relaxed linearly; numeric world records dropped,
    which only enlarges the set) and ``x[d,r]`` for candidate robots.  Constraints:
    ``x[d,r] <= y_d``; ``min_d y_d <= sum_r x[d,r] <= max_d y_d``; same-robot EC pairs
    ``x[d1,r] - x[d2,r] <= 1 - y_d2``; loads ``sum_d dur_d x[d,r] <= M``; start times
    ``s_second >= s_first + dur_first y_first`` on SEQ/FB and ``M >= s_d + dur_d y_d``.  This
    contains the classic bounds (total work over the robots able to do it, per capability
    group; longest precedence chain) and minimises ``M``.
    """
    import numpy as np
    import scipy.sparse as sp
    import clarabel

    from mutrose_cp.solve.boolean_model import FALSE, TRUE

    t0 = time.perf_counter()
    enc = dm.encoding
    bm = enc.model
    lp = _Lp()

    def lit(l):  # encoding literal -> linear expression (dict, const)
        if l == TRUE:
            return ({}, 1.0)
        if l == FALSE:
            return ({}, 0.0)
        j = lp.var(("b", abs(l)), 0.0, 1.0)
        return ({j: 1.0}, 0.0) if l > 0 else ({j: -1.0}, 1.0)

    for r in bm.records:
        ls = [lit(l) for l in r.lits]
        if r.kind == "clause":
            lp.add_le([(-1.0, x) for x in ls], -1.0)  # sum >= 1
        elif r.kind == "sum_eq":
            lp.add_eq([(1.0, x) for x in ls] + [(-1.0, lit(r.target))])
        elif r.kind == "and_eq":
            t = lit(r.target)
            for x in ls:
                lp.add_le([(1.0, t), (-1.0, x)])
            lp.add_le([(1.0, x) for x in ls] + [(-1.0, t)], len(ls) - 1.0)
        elif r.kind == "or_eq":
            t = lit(r.target)
            for x in ls:
                lp.add_le([(1.0, x), (-1.0, t)])
            lp.add_le([(1.0, t)] + [(-1.0, x) for x in ls])
        # int_sel / cmp_eq (numeric world values): dropped in the relaxation

    tg = dm.mission.task_graph
    dec_lit = {tg.vertices[v].content: l for v, l in enc.decomposition_lit.items()}
    y = {d: lit(dec_lit.get(d, FALSE)) for d in dm.decomposition}
    cand = candidates_of(dm, robots)
    M = lp.var("M", 0.0)
    Mx = ({M: 1.0}, 0.0)
    x = {}
    for d in dm.decomposition:
        rn = dm.decompositions_info[d].robot_number
        xs = []
        for r in cand[d]:
            j = lp.var(("x", d, r), 0.0, 1.0)
            x[(d, r)] = ({j: 1.0}, 0.0)
            xs.append(x[(d, r)])
            lp.add_le([(1.0, x[(d, r)]), (-1.0, y[d])])
        lp.add_le([(float(rn.min), y[d])] + [(-1.0, xe) for xe in xs])  # min*y <= sum x
        lp.add_le([(1.0, xe) for xe in xs] + [(-float(rn.max), y[d])])  # sum x <= max*y
    for d1, d2 in same_robots(dm):
        for r in set(cand[d1]) | set(cand[d2]):
            a1, a2 = x.get((d1, r), ({}, 0.0)), x.get((d2, r), ({}, 0.0))
            lp.add_le([(1.0, a1), (-1.0, a2), (1.0, y[d2])], 1.0)
            lp.add_le([(1.0, a2), (-1.0, a1), (1.0, y[d1])], 1.0)
    for robot in robots:
        load = [(float(durations[d]), x[(d, robot.name)]) for d in dm.decomposition if (d, robot.name) in x]
        if load:
            lp.add_le(load + [(-1.0, Mx)])
    s = {d: ({lp.var(("s", d), 0.0): 1.0}, 0.0) for d in dm.decomposition}
    for d in dm.decomposition:
        lp.add_le([(1.0, s[d]), (float(durations[d]), y[d]), (-1.0, Mx)])
    for first, second in precedences(dm):
        lp.add_le([(1.0, s[first]), (float(durations[first]), y[first]), (-1.0, s[second])])

    if structure:
        # longest chain along the operator structure: a task lasts sum_d dur_d y_d (0 when it is
        # not executed); ";", FALLBACK and OR operators add their children up (only one OR child
        # is active), "#" takes the largest.  This keeps the OR choice exact in the chain bound,
        # which the start-time chains above lose when y is fractional.
        from mutrose_cp.model.task_graph import OperatorVertex, TaskVertex

        memo: dict[int, tuple] = {}

        def chain_expr(v: int):
            if v not in memo:
                vx = tg.vertices[v]
                if isinstance(vx, TaskVertex):
                    j = lp.var(("L", v), 0.0)
                    lp.add_eq([(1.0, ({j: 1.0}, 0.0))] + [(-float(durations[dv.content]), y[dv.content])
                                                           for dv in tg.decompositions_of(v)])
                    memo[v] = ({j: 1.0}, 0.0)
                else:
                    kids = tg.children(v)
                    parts = [chain_expr(c) for c in kids]
                    j = lp.var(("L", v), 0.0)
                    lv = ({j: 1.0}, 0.0)
                    if tg.is_or(v) or (isinstance(vx, OperatorVertex) and vx.content in (";", "FALLBACK")):
                        lp.add_le([(-1.0, lv)] + [(1.0, pe) for pe in parts])
                    else:
                        for pe in parts:
                            lp.add_le([(-1.0, lv), (1.0, pe)])
                    memo[v] = lv
            return memo[v]

        if tg.vertices and not tg.unique_branch:
            lp.add_le([(1.0, chain_expr(0)), (-1.0, Mx)])

    n = len(lp.index)
    rows = lp.eq + lp.le
    data, ri, ci, b = [], [], [], []
    for i, (row, rhs) in enumerate(rows):
        for j, v in row.items():
            if v != 0.0:
                data.append(v)
                ri.append(i)
                ci.append(j)
        b.append(rhs)
    A = sp.csc_matrix((data, (ri, ci)), shape=(len(rows), n))
    P = sp.csc_matrix((n, n))
    q = np.zeros(n)
    q[M] = 1.0
    cones = []
    if lp.eq:
        cones.append(clarabel.ZeroConeT(len(lp.eq)))
    cones.append(clarabel.NonnegativeConeT(len(lp.le)))
    settings = clarabel.DefaultSettings()
    settings.verbose = False
    sol = clarabel.DefaultSolver(P, q, A, np.array(b, dtype=float), cones, settings).solve()
    status = str(sol.status)
    value = float(sol.obj_val) if "Solved" in status else float("nan")
    return {"value": value, "dual": float(sol.obj_val_dual), "status": status, "variables": n,
            "rows": len(rows), "time": time.perf_counter() - t0}


# ----------------------------------------------------------------------------------------------
# Driver


@dataclass
class AllocationResult:
    mission: str
    status: str
    objective: int | None  # makespan of the best solution found
    cp_bound: float  # CP-SAT's proven lower bound
    lp_bound: float  # LP relaxation optimum (Clarabel)
    lp_bound_int: int | None  # ceil of the LP bound (the makespan is integer)
    chosen: list[str]  # chosen decompositions
    assignment: dict[str, list[str]]  # chosen decomposition -> robots
    start: dict[str, int]
    end: dict[str, int]
    robots: list[Robot]
    durations: dict[str, int]
    dm: DecompositionModel = field(repr=False)
    times: dict[str, float] = field(default_factory=dict)
    sizes: dict[str, int] = field(default_factory=dict)

    @property
    def gap_cp(self) -> float | None:
        return None if not self.objective else (self.objective - self.cp_bound) / self.objective

    @property
    def gap_lp(self) -> float | None:
        return None if not self.objective else (self.objective - self.lp_bound) / self.objective


def solve(mission_dir: str | Path = DEFAULT_MISSION, config: str | None = None, robots: int = 3,
          time_limit: float = 10.0, workers: int = 1, seed: int = 0, durations_mode: str = "action",
          fleet: str | Path | None = None, lp: bool = True, log: bool = False,
          redundant: bool = True, deterministic_limit: float | None = None) -> AllocationResult:
    """Load the mission, build the joint model, solve it with CP-SAT and compute the LP bound.

    CP-SAT runs with a fixed ``seed``; one worker (the default) or several interleaved workers
    make the search deterministic, so a run that finishes before ``time_limit`` always returns
    the same solution.  A run cut by the wall-clock limit depends on the machine's speed; use
    ``deterministic_limit`` (CP-SAT's deterministic time) for reproducible truncated runs."""
    t0 = time.perf_counter()
    mission = Mission.load(*find_mission_files(mission_dir, config))
    dm = mission.decomposition_model()
    t_dm = time.perf_counter() - t0
    table: dict[str, int] = {}
    if fleet is not None:
        fleet_robots, table = load_fleet(fleet)
    else:
        fleet_robots = default_fleet(dm, robots)
    durations = decomposition_durations(dm, durations_mode, table)
    am = add_allocation(dm, fleet_robots, durations, redundant)
    t_build = time.perf_counter() - t0 - t_dm

    solver = cp_model.CpSolver()
    p = solver.parameters
    p.max_time_in_seconds = time_limit
    if deterministic_limit is not None:
        p.max_deterministic_time = deterministic_limit
    p.num_workers = workers
    p.random_seed = seed
    p.interleave_search = workers > 1  # deterministic multi-worker search
    p.log_search_progress = log
    status = solver.Solve(dm.model)
    t_solve = solver.WallTime()
    found = status in (cp_model.OPTIMAL, cp_model.FEASIBLE)
    chosen = dm.solution(solver) if found else []
    assignment = {d: [r.name for r in fleet_robots if (d, r.name) in am.assign and solver.BooleanValue(am.assign[(d, r.name)])]
                  for d in chosen}
    lpres = lp_bound(dm, fleet_robots, durations) if lp else {"value": float("nan"), "time": 0.0}
    lpv = lpres["value"]
    stats = dm.model.Proto()
    return AllocationResult(
        mission=str(mission_dir), status=solver.StatusName(status),
        objective=int(solver.ObjectiveValue()) if found else None,
        cp_bound=solver.BestObjectiveBound(), lp_bound=lpv,
        lp_bound_int=None if math.isnan(lpv) else math.ceil(lpv - 1e-6),
        chosen=chosen, assignment=assignment,
        start={d: solver.Value(am.start[d]) for d in chosen} if found else {},
        end={d: solver.Value(am.end[d]) for d in chosen} if found else {},
        robots=fleet_robots, durations=durations, dm=dm,
        times={"decomposition_model": t_dm, "allocation_build": t_build, "cpsat": t_solve,
               "lp": lpres["time"], "total": time.perf_counter() - t0},
        sizes={"decompositions": len(dm.decomposition), "tasks": len(dm.task), "robots": len(fleet_robots),
               "cp_variables": len(stats.variables), "cp_constraints": len(stats.constraints),
               "lp_variables": lpres.get("variables", 0), "lp_rows": lpres.get("rows", 0)},
    )


def report(res: AllocationResult) -> str:
    lines = [f"mission: {res.mission}",
             f"size: {res.sizes['tasks']} task instances, {res.sizes['decompositions']} decompositions, "
             f"{res.sizes['robots']} robots; CP-SAT {res.sizes['cp_variables']} variables / "
             f"{res.sizes['cp_constraints']} constraints; LP {res.sizes['lp_variables']} variables / "
             f"{res.sizes['lp_rows']} rows",
             "fleet: " + ", ".join(f"{r.name}{{{','.join(sorted(r.capabilities))}}}" for r in res.robots),
             f"status: {res.status}"]
    if res.objective is not None:
        lines.append("schedule (chosen decomposition: start-end robots):")
        for d in sorted(res.chosen, key=lambda d: (res.start[d], d)):
            lines.append(f"  {d:<10} {res.start[d]:>3}-{res.end[d]:<3} {' '.join(res.assignment[d])}"
                         f"   [{', '.join(res.dm.decompositions_info[d].actions)}]")
    fmt = lambda g: "n/a" if g is None else f"{100 * g + 0.0:.1f}%".replace("-0.0%", "0.0%")  # noqa: E731
    lines += [f"CP-SAT objective (makespan): {res.objective}",
              f"CP-SAT bound:                {res.cp_bound:g}   gap {fmt(res.gap_cp)}",
              f"LP bound (Clarabel):         {res.lp_bound:.4f} (ceil {res.lp_bound_int})   gap {fmt(res.gap_lp)}",
              "time: " + ", ".join(f"{k} {v:.2f}s" for k, v in res.times.items())]
    return "\n".join(lines)


def make_item_delivery_copy(n_deliveries: int, dest: str | Path, source: str | Path = DEFAULT_MISSION) -> Path:
    """A copy of the item-delivery mission whose world has ``n_deliveries`` pending deliveries
    (the existing ones, then new ones cycling over pickup points and destinations)."""
    dest = Path(dest) / "item-delivery-scaled"
    shutil.copytree(source, dest, ignore=shutil.ignore_patterns("output"))
    world = dest / "knowledge" / "world_db.xml"
    tree = ElementTree.parse(world)
    root = tree.getroot()
    pending = [d for d in root.findall("Delivery") if d.findtext("is_delivered") == "False"]
    pickups = ["CentralPharmacy", "SupplyRoom"]
    dests = ["WardA", "WardB", "Laboratory"]
    for i in range(len(pending), n_deliveries):
        el = ElementTree.SubElement(root, "Delivery")
        for tag, text in (("name", f"Extra{i + 1}"), ("item", f"Item {i + 1}"), ("pickup", pickups[i % 2]),
                          ("destination", dests[i % 3]), ("is_collected", "False"), ("is_delivered", "False")):
            ElementTree.SubElement(el, tag).text = text
    tree.write(world, encoding="utf-8", xml_declaration=True)
    return dest


def main(argv: list[str] | None = None) -> AllocationResult:
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("mission", nargs="?", default=str(DEFAULT_MISSION), help="mission folder (default: item-delivery)")
    ap.add_argument("--config", help="configuration name when the folder has several (e.g. Delivery)")
    ap.add_argument("--robots", type=int, default=3, help="size of the generated fleet (default 3)")
    ap.add_argument("--fleet", help="JSON fleet file {robots: {name: [capabilities]}, durations: {action: t}}")
    ap.add_argument("--durations", choices=("action", "unit"), default="action",
                    help="action: per-action table (default); unit: 1 per action")
    ap.add_argument("--time-limit", type=float, default=10.0, help="CP-SAT time limit in seconds (default 10)")
    ap.add_argument("--workers", type=int, default=1,
                    help="CP-SAT workers (default 1; more are interleaved, which stays deterministic)")
    ap.add_argument("--deterministic-limit", type=float,
                    help="also stop at this CP-SAT deterministic time (reproducible truncated runs)")
    ap.add_argument("--seed", type=int, default=0)
    ap.add_argument("--deliveries", type=int,
                    help="item-delivery only: solve a temporary copy with this many pending deliveries")
    ap.add_argument("--log", action="store_true", help="CP-SAT search log")
    args = ap.parse_args(argv)
    kwargs = dict(config=args.config, robots=args.robots, time_limit=args.time_limit, workers=args.workers,
                  seed=args.seed, durations_mode=args.durations, fleet=args.fleet, log=args.log,
                  deterministic_limit=args.deterministic_limit)
    if args.deliveries:
        with tempfile.TemporaryDirectory() as tmp:
            folder = make_item_delivery_copy(args.deliveries, tmp, args.mission)
            res = solve(folder, **kwargs)
    else:
        res = solve(args.mission, **kwargs)
    print(report(res))
    return res


if __name__ == "__main__":
    main(sys.argv[1:])
