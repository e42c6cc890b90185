"""Goal-model conditions (creation, achieve and forAll conditions) evaluated on a replayed state.

Goal-model variables are read back from each task of the file: its ``Location`` and the
parameters the configuration's ``var_mapping`` fills (the file's fields are checked against the
mission separately).  An atom is translated by the attribute mapping of its attribute and of the
variable's type; the evaluation is open-world (an unknown fact holds), and a required comparison
on a value the world does not give becomes a test of its start value.
"""
from __future__ import annotations

from typing import Callable

from ..io.decomposition_output import OutputTask
from ..model import Atom, BoolOp, Condition, Configuration, GMNode, GoalModel
from .numbers import AtomKey, StartValues, compare
from .replay import Values, task_values
from .state import State


def variables(cond: Condition) -> set[str]:
    if isinstance(cond, BoolOp):
        return set().union(*(variables(c) for c in cond.children))
    return {cond.variable} if cond.variable else set()


def show_condition(cond: Condition) -> str:
    if isinstance(cond, BoolOp):
        return f" {cond.op} ".join(show_condition(c) for c in cond.children)
    return cond.text


class GoalConditions:
    def __init__(self, gm: GoalModel, config: Configuration, note: Callable[[str], None], xml: bool) -> None:
        self.gm = gm
        self.config = config
        self.note = note
        self.xml = xml
        self.var_types = {d.name: d.base_type for n in gm.nodes for d in (*n.controls, *n.monitors) if d.type}
        self._mapped: dict[tuple[str, str, bool], str | None] = {}
        self._bindings: dict[str, Values] = {}

    def binding(self, task: OutputTask) -> Values:
        """Goal-model variables of a task, read back through its Location and var_mapping."""
        found = self._bindings.get(task.key)
        if found is not None:
            return found
        values = task_values(task, self.xml)
        out: Values = {}
        node = self.gm.by_id.get(task.gm_task)
        if node is not None and node.location and task.locations:
            out[node.location] = task.locations
        for vm in self.config.var_mapping:
            if vm.task_id == task.gm_task:
                for gm_var, hddl_var in vm.pairs:
                    if hddl_var in values:
                        out[gm_var] = values[hddl_var]
        self._bindings[task.key] = out
        return out

    def mapped(self, atom: Atom) -> str | None:
        """The predicate or function an atom's attribute maps to for its variable's type."""
        numeric = atom.op in ("=", "<>", ">", "<", ">=", "<=")
        key = (atom.attribute, self.var_types.get(atom.variable, ""), numeric)
        if key not in self._mapped:
            self._mapped[key] = next((m.pred for m in self.config.semantic_mapping
                                      if m.type == "attribute" and m.name == key[0] and m.relates_to == key[1]
                                      and m.mapped_type == ("function" if numeric else "predicate")), None)
        return self._mapped[key]

    def atoms(self, cond: Condition, binding: Values) -> list[AtomKey]:
        """The ground atoms a condition reads under ``binding``."""
        if isinstance(cond, BoolOp):
            return [a for c in cond.children for a in self.atoms(c, binding)]
        pred = self.mapped(cond)
        return [] if pred is None else [(pred, (v,)) for v in binding.get(cond.variable, ())]

    def holds(self, cond: Condition, binding: Values, state: State, goal: GMNode,
              start: StartValues | None = None) -> bool | None:
        """Open-world evaluation; None when an atom cannot be translated.  With ``start``, a
        comparison (an achieve condition's conjunct) on a value the world does not give is a
        condition on its start value, which must agree with the others."""
        if isinstance(cond, BoolOp):
            parts = [self.holds(c, binding, state, goal, start if cond.op == "&&" else None) for c in cond.children]
            if any(p is None for p in parts):
                return None
            return all(parts) if cond.op == "&&" else any(parts)
        return self._atom(cond, binding, state, goal, start)

    def _atom(self, atom: Atom, binding: Values, state: State, goal: GMNode,
              start: StartValues | None) -> bool | None:
        pred = self.mapped(atom)
        if pred is None:
            self.note(f"goal {goal.id}: {atom.text} has no attribute mapping for type "
                      f"{self.var_types.get(atom.variable) or '?'}: not checked")
            return None
        values = binding.get(atom.variable, ())
        if atom.op not in ("=", "<>", ">", "<", ">=", "<="):
            return all(state.facts.get((pred, (v,))) in (None, not atom.negated) for v in values)
        bound, op = float(atom.value), atom.op or "="
        result = True
        for key in [(pred, (v,)) for v in values]:
            if key in state.values:
                result = result and compare(state.values[key], op, bound)
            elif start is not None:
                start.fixed.setdefault(key, []).append((op, bound - state.offsets.get(key, 0.0), False,
                                                        f"achieve condition of goal {goal.id}"))
        return result
