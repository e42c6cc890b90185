"""The ``mutrose-cp`` parser, as a batch reads it: each command's options and what kind of path
each one names.

Every option of the command line that names a file declares its kind with its argparse type
(:mod:`mutrose_cp.cli.option_types`: ``output_file``, ``output_folder``, ``input_file``).  A batch
takes the files a job reads and writes from those types, not from a list of option names of its
own: an option added to a command later is then hashed (an input) or checked against the other
jobs (an output) without any change here.
"""
from __future__ import annotations

import argparse
from dataclasses import dataclass
from functools import cache

from ..option_types import input_file, output_file, output_folder

OUTPUT, FOLDER, INPUT = "output", "folder", "input"
KINDS = {output_file: OUTPUT, output_folder: FOLDER, input_file: INPUT}


@dataclass(frozen=True)
class PathOption:
    """An option that names a path: its argparse destination, its flag for messages (the first
    one: ``-o`` of ``-o/--output``) and its kind (:data:`OUTPUT`, :data:`FOLDER` or :data:`INPUT`)."""

    dest: str
    flag: str
    kind: str


@cache
def mutrose_parser() -> argparse.ArgumentParser:
    """The command line's own parser (built once: a batch parses every job with it)."""
    from ..parser import build_parser  # the command line imports this package's parser only

    return build_parser()


def command_parser(parser: argparse.ArgumentParser, command: str) -> argparse.ArgumentParser | None:
    """The sub-parser of ``command``, None for a command the parser does not know.  argparse has
    no public list of its actions: ``_actions`` is where every parser keeps them."""
    for action in parser._actions:
        choices = action.choices
        if isinstance(choices, dict) and command in choices:
            found = choices[command]
            return found if isinstance(found, argparse.ArgumentParser) else None
    return None


@cache
def path_options(command: str) -> tuple[PathOption, ...]:
    """The options of ``command`` that name a path, with their kind."""
    sub = command_parser(mutrose_parser(), command)
    if sub is None:
        return ()
    return tuple(PathOption(action.dest, action.option_strings[0], KINDS[action.type])
                 for action in sub._actions
                 if action.option_strings and action.type in KINDS)


@cache
def known_flags(command: str) -> frozenset[str]:
    """Every option string of ``command`` (``-q``, ``--quiet``, ``--json-summary``...)."""
    sub = command_parser(mutrose_parser(), command)
    return frozenset(flag for action in ([] if sub is None else sub._actions) for flag in action.option_strings)
