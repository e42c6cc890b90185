"""The preconditions and effects an output prints for a decomposition (semantics.md §2.5,
output.md §2.3), rebuilt from the path and the instance's values.

* Preconditions, in path order, duplicates kept: a boolean literal whose arguments the instance
  all binds is ground (one literal per combination of collection values) and left out when an
  earlier step has an effect on it; a literal with an unbound argument keeps the parameter's
  name, left out when an earlier step has an effect on exactly that literal.  Numeric conditions
  are not printed.
* Effects: the net effect of the path, each atom where it is first set, with its last value.
* A literal is printed through the first semantic mapping whose predicate and argument sorts fit
  it (a bound argument must be an object of the sort, a parameter's type the sort or its parent):
  ``[not ]<first argument>.<attribute>``, for attribute mappings to predicates only; ``vars`` and
  ``var_types`` hold the last argument and the last sort of the predicate's first declaration in
  JSON, all of them in XML.  A literal without a mapping over a robot parameter is not printed.
"""
from __future__ import annotations

import itertools
from dataclasses import dataclass

from ..model import Configuration, Domain, InitialState, Literal, SemanticMapping
from .numbers import AtomKey
from .numbering import Listed

Printed = tuple[str, str, str]  # (predicate, vars, var_types)


@dataclass(frozen=True)
class Grounded:
    preconditions: tuple[Literal, ...]
    effects: tuple[Literal, ...]

    def ground_effects(self) -> dict[AtomKey, bool]:
        """The net effects on ground atoms (what a context dependency looks at)."""
        return {(e.predicate, e.args): e.positive for e in self.effects if not any(a.startswith("?") for a in e.args)}


def _ground(args: tuple[str, ...], values: dict[str, tuple[str, ...]]) -> list[tuple[str, ...]] | None:
    if not all(a in values for a in args):
        return None
    return [tuple(c) for c in itertools.product(*(values[a] for a in args))]


def ground_conditions(path: Listed, values: dict[str, tuple[str, ...]]) -> Grounded:
    """The decomposition's literals as the output lists them, before printing."""
    pre: list[Literal] = []
    net: dict[AtomKey, bool] = {}
    seen_ground: set[AtomKey] = set()
    seen_free: set[AtomKey] = set()
    for step in path.steps:
        for c in step.preconditions:
            if not isinstance(c, Literal):
                continue
            grounds = _ground(c.args, values)
            if grounds is None:
                if (c.predicate, c.args) not in seen_free:
                    pre.append(c)
                continue
            pre.extend(Literal(c.predicate, g, c.positive) for g in grounds if (c.predicate, g) not in seen_ground)
        for e in step.effects:
            grounds = _ground(e.args, values)
            keys = [(e.predicate, e.args)] if grounds is None else [(e.predicate, g) for g in grounds]
            (seen_free if grounds is None else seen_ground).update(keys)
            net.update((k, e.positive) for k in keys)
    return Grounded(tuple(pre), tuple(Literal(p, a, v) for (p, a), v in net.items()))


class Printer:
    """Literals of one task's decompositions as the output prints them."""

    def __init__(self, domain: Domain, config: Configuration, state: InitialState) -> None:
        self.domain = domain
        self.config = config
        self.sorts = state.sorts
        self.unprintable: list[str] = []  # literals no mapping prints (the decomposers refuse them)

    def _fits(self, m: SemanticMapping, lit: Literal, types: dict[str, str]) -> bool:
        if m.pred != lit.predicate or len(m.arg_sorts) < len(lit.args):
            return False
        for arg, sort in zip(lit.args, m.arg_sorts):
            if arg.startswith("?"):
                t = types.get(arg)
                if t is None or (sort != t and sort != self.domain.parent_of.get(t)):
                    return False
            elif arg not in self.sorts.get(sort, ()):
                return False
        return True

    def printed(self, lit: Literal, types: dict[str, str], xml: bool) -> Printed | None:
        m = next((m for m in self.config.semantic_mapping if self._fits(m, lit, types)), None)
        if m is None:
            if not any(a.startswith("?") and types.get(a) in ("robot", "robotteam") for a in lit.args):
                self.unprintable.append(f"{lit.predicate}({', '.join(lit.args)})")
            return None
        if m.type != "attribute" or m.mapped_type != "predicate":
            return None
        decls = self.domain.predicate_declarations(lit.predicate)
        sorts = tuple(p.type for p in decls[0].parameters) if decls else ()
        text = f"{'' if lit.positive else 'not '}{lit.args[0] if lit.args else ''}.{m.name}"
        if xml:
            return text, ",".join(lit.args), ",".join(sorts)
        return text, lit.args[-1] if lit.args else "", sorts[-1] if sorts else ""

    def listing(self, task: str, literals: tuple[Literal, ...], xml: bool) -> tuple[Printed, ...]:
        types = {p.name: p.type for p in self.domain.task_by_name[task].parameters}
        out = (self.printed(lit, types, xml) for lit in literals)
        return tuple(p for p in out if p is not None)
