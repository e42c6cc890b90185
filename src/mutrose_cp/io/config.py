"""Configuration reader, JSON or XML (spec ``config-and-knowledge.md`` §1–§4).

Both formats give the frozen :class:`~mutrose_cp.model.Configuration`.  Every key the original
reads is kept; problems are located by key path
(``configuration.json: semantic_mapping[2].map.pred``).
"""
from __future__ import annotations

import os
from typing import Any, Callable

from lxml import etree

from ..errors import MissionError, Problem, closest, located
from ..model.configuration import Configuration, OutputConfig, SemanticMapping, VarMapping, WorldDbConfig
from ..model.records import element_children, text_of
from .text import decode_utf8, parse_json, read_bytes
from .tolerant_xml import parse_tolerant_xml, source_line

# ---------------------------------------------------------------------------------------------
# Reading
#
# Both formats are first turned into the same plain structure (dicts of strings, lists), the
# shape PropertyTree gives the original; one validator then reads every key and collects all
# problems, so a user sees every mistake of a configuration at once.

_MISSING: Any = object()
SEMANTIC_TYPES = ("attribute", "ownership", "relationship")
MAPPED_TYPES = ("predicate", "function")


def load_configuration(path: str | os.PathLike[str], *, lenient: bool = False) -> Configuration:
    """Read a configuration file; JSON if the extension (upper-cased) is ``JSON``, else XML."""
    source = os.fspath(path)
    data = read_bytes(path, "configuration")
    ext = source.rsplit(".", 1)[-1].upper() if "." in os.path.basename(source) else ""
    if ext == "JSON":
        return parse_configuration_json(decode_utf8(data, source, "configuration"), source)
    return parse_configuration_xml(data, source, lenient=lenient)


def parse_configuration_json(text: str, source: str) -> Configuration:
    """Parse a JSON configuration.  Scalars are kept as the text PropertyTree would store
    (numbers verbatim, ``true``/``false``/``null``)."""
    data = parse_json(text, source, parse_int=str, parse_float=str, parse_constant=str)
    if not isinstance(data, dict):
        raise MissionError(Problem(source, "the configuration must be a JSON object"))
    return _Builder(source).build(data)


def parse_configuration_xml(data: bytes | str, source: str, *, lenient: bool = False) -> Configuration:
    """Parse an XML configuration (root ``<configuration>``), tolerating, with a warning, the
    mismatched end tags of the shipped files (``<location_types> ... </location_type>``)."""
    builder = _Builder(source)
    root = parse_tolerant_xml(data, source, "configuration", lenient=lenient, warnings=builder.warnings)
    if root.tag != "configuration":
        raise MissionError(Problem(
            located(source, source_line(root)),
            f"missing key configuration (the root element is <{root.tag}>)",
        ))
    return builder.build(_xml_to_plain(root, builder))


def _xml_dict(el: etree._Element) -> dict[str, Any]:
    """Element children as a dict (tag -> text or nested dict); a repeated tag: last wins."""
    out: dict[str, Any] = {}
    for c in element_children(el):
        out[c.tag] = _xml_dict(c) if len(c) and next(element_children(c), None) is not None else text_of(c)
    return out


def _last_child(el: etree._Element, tag: str) -> etree._Element | None:
    found = None
    for c in el.iterchildren(tag=tag):
        found = c
    return found


def _xml_to_plain(root: etree._Element, builder: "_Builder") -> dict[str, Any]:
    """The XML schema of spec §3 mapped onto the JSON shape (spec §2)."""
    data: dict[str, Any] = {}
    for c in element_children(root):
        tag = c.tag
        if tag in ("world_db", "output"):
            data[tag] = _xml_dict(c)
        elif tag in ("location_types", "agent_types"):
            data[tag] = [text_of(t) for t in element_children(c)]
        elif tag == "type_mapping":
            data[tag] = [_xml_dict(m) for m in element_children(c)]
        elif tag == "var_mapping":
            data[tag] = [_xml_var_mapping(m) for m in element_children(c)]
        elif tag == "semantic_mapping":
            data[tag] = [_xml_semantic_mapping(m, i, builder) for i, m in enumerate(element_children(c))]
        else:
            data[tag] = _xml_dict(c)  # unknown keys are ignored by the validator
    return data


def _xml_var_mapping(m: etree._Element) -> dict[str, Any]:
    """``<mapping><task_id>AT1</task_id><map gm_var="r" hddl_var="?r"/>...</mapping>``."""
    entry: dict[str, Any] = {}
    task = _last_child(m, "task_id")
    if task is not None:
        entry["task_id"] = text_of(task)
    entry["map"] = [
        {k: v for k, v in mp.attrib.items() if k in ("gm_var", "hddl_var")}
        for mp in m.iterchildren(tag="map")
    ]
    return entry


