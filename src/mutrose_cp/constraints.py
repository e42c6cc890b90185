"""Mission constraints from the Task Graph (spec ``semantics.md`` §6).

Sequential (SEQ) and fallback (FB) constraints come from the operator structure, transformed
from task instances to their decompositions; parallel pairs become SEQ only where a context
dependency orders them; execution constraints (EC) come from Group/Divisible.  Redundant
SEQ/FB links are trimmed, and EC partners must agree on robot numbers.
"""
from __future__ import annotations

from enum import StrEnum
from typing import NamedTuple

from .errors import MissionError
from .model.task_graph import EdgeKind, OperatorVertex, TaskGraph, TaskVertex


class ConstraintKind(StrEnum):
    SEQ = "SEQ"  # sequential: the first runs before the second
    FB = "FB"  # fallback: the second runs only if the first fails
    EC = "EC"  # execution constraint: the two share robots (Group/Divisible)
    PAR = "PAR"  # parallel: only while generating (§6.1), never in the final list


SEQ, FB, EC, PAR = ConstraintKind.SEQ, ConstraintKind.FB, ConstraintKind.EC, ConstraintKind.PAR


class Constraint(NamedTuple):
    """``kind`` between two vertices (tasks while generating, decompositions when final).

    A named tuple: large missions have around a million of them."""

    kind: ConstraintKind
    first: int
    second: int
    group: bool = True
    divisible: bool = True


_Child = int | list[Constraint]  # a task vertex, or the constraint list of a subtree


def _pairs(kind: ConstraintKind, x: _Child, y: _Child) -> list[tuple[int, int]]:
    """Endpoint pairs generated between two children of a SEQ, FB or PAR node (§6.1)."""
    out: list[tuple[int, int]] = []
    if isinstance(x, int) and isinstance(y, int):
        return [(x, y)]
    if isinstance(x, int):
        assert isinstance(y, list)
        for c in y:
            if kind == SEQ:
                out += [(x, c.first)] if c.kind in (SEQ, FB) else [(x, c.first), (x, c.second)]
            elif kind == FB:
                out += [(x, c.first)] if c.kind == FB else [(x, c.first), (x, c.second)]
            else:
                out += [(x, c.first), (x, c.second)]
        return out
    if isinstance(y, int):
        for c in x:
            if kind == SEQ:
                out += [(c.second, y)] if c.kind == SEQ else [(c.first, y), (c.second, y)]
            elif kind == FB:
                out += [(c.second, y)] if c.kind == FB else [(c.first, y), (c.second, y)]
            else:
                out += [(c.first, y), (c.second, y)]
        return out
    for l in x:
        for r in y:
            four = [(l.first, r.first), (l.first, r.second), (l.second, r.first), (l.second, r.second)]
            if kind == SEQ:
                if l.kind == SEQ:
                    out += [(l.second, r.first)] if r.kind in (SEQ, FB) else [(l.second, r.first), (l.second, r.second)]
                else:
                    out += [(l.first, r.first), (l.second, r.first)] if r.kind in (SEQ, FB) else four
            elif kind == FB:
                if l.kind in (SEQ, PAR):
                    out += four if r.kind in (SEQ, PAR) else [(l.first, r.first), (l.second, r.first)]
                else:
                    out += [(l.second, r.first), (l.second, r.second)] if r.kind in (SEQ, PAR) else [(l.second, r.first)]
            else:
                out += four
    return out


def _tree_constraints(tg: TaskGraph, v: int, pairs_needed: bool) -> list[Constraint]:
    """The constraint list of the operator subtree rooted at ``v`` (§6.1).

    Parallel pairs only matter when a sequential or fallback ancestor fans out over their
    endpoints, or when a context dependency turns one into SEQ (§6.2).  Otherwise they would be
    dropped anyway, and there are quadratically many of them (every pair of forAll instances),
    so ``pairs_needed=False`` skips generating them: the result is the same."""
    vx = tg.vertices[v]
    kind = {";": SEQ, "FALLBACK": FB}.get(vx.content, PAR)
    children: list[_Child] = []
    for u in tg.out(v, EdgeKind.AND, EdgeKind.OR):
        ux = tg.vertices[u]
        if isinstance(ux, TaskVertex):
            children.append(u)
        elif isinstance(ux, OperatorVertex):
            children.append(_tree_constraints(tg, u, pairs_needed or kind != PAR))
    pairs: list[tuple[int, int]] = []
    if kind == PAR and not pairs_needed:
        combos = []
    elif kind == PAR:
        combos = [(i, j) for i in range(len(children)) for j in range(i + 1, len(children))]
    else:
        combos = [(i, i + 1) for i in range(len(children) - 1)]
    for i, j in combos:
        pairs += _pairs(kind, children[i], children[j])
    seen: set[tuple[int, int]] = set()
    out: list[Constraint] = []
    for p in pairs:
        if p not in seen:
            seen.add(p)
            out.append(Constraint(kind, *p))
    for c in children:
        if isinstance(c, list):
            for k in c:
                if (k.first, k.second) not in seen:
                    seen.add((k.first, k.second))
                    out.append(k)
    return out


