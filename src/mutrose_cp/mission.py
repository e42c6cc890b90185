"""A mission: the four inputs loaded, and the pipeline's stages and decomposers run on demand.

This is the library entry point (``Mission.load``) used by the CLI, the tests and embedding
applications.  It only calls down: the stages are :class:`~mutrose_cp.pipeline.stages.MissionStages`
(computed once and cached: expansion, HTN paths, Task Graph, constraints), the decomposers the
functions of :mod:`mutrose_cp.solve.decomposers`; both decomposition algorithms read the same
Task Graph.  Finding a mission folder's files is :mod:`mutrose_cp.io.mission_files` (its names
are kept here too, where users import them from).
"""
from __future__ import annotations

import os
from pathlib import Path
from typing import TYPE_CHECKING, Callable, TypeVar

from .errors import MissionError, Problem
from .io.config import load_configuration
from .io.goal_model import load_goal_model
from .io.hddl import load_domain
from .io.uncertainty import read_uncertainty
from .io.knowledge import load_knowledge
from .io.mission_files import (
    chosen_world_file,
    find_mission_files,
    resolve_config_path,
    resolve_output_path,
    world_ambiguity,
    world_file,
)
from .pipeline.checks import check_annotations, cross_check
from .pipeline.recursion import deep
from .pipeline.stages import MissionStages
from .solve import decomposers

if TYPE_CHECKING:  # the solvers import OR-Tools, which takes a while: loaded when first used
    from .allocate import AllocationOptions, Fleet
    from .allocate.allocation import Allocation
    from .allocate.search import Progress
    from .allocate.travel import TravelTimes
    from .solve.cpsat import DecompositionSpace
    from .solve.decompose import DecompositionRequest, DecompositionResult
    from .solve.embedding import DecompositionModel
    from .solve.encoding import Encoding
    from .solve.verify import Verdict
    from .model.properties import Property

__all__ = ["Mission", "find_mission_files", "resolve_config_path", "resolve_output_path", "world_file"]

T = TypeVar("T")


