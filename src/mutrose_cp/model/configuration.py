"""The mission configuration (spec ``config-and-knowledge.md`` §1–§4): where the world
knowledge and the output are, and how goal-model names map to HDDL.

Produced by :mod:`mutrose_cp.io.config` from JSON or XML (both forms of one configuration compare
equal); read by the world builder (type and semantic mappings), the expansion (variable
mappings) and the output writer.
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property


@dataclass(frozen=True)
class WorldDbConfig:
    """``world_db``: the world knowledge file and the element that holds its records."""

    type: str
    file_type: str
    path: str
    xml_root: str | None
    unique_id: str = "name"


@dataclass(frozen=True)
class OutputConfig:
    """``output``: where the decomposition is written and in which format."""

    output_type: str
    file_type: str  # "json" | "xml" (lower-cased)
    file_path: str


@dataclass(frozen=True)
class VarMapping:
    """``var_mapping``: goal-model variables -> parameters of the HDDL task of ``task_id``."""

    task_id: str
    pairs: tuple[tuple[str, str], ...]  # (gm_var, hddl_var)
    where: str = ""


@dataclass(frozen=True)
class SemanticMapping:
    """``semantic_mapping``: how world records become HDDL predicates or functions."""

    type: str  # "attribute" | "ownership" | "relationship" (lower-cased)
    mapped_type: str  # "predicate" | "function" (lower-cased)
    pred: str
    arg_sorts: tuple[str, ...]
    belongs_to: str = ""
    name: str = ""  # attribute
    relates_to: str = ""  # attribute
    owner: str = ""  # ownership
    owned: str = ""  # ownership
    main_entity: str = ""  # relationship
    related_entity: str = ""  # relationship
    relationship_type: str = ""
    attribute_name: str = ""
    predicate_type: str | None = None
    where: str = ""  # key path, for messages


@dataclass(frozen=True)
class Configuration:
    """A whole configuration file, as read."""

    source: str
    world_db: WorldDbConfig
    output: OutputConfig
    location_types: tuple[str, ...]
    agent_types: tuple[str, ...]
    type_mapping_entries: tuple[tuple[str, str], ...]  # (hddl_type, ocl_type) in file order
    var_mapping: tuple[VarMapping, ...]
    semantic_mapping: tuple[SemanticMapping, ...]
    warnings: tuple[str, ...] = ()  # located, non-fatal remarks (e.g. missing xml_root)
    # an uncertainty file (docs/formats/uncertainty.md), relative to the configuration; the
    # original ignores the key
    uncertainty_path: str | None = None

    def locate(self, key_path: str) -> str:
        """``Problem.where`` for a key path such as ``SemanticMapping.where``
        (``configuration.json: semantic_mapping[2]``); the paths stored in the model carry no
        file name so that the JSON and XML forms of one configuration compare equal."""
        return f"{self.source}: {key_path}" if key_path else self.source

    @cached_property
    def type_mapping(self) -> dict[str, str]:
        """OCL type -> HDDL type (a later entry with the same OCL type wins)."""
        return {ocl: hddl for hddl, ocl in self.type_mapping_entries}
