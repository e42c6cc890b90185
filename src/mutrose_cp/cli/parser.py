"""The ``mutrose-cp`` command line's parser: every command, its options and their types.

Each sub-command is named by ``args.command``; :data:`mutrose_cp.cli.program.COMMANDS` says which
function runs it.  The batch reads its jobs' command lines with this parser too.
"""
from __future__ import annotations

import argparse

from .. import __version__
from .batch.options import add_batch_parser
from ..output.ihtn import DEFAULT_MAX_FILES
from .option_types import count_option, input_file, output_file, output_folder, seconds, work_units
from ..solve.decompose import DEFAULT_LIMIT

def build_parser() -> argparse.ArgumentParser:
    """The whole command line: one sub-parser per command, each added by its own function."""
    parser = argparse.ArgumentParser(
        prog="mutrose-cp",
        description="Decompose MutRoSe multi-robot missions (goal model + HDDL + configuration + world).",
    )
    parser.add_argument("--version", action="version", version=f"mutrose-cp {__version__}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    add_check_parser(sub)
    add_decompose_parser(sub)
    add_allocate_parser(sub)
    add_count_parser(sub)
    add_validate_parser(sub)
    add_compare_parser(sub)
    add_graph_parser(sub)
    add_export_hddl_parser(sub)
    add_verify_parser(sub)
    add_explain_parser(sub)
    add_batch_parser(sub)
    return parser


def reading(p: argparse.ArgumentParser) -> None:
    """How the inputs are read: XML repair and the size bound."""
    p.add_argument("--lenient-xml", action="store_true",
                   help="read XML whose repair changes which records exist or how they nest, as the original "
                        "does (with warnings) instead of refusing it")
    p.add_argument("--max-input-mb", type=count_option(1), default=256, metavar="MB",
                   help="refuse input files larger than this (default 256)")


def mission_inputs(p: argparse.ArgumentParser) -> None:
    """Which mission: its three files, or its folder and the files to pick there."""
    p.add_argument("inputs", nargs="+", metavar="INPUT",
                   help="HDDL GM CONFIG, or one mission folder with hddl/ gm/ configuration/ knowledge/")
    p.add_argument("--config", type=input_file, help="in a mission folder with several configurations, the one to use")
    p.add_argument("--hddl", type=input_file, help="in a mission folder with several HDDL files, the one to use")
    p.add_argument("--gm", type=input_file, help="in a mission folder with several goal models, the one to use")


def common(p: argparse.ArgumentParser) -> None:
    """The options of every command that reads one mission."""
    mission_inputs(p)
    reading(p)
    p.add_argument("--world", metavar="FILE", type=input_file,
                   help="read the world knowledge from FILE instead of the configuration's world_db.path")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress and no summary on stderr")
    p.add_argument("--json-summary", action="store_true", help="print a machine-readable summary on stdout")


def uncertain_world(p: argparse.ArgumentParser) -> None:
    """The uncertainty file of the commands that read one (docs/formats/uncertainty.md)."""
    given = p.add_mutually_exclusive_group()
    given.add_argument("--uncertain", metavar="FILE", type=input_file,
                       help="world facts that are not known for sure, with their probabilities (default: the file "
                            "the configuration's key 'uncertainty' names, if any)")
    given.add_argument("--as-written", action="store_true",
                       help="read the world as written, without the uncertainty file the configuration names")


def add_check_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``check``: validate the mission inputs and report every problem found."""
    p = sub.add_parser("check", help="validate the mission inputs and report every problem found")
    common(p)
    uncertain_world(p)
    p.add_argument("--strict", action="store_true", help="treat every warning as an error (exit 2)")
    p.add_argument("--fleet", metavar="FLEET.json", type=input_file, help="also check a fleet file against the mission")
    p.add_argument("--properties", metavar="FILE", type=input_file,
                   help="also check a properties file (one 'name: quantifier formula' per line) against the mission")
    p.add_argument("--property", action="append", default=[], metavar="PROPERTY",
                   help="also check this property (repeatable), e.g. 'never uses(action drop-item)'")


def add_decompose_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``decompose``: decompose the mission and write the output file."""
    p = sub.add_parser("decompose", help="decompose the mission and write the output file")
    common(p)
    p.add_argument("-o", "--output", type=output_file,
                   help="output file (overrides the configuration's output.file_path)")
    p.add_argument("--format", choices=("json", "xml"),
                   help="output format (default: the suffix of -o, .json or .xml, else the configuration's)")
    p.add_argument("--json-style", choices=("boost", "standard"), default="boost",
                   help="boost (default): the original's JSON, which its readers expect; standard: valid UTF-8 "
                        "JSON with [] and {} for empty lists, numbers as numbers")
    p.add_argument("--algorithm", choices=("cpsat", "exploratory"), default="cpsat",
                   help="cpsat (default): solver-backed, factored; exploratory: the original's explicit combination")
    p.add_argument("--limit", type=count_option(0), default=DEFAULT_LIMIT, metavar="K",
                   help="cpsat: list the first K mission decompositions (0 = all; default 1000)")
    p.add_argument("--sample", type=count_option(1), metavar="K", help="cpsat: list K decompositions drawn uniformly at random")
    p.add_argument("--seed", type=count_option(0), default=0, help="random seed for --sample (default 0)")
    p.add_argument("--optimize", action="store_true",
                   help="cpsat: output the decomposition of least cost (fewest actions, or --costs)")
    p.add_argument("--costs", metavar="FILE", type=input_file, help='JSON cost file {"actions": {...}, "methods": {...}}')
    p.add_argument("--explain", action="store_true",
                   help="cpsat: when no decomposition exists, name the conflicting goals, tasks and facts")
    p.add_argument("--ihtn", metavar="DIR", type=output_folder,
                   help="write one iHTN file per ordering of each valid decomposition "
                                                 "into DIR instead of the output file")
    p.add_argument("--ihtn-orderings", choices=("all", "one"), default="all",
                   help="--ihtn: every ordering of each decomposition (default), or only the first consistent one")
    p.add_argument("--ihtn-max", type=count_option(1), default=DEFAULT_MAX_FILES, metavar="N",
                   help="--ihtn: refuse (exit 2) an export of more than N files (default 10000)")
    uncertain_world(p)
    listed = p.add_mutually_exclusive_group()
    listed.add_argument("--robust", action="store_true",
                        help="with uncertain facts: only the decompositions valid whatever their values")
    listed.add_argument("--most-likely", action="store_true",
                        help="with uncertain facts: the decomposition most likely to be valid (ties: the least cost)")


def add_allocate_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``allocate``: choose the decomposition, the robots and the schedule together."""
    from ..allocate.options import MAX_SEED, MAX_WORKERS

    p = sub.add_parser("allocate", help="choose the decomposition, the robots and the schedule together")
    common(p)
    p.add_argument("--fleet", required=True, metavar="FLEET.json", type=input_file,
                   help="the robots, durations and travel (JSON)")
    p.add_argument("-o", "--output", type=output_file, help="the chosen decomposition, in the output format (default: the "
                                          "configuration's output.file_path)")
    p.add_argument("--format", choices=("json", "xml"), help="format of -o (default: the configuration's)")
    p.add_argument("--schedule", metavar="FILE", type=output_file, help="the schedule (default: schedule.json beside -o)")
    p.add_argument("--gantt", metavar="FILE.png|svg", type=output_file, help="also draw the schedule (needs matplotlib)")
    p.add_argument("--objective", default="makespan", metavar="makespan|travel|weighted:A,B",
                   help="minimise the makespan (default), the total travel, or A * makespan + B * travel")
    limit = p.add_mutually_exclusive_group()
    limit.add_argument("--time-limit", type=seconds, default=10.0, metavar="S",
                       help="stop the search after S seconds with the best schedule found (default 10)")
    limit.add_argument("--work-limit", type=work_units, metavar="W",
                       help="stop after W units of deterministic work instead (about a second each): the same "
                            "schedule on every machine, with any --workers")
    p.add_argument("--workers", type=count_option(1, MAX_WORKERS), default=1, metavar="N",
                   help="CP-SAT search threads (default 1: the same schedule on every finished run)")
    p.add_argument("--seed", type=count_option(0, MAX_SEED), default=0, help="CP-SAT random seed (default 0)")


def add_count_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``count``: print the exact number of valid mission decompositions."""
    p = sub.add_parser("count", help="print the exact number of valid mission decompositions")
    common(p)
    uncertain_world(p)
    which = p.add_mutually_exclusive_group()
    which.add_argument("--robust", action="store_true",
                       help="with uncertain facts: count the decompositions valid whatever their values")
    which.add_argument("--possible", action="store_true",
                       help="with uncertain facts: count those valid for some value of them (the default)")


def add_explain_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``explain``: what the uncertain facts decide, and which to sense first."""
    p = sub.add_parser("explain", help="with uncertain facts: which of them to sense first")
    common(p)
    uncertain_world(p)


def add_validate_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``validate``: check an output file (ours or the original's) against the mission."""
    p = sub.add_parser("validate", help="check an output file (ours or the original's) against the mission")
    common(p)
    p.usage = "mutrose-cp validate [-h] [--config CONFIG] [-q] [--json-summary] (HDDL GM CONFIG | MISSION_DIR) OUTPUT"


def add_compare_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``compare``: run both decomposers (and the original tool) on the mission, each in its ."""
    from ..compare.run import DEFAULT_LIMIT as COMPARE_LIMIT, DEFAULT_TIME_LIMIT

    p = sub.add_parser("compare", help="run both decomposers (and the original tool) on the mission, each in its "
                                       "own process, and compare time, memory and results")
    mission_inputs(p)
    reading(p)  # passed on to the decomposers
    p.add_argument("--time-limit", type=seconds, default=DEFAULT_TIME_LIMIT, metavar="S",
                   help=f"wall-time limit of each run in seconds (default {DEFAULT_TIME_LIMIT:g}); a run over it "
                        "is killed")
    p.add_argument("--limit", type=count_option(0), default=COMPARE_LIMIT, metavar="K",
                   help="compare the sets of decompositions up to K of them, else only their counts "
                        f"(default {COMPARE_LIMIT}; 0 = always)")
    p.add_argument("--original", metavar="PATH",
                   help="also run this binary of the original tool (as PATH HDDL GM CONFIG, in a copy of the mission)")
    p.add_argument("--json", action="store_true", help="print the report as one JSON object instead of a table")
    p.add_argument("--plot", metavar="FILE", type=output_file, help="bar chart of time and memory: FILE.png, .svg or .pdf (needs matplotlib)")
    p.add_argument("-q", "--quiet", action="store_true", help="no progress lines on stderr")


def add_graph_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``graph``: draw the expanded goal model, the Task Graph or one decomposition."""
    p = sub.add_parser("graph", help="draw the expanded goal model, the Task Graph or one decomposition")
    common(p)
    p.add_argument("--view", choices=("goal-model", "task-graph", "decomposition"), default="task-graph")
    p.add_argument("--index", type=int, default=0, help="decomposition view: which valid decomposition (0-based)")
    p.add_argument("--from-output", metavar="FILE", type=input_file,
                   help="decomposition view: draw decomposition --index as listed in FILE (an output of decompose, "
                        "or a witness of verify), checked to be one of the mission's valid decompositions")
    p.add_argument("-o", "--output", required=True, type=output_file,
                   help="FILE.svg, FILE.png (needs graphviz) or FILE.dot")


def add_export_hddl_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``export-hddl``: write the domain (and the mission's problem) as standard HDDL."""
    p = sub.add_parser("export-hddl", help="write the domain (and the mission's problem) as standard HDDL")
    p.add_argument("input", metavar="INPUT", help="the HDDL domain, or a mission folder")
    p.add_argument("-o", "--output", required=True, metavar="OUT.hddl", type=output_file,
                   help="the standard HDDL domain to write")
    p.add_argument("--gm", type=input_file,
                   help="the goal model (with --config: also write the problem); in a folder, which one")
    p.add_argument("--config", type=input_file, help="the configuration (with --gm); in a mission folder, which one")
    p.add_argument("--hddl", type=input_file, help="in a mission folder with several HDDL files, the one to use")
    p.add_argument("--problem-out", metavar="FILE", type=output_file, help="the problem file (default OUT-problem.hddl); exit 2 "
                                                         "when the mission has no problem form")
    reading(p)
    p.add_argument("-q", "--quiet", action="store_true", help="no warnings and no summary on stderr")


def add_verify_parser(sub: "argparse._SubParsersAction[argparse.ArgumentParser]") -> None:
    """``verify``: decide properties over every valid mission decomposition."""
    p = sub.add_parser("verify", help="decide properties over every valid mission decomposition, with witnesses")
    common(p)
    p.add_argument("--property", action="append", default=[], metavar="PROPERTY",
                   help="a property (repeatable), e.g. 'never uses(action drop-item)' or 'name: count uses(method m)'")
    p.add_argument("--properties", metavar="FILE", type=input_file,
                   help="a properties file: one 'name: quantifier formula' per line")
    p.add_argument("--witness-dir", metavar="DIR", type=output_folder,
                   help="write a witness decomposition per failing property (and per some that holds) into DIR, "
                        "as NAME.json or NAME.xml in the output format")
