"""World objects (HDDL sorts) and the initial world state (spec ``config-and-knowledge.md``
§5.1 and §6).

The original builds the state from the world knowledge through the configuration's semantic
mappings only: there is no closed-world assumption, HDDL ``:init`` is never read, and only
ownership mappings yield explicit negative facts.  Everything here reproduces that, in the
original's order (mapping order, document order, ``std::set`` order for sort members), because
literal order is visible: the first matching literal decides a look-up.
"""
from __future__ import annotations

from typing import Iterator, NoReturn

from lxml import etree

from ..errors import MissionError, Problem, located
from ..io.knowledge import number_is_partial, parse_bool, parse_number
from ..io.tolerant_xml import source_line
from ..model import Configuration, Domain, GroundLiteral, InitialState, Number, SemanticMapping, WorldKnowledge
from ..model.records import child, element_children, text_of

# ---------------------------------------------------------------------------------------------
# Traversal


def _descendable(el: etree._Element) -> bool:
    """The original descends into elements with child elements and only whitespace text."""
    return len(el) > 0 and text_of(el) == ""


def _traverse(root: etree._Element, tags: str | tuple[str, ...], stop_at_tag: bool) -> Iterator[etree._Element]:
    """Pre-order over the elements below ``root`` with one of ``tags``, reachable through
    descendable containers (and, with ``stop_at_tag``, not through an element of the same tag).

    Implemented with lxml's C-level ``iter`` plus an ancestor check instead of a Python
    recursion over every element, which keeps 5000-record worlds fast."""
    tag_set = {tags} if isinstance(tags, str) else set(tags)
    tag_args = (tags,) if isinstance(tags, str) else tags
    ok_cache: dict[etree._Element, bool] = {}
    for el in root.iter(*tag_args):
        if el is root:
            continue
        parent = el.getparent()
        good = True
        chain: list[etree._Element] = []
        while parent is not None and parent is not root:
            cached = ok_cache.get(parent)
            if cached is not None:
                good = cached
                break
            chain.append(parent)
            if not _descendable(parent) or (stop_at_tag and parent.tag in tag_set):
                good = False
                break
            parent = parent.getparent()
        for c in chain:
            # every element of the chain below a failing one is unreachable as well
            ok_cache[c] = good
        if good:
            yield el


# ---------------------------------------------------------------------------------------------
# Sorts (§5.1)


def build_sorts(domain: Domain, config: Configuration, knowledge: WorldKnowledge) -> dict[str, frozenset[str]]:
    """HDDL sort -> objects: location records, every type-mapped element of the knowledge
    (exact mapped type only) and the domain constants (propagated to their supertypes)."""
    type_mapping = config.type_mapping
    uid = knowledge.unique_id
    sorts: dict[str, set[str]] = {t: set() for t, _ in domain.types}
    for hddl in type_mapping.values():
        sorts.setdefault(hddl, set())

    # 1. direct records of a location type
    location_types = set(config.location_types)
    for rec in knowledge.records:
        if rec.tag in location_types and rec.tag in type_mapping:
            rid = knowledge.record_id(rec)
            if rid is None:
                _missing_id(knowledge, rec)
            sorts[type_mapping[rec.tag]].add(rid)

    # 2. every element whose tag is a mapped OCL type, through descendable containers
    mapped_tags = tuple(t for t in type_mapping if t)
    if mapped_tags:
        for el in _traverse(knowledge.root, mapped_tags, stop_at_tag=False):
            id_el = child(el, uid)
            if id_el is None:
                _missing_id(knowledge, el)
            sorts[type_mapping[el.tag]].add(text_of(id_el))

    # 3. constants, in their type and every supertype
    parent_of = domain.parent_of
    for const, ctype in domain.constants:
        t: str | None = ctype
        seen: set[str] = set()
        while t is not None and t not in seen:
            seen.add(t)
            sorts.setdefault(t, set()).add(const)
            t = parent_of.get(t)
    return {t: frozenset(objs) for t, objs in sorts.items()}


def _missing_id(knowledge: WorldKnowledge, el: etree._Element) -> NoReturn:
    """The original aborts with ``No such node (name)``; we say which element lacks it."""
    raise MissionError(Problem(
        located(knowledge.source, source_line(el)),
        f"element <{el.tag}> is a type-mapped record but has no <{knowledge.unique_id}> child "
        f"(its unique id); do not use a mapped type name as a plain field tag: every <{el.tag}> "
        f"element is read as a {el.tag} record (type_mapping), so give it a <{knowledge.unique_id}> "
        f"child or rename the field",
    ))


# ---------------------------------------------------------------------------------------------
# Initial state (§6)


