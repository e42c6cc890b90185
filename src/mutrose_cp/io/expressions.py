"""Parsers of the expression languages embedded in the goal model (spec ``goal-model.md`` §5,
§7–§9), producing the values of :mod:`mutrose_cp.model.expressions`.

* runtime annotations: ``G1: text [G2;(G3#G4);FALLBACK(G5,G6)]``
* conditions (achieve/context conditions and select bodies), with the original's quirk that
  ``||`` binds tighter than ``&&``
* ``select`` queries and ``forAll`` achieve conditions

Each has a lark grammar in ``grammars/``; syntax errors raise
:class:`~mutrose_cp.errors.MissionError` with the column inside the expression.
"""
from __future__ import annotations

import re
from functools import lru_cache
from typing import Any, Iterable, TypeVar

from lark import Token, Transformer
from lark.exceptions import UnexpectedInput

from ..errors import MissionError
from .grammar import EmbeddedLanguage, error_position
from ..model.expressions import Annotation, AnnotationLeaf, AnnotationOp, Atom, BoolOp, Condition, ForAll, Select

# ---------------------------------------------------------------------------------------------
# The two languages.  Their parsers are built on first use and the parse functions are memoised:
# the same few expressions are parsed once per goal-model instance, i.e. thousands of times for
# large worlds, and every result is an immutable value.

Operator = TypeVar("Operator", AnnotationOp, BoolOp)


def _spliced(kind: type[Operator], op: str, operands: Iterable[Annotation] | Iterable[Condition]) -> Operator:
    """An operator node, with operands of the same operator spliced in (spec §5 flattening).

    ``;``, ``#`` and ``FALLBACK`` are flattened as the original does; ``&&`` and ``||`` are
    associative for every evaluator (and the original's select ``||`` bug, "keep only the left
    operand", gives the same result on ``(a||b)||c`` and ``a||b||c``), so flattening loses
    nothing and keeps trees shallow."""
    children: list[Any] = []
    for operand in operands:
        if isinstance(operand, kind) and operand.op == op:
            children.extend(operand.children)
        else:
            children.append(operand)
    return kind(op, tuple(children))


_AnnotationChild = Token | Annotation | None  # what _AnnotationBuilder's methods receive
_ConditionChild = Token | Condition | None  # what _ConditionBuilder's methods receive


def _annotation(node: _AnnotationChild) -> Annotation:
    """An operand the annotation grammar makes a sub-annotation (already transformed)."""
    if isinstance(node, (AnnotationLeaf, AnnotationOp)):
        return node
    raise AssertionError(f"the annotation grammar gives an operand here, not {node!r}")


def _condition(node: _ConditionChild) -> Condition:
    """An operand the condition grammar makes a sub-condition (already transformed)."""
    if isinstance(node, (Atom, BoolOp)):
        return node
    raise AssertionError(f"the condition grammar gives an operand here, not {node!r}")


class _AnnotationBuilder(Transformer[Token, tuple[str, Annotation | None]]):
    """Turns the ``annotation.lark`` parse into ``(id, Annotation | None)``."""

    def start(self, children: list[_AnnotationChild]) -> tuple[str, Annotation | None]:
        name, _description, annotation = children
        return str(name), None if annotation is None else _annotation(annotation)

    def description(self, _children: list[_AnnotationChild]) -> None:
        return None

    def annot(self, children: list[_AnnotationChild]) -> Annotation | None:
        operand = children[0]  # None for empty brackets
        return None if operand is None else _annotation(operand)

    def leaf(self, children: list[_AnnotationChild]) -> AnnotationLeaf:
        return AnnotationLeaf(str(children[0]))

    def seq_op(self, children: list[_AnnotationChild]) -> AnnotationOp:
        return _spliced(AnnotationOp, ";", map(_annotation, children))

    def par_op(self, children: list[_AnnotationChild]) -> AnnotationOp:
        return _spliced(AnnotationOp, "#", map(_annotation, children))

    def fallback_op(self, children: list[_AnnotationChild]) -> AnnotationOp:
        return _spliced(AnnotationOp, "FALLBACK", map(_annotation, children))


class _ConditionBuilder(Transformer[Token, Condition | None]):
    """Turns the ``condition.lark`` parse into a :data:`Condition` (or None)."""

    def start(self, children: list[_ConditionChild]) -> Condition | None:
        condition = children[0]  # None for an empty condition
        return None if condition is None else _condition(condition)

    def atom(self, children: list[_ConditionChild]) -> Atom:
        return make_atom(str(children[0]))

    def and_op(self, children: list[_ConditionChild]) -> BoolOp:
        return _spliced(BoolOp, "&&", map(_condition, children))

    def or_op(self, children: list[_ConditionChild]) -> BoolOp:
        return _spliced(BoolOp, "||", map(_condition, children))


