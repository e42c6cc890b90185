"""What the original prints on stdout by accident: its flex lexers' echo.

The original reads a goal's text (``G1: Check All Patient's Vital Signs [G2;G3]``) and every
condition of the goal model with flex lexers that have no rule for some characters, and flex's
default rule copies each such character to stdout.  The plug-in shows stdout, so ``mutrose`` prints
the same characters where the original prints them (checked against the original's recorded
output, ``tests/test_console_exact.py``, and against the original on generated and edited
missions, ``tests/test_console_original.py``):

* the goal-text lexer matches whitespace, ``( ) [ ] , : ; # |`` and names (a letter, then letters
  and digits); it echoes everything else: ``'``, ``-``, ``_``, ``.``, a digit that starts a word,
  any non-ASCII character...  The condition lexer matches whitespace, ``( )``, ``&&``, ``||`` and
  atoms (``!`` or a letter, then letters, digits and ``_. ="<>``); it echoes the rest (a hyphen,
  an apostrophe, a lone ``&``);
* what is read, and how often: first, while the goal model is loaded, every node's conditions
  once (its creation condition, then its forAll's or plain achieve condition or its query's
  condition); then the goal texts, in two walks of the goal model: the walk that makes the task
  instances (every visit of a node reads its parent's text, the root's own text for the root; a
  forAll visits its children once per element) and the walk that builds the runtime annotation
  (the root's text once, twice when its annotation is not an operator, i.e. a means-end root,
  then once per visit of every other node that the walk expands, i.e. one with children in the
  runtime annotation: not a forAll over nothing);
* where it appears: the echo goes through C stdio, whose stdout buffer (4096 bytes on a pipe or
  a file) is written out when a byte arrives at a full buffer and at exit, while everything else
  the original prints goes through ``std::cout``, flushed line by line.  The echo is complete
  before anything else is printed, so its whole 4096-byte blocks but the last come first on
  stdout and the rest comes last (:class:`LexerEcho`).

The original's HDDL lexer echoes too, but a domain with such characters is refused here (a
located syntax error: docs/deviations.md).
"""
from __future__ import annotations

import re
from dataclasses import dataclass
from typing import IO, Iterable, Iterator

from ..pipeline.annotation_tree import OPERATOR, RatNode
from ..model.goal_model import GMNode, GoalModel

STDIO_BUFFER = 4096  # bytes: glibc's stdout buffer on a pipe or a file
# what each lexer matches, and so does not echo (FALLBACK and OPT are names as far as echoing goes)
_TEXT_MATCHED = re.compile(r"[ \t\n\r()\[\],:;#|]+|[A-Za-z][A-Za-z0-9]*")
_CONDITION_MATCHED = re.compile(r'[ \t\n\r()]+|&&|\|\||[!A-Za-z][A-Za-z0-9_. ="<>]*')


def unmatched(text: str) -> str:
    """The characters of a goal's text that the goal-text lexer echoes, in order."""
    return _TEXT_MATCHED.sub("", text)


def unmatched_in_condition(text: str) -> str:
    """The characters of a condition that the condition lexer echoes, in order."""
    return _CONDITION_MATCHED.sub("", text)


def _select_condition(text: str) -> str:
    """The part of ``queried->select(var:Type | condition)`` that the original hands its query
    lexer: from the ``|`` after the ``:`` to the first ``)`` after it (how it cuts the text)."""
    arrow = text.index(">")
    bar = text.index("|", text.index(":", arrow))
    return text[bar + 1 : text.index(")", bar)]


def _conditions(node: GMNode) -> Iterator[str]:
    """A node's conditions in the order the original lexes them when it reads the node: the
    creation condition (a trigger is not lexed), then the forAll's condition, the plain achieve
    condition or the query's condition (a node has one of them)."""
    if node.context is not None and node.context.kind == "condition":
        yield node.context.text
    if node.forall is not None:
        yield node.forall.condition_text
    elif node.achieve_text:
        yield node.achieve_text
    if node.query is not None:
        yield _select_condition(node.query.text)


