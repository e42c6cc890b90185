"""The HDDL parser's tables are cached between runs (io/grammar.py): a speed-up only, never a
source of errors, output or stale tables."""
from __future__ import annotations

import os
import stat
import subprocess
import sys
from pathlib import Path

import pytest

from mutrose_cp.io import grammar

ROOT = Path(__file__).resolve().parent.parent
DOMAIN = ROOT / "models" / "delivery" / "delivery.hddl"
OPTIONS = {"lexer": "basic", "start": "domain", "propagate_positions": True, "maybe_placeholders": True}


@pytest.fixture
def cache(tmp_path, monkeypatch) -> Path:
    monkeypatch.setenv("XDG_CACHE_HOME", str(tmp_path))
    monkeypatch.delenv(grammar.CACHE_ENV, raising=False)
    return tmp_path / "mutrose-cp"


def _files(folder: Path) -> list[Path]:
    return sorted(folder.glob("hddl-*.lark")) if folder.is_dir() else []


def _tree(parser) -> str:
    return parser.parse(DOMAIN.read_text()).pretty()


def test_tables_are_saved_once_then_loaded(cache, monkeypatch):
    first = grammar.cached_lalr_parser("hddl.lark", **OPTIONS)
    (saved,) = _files(cache)
    assert stat.S_IMODE(cache.stat().st_mode) == 0o700
    built = []
    monkeypatch.setattr(grammar, "Lark", _Counting(built))
    second = grammar.cached_lalr_parser("hddl.lark", **OPTIONS)
    assert built == []  # loaded, not built
    assert _tree(second) == _tree(first)
    assert _files(cache) == [saved]


def test_other_options_or_grammar_get_other_tables(cache):
    grammar.cached_lalr_parser("hddl.lark", **OPTIONS)
    grammar.cached_lalr_parser("hddl.lark", **{**OPTIONS, "propagate_positions": False})
    assert len(_files(cache)) == 2


def test_a_damaged_cache_file_is_rebuilt_and_replaced(cache):
    grammar.cached_lalr_parser("hddl.lark", **OPTIONS)
    (saved,) = _files(cache)
    saved.write_bytes(saved.read_bytes()[:200])
    parser = grammar.cached_lalr_parser("hddl.lark", **OPTIONS)
    assert "domain" in _tree(parser)
    assert saved.stat().st_size > 1000  # written again in full


def test_an_unsafe_cache_folder_is_not_used(cache):
    cache.mkdir(mode=0o700)
    cache.chmod(0o777)  # others could plant a file that would be unpickled
    grammar.cached_lalr_parser("hddl.lark", **OPTIONS)
    assert _files(cache) == []


@pytest.mark.skipif(os.geteuid() == 0, reason="root writes into read-only folders")
def test_a_read_only_cache_folder_only_costs_the_build(cache):
    cache.mkdir(mode=0o500)
    try:
        assert "domain" in _tree(grammar.cached_lalr_parser("hddl.lark", **OPTIONS))
        assert _files(cache) == []
    finally:
        cache.chmod(0o700)


def test_the_cache_can_be_turned_off(cache, monkeypatch):
    monkeypatch.setenv(grammar.CACHE_ENV, "0")
    grammar.cached_lalr_parser("hddl.lark", **OPTIONS)
    assert not cache.exists()


def test_check_with_an_unwritable_cache_location_prints_nothing_more(tmp_path):
    """A cache location that is a file, not a folder: the command works as without a cache."""
    blocker = tmp_path / "not-a-folder"
    blocker.write_text("")
    env = {**os.environ, "XDG_CACHE_HOME": str(blocker)}
    mission = ROOT / "examples" / "item-delivery"
    run = subprocess.run([sys.executable, "-m", "mutrose_cp", "check", str(mission), "-q"], env=env,
                         capture_output=True, text=True, timeout=120)
    assert run.returncode == 0, run.stderr
    assert run.stderr == ""


class _Counting:
    """Stands in for ``lark.Lark``: counts builds, keeps ``Lark.load``."""

    def __init__(self, built: list[int]) -> None:
        from lark import Lark

        self.built = built
        self.load = Lark.load
        self._lark = Lark

    def __call__(self, *args, **kwargs):
        self.built.append(1)
        return self._lark(*args, **kwargs)
