"""``mutrose-cp verify``: properties decided over every valid mission decomposition.

One line per property on stdout (``name: holds``, ``fails``, ``vacuous`` or the count); with
``--witness-dir DIR`` a witness decomposition per failing property (and per ``some`` that
holds) as ``DIR/NAME.json`` (or ``.xml``) in the mission output format, which the simulator can
run and ``graph --view decomposition`` can draw.  The witness files are written all together or
not at all.  Exit status: 0 when every property holds (a count always does), 1 when one fails,
2 for bad input, 3 when the mission has no valid decomposition at all.
"""
from __future__ import annotations

import argparse
import json
import sys
import time
from pathlib import Path

from ..errors import MissionError
from ..interrupt import phase
from ..io.properties import given_properties
from ..mission import Mission
from ..model.properties import Property
from ..output.builder import OutputModel
from ..output.counts import shown_count
from ..output.files import staged_outputs
from ..output.formats import write_output
from ..pipeline.property_checks import check_properties
from ..solve.verify import Verdict
from .flow import expanded, load_mission, mission_paths, refuse_outputs
from .process import keep_until_exit

HOLDS, FAILS, NO_DECOMPOSITION = 0, 1, 3


def cmd_verify(args: argparse.Namespace) -> int:
    hddl, gm, cfg, _folder = mission_paths(args)
    start = time.perf_counter()
    properties = given_properties(args.properties, args.property)
    if not properties:
        raise MissionError("verify needs a property: give --property 'always ...' or --properties FILE")
    _refuse_repeated_names(properties)
    mission = load_mission(hddl, gm, cfg, lenient_xml=args.lenient_xml, quiet=args.quiet)
    check_properties(properties, mission.domain)
    suffix = mission.config.output.file_type
    witnesses = {p.name: Path(args.witness_dir) / f"{p.name}.{suffix}" for p in properties} if args.witness_dir else {}
    refuse_outputs(list(witnesses.values()), mission, (hddl, gm, cfg, args.properties), folders=(args.witness_dir,))
    expanded(mission)
    with phase("deciding the properties"):
        space = mission.decomposition_space()  # built once for all of them
        verdicts = [mission.verify(p, space) for p in properties]
    keep_until_exit(space, verdicts)
    written = _write_witnesses(mission, verdicts, witnesses) if witnesses else {}
    for v in verdicts:
        print(_line(v, written.get(v.property.name)))
    elapsed = time.perf_counter() - start
    if args.json_summary:
        print(json.dumps({"command": "verify", "seconds": round(elapsed, 3), "properties": [
            {"name": v.property.name, "property": v.property.text, "status": v.status, "count": str(v.count),
             "total": str(v.total), "witness": str(written[v.property.name]) if v.property.name in written else None}
            for v in verdicts]}, sort_keys=True))
    if not args.quiet:
        failing = sum(v.status == "fails" for v in verdicts)
        print(f"verified: {len(verdicts)} properties, {failing} failing ({elapsed:.2f} s)", file=sys.stderr)
    if any(v.status == "vacuous" for v in verdicts):
        return NO_DECOMPOSITION
    return FAILS if any(v.status == "fails" for v in verdicts) else HOLDS


def _refuse_repeated_names(properties: list[Property]) -> None:
    seen: dict[str, Property] = {}
    for p in properties:
        if p.name in seen:
            raise MissionError(f"property {p.name} is given twice ({seen[p.name].where} and {p.where})")
        seen[p.name] = p


def _line(v: Verdict, witness: Path | None) -> str:
    name = v.property.name
    if v.status == "vacuous":
        return f"{name}: vacuous (the mission has no valid decomposition)"
    shown = f" (witness {witness})" if witness is not None else ""
    # exact up to 15 digits, else their magnitude (the JSON summary has every digit)
    count, total = shown_count(v.count), shown_count(v.total, digit_count=True)
    if v.status == "count":
        return f"{name}: {count} of {total} valid decompositions"
    return f"{name}: {v.status}, {count} of {total} valid decompositions satisfy the formula{shown}"


def _write_witnesses(mission: Mission, verdicts: list[Verdict], paths: dict[str, Path]) -> dict[str, Path]:
    """The witnesses of failing properties and of ``some`` properties that hold, all together."""
    tg, constraints = mission.task_graph, mission.constraints
    wanted = {v.property.name: v.witness for v in verdicts if v.witness is not None
              and (v.status == "fails" or (v.status == "holds" and v.property.quantifier == "some"))}
    if not wanted:
        return {}
    with phase("writing the witnesses"), staged_outputs([paths[name] for name in wanted]):
        Path(paths[next(iter(wanted))]).parent.mkdir(parents=True, exist_ok=True)
        for name, witness in wanted.items():
            model = OutputModel(tg, constraints, [list(witness)], mission.domain, mission.config,
                                mission.initial_state)
            write_output(model, paths[name], mission.config.output.file_type)
    return {name: paths[name] for name in wanted}
