"""Reader of the property language (``grammars/property.lark``, docs/formats/properties.md)
into the values of :mod:`mutrose_cp.model.properties`.

A properties file holds one named property per line, ``name: quantifier formula``; blank lines
and lines starting with ``#`` are skipped.  On the command line a property may go unnamed
(``--property 'never uses(action drop)'``): it is then named after its position.  Every
syntax error is located (``file:line:col``, or ``--property N:col``) and names what could
have come there; a name used twice is refused at its second line.
"""
from __future__ import annotations

import os
import re
from typing import Iterable, Literal, Sequence, cast

from lark import Token, Transformer
from lark.exceptions import UnexpectedInput

from ..errors import MissionError, Problem, located
from ..model.properties import (
    Before,
    Comparison,
    Fact,
    Finally,
    Formula,
    Implies,
    InitiallyNeeded,
    Junction,
    Not,
    Property,
    Quantifier,
    Robots,
    TaskPattern,
    UsedKind,
    Uses,
)
from .grammar import EmbeddedLanguage, error_position
from .text import decode_utf8, read_bytes

_Child = Token | Formula | TaskPattern | Fact | tuple[str, ...] | bool | None


def _formula(node: _Child) -> Formula:
    if isinstance(node, (Uses, Before, Finally, InitiallyNeeded, Robots, Not, Junction, Implies)):
        return node
    raise AssertionError(f"the property grammar gives a formula here, not {node!r}")


def _task(node: _Child) -> TaskPattern:
    if isinstance(node, TaskPattern):
        return node
    raise AssertionError(f"the property grammar gives a task here, not {node!r}")


def _fact(node: _Child) -> Fact:
    if isinstance(node, Fact):
        return node
    raise AssertionError(f"the property grammar gives a fact here, not {node!r}")


def _junction(op: Literal["and", "or"], children: Iterable[_Child]) -> Junction:
    """An ``and``/``or`` node, with operands of the same operator spliced in."""
    operands: list[Formula] = []
    for child in map(_formula, children):
        operands.extend(child.operands if isinstance(child, Junction) and child.op == op else (child,))
    return Junction(op, tuple(operands))


class _PropertyBuilder(Transformer[Token, tuple[Quantifier, Formula]]):
    """Turns the ``property.lark`` parse into ``(quantifier, formula)``."""

    def start(self, children: list[_Child]) -> tuple[Quantifier, Formula]:
        quantifier, formula = children
        return cast(Quantifier, str(quantifier)), _formula(formula)

    def implies(self, children: list[_Child]) -> Implies:
        return Implies(_formula(children[0]), _formula(children[1]))

    def or_(self, children: list[_Child]) -> Junction:
        return _junction("or", children)

    def and_(self, children: list[_Child]) -> Junction:
        return _junction("and", children)

    def not_(self, children: list[_Child]) -> Not:
        return Not(_formula(children[0]))

    def uses(self, children: list[_Child]) -> Uses:
        target = children[0]
        if isinstance(target, tuple):
            return Uses((cast(UsedKind, target[0]), target[1]))
        return Uses(_task(target))

    def named(self, children: list[_Child]) -> tuple[str, ...]:
        return str(children[0]), str(children[1])

    def before(self, children: list[_Child]) -> Before:
        return Before(_task(children[0]), _task(children[1]))

    def finally_(self, children: list[_Child]) -> Finally:
        return Finally(_fact(children[0]))

    def initially_needed(self, children: list[_Child]) -> InitiallyNeeded:
        return InitiallyNeeded(_fact(children[0]))

    def robots(self, children: list[_Child]) -> Robots:
        task, comparison, bound = children
        return Robots(_task(task), _comparison(comparison), int(str(bound)))

    def task(self, children: list[_Child]) -> TaskPattern:
        name, arguments = children
        return TaskPattern(str(name), None if arguments is None else cast(tuple[str, ...], arguments))

    def arguments(self, children: list[_Child]) -> tuple[str, ...]:
        return tuple(str(c) for c in children if c is not None)

    def negated(self, _children: list[_Child]) -> bool:
        return True

    def fact(self, children: list[_Child]) -> Fact:
        negated, name, arguments, comparison, value = children
        compared = None if comparison is None else (_comparison(comparison), float(str(value)))
        return Fact(str(name), cast(tuple[str, ...], arguments), negated is not None, compared)


