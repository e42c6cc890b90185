"""HDDL domain reader (the extended subset of the MutRoSe decomposer, spec ``hddl.md``).

The domain is parsed with a lark grammar (``grammars/hddl.lark``) into the frozen
:class:`~mutrose_cp.model.Domain`.
Syntax errors and static domain errors (undeclared predicates or subtasks, arity) are raised as
:class:`~mutrose_cp.errors.MissionError` located at ``file:line:col``.
"""
from __future__ import annotations

import os
from dataclasses import dataclass
from functools import lru_cache
from typing import Callable, Iterable, cast

from lark import Lark, Token, Tree
from lark.exceptions import UnexpectedCharacters, UnexpectedInput, UnexpectedToken

from ..errors import MissionError, Problem, closest, counted, located
from ..model.domain import (
    AbstractTask,
    Action,
    Comparison,
    Declaration,
    Domain,
    Literal,
    Method,
    NumericEffect,
    Parameter,
    Precondition,
    Subtask,
    TypeMention,
)
from .grammar import cached_lalr_parser
from .text import decode_utf8, read_bytes

# ---------------------------------------------------------------------------------------------
# Reader

_RESERVED_NAMES = frozenset(
    "define domain problem and or not imply forall exists when increase decrease assign typeof "
    "sortof".split()
)
"""Keywords of hddl.md §1 that look like names. All but ``problem`` are terminals of the grammar
(the basic lexer re-types them); ``problem`` is unused by a domain, so it is checked by hand."""

_NATIVE_TYPES = ("object", "robot", "robotteam")
_ALWAYS_ACCEPTED_IN_PRECONDITIONS = frozenset({"at", "hascapability"})
_TERMINAL_DESCRIPTIONS = {
    "NAME": "a name",
    "VAR": "a variable",
    "NUMBER": "a number",
    "REQUIRE_NAME": "a requirement",
    "$END": "end of file",
}


@lru_cache(maxsize=1)
def _parser() -> Lark:
    """The LALR parser, built once per process (its tables cached between runs, ``grammar``)."""
    return cached_lalr_parser("hddl.lark", lexer="basic", start="domain", propagate_positions=True, maybe_placeholders=True)


def load_domain(path: str | os.PathLike[str]) -> Domain:
    """Read and parse the HDDL domain file at ``path``; locations in errors use ``path`` as given."""
    source = os.fspath(path)
    data = read_bytes(source, "HDDL domain")
    return parse_domain(decode_utf8(data, source, "HDDL domain"), source)


def parse_domain(text: str, source: str) -> Domain:
    """Parse the HDDL domain ``text`` (``source`` names it in error locations) and check it.

    A syntax error is reported alone (nothing after it can be trusted); otherwise every static
    problem is collected and raised together in one :class:`MissionError`, sorted by position."""
    try:
        tree = _parser().parse(text)
        return _DomainReader(source).read(tree)
    except UnexpectedInput as exc:
        raise MissionError(_syntax_problem(exc, text, source)) from None
    except RecursionError:
        line, column, depth = _deepest_paren(text)
        raise MissionError(Problem(
            located(source, line, column),
            f"the domain nests {depth} levels of parentheses, too deep to be read; no HDDL domain "
            "needs this: the file is probably damaged",
        )) from None


# --- syntax errors ----------------------------------------------------------------------------


def _describe_terminal(name: str) -> str:
    if name in _TERMINAL_DESCRIPTIONS:
        return _TERMINAL_DESCRIPTIONS[name]
    try:
        pattern = _parser().get_terminal(name).pattern
    except KeyError:
        return name
    return f"'{pattern.value}'"


def _expected_phrase(terminals: Iterable[str]) -> str:
    names = sorted({_describe_terminal(t) for t in terminals})
    if not names:
        return ""
    if len(names) == 1:
        return f"expected {names[0]}, "
    return f"expected one of {', '.join(names)}, "



def _end_of_text(text: str) -> tuple[int, int]:
    line = text.count("\n") + 1
    return line, len(text) - (text.rfind("\n") + 1) + 1