class Mission(MissionStages):
    """The loaded inputs of a mission, its lazily computed pipeline stages, and the calls into
    the decomposers and the allocator."""

    @classmethod
    def load(cls, hddl: str | os.PathLike[str], gm: str | os.PathLike[str], config: str | os.PathLike[str], *,
             lenient_xml: bool = False, uncertainty: str | os.PathLike[str] | None = None) -> "Mission":
        """Read and validate the four inputs (the world file is named by the configuration, unless
        :func:`world_file` names another one), and the uncertainty file ``uncertainty``
        (docs/formats/uncertainty.md; :meth:`configured_uncertainty` is the one the configuration
        names).

        All problems of the three named files are collected before raising, so one run reports
        everything that is wrong."""
        problems: list[Problem] = []

        def attempt(load: Callable[[], T]) -> T | None:
            try:
                return load()
            except MissionError as err:
                problems.extend(err.problems)
                return None

        domain = attempt(lambda: load_domain(hddl))
        goal_model = attempt(lambda: load_goal_model(gm))
        cfg = attempt(lambda: load_configuration(config, lenient=lenient_xml))
        if problems or domain is None or goal_model is None or cfg is None:
            raise MissionError(problems)
        chosen = chosen_world_file()
        world_path = chosen if chosen is not None else resolve_config_path(cfg.world_db.path, Path(config))
        ambiguity = "" if chosen is not None else world_ambiguity(cfg.world_db.path, Path(config), world_path)
        knowledge = load_knowledge(world_path, cfg.world_db.xml_root, cfg.world_db.unique_id, lenient=lenient_xml)
        mission = cls(domain, goal_model, cfg, knowledge, Path(config), world_path=world_path)
        mission.warnings.extend(cfg.warnings)
        mission.warnings.extend(knowledge.warnings)
        if ambiguity:
            mission.warnings.append(ambiguity)
        mission.warnings.extend(mission.goal_model.warnings)
        mission.warnings.extend(str(p) for p in check_annotations(mission.goal_model))
        cross = cross_check(mission.domain, mission.goal_model, cfg)
        if cross:
            raise MissionError(cross)
        if uncertainty is not None:
            mission.read_uncertainty(uncertainty)
        return mission

    def configured_uncertainty(self) -> Path | None:
        """The uncertainty file the configuration names (its key ``uncertainty``), if any."""
        named = self.config.uncertainty_path
        return resolve_config_path(named, self.config_path) if named else None

    def read_uncertainty(self, path: str | os.PathLike[str]) -> None:
        """Read the uncertainty file at ``path``: its facts' values are then chosen by the
        decomposer (``solve/uncertain.py``) instead of read from the world.  Before any stage
        is computed: the initial state forgets them."""
        if "initial_state" in self.__dict__:
            raise RuntimeError("read_uncertainty after the initial state was computed")
        entries, joints, problems = read_uncertainty(path)
        self.uncertainty_entries = tuple(entries)
        self.uncertainty_joints = tuple(joints)
        self.uncertainty_source = os.fspath(path)
        try:
            _ = self.uncertainty  # resolved now: its problems are the inputs'
        except MissionError as err:
            problems.extend(err.problems)
        if problems:  # in file order
            raise MissionError(sorted(problems, key=lambda p: (p.record()["line"] or 0, p.record()["column"] or 0)))

    # -- the decomposers (solve/) --------------------------------------------------------------
    def exploratory(self, progress: Callable[[int, int], None] | None = None) -> list[list[int]]:
        """Valid mission decompositions by the original's explicit combination."""
        return decomposers.exploratory(self, progress)

    def encoding(self, explain: bool = False) -> Encoding:
        """The boolean model of the valid mission decompositions (see ``solve/encoding.py``)."""
        return decomposers.encoding(self, explain)

    def decomposition_space(self, progress: Callable[[int, int], None] | None = None,
                            keep: bool = True, list_limit: int | None = None) -> DecompositionSpace:
        """The valid mission decompositions as a product of independently solved components
        (``list_limit``: see ``solve.cpsat.solve_component``)."""
        return decomposers.decomposition_space(self, progress, keep, list_limit)

    @deep
    def decompose(self, request: DecompositionRequest | None = None,
                  progress: Callable[[int, int], None] | None = None) -> DecompositionResult:
        """The valid mission decompositions ``request`` asks for (the first 1000 by default):
        everything ``mutrose-cp decompose`` does, for the API (see ``solve/decompose.py``)."""
        from .solve.decompose import DecompositionRequest, decompose  # deferred: start-up time

        return decompose(self, request if request is not None else DecompositionRequest(), progress)

    def verify(self, prop: Property, space: DecompositionSpace | None = None) -> Verdict:
        """Whether ``prop`` holds over every valid mission decomposition (``always``, ``never``),
        some (``some``), or for how many (``count``), with a witness decomposition; decided
        exactly through the components (see ``solve/verify.py``).  ``space``: the mission's
        :meth:`decomposition_space`, when it is already built (for several properties)."""
        from .solve.verify import verify  # deferred: start-up time

        space = space if space is not None else self.decomposition_space()
        return verify(prop, space, self.task_graph, self.domain, self.constraints, self.initial_state)

    def decomposition_model(self) -> DecompositionModel:
        """The whole decomposition space as one CP-SAT model, for embedding (see ``solve/embedding.py``)."""
        from .solve.embedding import DecompositionModel  # deferred: start-up time (OR-Tools)

        return DecompositionModel.build(self)

    def allocate(self, fleet: Fleet, options: AllocationOptions | None = None,
                 progress: Callable[[Progress], None] | None = None, travel: TravelTimes | None = None) -> Allocation:
        """A valid mission decomposition, its robots and its schedule chosen together for
        ``fleet``, with travel (see ``allocate/``); everything ``mutrose-cp allocate`` does.
        ``travel``: the fleet's table, when already built to check the fleet."""
        from .allocate import AllocationOptions, allocate  # deferred: start-up time (OR-Tools)

        return allocate(self, fleet, options if options is not None else AllocationOptions(), progress, travel)
