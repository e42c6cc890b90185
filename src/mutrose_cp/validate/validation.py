"""Validating one output file against its mission: the entry point :func:`validate`."""
from __future__ import annotations

import sys
from pathlib import Path
from typing import Callable

from ..io.decomposition_output import DecompositionOutput
from ..io.knowledge import load_knowledge
from ..model import Configuration, Domain, GoalModel, InitialState, WorldKnowledge
from .components import check_all
from .conditions import GoalConditions
from .decompositions import DecompositionChecker
from .expected import ExpectedMission
from .file_checks import ConstraintChecks, TaskChecks, check_actions
from .goal_relations import GoalRelations
from .report import Report, Violation
from .select import Unresolved


Progress = Callable[[int, int], None]
RECURSION_LIMIT = 100_000  # deep goal models (as the decomposers' stages allow)


def _world(config: Configuration) -> WorldKnowledge:
    """The world the configuration names, found as the decomposer finds it: from the current
    directory, else the mission folder (the configuration's parent's parent), else beside it."""
    relative = Path(config.world_db.path)
    source = Path(config.source)
    candidates = [relative] if relative.is_absolute() else \
        [Path.cwd() / relative, source.parent.parent / relative, source.parent / relative]
    path = next((c for c in candidates if c.is_file()), candidates[0])
    return load_knowledge(path, config.world_db.xml_root, config.world_db.unique_id, lenient=True)


class _Notes:
    def __init__(self, report: Report) -> None:
        self.report = report
        self.seen: set[str] = set()

    def __call__(self, message: str) -> None:
        if message not in self.seen:
            self.seen.add(message)
            self.report.notes.append(message)


def _file_checks(domain: Domain, gm: GoalModel, config: Configuration, initial: InitialState,
                 world: WorldKnowledge, output: DecompositionOutput, report: Report, note: _Notes) -> None:
    """The tasks and constraints of the file against those the mission implies."""
    try:
        expected = ExpectedMission(domain, gm, config, initial, world)
    except Unresolved as err:
        report.violations.append(Violation(None, "", f"the mission cannot be expanded against its world ({err}), "
                                                     "so no output of it can be checked valid"))
        return
    report.task_instances = len(expected.instances)
    tasks = TaskChecks(output, expected)
    report.violations.extend(tasks.run())
    report.violations.extend(ConstraintChecks(output, expected, tasks.ids).run())
    report.violations.extend(check_actions(output, expected))
    for literal in dict.fromkeys(expected.printer.unprintable):
        note(f"no semantic mapping prints {literal}: the decomposers refuse such a mission")
    if expected.instances and not output.mission_decompositions:
        report.violations.append(Violation(None, "", f"mission_decompositions: none listed, but the mission has "
                                                     f"{len(expected.instances)} task instances (an output lists "
                                                     "valid mission decompositions; without any, decompose writes "
                                                     "no output and exits with 3)"))


def validate(domain: Domain, gm: GoalModel, config: Configuration, initial: InitialState,
             output: DecompositionOutput, *, world: WorldKnowledge | None = None,
             progress: Progress | None = None) -> Report:
    """Check ``output`` against the mission inputs: the file's tasks and constraints, and every
    mission decomposition it lists.  ``world``: the world knowledge (read from the configuration
    when not given: a world that cannot be read is a :class:`MissionError`, as for the decomposers,
    since without it no task field can be checked); ``progress(done, total)`` is told how many
    mission decompositions are done."""
    previous = sys.getrecursionlimit()
    sys.setrecursionlimit(max(previous, RECURSION_LIMIT))  # the walks recurse once per goal level
    try:
        return _validate(domain, gm, config, initial, output, world, progress)
    finally:
        sys.setrecursionlimit(previous)


def _validate(domain: Domain, gm: GoalModel, config: Configuration, initial: InitialState,
              output: DecompositionOutput, world: WorldKnowledge | None, progress: Progress | None) -> Report:
    report = Report()
    note = _Notes(report)
    _file_checks(domain, gm, config, initial, world if world is not None else _world(config), output, report, note)
    relations = GoalRelations(gm)
    conditions = GoalConditions(gm, config, note, output.format == "xml")
    checker = DecompositionChecker(domain, gm, initial, output, relations, conditions, note)
    report.violations.extend(Violation(None, task, message) for task, message in checker.file_problems)
    report.violations.extend(check_all(checker, output, progress))
    report.checked = len(output.mission_decompositions)
    return report
