"""Charts (``allocate --gantt``, ``compare --plot``): the format read from the file name, and
matplotlib checked, before any work; the same bytes for the same chart; an atomic write.

Matplotlib is the optional ``bench`` extra, imported only when a chart is asked for.  A chart is
drawn on a :class:`matplotlib.figure.Figure` of its own (no pyplot: no global state, no
display), saved without a creation date or software version and with fixed SVG ids.
"""
from __future__ import annotations

import io
import os
from pathlib import Path
from typing import TYPE_CHECKING, Any

from ..errors import MissionError
from .files import atomic_writer

if TYPE_CHECKING:
    from matplotlib.figure import Figure

FORMATS = ("png", "svg", "pdf")
_UNDATED = {"png": {"Software": None}, "svg": {"Date": None}, "pdf": {"CreationDate": None}}


def chart_format(path: str | os.PathLike[str], option: str, formats: tuple[str, ...] = FORMATS) -> str:
    """The chart's format from the suffix of ``path`` (one of ``formats``), with matplotlib's
    presence; a located error naming ``option`` otherwise."""
    suffix = Path(path).suffix.lower().lstrip(".")
    if suffix not in formats:
        names = ", ".join(f".{f}" for f in formats[:-1]) + f" or .{formats[-1]}"
        raise MissionError(f"{option}: cannot tell the chart's format from {os.fspath(path)!r}: name a {names} file",
                           os.fspath(path))
    try:
        import matplotlib  # noqa: F401
    except ImportError:
        raise MissionError(f"{option} needs matplotlib, which is not installed: pip install 'mutrose-cp[bench]' "
                           "(or pip install matplotlib)", os.fspath(path)) from None
    return suffix


def figure(**options: Any) -> Figure:
    """A new figure (``matplotlib.figure.Figure(**options)``)."""
    from matplotlib.figure import Figure

    return Figure(**options)


def save_chart(chart: Figure, path: str | os.PathLike[str], fmt: str, dpi: float | None = None) -> None:
    """Write ``chart`` to ``path`` atomically, the same chart always as the same bytes."""
    import matplotlib

    buffer = io.BytesIO()
    with matplotlib.rc_context({"svg.hashsalt": "mutrose-cp"}):
        chart.savefig(buffer, format=fmt, metadata=_UNDATED[fmt], dpi=dpi if dpi is not None else "figure")
    with atomic_writer(path, "wb") as fh:
        fh.write(buffer.getvalue())