def condition_echo(nodes: Iterable[GMNode]) -> str:
    """What the condition lexer echoes while the goal model is loaded.  The original reads the
    nodes in the file's order; ``nodes`` come in vertex order, the only order the goal model
    keeps, which is the same output unless two nodes' conditions echo (docs/deviations.md)."""
    return "".join(unmatched_in_condition(text) for node in nodes for text in _conditions(node))


def _visits(rat: RatNode) -> Iterator[tuple[str, bool]]:
    """The goal-model nodes (by key) that the walk making the task instances visits, in order,
    each with whether the runtime-annotation walk expands it (it has children there; a forAll
    without elements has none).  A forAll over several elements is one visit of its goal; the
    copies under it are its elements' expansions (not visits), and an operator nested inside a
    goal's annotation is part of that goal."""
    stack: list[tuple[RatNode, bool]] = [(rat, False)]  # (node, is a forAll element's copy)
    while stack:
        node, copy = stack.pop()
        if node.is_forall_dummy:
            yield node.children[0].related_goal or "", True
            stack.extend((c, True) for c in reversed(node.children))
            continue
        if not copy and not (node.kind == OPERATOR and node.inner):
            yield node.related_goal or "", bool(node.children)
        stack.extend((c, False) for c in reversed(node.children))


def text_echo(gm: GoalModel, rat: RatNode) -> str:
    """What the goal-text lexer echoes in the two walks of ``gm`` (whose expansion against the
    world is ``rat``), in order."""
    visits = list(_visits(rat))
    if not visits:
        return ""
    cache: dict[str, str] = {}

    def of(key: str) -> str:
        if key not in cache:
            cache[key] = unmatched(gm.node(key).text)
        return cache[key]

    parts: list[str] = []
    for key, _ in visits:  # making the task instances: each visit reads its parent's text
        parent = gm.node(key).parent
        parts.append(of(parent if parent is not None else key))
    root = visits[0][0]
    parts.append(of(root))  # building the runtime annotation
    if rat.kind != OPERATOR and not rat.is_forall_dummy and rat.children:
        parts.append(of(root))  # a means-end root is read again when it is expanded
    parts.extend(of(key) for key, expanded in visits[1:] if expanded)
    return "".join(parts)


def echoed_text(gm: GoalModel, rat: RatNode) -> str:
    """Everything the lexers echo while the original reads ``gm`` and builds ``rat``."""
    return condition_echo(gm.nodes) + text_echo(gm, rat)


def split_point(data: bytes) -> int:
    """Where stdout shows the echo ``data`` split: after its last full buffer but one (a full
    buffer is written when the next byte comes), moved back to the start of a character that the
    buffer cuts in two.  The original writes half of that character first and the rest last,
    which the plug-in, decoding stdout as UTF-8, would show as two replacement characters."""
    cut = (len(data) - 1) // STDIO_BUFFER * STDIO_BUFFER if data else 0
    while 0 < cut < len(data) and data[cut] & 0xC0 == 0x80:  # a UTF-8 continuation byte
        cut -= 1
    return cut


@dataclass(frozen=True)
class LexerEcho:
    """The echo split where the original's stdout shows it: ``head`` before everything else
    (the full buffers written while the goal model was read), ``tail`` after everything else
    (what was left in the buffer at exit)."""

    head: str
    tail: str

    @classmethod
    def of(cls, gm: GoalModel, rat: RatNode) -> LexerEcho:
        """The echo of reading ``gm`` and building ``rat``."""
        return cls.split(echoed_text(gm, rat))

    @classmethod
    def split(cls, echo: str) -> LexerEcho:
        """``echo`` split at :func:`split_point` of its UTF-8 bytes.  A lone surrogate (a JSON
        escape such as ``\\ud800``, which the original refuses to read) is echoed as ``?``."""
        data = echo.encode("utf-8", "replace")
        cut = split_point(data)
        return cls(data[:cut].decode("utf-8"), data[cut:].decode("utf-8"))

    def print_head(self, out: IO[str]) -> None:
        out.write(self.head)

    def print_tail(self, out: IO[str]) -> None:
        out.write(self.tail)