# lexer="basic" (not the contextual lexer) so that FALLBACK is always the keyword, even among
# description words, exactly like the original flex lexer.
ANNOTATIONS = EmbeddedLanguage("annotation.lark", _AnnotationBuilder, lexer="basic", maybe_placeholders=True)
CONDITIONS = EmbeddedLanguage("condition.lark", _ConditionBuilder, lexer="basic", maybe_placeholders=True)


# ---------------------------------------------------------------------------------------------
# Syntax error messages: "Parse error in <what>: <expression>: column <n>: expected <...>"

_ANNOTATION_TERMINALS = {
    "NAME": "a goal or task name",
    "_FALLBACK": "FALLBACK",
    "_LPAR": "'('",
    "_RPAR": "')'",
    "_COMMA": "','",
    "_SEQ": "';'",
    "_PAR": "'#'",
    "_LSQB": "'['",
    "_RSQB": "']'",
    "_COLON": "':'",
    "$END": "end of text",
}

_CONDITION_TERMINALS = {
    "ATOM": "an atom such as v.attr",
    "_LPAR": "'('",
    "_AND": "'&&'",
    "_OR": "'||'",
    "_RPAR": "')'",
    "$END": "end of expression",
}

# Terminals that start an operand; when a name/atom is acceptable, naming the name alone reads
# better than listing every way an operand can start.
_OPERAND_STARTS = {"NAME": {"_LPAR", "_FALLBACK"}, "ATOM": {"_LPAR"}}


def _join_alternatives(words: list[str]) -> str:
    if not words:
        return "nothing"
    if len(words) == 1:
        return words[0]
    return ", ".join(words[:-1]) + " or " + words[-1]


def _expected_text(expected: Iterable[str], names: dict[str, str], overrides: dict[str, str]) -> str:
    wanted = set(expected)
    for operand, starts in _OPERAND_STARTS.items():
        if operand in wanted:
            wanted -= starts
    table = {**names, **overrides}
    return _join_alternatives([table[t] for t in table if t in wanted])


# ---------------------------------------------------------------------------------------------
# Runtime annotations


@lru_cache(maxsize=4096)
def parse_node_text(text: str) -> tuple[str, Annotation | None]:
    """Parse a whole goal text ``G3: description words [annotation]`` (spec §2.1, §5).

    Returns the name before ``:`` and the annotation (None for no or empty brackets).  The
    whole text is parsed, as in the original, so a stray ``,``/``;``/``:`` or the word FALLBACK
    in the description is a syntax error; other characters outside the grammar are skipped.
    Raises :class:`MissionError` ``Parse error in runtime annotation: <expr>: column <n>:
    expected <...>`` where ``<expr>`` is the bracketed annotation when the error lies inside it
    (the column then counts from its ``[``), else the whole text.
    """
    try:
        return ANNOTATIONS.parse(text)
    except UnexpectedInput as err:
        raise _annotation_error(text, err) from None


def _annotation_error(text: str, err: UnexpectedInput) -> MissionError:
    pos = error_position(err, text)
    bracket = text.find("[")  # '[' is always a token: no skipped character can be '['
    colon = text.find(":")
    if bracket != -1 and pos >= bracket:
        shown, column, name = text[bracket:], pos - bracket + 1, "a goal or task name"
    else:
        shown, column = text, pos + 1
        name = "a goal id such as G1" if colon == -1 or pos <= colon else "a description word"
    terminals = ANNOTATIONS.terminals_accepted_at(text, err, pos)
    expected = _expected_text(terminals, _ANNOTATION_TERMINALS, {"NAME": name})
    return MissionError(f"Parse error in runtime annotation: {shown}: column {column}: expected {expected}")


# ---------------------------------------------------------------------------------------------
# Conditions

_NOT_PREFIX = re.compile(r"not\s+")
_IN_ATOM = re.compile(r"(\S+)\s+in\s+(.*)", re.S)
# The first comparison operator wins; longer spellings are tried first at that position.  The
# original reads ``==`` like ``=`` in selects (the right side is the first identifier after the
# first '='), so it is normalised to ``=`` here.
_COMPARISON_ATOM = re.compile(r"(.*?)\s*(==|<>|>=|<=|=|>|<)\s*(.*)", re.S)


@lru_cache(maxsize=4096)
def make_atom(text: str) -> Atom:
    """Split an atom's text into the structured fields of :class:`Atom` (best effort).

    ``!v.a`` / ``not v.a`` set ``negated``; ``l in r`` gives op ``in``; otherwise the first
    comparison operator splits left and right.  ``variable``/``attribute`` come from the left
    operand split at its first '.'; ``value`` is the right side trimmed, quotes stripped.  The
    evaluators decide which forms they accept (spec §8.1, §9) using ``text`` where needed.
    """
    text = text.rstrip()
    body = text
    negated = False
    if body.startswith("!"):
        negated, body = True, body[1:].lstrip()
    elif (m := _NOT_PREFIX.match(body)) is not None:
        negated, body = True, body[m.end() :]
    op: str | None = None
    value = ""
    left = body
    if (m := _IN_ATOM.fullmatch(body)) is not None:
        left, op, value = m[1], "in", m[2]
    elif (m := _COMPARISON_ATOM.fullmatch(body)) is not None:
        left, op, value = m[1], ("=" if m[2] == "==" else m[2]), m[3]
    value = value.strip().strip('"').strip()
    variable, _, attribute = left.strip().partition(".")
    return Atom(text=text, variable=variable, attribute=attribute, negated=negated, op=op, value=value)


