"""A mission: the four inputs loaded, and the pipeline stages run on demand.

This is the library entry point (``Mission.load``) used by the CLI, the tests and embedding
applications.  Each stage is computed once and cached: expansion, HTN paths, Task Graph,
constraints.  Both decomposition algorithms read the same Task Graph.
"""
from __future__ import annotations

import functools
import os
import sys
from contextlib import contextmanager
from contextvars import ContextVar
from dataclasses import dataclass, field
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any, Callable, Iterator, TypeVar

from .constraints import Constraints, generate_constraints
from .errors import MissionError, Problem
from .expansion import Expansion, expand
from .htn import DecompositionPath, all_task_paths
from .io.config import load_configuration
from .io.goal_model import load_goal_model
from .io.hddl import load_domain
from .io.knowledge import load_knowledge
from .model import Configuration, Domain, GoalModel, InitialState, WorldKnowledge
from .model.task_graph import TaskGraph
from .taskgraph import build_task_graph
from .world import build_initial_state

if TYPE_CHECKING:  # the solvers import OR-Tools, which takes a while: loaded when first used
    from .allocate import AllocationOptions, Fleet
    from .allocate.allocation import Allocation
    from .allocate.search import Progress
    from .allocate.travel import TravelTimes
    from .solve.cpsat import DecompositionSpace
    from .solve.decompose import DecompositionRequest, DecompositionResult
    from .solve.embedding import DecompositionModel
    from .solve.encoding import Encoding


_world_file: ContextVar[Path | None] = ContextVar("world_file", default=None)


@contextmanager
def world_file(path: str | os.PathLike[str] | None) -> Iterator[None]:
    """Read the world knowledge from ``path`` instead of the configuration's ``world_db.path``
    in every :meth:`Mission.load` while the block runs (``--world``: one mission, many worlds)."""
    token = _world_file.set(None if path is None else Path(path))
    try:
        yield
    finally:
        _world_file.reset(token)


def _world_ambiguity(relative: str, config_path: Path, read: Path) -> str:
    """A warning when the world path names two different existing files, one from the current
    directory and one from the mission folder."""
    p = Path(relative)
    if p.is_absolute():
        return ""
    here, beside = Path.cwd() / p, config_path.parent.parent / p
    if not (here.is_file() and beside.is_file()) or here.samefile(beside):
        return ""
    return (f"{config_path}: world_db.path {relative} names two files, {here} (from the current directory) and "
            f"{beside} (from the mission folder); read {read}, as the original does")


def resolve_config_path(relative: str, config_path: Path) -> Path:
    """Resolve a path from the configuration: the current directory first (as the original
    does), then the mission folder (the configuration's parent's parent), then its folder."""
    p = Path(relative)
    if p.is_absolute():
        return p
    candidates = [Path.cwd() / p, config_path.parent.parent / p, config_path.parent / p]
    for c in candidates:
        if c.exists():
            return c
    return candidates[1] if (config_path.parent.parent / p).parent.exists() else candidates[0]


def _pick(candidates: list[Path], chosen: str | None, what: str, option: str, folder: Path) -> Path:
    """The one candidate file of a mission sub-folder; several without ``option`` is an error
    (a stale copy beside the real file must never be read silently)."""
    if chosen:
        as_path = Path(chosen)
        if as_path.is_file():
            return as_path
        named = [c for c in candidates if c.name == chosen or c.stem == chosen]
        if not named:
            raise MissionError(f"no {what} named {chosen!r}; available: " + ", ".join(c.name for c in candidates),
                               str(folder))
        return named[0]
    if len(candidates) > 1:
        raise MissionError(f"several {what} files: " + ", ".join(c.name for c in candidates)
                           + f"; choose one with {option}", str(folder))
    return candidates[0]


def find_mission_files(folder: str | os.PathLike[str], config_name: str | None = None, *, hddl_name: str | None = None,
                       gm_name: str | None = None) -> tuple[Path, Path, Path]:
    """The HDDL, goal model and configuration of a mission folder (``hddl/ gm/ configuration/``).

    With several configurations, ``config_name`` picks one (file name or its distinguishing
    suffix, e.g. ``Delivery`` for ``configurationDelivery.json``); the goal model whose name
    contains that suffix is chosen.  Several HDDL files, or several goal models that the
    configuration does not tell apart, are an error unless ``hddl_name``/``gm_name`` choose."""
    root = Path(folder)
    if not root.is_dir():
        raise MissionError(f"cannot read mission folder: {root} is not a directory", str(root))
    hddls = sorted((root / "hddl").glob("*.hddl"))
    gms = sorted(p for p in (root / "gm").glob("*") if p.is_file())
    configs = sorted(p for p in (root / "configuration").glob("*") if p.suffix.lower() in (".json", ".xml"))
    missing = [n for n, lst in (("hddl/*.hddl", hddls), ("gm/*", gms), ("configuration/*.json|xml", configs)) if not lst]
    if missing and not (hddl_name and gm_name and configs):
        raise MissionError(f"mission folder has no {', '.join(missing)} (expected hddl/ gm/ configuration/ knowledge/)",
                           str(root))
    if config_name:
        chosen = [c for c in configs if c.name == config_name or c.stem == config_name
                  or c.stem.removeprefix("configuration") == config_name]
        if not chosen:
            raise MissionError(f"no configuration named {config_name!r}; available: "
                               + ", ".join(c.name for c in configs), str(root / "configuration"))
        config = chosen[0]
    else:
        jsons = [c for c in configs if c.suffix.lower() == ".json"]
        if len({c.stem for c in configs}) > 1:
            raise MissionError("several configurations; choose one with --config: "
                               + ", ".join(c.name for c in configs), str(root / "configuration"))
        config = (jsons or configs)[0]
    hddl = _pick(hddls, hddl_name, "HDDL domain", "--hddl", root / "hddl")
    suffix = config.stem.removeprefix("configuration")
    matching = [g for g in gms if suffix and suffix in g.stem]
    gm = _pick(gms if gm_name else (matching or gms), gm_name, "goal model", "--gm", root / "gm")
    return hddl, gm, config


