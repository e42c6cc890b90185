"""The entries of an uncertainty file resolved against the mission: each entity's attribute
becomes the ground atom the configuration's semantic mapping reads it as (spec
``config-and-knowledge.md`` section 6), checked so that a typo never makes a fact silently
certain.

What the goal model reads (queries, contexts, achieve and forAll conditions) decides which task
instances exist, before any decomposition: an uncertain attribute read there is *expanded* (the
mission is expanded once per value, ``pipeline/scenarios.py``).  It need not be mapped to HDDL;
when it is, the expansion's world gives the domain the same value.
"""
from __future__ import annotations

from dataclasses import replace
from typing import Iterable, Iterator, NamedTuple

from ..errors import MissionError, Problem, closest
from ..model import Configuration, GoalModel, SemanticMapping, WorldKnowledge
from ..model.expressions import Atom, BoolOp, Condition
from ..model.uncertainty import AtomKey, Joint, JointEntry, UncertainEntry, UncertainFact, Uncertainty


def resolve_uncertainty(entries: Iterable[UncertainEntry], source: str, config: Configuration,
                        sorts: dict[str, frozenset[str]], goal_model: GoalModel,
                        joints: Iterable[JointEntry] = (), knowledge: WorldKnowledge | None = None) -> Uncertainty:
    """The uncertain facts of the mission and their joint tables; every problem at once (exit 2).
    ``knowledge``: the world, whose records an attribute the goal model reads must belong to."""
    problems: list[Problem] = []
    facts: list[UncertainFact] = []
    seen: set[tuple[str, tuple[str, ...]]] = set()
    read = _first_readings(goal_model)
    mappings = _AttributeMappings(config, sorts, knowledge)
    for entry in entries:
        if entry.attribute == config.world_db.unique_id:
            problems.append(Problem(entry.where, f"{entry.entity}.{entry.attribute}: {entry.attribute} is the unique id "
                                                 "that names the entity (world_db.unique_id), not a fact about it"))
            continue
        try:
            fact = _goal_fact(entry, read[entry.attribute], mappings, knowledge) if entry.attribute in read \
                else mappings.resolve(entry)
        except MissionError as err:
            problems.extend(err.problems)
            continue
        taken = next((atom for atom in fact.atoms if atom in seen), None)
        if taken is not None:
            problems.append(Problem(entry.where, f"{entry.entity}.{entry.attribute} is the fact "
                                                 f"{taken[0]}({', '.join(taken[1])}), already uncertain by an earlier entry"))
            continue
        seen.update(fact.atoms)
        facts.append(fact)
    tables = _joints(joints, facts, problems)
    for table in tables:
        if len({bool(f.read_by_goal) for f in table.facts}) > 1:
            expanded = next(f for f in table.facts if f.read_by_goal)
            problems.append(Problem(table.facts[0].entry.where, f"a joint table links {expanded.text}, which "
                                    f"{expanded.read_by_goal}, with facts the goal model does not read: a table holds "
                                    "either kind, not both"))
    if problems:
        raise MissionError(problems)
    # a fact of a joint table has the marginal of the table as its probabilities
    marginal = {f.atom: tuple(j.probability({f.atom: v}) for v in f.values) for j in tables for f in j.facts}
    resolved = tuple(replace(f, probabilities=marginal[f.atom]) if f.atom in marginal else f for f in facts)
    by_atom = {f.atom: f for f in resolved}
    tables = [Joint(tuple(by_atom[f.atom] for f in j.facts), j.outcomes) for j in tables]
    return Uncertainty(source, resolved, tuple(tables))


def _first_readings(goal_model: GoalModel) -> dict[str, GoalReading]:
    """Each attribute the goal model reads: where first, and the kind of value, when the
    conditions that tell agree (one read bare and one compared tell nothing)."""
    read: dict[str, GoalReading] = {}
    kinds: dict[str, set[str]] = {}
    for attribute, reading in goal_model_reads(goal_model):
        read.setdefault(attribute, reading)
        if reading.kind:
            kinds.setdefault(attribute, set()).add(reading.kind)
    return {a: r._replace(kind=next(iter(kinds[a])) if len(kinds.get(a, ())) == 1 else "") for a, r in read.items()}