def _xml_semantic_mapping(m: etree._Element, index: int, builder: "_Builder") -> dict[str, Any]:
    """A semantic mapping: its fields, and its ``<map>`` read by :func:`_xml_map`."""
    entry = _xml_dict(m)
    mp = _last_child(m, "map")
    if mp is not None:
        entry["map"] = _xml_map(mp, f"semantic_mapping[{index}].map", builder)
    return entry


def _xml_map(mp: etree._Element, path: str, builder: "_Builder") -> dict[str, Any]:
    """``<map><pred>p</pred><arg_sorts number="N">s1 s2</arg_sorts></map>``: the first N
    whitespace-separated tokens are the argument sorts."""
    out: dict[str, Any] = {}
    pred = _last_child(mp, "pred")
    if pred is not None:
        out["pred"] = text_of(pred)
    sorts = _last_child(mp, "arg_sorts")
    hint = (
        'The number attribute says how many sorts are listed, e.g. <arg_sorts number="2">obj '
        "storage</arg_sorts>."
    )
    if sorts is not None:
        tokens = text_of(sorts).split()
        number = sorts.get("number")
        if number is None:
            builder.problem(f"{path}.arg_sorts", "missing attribute [number] in arg_sorts", hint)
            out["arg_sorts"] = tokens
        else:
            try:
                n = int(number.strip())
            except ValueError:
                builder.problem(f"{path}.arg_sorts", f"invalid attribute number [{number}] in arg_sorts",
                                hint)
                n = len(tokens)
            if n < 0 or n > len(tokens):
                builder.problem(
                    f"{path}.arg_sorts", f"arg_sorts declares {number.strip()} sorts but lists {len(tokens)}",
                    hint,
                )
            out["arg_sorts"] = tokens[: max(n, 0)]
    return out


