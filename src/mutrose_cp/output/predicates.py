"""Predicates as the output prints them: a decomposition's literals turned into
``<arg>.<attribute>`` texts through the configuration's semantic mappings (spec ``output.md`` §2)."""
from __future__ import annotations

from dataclasses import dataclass
from typing import TYPE_CHECKING, Mapping

from ..errors import MissionError
from ..model import Configuration, Domain, InitialState, Literal, SemanticMapping
from ..model.task_graph import Decomposition

if TYPE_CHECKING:
    from ..model.decomposition_paths import GroundPredicates


@dataclass(frozen=True)
class PrintedPredicate:
    text: str  # "not RoomA.is_clean"
    args: tuple[str, ...]
    sorts: tuple[str, ...]  # argument sorts of the first HDDL declaration


class PredicatePrinter:
    """Turns decomposition literals into ``<arg>.<attribute>`` strings via semantic mappings."""

    def __init__(self, domain: Domain, config: Configuration, state: InitialState) -> None:
        self.domain = domain
        self.config = config
        self.sorts = state.sorts

    def _mapping(self, lit: Literal, types: Mapping[str, str],
                 real: Mapping[str, str] | None = None) -> SemanticMapping | None:
        """The first attribute mapping whose argument sorts fit ``lit`` (a ground argument fits a
        sort it belongs to; ``real`` names the value a placeholder stands for)."""
        for m in self.config.semantic_mapping:
            if m.pred != lit.predicate or len(m.arg_sorts) < len(lit.args):
                continue
            ok = True
            for arg, sort in zip(lit.args, m.arg_sorts):
                if arg.startswith("?"):
                    t = types.get(arg)
                    if t is None or (sort != t and sort != self.domain.parent_of.get(t)):
                        ok = False
                        break
                elif (real.get(arg, arg) if real else arg) not in self.sorts.get(sort, ()):
                    ok = False
                    break
            if ok:
                return m
        return None

    def render(self, lit: Literal, types: Mapping[str, str], dec: Decomposition,
               real: Mapping[str, str] | None = None) -> PrintedPredicate | None:
        m = self._mapping(lit, types, real)
        if m is None:
            robot_typed = any(a.startswith("?") and types.get(a) in ("robot", "robotteam") for a in lit.args)
            if any(a.startswith("?") for a in lit.args) and robot_typed:
                return None
            args = " ".join(lit.args)
            raise MissionError(
                f"No Semantic Mapping exists for predicate [{lit.predicate} {args}] when trying to generate "
                f"output for task {dec.instance.id}: {dec.instance.name} (add an attribute mapping for "
                f"'{lit.predicate}' to the configuration's semantic_mapping)",
                f"{self.config.source}: semantic_mapping",
            )
        if m.type != "attribute" or m.mapped_type != "predicate":
            return None
        decls = self.domain.predicate_declarations(lit.predicate)
        sorts = tuple(p.type for p in decls[0].parameters) if decls else ()
        prefix = "" if lit.positive else "not "
        first = lit.args[0] if lit.args else ""
        return PrintedPredicate(f"{prefix}{first}.{m.name}", lit.args, sorts)

    def printed(self, dec: Decomposition, predicates: GroundPredicates | None = None,
                real: Mapping[str, str] | None = None) -> tuple[list[PrintedPredicate], list[PrintedPredicate]]:
        """The preconditions and effects of ``dec`` as printed (of ``predicates`` instead, a
        grounding with placeholders whose values ``real`` names: see ``entry_templates``)."""
        grounded = predicates if predicates is not None else dec.predicates
        task = self.domain.task_by_name[dec.instance.name]
        types = {p.name: p.type for p in task.parameters}
        pre = [self.render(c, types, dec, real) for c in grounded.preconditions if isinstance(c, Literal)]
        eff = [self.render(e, types, dec, real) for e in grounded.effects]
        return [p for p in pre if p is not None], [e for e in eff if e is not None]