def _joints(joints: Iterable[JointEntry], facts: list[UncertainFact], problems: list[Problem]) -> list[Joint]:
    """The joint tables over the resolved facts: each names uncertain entries given without
    probabilities of their own, once, with values they may take."""
    by_name = {(f.entry.entity, f.entry.attribute): f for f in facts}
    tables: list[Joint] = []
    placed: dict[tuple[str, str], str] = {}
    for j in joints:
        found: list[UncertainFact] = []
        for name in j.facts:
            fact = by_name.get(name)
            if fact is None:
                problems.append(Problem(j.where, f"{name[0]}.{name[1]}: a joint table names only facts listed under "
                                                 '"uncertain"'))
            elif fact.entry.probabilities is not None:
                problems.append(Problem(fact.entry.where, f"{fact.text} has probabilities of its own and a joint table "
                                                          f"at {j.where}: give them in one place"))
            elif placed.setdefault(name, j.where) != j.where:
                problems.append(Problem(j.where, f"{fact.text} is in the joint table at {placed[name]} already"))
            else:
                found.append(fact)
        if len(found) != len(j.facts):
            continue
        bad = [(outcome, f) for outcome, _ in j.outcomes for f, v in zip(found, outcome)
               if v not in f.values or isinstance(v, bool) == f.numeric]
        if bad:
            outcome, fact = bad[0]
            problems.append(Problem(j.where, f"the outcome {list(outcome)} gives {fact.text} a value it cannot take "
                                             f"(one of {', '.join(str(v) for v in fact.values)})"))
            continue
        tables.append(Joint(tuple(found), j.outcomes))
    return tables


def _goal_fact(entry: UncertainEntry, read: "GoalReading", mappings: "_AttributeMappings",
               knowledge: WorldKnowledge | None) -> UncertainFact:
    """An entry whose attribute the goal model reads: the atom the domain reads it as, when the
    configuration maps it for the entity's type, else the attribute itself; the entity must be a
    record of the world, and the entry's kind (a probability of true, or numbers) the kind the
    mapping, or else the goal model's condition, reads."""
    reader = f"goal {read.goal} reads {entry.attribute} ({read.text})"
    entities = knowledge.entity_names if knowledge is not None else frozenset()  # read only when needed
    if entry.entity not in entities:
        guess = closest(entry.entity, sorted(entities))
        raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute}: the world has no record "
                                                f"{entry.entity}" + (f" (did you mean {guess}?)" if guess else "")))
    mapped = mappings.mapping_for(entry)
    if mapped is not None:  # else mapped for other types only: the goal model alone reads it of this entity
        return replace(_fact(entry, *mapped), read_by_goal=reader)
    if read.kind == "predicate" and entry.numeric:
        raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute}: {reader} as a boolean: give "
                                                '"probability" (of true), or nothing, not numeric values'))
    if read.kind == "function" and not entry.numeric:
        raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute}: {reader} as a number: give its "
                                                'possible "values" or a "distribution", not a probability of true'))
    values = entry.values if entry.numeric else (False, True)
    assert values is not None
    return UncertainFact(entry, (entry.attribute, (entry.entity,)), entry.numeric, values, entry.probabilities,
                         read_by_goal=reader)


