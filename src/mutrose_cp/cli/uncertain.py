"""``mutrose-cp explain``: what the uncertain facts of a mission decide, and what a robot
should look at before the mission is committed (docs/cli.md#explain).

For a mission with no robust decomposition, the smallest set of uncertain facts whose values,
once known, leave some decomposition certainly valid; with probabilities, the probability of
the most likely decomposition now, and for each fact the best probability expected once its
value is known.  Exit status 0 with an answer (which may be "nothing needs sensing", or "in
some scenario nothing is valid"), 2 for bad input, 3 when no decomposition is valid in any
scenario.
"""
from __future__ import annotations

import argparse
import json
import sys
import time

from ..errors import MissionError
from ..interrupt import phase
from ..output.counts import shown_count
from ..output.uncertainty_section import shown_probability
from ..solve.scenarios import ExpandedSpace, decided_space
from ..solve.uncertain import Sensing, sensing
from .flow import expanded, load_mission, mission_paths
from .process import keep_until_exit

ANSWERED, NOTHING_VALID = 0, 3


def worlds_line(space: ExpandedSpace) -> str:
    """How many worlds of the facts the goal model reads were expanded, and why a world has no
    decomposition when the mission cannot be expanded there."""
    facts = space.uncertainty.expanded
    worlds = len(space.worlds)
    line = (f"  expanded in {worlds} {'world' if worlds == 1 else 'worlds'} of the {len(facts)} "
            f"{'fact' if len(facts) == 1 else 'facts'} the goal model reads")
    for w in space.worlds:
        if w.space is None:
            line += f"\n  no decomposition when {w.world.shown(facts)}: {w.problem}"
    return line


def _sensing_lines(plan: Sensing) -> list[str]:
    """What to sense first, and what sensing each fact is expected to be worth."""
    lines = []
    if plan.facts is None:
        lines.append(plan.reason)
    elif not plan.facts:
        lines.append("nothing needs sensing: a robust decomposition exists (decompose --robust lists them)")
    else:
        lines.append("sense first: " + ", ".join(f.text for f in plan.facts)
                     + " (once their values are known, some decomposition is certainly valid)")
    if plan.best is not None:
        lines.append(f"most likely decomposition now: valid with probability {shown_probability(plan.best)}")
        raising = [(fact, expected) for fact, expected in plan.gains if expected > plan.best + 1e-12]
        for fact, expected in raising[:3]:
            lines.append(f"  sensing {fact.text} first raises it to {shown_probability(expected)} (expected)")
        if not raising:
            lines.append("  no single fact, once sensed, raises it")
    return lines


def cmd_explain(args: argparse.Namespace) -> int:
    hddl, gm, cfg, _folder = mission_paths(args)
    start = time.perf_counter()
    mission = load_mission(hddl, gm, cfg, lenient_xml=args.lenient_xml, quiet=args.quiet, uncertain=args.uncertain,
                           reads_uncertainty=True, as_written=args.as_written)
    if mission.uncertainty is None:
        raise MissionError("explain says which uncertain facts to sense: give --uncertain FILE, or name one in the "
                           "configuration (docs/formats/uncertainty.md); why a mission has no valid decomposition "
                           "at all: decompose --explain")
    if not mission.expands_per_world:
        expanded(mission)
    with phase("solving"):
        space = decided_space(mission)
        robust, possible = space.count(robust=True), space.count(robust=False)
        plan = sensing(space)
    keep_until_exit(space)
    lines = [f"{shown_count(possible)} mission decompositions are valid for some value of the "
             f"{len(mission.uncertainty.facts)} uncertain facts, {shown_count(robust)} whatever their values"]
    lines.extend(_sensing_lines(plan))
    if isinstance(space, ExpandedSpace):
        lines.append(worlds_line(space))
    print("\n".join(lines))
    elapsed = time.perf_counter() - start
    if args.json_summary:
        print(json.dumps({
            "command": "explain", "possible": str(possible), "robust": str(robust),
            "sense": None if plan.facts is None else [f.text for f in plan.facts],
            "best_probability": plan.best, "gains": [{"fact": f.text, "expected": p} for f, p in plan.gains],
            "seconds": round(elapsed, 3)}, sort_keys=True))
    if not args.quiet:
        print(f"explained: {len(mission.uncertainty.facts)} uncertain facts ({elapsed:.2f} s)", file=sys.stderr)
    return NOTHING_VALID if possible == 0 else ANSWERED