def _decompositions(tg: TaskGraph, task: int) -> list[int]:
    return [d.index for d in tg.decompositions_of(task)]


def _to_decompositions(tg: TaskGraph, task_constraints: list[Constraint]) -> list[Constraint]:
    """§6.2: SEQ/FB over all decomposition pairs; PAR only where a CD edge orders the pair."""
    out: list[Constraint] = []
    for c in task_constraints:
        if c.kind in (SEQ, FB):
            out += [Constraint(c.kind, da, db) for da in _decompositions(tg, c.first) for db in _decompositions(tg, c.second)]
        else:
            for da in _decompositions(tg, c.first):
                if c.second in tg.out(da, EdgeKind.CD):
                    out += [Constraint(SEQ, da, db) for db in _decompositions(tg, c.second)]
    return out


def _execution_constraints(tg: TaskGraph) -> list[Constraint]:
    """§6.3: one EC per decomposition pair of every EC-linked task pair."""
    out: list[Constraint] = []
    done: set[tuple[int, int]] = set()
    for s in (v.index for v in tg.tasks()):
        for t, group, divisible in tg.ec_partners(s):
            if (t, s) in done:
                continue
            done.add((s, t))
            for ds in _decompositions(tg, s):
                for dt in _decompositions(tg, t):
                    out.append(Constraint(EC, ds, dt, group, divisible))
    return out


def _trim(constraints: list[Constraint]) -> list[Constraint]:
    """§6.4: drop SEQ implied through SEQ/FB and FB implied through FB (one pass)."""
    seq_succ: dict[int, set[int]] = {}
    fb_succ: dict[int, set[int]] = {}
    seq_pred: dict[int, set[int]] = {}
    fb_pred: dict[int, set[int]] = {}
    for c in constraints:
        if c.kind == SEQ:
            seq_succ.setdefault(c.first, set()).add(c.second)
            seq_pred.setdefault(c.second, set()).add(c.first)
        elif c.kind == FB:
            fb_succ.setdefault(c.first, set()).add(c.second)
            fb_pred.setdefault(c.second, set()).add(c.first)
    empty: set[int] = set()
    kept: list[Constraint] = []
    for c in constraints:
        kind = c[0]
        if kind == SEQ:
            mids = seq_succ.get(c.first, empty)
            if mids and (mids & seq_pred.get(c.second, empty) or mids & fb_pred.get(c.second, empty)):
                continue
        elif kind == FB:
            if fb_succ.get(c.first, empty) & fb_pred.get(c.second, empty):
                continue
        kept.append(c)
    return kept


def _check_robot_numbers(tg: TaskGraph, constraints: list[Constraint]) -> None:
    """§6.5: execution-constrained decompositions need compatible robot numbers."""
    for c in constraints:
        if c.kind != EC:
            continue
        a = tg.decomposition(c.first).instance
        b = tg.decomposition(c.second).instance
        ra, rb = a.robot_number, b.robot_number
        if ra.fixed and rb.fixed:
            ok = ra.min == rb.min
        else:
            ok = ra.min <= rb.max and rb.min <= ra.max
        if not ok:
            raise MissionError(
                f"Wrong robot number for execution constrained tasks [{tg.vertices[c.first].content}] and "
                f"[{tg.vertices[c.second].content}]: they share robots (a Group=False or Divisible=False goal "
                f"above them), so their RobotNumber values must overlap; set RobotNumber on {a.gm_task} or "
                f"{b.gm_task} to agree",
                f"goal model: tasks {a.gm_task} and {b.gm_task}",
            )


def generate_constraints(tg: TaskGraph) -> list[Constraint]:
    """The final constraint list over decomposition vertices, in the original's order."""
    out: list[Constraint] = []
    if not tg.unique_branch:
        root = tg.vertices[0]
        if not isinstance(root, OperatorVertex):
            raise MissionError("Could not generate constraints: the Task Graph root is not an operator")
        has_cd = any(e.kind == EdgeKind.CD for e in tg.edges())
        out = _to_decompositions(tg, _tree_constraints(tg, 0, has_cd))
    out += _execution_constraints(tg)
    out = _trim(out)
    _check_robot_numbers(tg, out)
    return out
