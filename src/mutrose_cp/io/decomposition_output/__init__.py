"""Reader of decomposition outputs (spec ``output.md``), ours or the original tool's.

The validator checks an output file against the mission it claims to decompose, so it reads the
file the way other tools do: the JSON object of the original (``""`` for an empty list, the
strings ``"True"``/``"False"``), the standard style (``[]``, numbers and booleans) or the XML
form (several top-level elements, no single root; ``task<i>`` keys).  All become one
:class:`DecompositionOutput` (:mod:`.records`); the mission decompositions are read one at a
time (:mod:`.json_form`, :mod:`.xml_form`), so that a file of hundreds of thousands of them is
held as compactly as its keys allow.

A file that is not a decomposition output at all (``{}``, an XML document of something else, a
section of the wrong kind) is refused with a located error (exit status 2): checking nothing and
calling it valid would let any file pass.  Inside a task, a field that is missing or has the
wrong shape is not a reading error: it is recorded in :attr:`OutputTask.problems` and the
validator reports it as a violation of that task, with the other fields still checked.
"""
from __future__ import annotations

from .loader import load_decomposition_output
from .records import (
    SECTIONS,
    DecompositionOutput,
    OutputAction,
    OutputConstraint,
    OutputPredicate,
    OutputTask,
    RobotsNum,
)

__all__ = ["DecompositionOutput", "OutputAction", "OutputConstraint", "OutputPredicate", "OutputTask",
           "RobotsNum", "SECTIONS", "load_decomposition_output"]
