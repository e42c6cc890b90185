"""The output file in the format and JSON style asked for: the one place that chooses a writer."""
from __future__ import annotations

import os

from .builder import OutputBuilder, OutputModel
from .files import atomic_writer


def write_output(model: OutputModel, path: str | os.PathLike[str], file_type: str, json_style: str = "boost") -> None:
    """Write the output file atomically in ``json`` or ``xml``; JSON in the Boost style the
    original's readers expect, or in standard JSON (``standard_json.py``)."""
    builder = OutputBuilder(model)
    with atomic_writer(path, behind=True) as fh:
        if file_type == "xml":
            builder.write_xml(fh)
        elif json_style == "standard":
            from .standard_json import write_standard_json

            write_standard_json(builder, fh)
        else:
            builder.write_json(fh)
