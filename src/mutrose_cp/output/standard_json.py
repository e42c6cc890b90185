"""The output file in standard JSON (``--json-style standard``), for new consumers.

The default output copies Boost.PropertyTree's JSON (``output.py``), which today's consumers
read: every scalar a string, an empty list or object written as ``""``, non-ASCII text escaped
byte by byte, and a repeated key (a task's capabilities) reduced to its last value.  A reader
written for plain JSON trips over these: the 2D simulator's reader crashes on the ``"tasks": ""``
of a mission without task instances.  This style keeps the schema and writes valid UTF-8 JSON:
``[]`` and ``{}`` for empty lists and objects, numbers as numbers, flags as booleans, every
capability of an action, and a task's locations always as a list.

The exact count of the decomposition-space section stays a string: it can have thousands of
digits, beyond what most JSON readers hold in a number.
"""
from __future__ import annotations

import json
from typing import IO, Any, Iterable, Mapping

from ..pipeline.constraints import EC, SEQ, Constraint
from ..model.task_graph import Decomposition
from .builder import OutputBuilder


def _dumps(value: Any, indent: int) -> str:
    """``value`` as indented JSON, nested at ``indent`` spaces."""
    text = json.dumps(value, ensure_ascii=False, indent=4)
    return text.replace("\n", "\n" + " " * indent)


def _flag(text: Any) -> bool:
    return str(text) == "True"


def _task(builder: OutputBuilder, dec: Decomposition, group: bool, divisible: bool) -> dict[str, Any]:
    """A task entry of the Boost writer with its values typed."""
    entry: dict[str, Any] = dict(builder.task_entry(dec, group, divisible))
    loc = dec.instance.location
    entry["locations"] = list(loc) if isinstance(loc, tuple) else ([loc] if loc else [])
    entry["robots_num"] = {k: _flag(v) if k == "fixed" else int(str(v)) for k, v in entry["robots_num"].items()}
    entry["group"], entry["divisible"] = group, divisible
    return entry


def _constraint(builder: OutputBuilder, c: Constraint) -> dict[str, Any]:
    out: dict[str, Any] = {"type": "SEQ" if c.kind == SEQ else "EC",
                           "task_instances": {"t0": builder.key[c.first], "t1": builder.key[c.second]}}
    if c.kind == EC:
        out["group"], out["divisible"] = c.group, c.divisible
    return out


def _space(space: Mapping[str, Any]) -> dict[str, Any]:
    out = dict(space)
    if "optimum" in out:
        out["optimum"] = {**out["optimum"], "cost": int(out["optimum"]["cost"])}
    return out


def _decompositions(builder: OutputBuilder) -> Iterable[list[str]]:
    return ([builder.key[d] for d in md] for md in builder.m.decompositions)


def _write_items(fh: IO[str], items: Iterable[str], opening: str, closing: str) -> None:
    """A JSON list or object whose members are already serialized at indent 8; streamed, since
    mission decompositions may be many."""
    first = True
    for item in items:
        fh.write(f"{opening}\n        " if first else ",\n        ")
        fh.write(item)
        first = False
    fh.write(opening + closing if first else f"\n    {closing}")


def write_standard_json(builder: OutputBuilder, fh: IO[str]) -> None:
    """Stream the output document in standard JSON (same keys and order as the Boost style)."""
    actions = [{"name": name, "capabilities": list(caps)} for name, caps in builder.actions()]
    fh.write('{\n    "actions": ' + _dumps(actions, 4))
    fh.write(',\n    "tasks": ')
    tasks = (f'{json.dumps(builder.key[d.index])}: {_dumps(_task(builder, d.decomposition, d.group, d.divisible), 8)}'
             for d in builder.decs)
    _write_items(fh, tasks, "{", "}")
    fh.write(',\n    "constraints": ')
    _write_items(fh, (_dumps(_constraint(builder, c), 8) for c in builder.m.constraints), "[", "]")
    fh.write(',\n    "mission_decompositions": ')
    _write_items(fh, (_dumps(md, 8) for md in _decompositions(builder)), "[", "]")
    if builder.m.space is not None:
        fh.write(',\n    "mission_decomposition_space": ' + _dumps(_space(builder.m.space), 4))
    if builder.m.uncertainty is not None:
        fh.write(',\n    "mission_decomposition_uncertainty": ' + _dumps(builder.m.uncertainty(True), 4))
    fh.write("\n}\n")
