"""Values both forms of an output write the same way: flags, robot numbers, empty lists."""
from __future__ import annotations

from typing import Any

from ...errors import MissionError, Problem
from .records import SECTIONS, RobotsNum


def flag(value: Any) -> bool | None:
    """``"True"``/``"False"`` (any case) or a JSON boolean; None for anything else."""
    text = str(value).strip().lower()
    return True if text in ("true", "1") else False if text in ("false", "0") else None


def robots(value: Any) -> RobotsNum | None:
    """``{fixed, num}`` or ``{fixed, min, max}``; None when it is no robot number."""
    if not isinstance(value, dict):
        return None
    try:
        fixed = flag(value.get("fixed"))
        if fixed:
            n = int(value["num"])
            return RobotsNum(True, n, n)
        if fixed is None:
            return None
        return RobotsNum(False, int(value["min"]), int(value["max"]))
    except (KeyError, TypeError, ValueError):
        return None


def as_list(value: Any) -> list[Any] | None:
    """The original writes ``""`` for an empty list (and an object where Boost names the
    members); None when ``value`` is no list at all."""
    if value == "" or value is None:
        return []
    if isinstance(value, dict):
        return list(value.values())
    if isinstance(value, list):
        return value
    return None


def require_sections(present: set[str], source: str, form: str) -> None:
    """Refuse a document that lacks a section the validator needs, naming it: checking nothing
    and calling it valid would let any file pass."""
    missing = [s for s in SECTIONS if s not in present]
    if missing:
        raise MissionError([Problem(f"{source}: {s}", f"the output has no {s} section: this is not a MutRoSe "
                                                      f"decomposition output (expected the {form} actions, tasks, "
                                                      "constraints and mission_decompositions)") for s in missing])
