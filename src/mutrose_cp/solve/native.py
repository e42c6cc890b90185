"""OR-Tools' lean CP-SAT helper module (model protos and the solve wrapper, without pandas or
numpy), imported on first use with interrupts held back: an exception raised inside a native
module's initialisation aborts the process."""
from __future__ import annotations

from typing import TYPE_CHECKING

from ..interrupt import native_import

if TYPE_CHECKING:
    from ortools.sat.python import cp_model_helper as cmh
else:
    cmh = native_import("ortools.sat.python.cp_model_helper")

__all__ = ["cmh"]