def _deepest_paren(text: str) -> tuple[int, int, int]:
    """(line, column, depth) of the first ``(`` at the deepest nesting (comments skipped)."""
    depth = deepest = 0
    at = (1, 1)
    for line_no, line in enumerate(text.split("\n"), start=1):
        for col, char in enumerate(line.split(";", 1)[0], start=1):
            if char == "(":
                depth += 1
                if depth > deepest:
                    deepest, at = depth, (line_no, col)
            elif char == ")":
                depth -= 1
    return at[0], at[1], deepest


def signature(name: str, parameters: Iterable[Parameter]) -> str:
    """``(name ?a - t1 ?b - t2)`` as declared."""
    return "(" + " ".join([name, *(f"{p.name} - {p.type}" for p in parameters)]) + ")"


def _innermost_unclosed_paren(text: str) -> tuple[int, int] | None:
    """Position of the last ``(`` left open at the end of ``text`` (comments skipped)."""
    stack: list[tuple[int, int]] = []
    for line_no, line in enumerate(text.split("\n"), start=1):
        for col, char in enumerate(line.split(";", 1)[0], start=1):
            if char == "(":
                stack.append((line_no, col))
            elif char == ")" and stack:
                stack.pop()
    return stack[-1] if stack else None


def _accepted_terminals(exc: UnexpectedInput) -> set[str]:
    """The terminals the parser would have accepted where it failed (empty when unknown)."""
    if exc.interactive_parser is None:
        return set()
    # lark leaves InteractiveParser.accepts unannotated; it returns the set of terminal names
    accepts = cast(Callable[[], set[str]], exc.interactive_parser.accepts)
    try:
        return set(accepts())
    except Exception:  # accepts() replays the parser; never let it hide the real error
        return set()


def _syntax_problem(exc: UnexpectedInput, text: str, source: str) -> Problem:
    """Turn a lark error into ``file:line:col: syntax error: expected ..., found ...``."""
    expected = _accepted_terminals(exc)
    if isinstance(exc, UnexpectedToken):
        expected = expected or set(exc.expected)
        token = exc.token
        if token.type == "$END":
            line, column = _end_of_text(text)
            message = f"syntax error: {_expected_phrase(expected)}found end of file"
            paren = _innermost_unclosed_paren(text)
            if paren is not None and "_RP" in expected:
                message += f" (the '(' at {paren[0]}:{paren[1]} is not closed)"
            return Problem(located(source, line, column), message)
        message = f"syntax error: {_expected_phrase(expected)}found '{token.value}'"
        if "NAME" in expected and token.value in _RESERVED_NAMES:
            message += f" ('{token.value}' is a reserved word and cannot be used as a name)"
        return Problem(located(source, token.line, token.column), message)
    if isinstance(exc, UnexpectedCharacters):
        pos = exc.pos_in_stream  # always set by the lexer that raises UnexpectedCharacters
        char = text[pos] if pos is not None and pos < len(text) else ""
        message = f"syntax error: {_expected_phrase(expected)}found invalid character '{char}'"
        return Problem(located(source, exc.line, exc.column), message)
    eof_line: int | None = getattr(exc, "line", None)  # UnexpectedEOF
    eof_column: int | None = getattr(exc, "column", None)
    return Problem(located(source, eof_line, eof_column), f"syntax error: {exc}")


# --- tree reading and static checks -----------------------------------------------------------
#
# lark types every child of a tree as ``Token | Tree``, and an optional clause ``[...]`` may also
# be None (``maybe_placeholders``).  The grammar fixes which one each position holds; these
# accessors check it once, where the child is taken, so the reader below works on precise types.

_Where = Token | Tree[Token] | tuple[int, int]


def _token(node: object) -> Token:
    """A child the grammar makes a terminal (a name, variable, number or kept keyword)."""
    if isinstance(node, Token):
        return node
    raise AssertionError(f"the HDDL grammar gives a token here, not {node!r}")


def _tree(node: object) -> Tree[Token]:
    """A child the grammar makes a rule."""
    if isinstance(node, Tree):
        return node
    raise AssertionError(f"the HDDL grammar gives a rule here, not {node!r}")


def _optional_tree(node: object) -> Tree[Token] | None:
    """An optional clause ``[...]`` of the grammar: None when the domain omits it."""
    return None if node is None else _tree(node)


def _tokens(nodes: Iterable[object]) -> list[Token]:
    return [_token(n) for n in nodes]


