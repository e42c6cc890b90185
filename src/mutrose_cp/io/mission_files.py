"""Finding a mission's files: the HDDL, goal model and configuration of a mission folder, the
paths a configuration names (resolved as the original resolves them), and the world file a
run reads instead of the configuration's (``--world``)."""
from __future__ import annotations

import os
from contextlib import contextmanager
from contextvars import ContextVar
from pathlib import Path
from typing import Iterator

from ..errors import MissionError

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


def world_ambiguity(relative: str, config_path: Path, read: Path) -> str:
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


def pick_file(candidates: list[Path], chosen: str | None, what: str, option: str, folder: Path) -> Path:
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
    hddl = pick_file(hddls, hddl_name, "HDDL domain", "--hddl", root / "hddl")
    suffix = config.stem.removeprefix("configuration")
    matching = [g for g in gms if suffix and suffix in g.stem]
    gm = pick_file(gms if gm_name else (matching or gms), gm_name, "goal model", "--gm", root / "gm")
    return hddl, gm, config


def chosen_world_file() -> Path | None:
    """The world file :func:`world_file` names for the loads of the running block, if any."""
    return _world_file.get()


def resolve_output_path(relative: str, config_path: Path) -> Path:
    """Outputs go where the configuration says, relative to the current directory."""
    p = Path(relative)
    return p if p.is_absolute() else Path.cwd() / p