T = TypeVar("T")
STAGE_RECURSION_LIMIT = 100_000


def _deep(stage: Callable[..., T]) -> Callable[..., T]:
    """Run a pipeline stage with a recursion limit for deep goal models.

    The stages recurse once per goal level (up to ``expansion.MAX_GOAL_DEPTH`` levels, a few
    frames each).  Python-to-Python calls need no C stack, so a high limit is safe there; it is
    not raised while inputs are parsed, where C decoders (JSON) recurse on the C stack."""
    @functools.wraps(stage)
    def run(*args: Any, **kwargs: Any) -> T:
        previous = sys.getrecursionlimit()
        sys.setrecursionlimit(max(previous, STAGE_RECURSION_LIMIT))
        try:
            return stage(*args, **kwargs)
        finally:
            sys.setrecursionlimit(previous)

    return run


@dataclass
class Mission:
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

    @classmethod
    def load(cls, hddl: str | os.PathLike[str], gm: str | os.PathLike[str], config: str | os.PathLike[str], *,
             lenient_xml: bool = False) -> "Mission":
        """Read and validate the four inputs (the world file is named by the configuration, unless
        :func:`world_file` names another one).

        All problems of the three named files are collected before raising, so one run reports
        everything that is wrong."""
        from .check import check_annotations, cross_check  # local import: check builds on the loaders

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
        chosen = _world_file.get()
        world_path = chosen if chosen is not None else resolve_config_path(cfg.world_db.path, Path(config))
        ambiguity = "" if chosen is not None else _world_ambiguity(cfg.world_db.path, Path(config), world_path)
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
        return mission

    # -- pipeline stages ------------------------------------------------------------------------
    @cached_property
    def initial_state(self) -> InitialState:
        return build_initial_state(self.domain, self.config, self.knowledge)

    @cached_property
    @_deep
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
    @_deep
    def task_graph(self) -> TaskGraph:
        graph = build_task_graph(self.expansion, self.goal_model, self.config, self.initial_state, self.paths)
        for warning in graph.warnings:
            self.warnings.append(warning)
            if self.report_warning is not None:
                self.report_warning(warning)
        return graph

    @cached_property
    @_deep
    def constraints(self) -> Constraints:
        return generate_constraints(self.task_graph)

    @_deep
    def exploratory(self, progress: Callable[[int, int], None] | None = None) -> list[list[int]]:
        """Valid mission decompositions by the original's explicit combination."""
        from .solve.exploratory import ExploratoryDecomposer

        return ExploratoryDecomposer(self.task_graph, self.constraints, self.domain, self.goal_model,
                                     self.config, self.initial_state, progress).run()

    @_deep
    def encoding(self, explain: bool = False) -> Encoding:
        """The boolean model of the valid mission decompositions (see ``solve/encoding.py``)."""
        from .solve.encoding import Encoder

        return Encoder(self.task_graph, self.constraints, self.domain, self.goal_model, self.config,
                       self.initial_state, explain).encode()

    @_deep
    def decomposition_space(self, progress: Callable[[int, int], None] | None = None,
                            keep: bool = True, list_limit: int | None = None) -> DecompositionSpace:
        """The valid mission decompositions as a product of independently solved components
        (``list_limit``: see ``solve.cpsat.solve_component``)."""
        from .solve.cpsat import ENUMERATION_CAP, build_space

        return build_space(self.encoding(), keep=keep, progress=progress,
                           list_limit=ENUMERATION_CAP if list_limit is None else list_limit)

    @_deep
    def decompose(self, request: DecompositionRequest | None = None,
                  progress: Callable[[int, int], None] | None = None) -> DecompositionResult:
        """The valid mission decompositions ``request`` asks for (the first 1000 by default):
        everything ``mutrose-cp decompose`` does, for the API (see ``solve/decompose.py``)."""
        from .solve.decompose import DecompositionRequest, decompose

        return decompose(self, request if request is not None else DecompositionRequest(), progress)

    def decomposition_model(self) -> DecompositionModel:
        """The whole decomposition space as one CP-SAT model, for embedding (see ``solve/embedding.py``)."""
        from .solve.embedding import DecompositionModel

        return DecompositionModel.build(self)

    def allocate(self, fleet: Fleet, options: AllocationOptions | None = None,
                 progress: Callable[[Progress], None] | None = None, travel: TravelTimes | None = None) -> Allocation:
        """A valid mission decomposition, its robots and its schedule chosen together for
        ``fleet``, with travel (see ``allocate/``); everything ``mutrose-cp allocate`` does.
        ``travel``: the fleet's table, when already built to check the fleet."""
        from .allocate import AllocationOptions, allocate

        return allocate(self, fleet, options if options is not None else AllocationOptions(), progress, travel)

    def output_path(self) -> Path:
        return resolve_output_path(self.config.output.file_path, self.config_path)


def resolve_output_path(relative: str, config_path: Path) -> Path:
    """Outputs go where the configuration says, relative to the current directory."""
    p = Path(relative)
    return p if p.is_absolute() else Path.cwd() / p