def _comparison(token: _Child) -> Comparison:
    text = str(token)
    return cast(Comparison, "==" if text == "=" else text)


PROPERTIES = EmbeddedLanguage("property.lark", _PropertyBuilder, maybe_placeholders=True)

_TERMINALS = {
    "QUANTIFIER": "always, some, never or count",
    "_USES": "uses(...)", "_BEFORE": "before(...)", "_FINALLY": "finally(...)",
    "_NEEDED": "initially-needed(...)", "_ROBOTS": "robots(...)",
    "_NOT": "not", "_LPAR": "'('", "_RPAR": "')'", "_COMMA": "','",
    "_AND": "and", "_OR": "or", "_IMPLIES": "implies",
    "_TASK": "task", "KIND": "method, action, capability or decomposition",
    "NAME": "a name", "VARIABLE": "a ?variable", "INT": "a whole number", "NUMBER": "a number",
    "COMPARISON": "a comparison (>=, <=, ==, !=, >, <)", "$END": "end of property",
}
_WORD = re.compile(r"\s*([\w?\-|.]+|\S)")
_NAMED = re.compile(r"\s*([A-Za-z][\w\-]*)\s*:(?!=)")


def _expected(terminals: set[str]) -> str:
    words = [text for terminal, text in _TERMINALS.items() if terminal in terminals]
    if not words:
        return "nothing more"
    return words[0] if len(words) == 1 else ", ".join(words[:-1]) + " or " + words[-1]


def parse_property(text: str, name: str, where: str, *, line: int | None = None, offset: int = 0) -> Property:
    """The property ``text`` named ``name``; ``where`` (a file or ``--property N``) and ``line``
    locate its errors, ``offset`` is where ``text`` starts on that line."""
    try:
        quantifier, formula = PROPERTIES.parse(text)
    except UnexpectedInput as err:
        position = error_position(err, text)
        word = _WORD.match(text, position)
        found = repr(word[1]) if word else "the end"
        expected = _expected(PROPERTIES.terminals_accepted_at(text, err, position))
        column = offset + position + 1
        at = located(where, line, column) if line is not None else f"{where}:{column}"
        raise MissionError(Problem(at, f"property {name}: expected {expected}, found {found}")) from None
    shown = located(where, line)
    return Property(name, quantifier, formula, text.strip(), shown)


def read_properties(path: str | os.PathLike[str]) -> list[Property]:
    """Every property of the file at ``path``, in order; all its problems raised together."""
    source = os.fspath(path)
    text = decode_utf8(read_bytes(source, "properties"), source, "properties file")
    properties: list[Property] = []
    problems: list[Problem] = []
    seen: dict[str, int] = {}
    for number, line in enumerate(text.splitlines(), start=1):
        if not line.strip() or line.lstrip().startswith("#"):
            continue
        named = _NAMED.match(line)
        if named is None:
            problems.append(Problem(located(source, number, len(line) - len(line.lstrip()) + 1),
                                    "a property needs a name: write name: always ... (one property per line)"))
            continue
        name = named[1]
        if name in seen:
            problems.append(Problem(located(source, number, named.start(1) + 1),
                                    f"property {name} is also defined at line {seen[name]}"))
            continue
        seen[name] = number
        try:
            properties.append(parse_property(line[named.end():], name, source, line=number, offset=named.end()))
        except MissionError as err:
            problems.extend(err.problems)
    if problems:
        raise MissionError(problems)
    if not properties:
        raise MissionError(Problem(located(source), "the file holds no property (write name: always ...)"))
    return properties


def command_line_properties(texts: Sequence[str]) -> list[Property]:
    """The ``--property`` values, in order: ``name: ...`` or unnamed (``property-N``)."""
    properties: list[Property] = []
    problems: list[Problem] = []
    for number, text in enumerate(texts, start=1):
        named = _NAMED.match(text)
        name, offset = (named[1], named.end()) if named else (f"property-{number}", 0)
        try:
            properties.append(parse_property(text[offset:], name, f"--property {number}", offset=offset))
        except MissionError as err:
            problems.extend(err.problems)
    if problems:
        raise MissionError(problems)
    return properties


def given_properties(path: str | os.PathLike[str] | None, texts: Sequence[str]) -> list[Property]:
    """The properties of a command line: those of the file at ``path`` (when given), then each
    of ``texts`` (``--property``), in order."""
    return [*(read_properties(path) if path else ()), *command_line_properties(texts)]
