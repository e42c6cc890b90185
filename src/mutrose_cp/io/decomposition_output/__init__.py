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

from ..text import decode_utf8, read_bytes
from .json_form import read_json
from .records import (
    SECTIONS,
    DecompositionOutput,
    OutputAction,
    OutputConstraint,
    OutputPredicate,
    OutputTask,
    RobotsNum,
)
from .xml_form import read_xml

__all__ = ["SECTIONS", "DecompositionOutput", "OutputAction", "OutputConstraint", "OutputPredicate", "OutputTask",
           "RobotsNum", "load_decomposition_output"]


def load_decomposition_output(path: str) -> DecompositionOutput:
    """Read an output file; the format is told by its first character (``<`` is XML)."""
    data = read_bytes(path, "decomposition output")
    if data.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"<"):
        return read_xml(data, path)
    text = decode_utf8(data, path, "decomposition output")
    del data  # the text is what is read from here on
    return read_json(text, path)
