"""Configuration reader, JSON or XML (spec ``config-and-knowledge.md`` §1–§4).

Every key the original reads is kept; problems are located by key path
(``configuration.json: semantic_mapping[2].map.pred``).
"""
from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property


@dataclass(frozen=True)
class WorldDbConfig:
    type: str
    file_type: str
    path: str
    xml_root: str | None
    unique_id: str = "name"


@dataclass(frozen=True)
class OutputConfig:
    output_type: str
    file_type: str  # "json" | "xml" (lower-cased)
    file_path: str


@dataclass(frozen=True)
class VarMapping:
    task_id: str
    pairs: tuple[tuple[str, str], ...]  # (gm_var, hddl_var)
    where: str = ""


@dataclass(frozen=True)
class SemanticMapping:
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
    source: str
    world_db: WorldDbConfig
    output: OutputConfig
    location_types: tuple[str, ...]
    agent_types: tuple[str, ...]
    type_mapping_entries: tuple[tuple[str, str], ...]  # (hddl_type, ocl_type) in file order
    var_mapping: tuple[VarMapping, ...]
    semantic_mapping: tuple[SemanticMapping, ...]

    @cached_property
    def type_mapping(self) -> dict[str, str]:
        """OCL type -> HDDL type (a later entry with the same OCL type wins)."""
        return {ocl: hddl for hddl, ocl in self.type_mapping_entries}
