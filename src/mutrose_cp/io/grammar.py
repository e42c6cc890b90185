"""The packaged lark grammars, with their parsers' LALR tables cached between runs, and
:class:`EmbeddedLanguage`, the base of the readers that turn one grammar's parse into values.

Building the HDDL parser's tables takes about 0.2 s, most of a small mission's whole run, and
each expression grammar's 0.017 s; loading them back takes 0.02 s and 0.003 s.  The tables are saved in the user's cache folder
(``$XDG_CACHE_HOME/mutrose-cp``, else ``~/.cache/mutrose-cp``), in a file named after a digest of
the grammar, the parser options and the lark and Python versions, so a changed grammar or an
upgraded lark never meets stale tables.  The cache is only a speed-up: a folder that cannot be
created or written (a read-only home), one that other users could write to, or an unreadable or
damaged file all fall back to building the tables, silently.  Files are written to a temporary
name and renamed, so concurrent runs never read a half-written file.  ``MUTROSE_CP_CACHE=0``
turns the cache off.
"""
from __future__ import annotations

import hashlib
import os
import stat
import sys
import tempfile
from importlib import resources
from pathlib import Path
from functools import cached_property
from typing import Any, Callable, Generic, TypeVar, cast

import lark
from lark import Lark, Token, Transformer
from lark.exceptions import UnexpectedCharacters, UnexpectedEOF, UnexpectedInput, UnexpectedToken

CACHE_ENV = "MUTROSE_CP_CACHE"
Result = TypeVar("Result")


def grammar_text(name: str) -> str:
    """The text of the packaged grammar ``grammars/<name>``."""
    return resources.files("mutrose_cp").joinpath("grammars", name).read_text("utf-8")


def cached_lalr_parser(name: str, **options: Any) -> Lark:
    """The LALR parser of the packaged grammar ``name`` with lark ``options``, its tables
    read from the cache when they are there (about 6x faster than building them)."""
    grammar = grammar_text(name)
    path = _cache_file(name, grammar, options)
    if path is not None:
        loaded = _load(path)
        if loaded is not None:
            return loaded
    parser = Lark(grammar, parser="lalr", **options)
    if path is not None:
        _save(parser, path)
    return parser


def _cache_folder() -> Path | None:
    """The cache folder, created if needed; None when caching is off or the folder is unsafe
    (not ours, or writable by others: a planted file would be unpickled) or cannot be made."""
    if os.environ.get(CACHE_ENV, "1") == "0":
        return None
    base = os.environ.get("XDG_CACHE_HOME") or os.path.join(os.path.expanduser("~"), ".cache")
    folder = Path(base) / "mutrose-cp"
    try:
        folder.mkdir(mode=0o700, parents=True, exist_ok=True)
        info = folder.stat()
    except OSError:
        return None
    if not stat.S_ISDIR(info.st_mode) or info.st_uid != os.getuid() or info.st_mode & 0o022:
        return None
    return folder


def _cache_file(name: str, grammar: str, options: dict[str, Any]) -> Path | None:
    folder = _cache_folder()
    if folder is None:
        return None
    key = repr((grammar, sorted(options.items()), lark.__version__, sys.version_info[:2]))
    digest = hashlib.sha256(key.encode("utf-8")).hexdigest()[:24]
    return folder / f"{Path(name).stem}-{digest}.lark"


def _load(path: Path) -> Lark | None:
    """The parser saved at ``path``, or None when there is none or it cannot be read back."""
    try:
        info = path.lstat()
        if not stat.S_ISREG(info.st_mode) or info.st_uid != os.getuid():
            return None
        with path.open("rb") as f:
            return Lark.load(f)
    except Exception:  # noqa: BLE001 - a missing or damaged cache file only costs the rebuild
        return None


def _save(parser: Lark, path: Path) -> None:
    """Write the tables under a temporary name in the same folder, then rename."""
    try:
        fd, tmp = tempfile.mkstemp(dir=path.parent, prefix=f".{path.name}.")
    except OSError:
        return
    try:
        with os.fdopen(fd, "wb") as f:
            parser.save(f)
        os.replace(tmp, path)
    except Exception:  # noqa: BLE001 - disk full, read-only, or tables lark cannot save
        try:
            os.unlink(tmp)
        except OSError:
            pass


class EmbeddedLanguage(Generic[Result]):
    """One packaged grammar read into values: its LALR parser, built once and cached between
    runs, and the lark Transformer that turns a parse tree into the model's value.

    The readers of the goal model's expression languages share it (AI-Planning/pddl's
    ``parser/base.py`` is the pattern): a language is its grammar, its options and its builder,
    and a syntax error is turned into the terminals that could have come where it failed."""

    def __init__(self, grammar: str, builder: Callable[[], Transformer[Token, Result]], **options: Any) -> None:
        self.grammar = grammar
        self.builder = builder
        self.options = options

    @cached_property
    def parser(self) -> Lark:
        """The parser, built on first use: a call that never reads this language never pays."""
        return cached_lalr_parser(self.grammar, **self.options)

    def parse(self, text: str) -> Result:
        """The value of ``text``; lark's :class:`UnexpectedInput` on a syntax error.

        The tree is transformed after the parse: a cached parser carries no transformer."""
        return self.builder().transform(self.parser.parse(text))

    def terminals_accepted_at(self, text: str, err: UnexpectedInput, position: int) -> set[str]:
        """Terminals that can really come at ``position`` (where the parse of ``text`` failed).

        LALR detects an error only after reducing with the offending look-ahead, and its states
        share look-aheads from other contexts, so ``err.expected`` is both too wide (']' inside
        parentheses) and too narrow ('#' after the reduction to ';').  Errors are rare, so the
        tokens before ``position`` are replayed and the interactive parser says which terminals
        it accepts there."""
        try:
            interactive = self.parser.parse_interactive(text)
            for token in interactive.iter_parse():  # yields each token before feeding it
                if token.start_pos is not None and token.start_pos >= position:
                    break
            # lark leaves InteractiveParser.accepts unannotated; it returns the terminal names
            accepts = cast(Callable[[], set[str]], interactive.accepts)
            return set(accepts())
        except UnexpectedInput:
            pass
        if isinstance(err, (UnexpectedToken, UnexpectedEOF)):
            return set(err.expected)
        if isinstance(err, UnexpectedCharacters):
            return set(err.allowed or ())
        return set()


def error_position(err: UnexpectedInput, text: str) -> int:
    """0-based offset in ``text`` of the offending token (its end for an early end of input)."""
    if isinstance(err, UnexpectedToken):
        if err.token.type == "$END":
            return len(text)
        return err.token.start_pos or 0
    if isinstance(err, UnexpectedEOF):
        return len(text)
    if isinstance(err, UnexpectedCharacters):
        return err.pos_in_stream or 0  # always set by the lexer that raises it
    position: int | None = getattr(err, "pos_in_stream", 0)
    return position or 0
