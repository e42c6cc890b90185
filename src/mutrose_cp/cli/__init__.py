"""The command lines: ``mutrose-cp`` (:mod:`.program`: the entry point and the lazy table of
commands; :mod:`.parser`; :mod:`.commands`, one handler per command), the drop-in ``mutrose``
with the original's command line (:mod:`.dropin`), and ``batch``.

``main``, ``entry`` and ``build_parser`` are offered here too, where scripts import them from,
and loaded on first use: the drop-in, a module of this package, loads none of ``mutrose-cp``'s
command line.
"""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..lazy_exports import lazy_attributes

if TYPE_CHECKING:
    from .parser import build_parser
    from .program import entry, main

_EXPORTS = {"main": "program", "entry": "program", "build_parser": "parser"}


__getattr__ = lazy_attributes(__name__, _EXPORTS)


__all__ = ["build_parser", "entry", "main"]
