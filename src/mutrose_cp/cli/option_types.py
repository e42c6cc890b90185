"""The argparse types of the command line's numeric options, shared by every sub-command.

A value out of its domain is a usage error (argparse prints ``argument --X: ...`` and exits
with 2) before any work, never a traceback nor a value silently taken as something else: ``inf``
or ``nan`` seconds, a negative count.  ``batch`` registers its options with these types too, so
``batch --time-limit`` accepts what ``allocate --time-limit`` accepts.
"""
from __future__ import annotations

import argparse
import math
from typing import Callable

MAX_COUNT = 2**62  # beyond any listing that fits on a disk; CP-SAT's limits are 64-bit
MAX_SECONDS = 10**7  # about 115 days: any longer limit is a typo


def count_option(minimum: int, maximum: int = MAX_COUNT) -> Callable[[str], int]:
    """An argparse type: an integer from ``minimum`` to ``maximum``."""
    def parse(text: str) -> int:
        try:
            value = int(text)
        except ValueError:
            raise argparse.ArgumentTypeError(f"expected a whole number, got {text!r}") from None
        if not minimum <= value <= maximum:
            raise argparse.ArgumentTypeError(f"{text} is out of range: give a number from {minimum} to {maximum}")
        return value
    return parse


def _positive(text: str, unit: str) -> float:
    """A finite positive number of ``unit``, at most ``MAX_SECONDS``."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"expected a number of {unit}, got {text!r}") from None
    if not (math.isfinite(value) and value > 0):
        raise argparse.ArgumentTypeError(f"{text} is not a positive number of {unit}")
    if value > MAX_SECONDS:
        raise argparse.ArgumentTypeError(f"{text} is out of range: give at most {MAX_SECONDS} {unit}")
    return value


def seconds(text: str) -> float:
    """An argparse type: a finite positive number of seconds, at most ``MAX_SECONDS``."""
    return _positive(text, "seconds")


def work_units(text: str) -> float:
    """An argparse type: a finite positive number of units of deterministic work (about a second
    each, see ``allocate/budget.py``), at most ``MAX_SECONDS``."""
    return _positive(text, "units of work")


# ---------------------------------------------------------------------------------------------
# Paths.  Every option that names a file says which kind of file with its type, so that the
# output rules (output_file.refuse_unsafe_outputs) can be applied to all of them and a test can
# find them all in the parser (tests/test_command_outputs.py).


def output_file(text: str) -> str:
    """An argparse type: a file a command writes (``-`` is standard output).  An empty path, and
    one that ends with ``/`` (a folder), name no file."""
    if not text:
        raise argparse.ArgumentTypeError("the path is empty: give a file name")
    if text.endswith("/"):
        raise argparse.ArgumentTypeError(f"{text} ends with /, so it names a folder: give a file name "
                                         f"(for example {text}out.json)")
    return text


def output_folder(text: str) -> str:
    """An argparse type: a folder a command writes files into."""
    if not text:
        raise argparse.ArgumentTypeError("the path is empty: give a folder")
    return text


def input_file(text: str) -> str:
    """An argparse type: a file a command reads."""
    if not text:
        raise argparse.ArgumentTypeError("the path is empty: give a file name")
    return text


PATH_TYPES = (output_file, output_folder, input_file)
