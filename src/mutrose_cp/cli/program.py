"""The ``mutrose-cp`` command line: ``check``, ``decompose`` (and friends).

The commands are looked up by name in :data:`COMMANDS` and imported when run: a call
loads only what its command uses (unified-planning's engine factory is the model).

Bad input ends with located messages on stderr and exit status 2; a mission without any valid
decomposition exits with 3; nothing here prints a Python traceback."""
from __future__ import annotations

import argparse
import importlib
import json
import signal
import sys
from typing import Callable, Sequence

from ..errors import MissionError
from ..interrupt import signal_handlers
from ..io.text import MB, input_limit
from ..io.mission_files import world_file
from .process import (
    FAILURES,
    Failure,
    command_settings,
    exit_process,
    failure_lines,
    failure_problems,
    failure_status,
    prepare_process,
    process_ends_with_command,
    reader_gone,
)



from .parser import build_parser

#: sub-command -> (module, function) of its handler, imported when the command runs
COMMANDS: dict[str, tuple[str, str]] = {
    "check": ("mutrose_cp.cli.commands", "cmd_check"),
    "decompose": ("mutrose_cp.cli.commands", "cmd_decompose"),
    "allocate": ("mutrose_cp.cli.commands", "cmd_allocate"),
    "count": ("mutrose_cp.cli.commands", "cmd_count"),
    "validate": ("mutrose_cp.cli.commands", "cmd_validate"),
    "compare": ("mutrose_cp.cli.commands", "cmd_compare"),
    "graph": ("mutrose_cp.cli.commands", "cmd_graph"),
    "export-hddl": ("mutrose_cp.cli.commands", "cmd_export_hddl"),
    "verify": ("mutrose_cp.cli.verify", "cmd_verify"),
    "explain": ("mutrose_cp.cli.uncertain", "cmd_explain"),
    "batch": ("mutrose_cp.cli.batch.command", "cmd_batch"),
}


def command_handler(command: str) -> Callable[[argparse.Namespace], int]:
    """The function that runs ``command`` (a name of :data:`COMMANDS`)."""
    module, function = COMMANDS[command]
    handler: Callable[[argparse.Namespace], int] = getattr(importlib.import_module(module), function)
    return handler


def entry() -> None:
    """The console script (and ``python -m mutrose_cp``): run the command and exit with its
    status."""
    process_ends_with_command()
    try:
        status = main()
    except KeyboardInterrupt:  # a Ctrl-C after the command's own handlers are gone: stopping already
        status = 128 + signal.SIGINT
    exit_process(status)


def main(argv: Sequence[str] | None = None) -> int:
    with command_settings():
        try:
            return _main(argv)
        except BrokenPipeError:  # telling why failed too: stderr is the closed pipe (2>&1 | head)
            return reader_gone()


def _main(argv: Sequence[str] | None) -> int:
    prepare_process()
    parser = build_parser()
    try:
        args = parser.parse_args(argv)
    except SystemExit as exit_:  # usage errors (status 2), --help and --version (status 0)
        return int(exit_.code or 0)
    if not getattr(args, "command", None):
        parser.print_help(sys.stderr)
        return 2
    try:
        with signal_handlers(), input_limit(args.max_input_mb * MB), world_file(getattr(args, "world", None)):
            status: int = command_handler(args.command)(args)
            return status
    except FAILURES as err:
        status = _report(err)
        if getattr(args, "json_summary", False):
            print(json.dumps({"command": args.command, "ok": False, "status": status, "problems": _problems(err)},
                             sort_keys=True))
        return status


def _problems(err: Failure) -> list[dict[str, str | int | None]]:
    """Why a command failed, as the records ``--json-summary`` lists."""
    return [p.record() for p in failure_problems(err)]


def _report(err: Failure) -> int:
    """Print why a command stopped (never a traceback) and return its exit status."""
    lines = failure_lines(err)
    for line in lines:
        print(line, file=sys.stderr)
    if isinstance(err, MissionError) and len(lines) > 1:
        print(f"{len(lines)} problems found", file=sys.stderr)
    return failure_status(err)