def _trees(nodes: Iterable[object]) -> list[Tree[Token]]:
    return [_tree(n) for n in nodes]


def _position(token: Token) -> tuple[int, int]:
    """``(line, column)`` of a token (the parser propagates positions, so both are set)."""
    return token.line or 0, token.column or 0


def _values(tokens: Iterable[Token]) -> tuple[str, ...]:
    return tuple(t.value for t in tokens)


@dataclass
class _Body:
    """What a precondition/effect is checked against: the owner's name, kind and variables."""

    kind: str  # "action" | "method"
    name: str
    variables: frozenset[str]


class _DomainReader:
    """Builds the :class:`Domain` from the parse tree and collects every static problem.

    Declarations are gathered first (sections may come in any order), then task, action and method
    bodies are converted and checked against them."""

    def __init__(self, source: str) -> None:
        self.source = source
        self._problems: list[tuple[int, int, str]] = []
        self._subtask_counter = 0
        self.predicates: list[Declaration] = []
        self.functions: list[Declaration] = []
        self.capabilities: list[str] = []
        self.constants: list[tuple[str, str]] = []
        self._type_groups: list[tuple[list[str], str | None]] = []
        self._mentioned_sorts: dict[str, Token] = {}  # sort -> its first mention in a declaration
        self._known_types: set[str] = set()
        self.tasks: dict[str, AbstractTask] = {}
        self.actions: dict[str, Action] = {}

    # ---- problems

    def _error(self, where: _Where, message: str) -> None:
        if isinstance(where, Token):
            line, column = _position(where)
        elif isinstance(where, Tree):
            line, column = getattr(where.meta, "line", 0), getattr(where.meta, "column", 0)
        else:
            line, column = where
        self._problems.append((line, column, message))

    def _raise_if_problems(self) -> None:
        if self._problems:
            ordered = sorted(self._problems, key=lambda p: (p[0], p[1]))
            raise MissionError(
                [Problem(located(self.source, line, col), msg) for line, col, msg in ordered]
            )

    # ---- entry point

    def read(self, tree: Tree[Token]) -> Domain:
        name_token, *sections = tree.children
        self._check_reserved_names(tree)
        bodies = self._read_declarations(_trees(sections))
        types = self._build_types()
        self._known_types = {t for t, _ in types} | {p for _, p in types if p} | set(_NATIVE_TYPES)

        declared_at: dict[str, tuple[str, Token]] = {}
        for body in bodies:
            if body.data != "method_def":
                self._read_task_or_action(body, declared_at)
        methods = self._read_methods([b for b in bodies if b.data == "method_def"])
        self._raise_if_problems()
        return Domain(
            name=str(name_token),
            source=self.source,
            types=types,
            constants=tuple(self.constants),
            predicates=tuple(self.predicates),
            functions=tuple(self.functions),
            capabilities=tuple(self.capabilities),
            tasks=tuple(self.tasks.values()),
            actions=tuple(self.actions.values()),
            methods=tuple(methods),
            undeclared_types=self._undeclared_types(),
        )

    def _read_declarations(self, sections: list[Tree[Token]]) -> list[Tree[Token]]:
        """Read the declaration sections; return the task, action and method bodies in file
        order, to be read once every declaration is known (sections may come in any order)."""
        bodies: list[Tree[Token]] = []
        for section in sections:
            kind = section.data
            if kind in ("task_def", "action_def", "method_def"):
                bodies.append(section)
            elif kind == "types":
                self._read_types(section)
            elif kind == "constants":
                self._read_constants(section)
            elif kind == "predicates":
                self.predicates.extend(self._read_declaration(d) for d in _trees(section.children))
            elif kind == "functions":
                self.functions.extend(
                    self._read_declaration(d) for d in _trees(section.children) if d.data == "atomic_decl"
                )
            elif kind == "capabilities":
                self.capabilities.extend(str(t) for t in section.children)
            # requirements and rewards are ignored (hddl.md §2)
        return bodies

    def _read_methods(self, bodies: list[Tree[Token]]) -> list[Method]:
        method_names: dict[str, Token] = {}
        methods: list[Method] = []
        for body in bodies:
            method = self._read_method(body, method_names)
            if method is not None:
                methods.append(method)
        return methods

    def _check_reserved_names(self, tree: Tree[Token]) -> None:
        # Every other reserved word is a terminal and already a syntax error where a name goes.
        for token in tree.scan_values(
            lambda v: isinstance(v, Token) and v.type == "NAME" and v.value in _RESERVED_NAMES
        ):
            self._error(token, f"'{token.value}' is a reserved word and cannot be used as a name")

    # ---- declarations

    def _mention_sort(self, sort: Token) -> None:
        self._mentioned_sorts.setdefault(sort.value, sort)

    def _read_types(self, section: Tree[Token]) -> None:
        pending: list[str] = []
        for item in section.children:
            if isinstance(item, Token):
                pending.append(item.value)
                continue
            minus, parent = _tokens(item.children)
            if not pending:
                self._error(minus, f"'- {parent}' is not preceded by any type name")
                continue
            self._type_groups.append((pending, parent.value))
            self._mention_sort(parent)
            pending = []
        if pending:
            self._type_groups.append((pending, None))

    def _read_constants(self, section: Tree[Token]) -> None:
        for group in _trees(section.children):
            *names, _minus, sort = _tokens(group.children)
            self._mention_sort(sort)
            self.constants.extend((n.value, sort.value) for n in names)

    def _read_declaration(self, decl: Tree[Token]) -> Declaration:
        name_node, typed_vars = decl.children
        name = _token(name_node)
        typed = self._typed_vars(_tree(typed_vars))
        for _variable, sort in typed:
            self._mention_sort(sort)
        return Declaration(name.value, tuple(Parameter(v.value, t.value) for v, t in typed), *_position(name))

    def _build_types(self) -> tuple[tuple[str, str | None], ...]:
        """(type, parent) in declaration order, with the native sorts of hddl.md §2.1.

        ``robot``/``robotteam`` join the first ``- object`` group (else they are parentless roots)
        unless the domain declares them itself. Sorts only *mentioned* (undeclared parents, sorts
        of predicate/function/constant declarations, which PANDA creates on the fly) follow as
        parentless types so that every sort of the domain has an entry."""
        groups = [(list(names), parent) for names, parent in self._type_groups]
        declared = {t for names, _ in groups for t in names}
        natives = [t for t in ("robot", "robotteam") if t not in declared]
        object_group = next((g for g in groups if g[1] == "object"), None)
        if object_group is not None:
            object_group[0].extend(natives)
        else:
            groups.append((natives, None))
        types: list[tuple[str, str | None]] = []
        for names, parent in groups:
            for name in names:
                if (name, parent) not in types:
                    types.append((name, parent))
        known = {t for t, _ in types}
        for sort in self._mentioned_sorts:
            if sort not in known and sort != "object":
                types.append((sort, None))
                known.add(sort)
        return tuple(types)

    def _undeclared_types(self) -> tuple[TypeMention, ...]:
        """The sorts mentioned but declared neither in ``:types`` nor natively (hddl.md §2.1),
        each at its first mention."""
        declared = {t for names, _ in self._type_groups for t in names} | set(_NATIVE_TYPES)
        return tuple(TypeMention(sort, *_position(token))
                     for sort, token in self._mentioned_sorts.items() if sort not in declared)

    def _typed_vars(self, tree: Tree[Token]) -> list[tuple[Token, Token]]:
        pairs: list[tuple[Token, Token]] = []
        for group in _trees(tree.children):
            *variables, _minus, sort = _tokens(group.children)
            pairs.extend((v, sort) for v in variables)
        return pairs

    def _parameters(self, tree: Tree[Token], owner: str) -> tuple[Parameter, ...]:
        """Typed parameters of a task/action/method; checks sorts and duplicate variables."""
        seen: set[str] = set()
        parameters: list[Parameter] = []
        for variable, sort in self._typed_vars(tree):
            if variable.value in seen:
                self._error(variable, f"parameter {variable.value} of {owner} is declared twice")
            seen.add(variable.value)
            if sort.value not in self._known_types:
                self._error(sort, f"unknown type '{sort.value}' of parameter {variable.value} of {owner}")
            parameters.append(Parameter(variable.value, sort.value))
        return tuple(parameters)

    # ---- abstract tasks and actions

    def _read_task_or_action(self, tree: Tree[Token], declared_at: dict[str, tuple[str, Token]]) -> None:
        name_node, params, capabilities_node, precondition, effect, _reliability = tree.children
        name = _token(name_node)
        kind = "abstract task" if tree.data == "task_def" else "action"
        owner = f"{kind} '{name.value}'"
        if name.value in declared_at:
            first_kind, first = declared_at[name.value]
            self._error(
                name,
                f"duplicate {kind} '{name.value}': the name is already declared as {first_kind} "
                f"at {first.line}:{first.column}",
            )
            return
        declared_at[name.value] = (f"an {kind}", name)
        parameters = self._parameters(_tree(params), owner)
        line, column = _position(name)
        if tree.data == "task_def":
            # hddl.md §3: capabilities, precondition and effect of abstract tasks are ignored.
            self.tasks[name.value] = AbstractTask(name.value, parameters, line, column)
            return
        body = _Body("action", name.value, frozenset(p.name for p in parameters))
        preconditions = self._preconditions(_optional_tree(precondition), body)
        effects, numeric = self._effects(_optional_tree(effect), body)
        capabilities = _optional_tree(capabilities_node)
        self.actions[name.value] = Action(
            name=name.value,
            parameters=parameters,
            capabilities=_values(_tokens(capabilities.children)) if capabilities else (),
            preconditions=preconditions,
            effects=effects,
            numeric_effects=numeric,
            line=line,
            column=column,
        )

    # ---- methods

    def _read_method(self, tree: Tree[Token], method_names: dict[str, Token]) -> Method | None:
        (name_node, params, task_call, precondition, effect, network, ordering,
         _constraints, _causal_links) = tree.children
        name = _token(name_node)
        owner = f"method '{name.value}'"
        if name.value in method_names:
            first = method_names[name.value]
            self._error(
                name,
                f"duplicate method '{name.value}' (already declared at {first.line}:{first.column})",
            )
        else:
            method_names[name.value] = name
        method_params = _optional_tree(params)
        parameters = self._parameters(_tree(method_params.children[0]), owner) if method_params else ()
        body = _Body("method", name.value, frozenset(p.name for p in parameters))

        task_name, *task_args = _tokens(_tree(task_call).children)
        self._check_variables(task_args, body)
        self._check_decomposed_task(task_name, len(task_args), owner)

        preconditions = self._preconditions(_optional_tree(precondition), body)
        effects, numeric = self._effects(_optional_tree(effect), body)
        subtasks, ordered = self._subtasks(_optional_tree(network), body)
        pairs = self._ordering(_optional_tree(ordering), subtasks, ordered, owner)
        if ordered:
            pairs = tuple((a.id, b.id) for a, b in zip(subtasks, subtasks[1:]))
        line, column = _position(name)
        return Method(
            name=name.value,
            parameters=parameters,
            task=task_name.value,
            task_args=_values(task_args),
            preconditions=preconditions,
            effects=effects,
            numeric_effects=numeric,
            subtasks=subtasks,
            ordering=pairs,
            ordered=ordered,
            line=line,
            column=column,
        )

    def _check_decomposed_task(self, task_name: Token, arity: int, owner: str) -> None:
        """The task a method decomposes must be a declared abstract task of that arity."""
        task = self.tasks.get(task_name.value)
        if task is None:
            what = "an action, not an abstract task" if task_name.value in self.actions else "not declared"
            self._error(
                task_name,
                f"{owner} decomposes unknown abstract task '{task_name.value}' ({what})",
            )
        elif arity != len(task.parameters):
            self._error(
                task_name,
                f"{owner} decomposes '{task_name.value}' with {counted(arity, 'argument')} "
                f"but the task declares {counted(len(task.parameters), 'parameter')}",
            )

    def _subtasks(self, network: Tree[Token] | None, body: _Body) -> tuple[tuple[Subtask, ...], bool]:
        """The task network; an omitted network is an empty *ordered* one (hddl.md §5)."""
        if network is None:
            return (), True
        keyword, defs = network.children
        ordered = _token(keyword).type in ("K_ORDERED_SUBTASKS", "K_ORDERED_TASKS")
        subtasks: list[Subtask] = []
        ids: set[str] = set()
        for definition in _trees(_tree(defs).children):
            if definition.data == "subtask_named":
                id_token, callee, *args = _tokens(definition.children)
                subtask_id = id_token.value
                if subtask_id in ids:
                    self._error(id_token, f"duplicate subtask id '{subtask_id}' in method '{body.name}'")
            else:
                callee, *args = _tokens(definition.children)
                subtask_id = f"__t_id_{self._subtask_counter}"
                self._subtask_counter += 1
            ids.add(subtask_id)
            self._check_variables(args, body)
            self._check_callee(callee, len(args), body)
            subtasks.append(Subtask(subtask_id, callee.value, _values(args), *_position(callee)))
        return tuple(subtasks), ordered

    def _check_callee(self, callee: Token, arity: int, body: _Body) -> None:
        declared = self.tasks.get(callee.value) or self.actions.get(callee.value)
        if declared is None:
            close = closest(callee.value, [*self.tasks, *self.actions])
            self._error(
                callee,
                f"There is no declaration of the subtask {callee.value} (method '{body.name}'): "
                "it is neither an abstract task nor an action"
                + (f"; did you mean '{close}'?" if close is not None else ""),
            )
        elif arity > len(declared.parameters):
            self._error(
                callee,
                f"subtask {callee.value} in method '{body.name}' is given {counted(arity, 'argument')} "
                f"but declares only {counted(len(declared.parameters), 'parameter')}: "
                f"{signature(declared.name, declared.parameters)}; remove the extra arguments",
            )

    def _ordering(
        self, ordering: Tree[Token] | None, subtasks: tuple[Subtask, ...], ordered: bool, owner: str
    ) -> tuple[tuple[str, str], ...]:
        if ordering is None:
            return ()
        keyword_node, defs = ordering.children
        keyword = _token(keyword_node)
        pairs = [_tokens(pair.children) for pair in _trees(_tree(defs).children)]
        if ordered and pairs:
            self._error(
                keyword,
                f"{owner} has an explicit {keyword.value} but its subtasks are already totally "
                "ordered (:ordered-subtasks / :ordered-tasks or no network)",
            )
            return ()
        ids = {s.id for s in subtasks}
        for pair in pairs:
            for token in pair:
                if token.value not in ids:
                    self._error(token, f"ordering of {owner} refers to unknown subtask id '{token.value}'")
        return tuple((a.value, b.value) for a, b in pairs)

    # ---- preconditions and effects

    def _check_variables(self, terms: Iterable[Token], body: _Body) -> None:
        for term in terms:
            if term.type == "VAR" and term.value not in body.variables:
                self._error(term, f"variable {term.value} is not a parameter of {body.kind} '{body.name}'")

    def _check_symbol(
        self, name: Token, arity: int, declarations: list[Declaration], what: str, body: _Body, clause: str
    ) -> None:
        matching = [d for d in declarations if d.name == name.value]
        if not matching:
            message = f"undeclared {what} '{name.value}' in the {clause} of {body.kind} '{body.name}'"
            close = closest(name.value, (d.name for d in declarations))
            if close is not None:
                section = ":predicates" if what == "predicate" else ":functions"
                message += f": did you mean '{close}'? If not, declare it in ({section} ...)"
            self._error(name, message)
            return
        arities = sorted({len(d.parameters) for d in matching})
        if arity not in arities:
            declared = " or ".join(str(a) for a in arities)
            signatures = " or ".join(signature(d.name, d.parameters) for d in matching)
            self._error(
                name,
                f"{what} '{name.value}' is used with {counted(arity, 'argument')} in {body.kind} "
                f"'{body.name}' but is declared with {declared}: {signatures}; pass one argument "
                "per declared parameter",
            )

    def _preconditions(self, clause: Tree[Token] | None, body: _Body) -> tuple[Precondition, ...]:
        conditions: list[Precondition] = []
        if clause is not None:
            self._gd(_tree(clause.children[0]), body, False, conditions)
        return tuple(conditions)

    def _gd(self, gd: Tree[Token], body: _Body, negated: bool, out: list[Precondition]) -> None:
        """Flatten a goal description into ``out``: conjunctions are spliced, negations pushed
        down to the atoms (each atom is checked against the declarations on the way)."""
        kind = gd.data
        if kind == "empty":
            return
        if kind == "gd_and":
            self._gd_and(gd, body, negated, out)
        elif kind == "gd_not":
            self._gd(_tree(gd.children[0]), body, not negated, out)
        elif kind == "atom":
            out.append(self._precondition_atom(gd, body, negated))
        elif kind == "comparison":
            out.append(self._comparison(gd, body, negated))
        elif kind == "equality":
            # (= ?x ?y) codesignation constraints are ignored by the decomposer (hddl.md §4.1).
            self._check_variables(_tokens(gd.children), body)
        elif kind == "gd_unsupported":
            keyword = _token(gd.children[0])
            self._error(keyword, f"'{keyword.value}' is not supported by the decomposer")
        else:  # pragma: no cover - the grammar produces no other gd node
            raise AssertionError(kind)

    def _gd_and(self, gd: Tree[Token], body: _Body, negated: bool, out: list[Precondition]) -> None:
        """A conjunction; under a negation it would be a disjunction, which the decomposer
        cannot use."""
        if negated and gd.children:
            self._error(gd, "a negated conjunction (not (and ...)) is not supported by the decomposer")
            return
        for child in _trees(gd.children):
            self._gd(child, body, negated, out)

    def _precondition_atom(self, atom: Tree[Token], body: _Body, negated: bool) -> Literal:
        """A boolean atom; ``at`` and ``hascapability`` need no declaration (the original
        accepts them in preconditions)."""
        predicate, *args = _tokens(atom.children)
        self._check_variables(args, body)
        if predicate.value not in _ALWAYS_ACCEPTED_IN_PRECONDITIONS:
            self._check_symbol(predicate, len(args), self.predicates, "predicate", body, "precondition")
        return Literal(predicate.value, _values(args), not negated)

    def _comparison(self, comparison: Tree[Token], body: _Body, negated: bool) -> Comparison:
        op, head, number = comparison.children
        function, *args = _tokens(_tree(head).children)
        self._check_variables(args, body)
        self._check_symbol(function, len(args), self.functions, "function", body, "precondition")
        text = _token(number).value
        value: int | float = float(text) if "." in text else int(text)
        return Comparison(function.value, _values(args), _token(op).value, value, negated)

    def _effects(
        self, clause: Tree[Token] | None, body: _Body
    ) -> tuple[tuple[Literal, ...], tuple[NumericEffect, ...]]:
        literals: list[Literal] = []
        numeric: list[NumericEffect] = []
        if clause is not None:
            self._effect(_tree(clause.children[0]), body, literals, numeric)
        return tuple(literals), tuple(numeric)

    def _effect(
        self, effect: Tree[Token], body: _Body, literals: list[Literal], numeric: list[NumericEffect]
    ) -> None:
        kind = effect.data
        if kind == "empty":
            return
        if kind == "eff_and":
            for child in _trees(effect.children):
                self._effect(child, body, literals, numeric)
        elif kind in ("atom", "eff_not"):
            atom = effect if kind == "atom" else _tree(effect.children[0])
            predicate, *args = _tokens(atom.children)
            self._check_variables(args, body)
            self._check_symbol(predicate, len(args), self.predicates, "predicate", body, "effect")
            literals.append(Literal(predicate.value, _values(args), kind == "atom"))
        elif kind == "numeric_effect":
            found = self._numeric_effect(effect, body)
            if found is not None:
                numeric.append(found)
        elif kind == "eff_unsupported":
            keyword = _token(effect.children[0])
            self._error(keyword, f"'{keyword.value}' effects are not supported by the decomposer")
        else:  # pragma: no cover - the grammar produces no other effect node
            raise AssertionError(kind)

    def _numeric_effect(self, effect: Tree[Token], body: _Body) -> NumericEffect | None:
        """``(increase (f a..) N)``; None (problem reported) unless N is an integer literal."""
        op_node, head, amount = effect.children
        op = _token(op_node)
        function, *args = _tokens(_tree(head).children)
        self._check_variables(args, body)
        self._check_symbol(function, len(args), self.functions, "function", body, "effect")
        if isinstance(amount, Tree):
            self._error(amount, f"the amount of {op.value} must be an integer, found a function term")
            return None
        if "." in amount.value:
            # The original parses a decimal amount as a reward object and crashes (hddl.md §4.2).
            self._error(amount, f"the amount of {op.value} must be an integer, found {amount.value}")
            return None
        return NumericEffect(op.value, function.value, _values(args), int(amount.value))