@lru_cache(maxsize=4096)
def _parse_condition_in(source: str, what: str, shown: str, offset: int) -> Condition | None:
    """Parse ``source``, which sits at ``offset`` inside ``shown`` (for error columns)."""
    try:
        return CONDITIONS.parse(source)
    except UnexpectedInput as err:
        pos = error_position(err, source)
        terminals = CONDITIONS.terminals_accepted_at(source, err, pos)
        expected = _expected_text(terminals, _CONDITION_TERMINALS, {})
        column = offset + pos + 1
        raise MissionError(
            f"Parse error in {what}: {shown}: column {column}: expected {expected}"
        ) from None


def parse_condition(text: str) -> Condition | None:
    """Parse a condition (spec §9); None for an empty/blank one.

    ``||`` binds tighter than ``&&`` (``a && b || c`` == ``a && (b || c)``), as in the original.
    Raises :class:`MissionError` ``Parse error in condition: <text>: column <n>: expected ...``.
    """
    return _parse_condition_in(text, "condition", text, 0)


# ---------------------------------------------------------------------------------------------
# select / forAll.  The validating regexes are the original's (spec §7, §8), applied to the whole
# value; the parts are then extracted the way the original does (first '>', '(', ':', '|', and
# the condition ends at the first ')' after '|').

_SELECT_RE = re.compile(
    r"[a-zA-Z]{1}[\w.]*(->select)[(][a-zA-Z]{1}[\w.]*[:][a-zA-Z]+[\w.]+[ ]*[|][ ]*(.*)[)]", re.ASCII
)
_FORALL_RE = re.compile(r"[a-zA-Z]+[\w.]*(->forAll)[(][a-zA-Z]+[\w.]*[ ]*[|][ ]*(.)*[)]", re.ASCII)
_IDENTIFIER = re.compile(r"[a-zA-Z]+[\w.]*", re.ASCII)

# How to fix a value the regexes reject (the goal-model reader adds them to its located problems).
SELECT_HINT = (
    "Write <source>->select(<var>:<Type> | <condition>), e.g. world_db->select(r:Room | !r.is_clean), "
    "with no spaces around ':' and a type of at least two characters."
)
FORALL_HINT = (
    "Write <collection>->forAll(<var> | <condition>), e.g. rooms->forAll(r | r.is_clean); the "
    "iteration variable has no type here (declare it in the goal's Controls)."
)


def _first_identifier(text: str) -> str:
    m = _IDENTIFIER.search(text)
    return m.group() if m else ""


@lru_cache(maxsize=1024)
def parse_select(text: str) -> Select:
    """Parse a ``QueriedProperty`` ``queried->select(var:Type | condition)`` (spec §8).

    Raises :class:`MissionError` ``Invalid select statement <text> in GM.`` when the value does
    not match the original's regex (e.g. empty, spaces around ':', a one-letter type), and
    ``Parse error in query: ...`` for a bad condition.
    """
    if _SELECT_RE.fullmatch(text) is None:
        raise MissionError(f"Invalid select statement {text} in GM.")
    arrow = text.index(">")
    colon = text.index(":", arrow)
    paren = text.index("(", arrow)
    bar = text.index("|", colon)
    close = text.index(")", bar)
    source = text[bar + 1 : close]
    return Select(
        queried=_first_identifier(text[:arrow]),
        variable=_first_identifier(text[paren + 1 : colon]),
        type=_first_identifier(text[colon + 1 : bar]),
        condition=_parse_condition_in(source, "query", text, bar + 1),
        text=text,
    )


@lru_cache(maxsize=1024)
def parse_forall(text: str) -> ForAll:
    """Parse a universal ``AchieveCondition`` ``iterated->forAll(iteration | condition)`` (§7).

    The condition is the text between ``|`` and the first ``)`` (so it cannot contain
    parentheses, as in the original) and may be empty (condition None).  Raises
    :class:`MissionError` ``Invalid forAll statement <text> in GM.`` when the original's regex
    does not match (e.g. a typed iteration variable ``x : T``), ``Parse error in condition: ...``
    for a bad condition.
    """
    if _FORALL_RE.fullmatch(text) is None:
        raise MissionError(f"Invalid forAll statement {text} in GM.")
    arrow = text.index(">")
    bar = text.index("|", arrow)
    head = text[arrow + 1 : bar]
    close = text.index(")", bar)
    source = text[bar + 1 : close]
    return ForAll(
        iterated=_first_identifier(text[:arrow]),
        iteration=_first_identifier(head[head.find("(") + 1 :]),
        condition=_parse_condition_in(source, "condition", text, bar + 1),
        condition_text=source.strip(),
        text=text,
    )