class _AttributeMappings:
    """The configuration's attribute mappings by attribute name, read once for every entry."""

    def __init__(self, config: Configuration, sorts: dict[str, frozenset[str]],
                 knowledge: WorldKnowledge | None = None) -> None:
        self.config = config
        self.sorts = sorts
        self.knowledge = knowledge
        self.by_name: dict[str, list[SemanticMapping]] = {}
        for m in config.semantic_mapping:
            if m.type == "attribute" and m.mapped_type in ("predicate", "function") and m.relates_to.lower() != "robot":
                self.by_name.setdefault(m.name, []).append(m)

    def mapping_for(self, entry: UncertainEntry) -> tuple[tuple[AtomKey, ...], bool, str] | None:
        """The atoms the domain reads the entry's attribute of its entity as (every mapping of
        the attribute for the entity's type: each starts with the fact's value), whether they are
        functions, and the first one's name; None when no mapping is for the entity's type.  An
        attribute mapped to a predicate and to a function is refused: one value cannot be both."""
        candidates = [m for m in self.by_name.get(entry.attribute, [])
                      if (hddl := self.config.type_mapping.get(m.relates_to)) is not None
                      and entry.entity in self.sorts.get(hddl, frozenset())]
        if len({m.relates_to for m in candidates}) > 1 and self.knowledge is not None:
            # types that share an HDDL sort (Room and Pharmacy as room): the world reads a
            # mapping of the records of its type only (the scan is made only for such a case)
            tags = self.knowledge.entity_tags.get(entry.entity, frozenset())
            candidates = [m for m in candidates if m.relates_to in tags]
        found: list[tuple[AtomKey, SemanticMapping]] = []
        for m in candidates:
            hddl = self.config.type_mapping[m.relates_to]
            atom = (m.pred, (entry.entity,) * sum(1 for s in m.arg_sorts if s == hddl))
            if all(atom != earlier for earlier, _ in found):
                found.append((atom, m))
        if not found:
            return None
        kinds = {m.mapped_type for _, m in found}
        if len(kinds) > 1:
            names = " and ".join(f"the {m.mapped_type} {m.pred}" for _, m in found)
            raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute} is mapped to {names}: one "
                                                    "uncertain value cannot be both a truth value and a number"))
        return tuple(atom for atom, _ in found), found[0][1].mapped_type == "function", found[0][1].pred

    def resolve(self, entry: UncertainEntry) -> UncertainFact:
        config, sorts = self.config, self.sorts
        mappings = self.by_name.get(entry.attribute, [])
        if not mappings:
            attributes = [m for m in config.semantic_mapping if m.type == "attribute" and m.name]
            if any(m.name == entry.attribute for m in attributes):
                raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute}: the configuration maps "
                                                        f"{entry.attribute} only for robots or to no predicate or "
                                                        "function, which the decomposer does not read of the world"))
            guess = closest(entry.attribute, sorted({m.name for m in attributes}))
            raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute}: the configuration maps no "
                                                    f"attribute {entry.attribute} to a predicate or function"
                                                    + (f" (did you mean {guess}?)" if guess else "")))
        found = self.mapping_for(entry)
        if found is not None:
            return _fact(entry, *found)
        types = " or ".join(sorted({m.relates_to for m in mappings}))
        known = sorted({e for m in mappings for e in sorts.get(config.type_mapping.get(m.relates_to, ""), frozenset())})
        guess = closest(entry.entity, known)
        raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute}: the world has no {types} "
                                                f"{entry.entity}" + (f" (did you mean {guess}?)" if guess else "")))


def _fact(entry: UncertainEntry, atoms: tuple[AtomKey, ...], numeric: bool, name: str) -> UncertainFact:
    boolean = not entry.numeric
    if numeric and boolean:
        raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute} is the function {name}: give its "
                                                'possible "values" or a "distribution", not a probability of true'))
    if not numeric and not boolean:
        raise MissionError(Problem(entry.where, f"{entry.entity}.{entry.attribute} is the predicate {name}: give "
                                                '"probability" (of true), or nothing, not numeric values'))
    values = (False, True) if boolean else entry.values
    assert values is not None
    return UncertainFact(entry, atoms[0], numeric, values, entry.probabilities, aliases=atoms[1:])


class GoalReading(NamedTuple):
    """Where the goal model reads an attribute: the goal, its condition, and the kind of value
    the condition reads (``predicate`` for a bare ``r.a``, ``function`` for a comparison of
    order, ``""`` when it cannot tell: an equality, a membership, a right-hand side)."""

    goal: str
    text: str
    kind: str


def goal_model_reads(gm: GoalModel) -> Iterator[tuple[str, GoalReading]]:
    """(attribute, where and how) for each attribute a goal-model condition reads."""
    for node in gm.nodes:
        conditions: list[tuple[Condition | None, str]] = []
        if node.query is not None:
            conditions.append((node.query.condition, node.query.text))
        if node.forall is not None:
            conditions.append((node.forall.condition, node.forall.text))
        if node.achieve_condition is not None:
            conditions.append((node.achieve_condition, node.achieve_text))
        if node.context is not None and node.context.condition is not None:
            conditions.append((node.context.condition, node.context.text))
        for condition, text in conditions:
            for atom in _atoms(condition):
                if atom.attribute:
                    yield atom.attribute, GoalReading(node.id, text, _kind(atom))
                for attribute in _dotted(atom.value):
                    yield attribute, GoalReading(node.id, text, "")


def _kind(atom: Atom) -> str:
    if atom.op is None:
        return "predicate"
    return "function" if atom.op in (">", "<", ">=", "<=") else ""


def _atoms(condition: Condition | None) -> Iterator[Atom]:
    if isinstance(condition, Atom):
        yield condition
    elif isinstance(condition, BoolOp):
        for child in condition.children:
            yield from _atoms(child)


def _dotted(value: str) -> list[str]:
    """The attribute of a right-hand side ``r.patients`` (none for a constant)."""
    return [value.split(".", 1)[1]] if "." in value and not value.replace(".", "", 1).isdigit() else []