class _Builder:
    """Validates the plain structure and builds the :class:`Configuration`."""

    def __init__(self, source: str) -> None:
        self.source = source
        self.problems: list[Problem] = []
        self.warnings: list[str] = []

    # -- reporting ----------------------------------------------------------------------------

    def problem(self, path: str, message: str, hint: str = "") -> None:
        self.problems.append(Problem(f"{self.source}: {path}", message, hint))

    def warn(self, path: str, message: str) -> None:
        self.warnings.append(f"{self.source}: {path}: {message}")

    # -- typed access -------------------------------------------------------------------------

    def scalar(self, obj: dict[str, Any], key: str, path: str, missing: str | None = None) -> str | None:
        """``obj[key]`` as a string; a missing key reports ``missing`` (default ``missing key``)."""
        value = obj.get(key, _MISSING)
        full = f"{path}.{key}" if path else key
        if value is _MISSING:
            if missing is not None:
                self.problem(full, missing)
            return None
        if isinstance(value, bool):
            return "true" if value else "false"
        if value is None:
            return "null"
        if isinstance(value, str):
            return value
        self.problem(full, f"expected a value, found {'a list' if isinstance(value, list) else 'an object'}")
        return None

    def choice(self, obj: dict[str, Any], key: str, path: str, missing: str, allowed: tuple[str, ...],
               unsupported: str, hint: str) -> str | None:
        """A required key whose lower-cased value must be one of ``allowed``; ``unsupported``
        is formatted with the value as written.  None (problem reported) otherwise."""
        value = self.scalar(obj, key, path, missing)
        if value is None:
            return None
        if value.lower() not in allowed:
            self.problem(f"{path}.{key}", unsupported.format(value), hint)
            return None
        return value.lower()

    def obj(self, value: Any, path: str) -> dict[str, Any] | None:
        if isinstance(value, dict):
            return value
        if isinstance(value, str) and not value.strip():
            return {}  # an empty XML element / empty JSON string: no children
        self.problem(path, "expected an object")
        return None

    def lst(self, value: Any, path: str) -> list[Any] | None:
        if isinstance(value, list):
            return value
        if isinstance(value, str) and not value.strip() or value == {}:
            return []
        self.problem(path, "expected a list")
        return None

    def strings(self, value: Any, path: str) -> tuple[str, ...]:
        items = self.lst(value, path)
        out: list[str] = []
        for i, item in enumerate(items or ()):
            if isinstance(item, (dict, list)):
                self.problem(f"{path}[{i}]", "expected a string")
            else:
                out.append(self.scalar({"_": item}, "_", "") or "")
        return tuple(out)

    # -- sections -----------------------------------------------------------------------------

    def build(self, data: dict[str, Any]) -> Configuration:
        world_db = self.world_db(data)
        output = self.output(data)
        location_types = self.strings(data.get("location_types", []), "location_types")
        agent_types = self.strings(data.get("agent_types", []), "agent_types")
        type_mapping = self.type_mapping(data.get("type_mapping", []))
        var_mapping = self.var_mapping(data)
        semantic = self.semantic_mapping(data)
        uncertainty = data.get("uncertainty")
        if uncertainty is not None and (not isinstance(uncertainty, str) or not uncertainty.strip()):
            self.problem("uncertainty", "expected the path of an uncertainty file (docs/formats/uncertainty.md)")
            uncertainty = None
        if self.problems or world_db is None or output is None:
            raise MissionError(self.problems)
        return Configuration(
            source=self.source,
            world_db=world_db,
            output=output,
            location_types=location_types,
            agent_types=agent_types,
            type_mapping_entries=type_mapping,
            var_mapping=var_mapping,
            semantic_mapping=semantic,
            warnings=tuple(self.warnings),
            uncertainty_path=uncertainty.strip() if uncertainty else None,
        )

    def world_db(self, data: dict[str, Any]) -> WorldDbConfig | None:
        if "world_db" not in data:
            self.problem("world_db", "Knowledge [world_db] was not defined in the configuration file")
            return None
        wd = self.obj(data["world_db"], "world_db")
        if wd is None:
            return None
        db_type = self.choice(wd, "type", "world_db", "Database type for [world_db] was not defined", ("file",),
                              "Database type [{}] is not supported", "The only supported database type is file.")
        file_type = self.choice(wd, "file_type", "world_db", "Database file type for [world_db] was not defined",
                                ("xml",), "Database file type [{}] is not supported",
                                "The only supported database file type is xml.")
        path = self.scalar(wd, "path", "world_db", "Missing attributes [path] in world_db definition")
        xml_root = self.scalar(wd, "xml_root", "world_db")
        if not xml_root:
            # the original prints a warning and waits for ENTER; we never block on stdin
            self.warn(
                "world_db.xml_root",
                "xml_root was not defined: the document root element is used as the record container",
            )
            xml_root = None
        unique_id = self.scalar(wd, "unique_id", "world_db") or "name"
        if db_type is None or file_type is None or path is None:
            return None
        return WorldDbConfig(db_type, file_type, path, xml_root, unique_id)

    def output(self, data: dict[str, Any]) -> OutputConfig | None:
        if "output" not in data:
            self.problem("output", "Output [output] was not defined in the configuration file")
            return None
        out = self.obj(data["output"], "output")
        if out is None:
            return None
        output_type = self.choice(out, "output_type", "output", "missing key output.output_type", ("file",),
                                  "Output type [{}] is not supported",
                                  "The only supported output type is file (the output is written to output.file_path).")
        file_type = self.choice(out, "file_type", "output", "missing key output.file_type", ("json", "xml"),
                                "File type [{}] is not supported", "Use json or xml.")
        file_path = self.scalar(out, "file_path", "output", "missing key output.file_path")
        if output_type is None or file_type is None or file_path is None:
            return None
        return OutputConfig(output_type, file_type, file_path)

    def type_mapping(self, value: Any) -> tuple[tuple[str, str], ...]:
        out: list[tuple[str, str]] = []
        for i, entry in enumerate(self.lst(value, "type_mapping") or ()):
            path = f"type_mapping[{i}]"
            e = self.obj(entry, path)
            if e is None:
                continue
            hddl = self.scalar(e, "hddl_type", path, "missing key hddl_type")
            ocl = self.scalar(e, "ocl_type", path, "missing key ocl_type")
            if hddl is not None and ocl is not None:
                out.append((hddl, ocl))
        return tuple(out)

    def var_mapping(self, data: dict[str, Any]) -> tuple[VarMapping, ...]:
        if "var_mapping" not in data:
            self.problem("var_mapping", "missing key var_mapping")
            return ()
        out: list[VarMapping] = []
        for i, entry in enumerate(self.lst(data["var_mapping"], "var_mapping") or ()):
            path = f"var_mapping[{i}]"
            e = self.obj(entry, path)
            if e is None:
                continue
            task_id = self.scalar(e, "task_id", path, "missing key task_id")
            pairs: list[tuple[str, str]] = []
            if "map" not in e:
                self.problem(f"{path}.map", "missing key map")
            for j, m in enumerate(self.lst(e.get("map", []), f"{path}.map") or ()):
                mpath = f"{path}.map[{j}]"
                mo = self.obj(m, mpath)
                if mo is None:
                    continue
                gm_var = self.scalar(mo, "gm_var", mpath, f"missing key map[{j}].gm_var")
                hddl_var = self.scalar(mo, "hddl_var", mpath, f"missing key map[{j}].hddl_var")
                if gm_var is not None and hddl_var is not None:
                    pairs.append((gm_var, hddl_var))
            if task_id is not None:
                out.append(VarMapping(task_id, tuple(pairs), path))
        return tuple(out)

    def semantic_mapping(self, data: dict[str, Any]) -> tuple[SemanticMapping, ...]:
        if "semantic_mapping" not in data:
            self.problem("semantic_mapping", "missing key semantic_mapping")
            return ()
        out: list[SemanticMapping] = []
        for i, entry in enumerate(self.lst(data["semantic_mapping"], "semantic_mapping") or ()):
            path = f"semantic_mapping[{i}]"
            e = self.obj(entry, path)
            if e is not None:
                m = self.one_semantic(e, path)
                if m is not None:
                    out.append(m)
        return tuple(out)

    def one_semantic(self, e: dict[str, Any], path: str) -> SemanticMapping | None:
        """One semantic mapping (spec §4); every required field of its kind is checked."""
        before = len(self.problems)
        kind_raw = self.scalar(e, "type", path, "missing key type")
        kind = kind_raw.lower() if kind_raw is not None else ""
        mapped_raw = self.scalar(e, "mapped_type", path, "missing key mapped_type")
        mapped = mapped_raw.lower() if mapped_raw is not None else ""
        if mapped_raw is not None and mapped not in MAPPED_TYPES:
            self.warn(f"{path}.mapped_type", f"mapped_type [{mapped_raw}] is neither predicate nor function: mapping ignored")
        pred, arg_sorts = self.semantic_map(e, path)
        predicate_type = self.scalar(e, "predicate_type", path)
        fields = self.semantic_fields(e, path, kind_raw) if kind_raw is not None else {}
        if len(self.problems) > before:
            return None
        return SemanticMapping(
            type=kind,
            mapped_type=mapped,
            pred=pred,
            arg_sorts=arg_sorts,
            predicate_type=predicate_type,
            where=path,
            **fields,
        )

    def semantic_map(self, e: dict[str, Any], path: str) -> tuple[str, tuple[str, ...]]:
        """The ``map`` of a semantic mapping: the HDDL predicate or function and its argument
        sorts ("" and () when missing, with a problem)."""
        pred = ""
        arg_sorts: tuple[str, ...] = ()
        if "map" not in e:
            self.problem(f"{path}.map", "missing key map")
            return pred, arg_sorts
        mp = self.obj(e["map"], f"{path}.map")
        if mp is not None:
            pred = self.scalar(mp, "pred", f"{path}.map", "missing key map.pred") or ""
            if "arg_sorts" not in mp:
                self.problem(f"{path}.map.arg_sorts", "missing key map.arg_sorts")
            else:
                arg_sorts = self.strings(mp["arg_sorts"], f"{path}.map.arg_sorts")
        return pred, arg_sorts

    def semantic_fields(self, e: dict[str, Any], path: str, kind_raw: str) -> dict[str, str]:
        """The fields a mapping of type ``kind_raw`` requires (spec §4), as read."""
        kind = kind_raw.lower()

        def req(key: str) -> str:
            return self.scalar(e, key, path, f"missing key {key}") or ""

        fields: dict[str, str] = {}
        if kind == "attribute":
            fields["name"] = req("name")
            fields["relates_to"] = req("relates_to")
            if fields["relates_to"].lower() != "robot":
                fields["belongs_to"] = req("belongs_to")
            else:
                fields["belongs_to"] = self.scalar(e, "belongs_to", path) or ""
        elif kind in ("ownership", "relationship"):
            fields.update(self.relation_fields(kind, req))
        else:
            close = closest(kind, SEMANTIC_TYPES, cutoff=0.6)
            self.problem(
                f"{path}.type",
                f"No mapping type [{kind_raw}] for semantic mappings.",
                (f"Did you mean {close}? " if close else "")
                + f"Set {path}.type to attribute (a field of a record), ownership (records listed "
                "inside another record) or relationship (records related to another record).",
            )
        return fields

    @staticmethod
    def relation_fields(kind: str, req: Callable[[str], str]) -> dict[str, str]:
        """Ownership (records listed inside another record) and relationship mappings: the two
        record types, how they are related, and the owner of the predicate."""
        fields: dict[str, str] = {}
        if kind == "ownership":
            fields["owner"] = req("owner")
            fields["owned"] = req("owned")
        else:
            fields["main_entity"] = req("main_entity")
            fields["related_entity"] = req("related_entity")
        fields["relationship_type"] = req("relationship_type")
        if fields["relationship_type"] == "attribute":
            fields["attribute_name"] = req("attribute_name")
        fields["belongs_to"] = req("belongs_to")
        return fields
