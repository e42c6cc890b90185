"""The stages of the pipeline for one loaded mission, each computed once when first read:
initial state, expansion, decomposition paths, Task Graph, constraints.

:class:`MissionStages` is what the solvers, the allocator and the writers read of a mission;
:class:`mutrose_cp.mission.Mission` adds loading and the calls into the solvers.
"""
from __future__ import annotations

from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import Callable

from .constraints import Constraints, generate_constraints
from .expansion import Expansion, expand
from ..model.decomposition_paths import DecompositionPath
from .htn import all_task_paths
from ..io.mission_files import resolve_output_path
from ..model import Configuration, Domain, GoalModel, InitialState, WorldKnowledge
from ..model.task_graph import TaskGraph
from .task_graph_builder import build_task_graph
from .initial_state import build_initial_state, build_sorts
from .uncertain_facts import resolve_uncertainty
from ..model.uncertainty import JointEntry, UncertainEntry, Uncertainty
from .recursion import deep


@dataclass
class MissionStages:
    """The loaded inputs of a mission and its lazily computed pipeline stages."""

    domain: Domain
    goal_model: GoalModel
    config: Configuration
    knowledge: WorldKnowledge
    config_path: Path
    warnings: list[str] = field(default_factory=list)
    world_path: Path | None = None  # the world knowledge file the configuration named
    # optional progress reporter for long stages: called with (stage, done, total)
    progress: Callable[[str, int, int], None] | None = None
    # where a warning found by a later stage goes as it is found (the loaders' are in
    # ``warnings`` before any stage runs; a later one is added there too)
    report_warning: Callable[[str], None] | None = None
    # the entries of an uncertainty file and its name (docs/formats/uncertainty.md); None: the
    # world is read as it is written
    uncertainty_entries: tuple[UncertainEntry, ...] | None = None
    uncertainty_joints: tuple[JointEntry, ...] = ()
    uncertainty_source: str = ""

    @cached_property
    def uncertainty(self) -> Uncertainty | None:
        """The uncertain facts, resolved against the mission (None without an uncertainty file)."""
        if self.uncertainty_entries is None:
            return None
        sorts = build_sorts(self.domain, self.config, self.knowledge)
        return resolve_uncertainty(self.uncertainty_entries, self.uncertainty_source, self.config, sorts,
                                   self.goal_model, self.uncertainty_joints, self.knowledge)

    @property
    def expands_per_world(self) -> bool:
        """Whether the goal model reads uncertain facts: the mission is then expanded once per
        world of them (``pipeline/scenarios.py``), not as written."""
        return self.uncertainty is not None and bool(self.uncertainty.expanded)

    @cached_property
    def initial_state(self) -> InitialState:
        """The world's initial state; an uncertain fact's value is left unknown here, for the
        decomposer to choose (``solve/uncertain.py``); one the goal model reads is given by the
        world of each expansion (``pipeline/scenarios.py``)."""
        state = build_initial_state(self.domain, self.config, self.knowledge)
        if self.uncertainty is not None:
            state = state.forgetting({atom for f in self.uncertainty.decided for atom in f.atoms})
        return state

    @cached_property
    @deep
    def expansion(self) -> Expansion:
        report = None
        if self.progress is not None:
            progress = self.progress

            def report(done: int, total: int) -> None:
                progress("expanding the goal model: forAll instances", done, total)

        return expand(self.goal_model, self.domain, self.config, self.knowledge, report)

    @cached_property
    def paths(self) -> dict[str, list[DecompositionPath]]:
        """Decomposition paths of every abstract task of the domain (used or not)."""
        return all_task_paths(self.domain)

    @cached_property
    @deep
    def task_graph(self) -> TaskGraph:
        graph = build_task_graph(self.expansion, self.goal_model, self.config, self.initial_state, self.paths)
        for warning in graph.warnings:
            self.warnings.append(warning)
            if self.report_warning is not None:
                self.report_warning(warning)
        return graph

    @cached_property
    @deep
    def constraints(self) -> Constraints:
        return generate_constraints(self.task_graph)

    def output_path(self) -> Path:
        return resolve_output_path(self.config.output.file_path, self.config_path)
