"""Package faces that load their public names on first use (PEP 562).

A face whose modules are costly to import (OR-Tools, the whole command line) offers its names
without loading them: the first read of a name imports its module and keeps the value, so
later reads are plain attribute look-ups.
"""
from __future__ import annotations

import importlib
import sys
from typing import Any, Callable, Mapping


def lazy_attributes(package: str, exports: Mapping[str, str]) -> Callable[[str], Any]:
    """The module ``__getattr__`` of ``package``: ``exports`` maps each name to the module of
    the package (relative, without the dot) that defines it."""
    def load(name: str) -> Any:
        module = exports.get(name)
        if module is None:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f".{module}", package), name)
        setattr(sys.modules[package], name, value)
        return value

    return load