def build_initial_state(domain: Domain, config: Configuration, knowledge: WorldKnowledge) -> InitialState:
    """Apply the semantic mappings to the knowledge, in mapping order."""
    sorts = build_sorts(domain, config, knowledge)
    records = _RecordCache(knowledge)
    literals: list[GroundLiteral] = []
    functions: list[tuple[tuple[str, tuple[str, ...]], Number]] = []
    warnings: list[str] = []
    for mapping in config.semantic_mapping:
        if mapping.type == "attribute":
            _attribute(mapping, config, records, sorts, literals, functions, warnings, knowledge.source)
        elif mapping.type == "ownership" and mapping.mapped_type == "predicate":
            _ownership(mapping, config, records, sorts, literals)
        # relationship mappings add nothing [bug of the original, reproduced]
    return InitialState(sorts=sorts, literals=tuple(literals), functions=tuple(functions), warnings=tuple(warnings))


class _RecordCache:
    """Per tag, the records a mapping traversal reaches, with their id and first child per
    field tag.  Several mappings usually relate to the same type (VSM: five Patient
    attributes), so each record's children are read once instead of once per mapping."""

    def __init__(self, knowledge: WorldKnowledge) -> None:
        self.knowledge = knowledge
        self._cache: dict[str, list[tuple[etree._Element, str, dict[str, etree._Element]]]] = {}

    def of(self, tag: str) -> list[tuple[etree._Element, str, dict[str, etree._Element]]]:
        found = self._cache.get(tag)
        if found is None:
            uid = self.knowledge.unique_id
            found = []
            for el in _traverse(self.knowledge.root, tag, stop_at_tag=True):
                kids = list(element_children(el))
                kids.reverse()  # the first child of a tag wins, as in PropertyTree
                fields = {k.tag: k for k in kids}
                id_el = fields.get(uid)
                if id_el is not None:
                    found.append((el, text_of(id_el), fields))
            self._cache[tag] = found
        return found


def _attribute(
    m: SemanticMapping,
    config: Configuration,
    records: _RecordCache,
    sorts: dict[str, frozenset[str]],
    literals: list[GroundLiteral],
    functions: list[tuple[tuple[str, tuple[str, ...]], Number]],
    warnings: list[str],
    knowledge_source: str,
) -> None:
    if m.relates_to.lower() == "robot" or m.mapped_type not in ("predicate", "function"):
        return  # robot attributes only serve the output; there is no robot knowledge
    hddl = config.type_mapping.get(m.relates_to)
    if hddl is None or not m.relates_to:
        return
    members = sorts.get(hddl, frozenset())
    copies = sum(1 for s in m.arg_sorts if s == hddl)
    name, pred = m.name, m.pred
    is_predicate = m.mapped_type == "predicate"
    for _, rid, fields in records.of(m.relates_to):
        if rid not in members:
            continue
        value_el = fields.get(name)
        if value_el is None:
            continue  # unknown
        args = (rid,) * copies
        if is_predicate:
            literals.append(GroundLiteral(pred, args, parse_bool(text_of(value_el))))
        else:
            text = text_of(value_el)
            value = parse_number(text)
            if number_is_partial(text):
                warnings.append(f"{located(knowledge_source, source_line(value_el))}: {m.relates_to} {rid}: {name} "
                                f"{text.strip()!r} is read as {value}, as the original reads numbers (the longest "
                                "number at its start, else 0); write a plain number")
            functions.append(((pred, args), value))


def _ownership(
    m: SemanticMapping,
    config: Configuration,
    records: _RecordCache,
    sorts: dict[str, frozenset[str]],
    literals: list[GroundLiteral],
) -> None:
    """``pred(owned, owner)`` for every owned object an owner record lists, and ``not
    pred(owned, owner)`` for every other object of the owned sort: the one mapping that yields
    explicit negative facts (the original's closed world per owner)."""
    if m.owner.lower() == "robot" or m.owned.lower() == "robot":
        return
    owner_sort = config.type_mapping.get(m.owner)
    owned_sort = config.type_mapping.get(m.owned)
    if owner_sort is None or owned_sort is None or not m.owner:
        return
    owners = sorts.get(owner_sort, frozenset())
    owned_objects = sorted(sorts.get(owned_sort, frozenset()))  # std::set order
    owned_members = frozenset(owned_objects)
    for _, owner_id, fields in records.of(m.owner):
        if owner_id not in owners:
            continue
        container = fields.get(m.attribute_name) if m.attribute_name else None
        listed = _listed_objects(m, container, records.knowledge.unique_id, owned_members)
        for oid in listed:
            literals.append(GroundLiteral(m.pred, (oid, owner_id), True))
        listed_set = set(listed)
        for oid in owned_objects:
            if oid not in listed_set:
                literals.append(GroundLiteral(m.pred, (oid, owner_id), False))


def _listed_objects(
    m: SemanticMapping, container: etree._Element | None, uid: str, owned_members: frozenset[str]
) -> list[str]:
    """Ids of the owned records an owner's ``attribute_name`` field lists, in document order,
    restricted to objects of the owned sort."""
    listed: list[str] = []
    if container is None or not m.owned:
        return listed
    for item in container.iterchildren(tag=m.owned):
        item_id = child(item, uid)
        if item_id is None:
            continue
        oid = text_of(item_id)
        if oid in owned_members:
            listed.append(oid)
    return listed
