"""Loading a decomposition output file: the form is told by its first character."""
from __future__ import annotations

from ..text import decode_utf8, read_bytes
from .json_form import read_json
from .records import DecompositionOutput
from .xml_form import read_xml



def load_decomposition_output(path: str) -> DecompositionOutput:
    """Read an output file; the format is told by its first character (``<`` is XML)."""
    data = read_bytes(path, "decomposition output")
    if data.lstrip(b"\xef\xbb\xbf \t\r\n").startswith(b"<"):
        return read_xml(data, path)
    text = decode_utf8(data, path, "decomposition output")
    del data  # the text is what is read from here on
    return read_json(text, path)
