"""Records posted as CP-SAT constraint protos, through OR-Tools' lean helper module.

``ortools.sat.python.cp_model`` imports pandas and numpy, half a second before anything is
solved; ``cp_model_helper`` holds the model protos and the solve wrapper without them.  The
decomposers build every component's model here, as a ``CpModelProto``: a variable is its index
in the proto, and a negated literal is ``-index - 1`` (CP-SAT's convention).  The embedding API
posts into a ``cp_model.CpModel``'s proto with the same code (:mod:`.embedding`).
"""
from __future__ import annotations

from typing import Sequence

from .boolean_model import (
    FALSE,
    TRUE,
    AndOf,
    BoolModel,
    Clause,
    Compare,
    Const,
    Difference,
    Exactly,
    Lit,
    NumericEffectKind,
    OrOf,
    Record,
    ValueAfter,
)
from .native import cmh

INT_MIN, INT_MAX = -(2**63), 2**63 - 1


def negated(ref: int) -> int:
    """The proto literal of the negation of ``ref``."""
    return -ref - 1


def _intervals(op: str, bound: int) -> tuple[list[int], list[int]]:
    """The values satisfying ``value op bound`` and those that do not, as flat interval lists."""
    below, above = [INT_MIN, bound - 1], [bound + 1, INT_MAX]
    return {
        "=": ([bound, bound], below + above),
        "<>": (below + above, [bound, bound]),
        ">": (above, [INT_MIN, bound]),
        "<": (below, [bound, INT_MAX]),
        ">=": ([bound, INT_MAX], below),
        "<=": ([INT_MIN, bound], above),
    }[op]


class ProtoBuilder:
    """Posts records (:mod:`.boolean_model`) into a ``CpModelProto`` (the whole model or one
    component); boolean-model variables get proto indices as they are first met."""

    def __init__(self, bm: BoolModel, proto: cmh.CpModelProto | None = None) -> None:
        self.bm = bm
        self.proto = proto if proto is not None else cmh.CpModelProto()
        self.vars: dict[int, int] = {}
        self._constants: dict[int, int] = {}

    def var(self, v: int) -> int:
        """The proto index of boolean-model variable ``v``."""
        index = self.vars.get(v)
        if index is None:
            index = len(self.proto.variables)
            variable = self.proto.variables.add()
            bounds = self.bm.ints.get(v)
            variable.domain.extend([bounds.lo, bounds.hi] if bounds is not None else [0, 1])
            variable.name = self.bm.name(v)
            self.vars[v] = index
        return index

    def constant(self, value: int) -> int:
        """The proto index of a variable fixed to ``value`` (one per value)."""
        index = self._constants.get(value)
        if index is None:
            index = len(self.proto.variables)
            self.proto.variables.add().domain.extend([value, value])
            self._constants[value] = index
        return index

    def lit(self, l: Lit) -> int:
        """The proto literal of ``l``."""
        if isinstance(l, Const):
            return self.constant(1 if l is TRUE else 0)
        return self.var(l) if l > 0 else negated(self.var(-l))

    def new_bool(self, name: str) -> int:
        """A fresh boolean proto variable that no record defines (an assumption, say)."""
        index = len(self.proto.variables)
        variable = self.proto.variables.add()
        variable.domain.extend([0, 1])
        variable.name = name
        return index

    # --- constraints -----------------------------------------------------------------------------
    def _constraint(self, enforcement: Sequence[int] = ()) -> cmh.ConstraintProto:
        c: cmh.ConstraintProto = self.proto.constraints.add()  # untyped in OR-Tools' stubs
        c.enforcement_literal.extend(enforcement)
        return c

    def _linear(self, terms: Sequence[tuple[int, int]], low: int, high: int,
                enforcement: Sequence[int] = ()) -> cmh.ConstraintProto:
        """``low <= sum(coefficient * literal) <= high``; a negated literal ``¬x`` counts as
        ``1 - x`` (linear constraints take variables only)."""
        c = self._constraint(enforcement)
        offset = 0
        for ref, coefficient in terms:
            if ref >= 0:
                c.linear.vars.append(ref)
                c.linear.coeffs.append(coefficient)
            else:
                c.linear.vars.append(negated(ref))
                c.linear.coeffs.append(-coefficient)
                offset += coefficient
        c.linear.domain.extend([max(low - offset, INT_MIN), min(high - offset, INT_MAX)])
        return c

    def _in_domain(self, index: int, intervals: list[int], enforcement: Sequence[int]) -> cmh.ConstraintProto:
        """Variable ``index`` takes a value of the flat interval list ``intervals``."""
        c = self._constraint(enforcement)
        c.linear.vars.append(index)
        c.linear.coeffs.append(1)
        c.linear.domain.extend(intervals)
        return c

    def post(self, r: Record, enforce: int | None = None) -> cmh.ConstraintProto | None:
        """Post ``r``; with ``enforce``, the record's defining constraint holds only when
        ``enforce`` is true (how :func:`.cpsat.explain` names the records of a conflict)."""
        c: cmh.ConstraintProto | None
        match r:
            case Clause(lits=lits):
                c = self._constraint()
                c.bool_or.literals.extend([self.lit(l) for l in lits] or [self.constant(0)])
            case Exactly():
                c = self._exactly(r, enforced=enforce is not None)
            case AndOf(lits=lits, target=target):
                parts, t = [self.lit(l) for l in lits], self.var(target)
                self._constraint([t]).bool_and.literals.extend(parts)
                c = self._constraint()
                c.bool_or.literals.extend([negated(p) for p in parts] + [t])
            case OrOf(lits=lits, target=target):
                parts, t = [self.lit(l) for l in lits], self.var(target)
                self._constraint([t]).bool_or.literals.extend(parts)
                for p in parts:
                    self._constraint([p]).bool_and.literals.append(t)
                c = None
            case ValueAfter():
                c = self._value_after(r)
            case Difference(target=target, first=first, second=second):
                terms = [(self.var(target), 1)] + [(self.var(v), sign) for v, sign in ((first, -1), (second, 1))
                                                   if v is not None]
                c = self._linear(terms, 0, 0)
            case Compare(holds=holds, value=value, op=op, bound=bound):
                sat, index = self.lit(holds), self.var(value)
                satisfying, failing = _intervals(op, bound)
                self._in_domain(index, satisfying, [sat])
                c = self._in_domain(index, failing, [negated(sat)])
        if enforce is not None and c is not None:
            c.enforcement_literal.append(enforce)
        return c

    def _exactly(self, r: Exactly, *, enforced: bool) -> cmh.ConstraintProto:
        """As many of the choices as ``r.target`` says (an enforced exactly-one is a sum, as
        CP-SAT's exactly-one constraint cannot be made conditional)."""
        choices = [(self.lit(l), 1) for l in r.lits]
        if r.target is TRUE and not enforced:
            c = self._constraint()
            c.exactly_one.literals.extend([ref for ref, _ in choices])
            return c
        if r.target is TRUE:
            return self._linear(choices, 1, 1)
        if r.target is FALSE:
            return self._linear(choices, 0, 0)
        return self._linear(choices + [(self.lit(r.target), -1)], 0, 0)

    def _value_after(self, r: ValueAfter) -> cmh.ConstraintProto:
        target = self.var(r.target)
        written = self.lit(r.writer)
        if r.effect == NumericEffectKind.ASSIGN:
            self._linear([(target, 1)], r.amount, r.amount, [written])
        else:
            after = r.amount + self._before_constant(r)
            self._linear(self._minus_before(target, r), after, after, [written])
        return self._linear(self._minus_before(target, r), self._before_constant(r), self._before_constant(r),
                            [negated(written)])

    def _minus_before(self, target: int, r: ValueAfter) -> list[tuple[int, int]]:
        """``target - before`` as terms (the value before is a variable, or a constant)."""
        return [(target, 1)] + ([(self.var(r.previous), -1)] if r.previous is not None else [])

    @staticmethod
    def _before_constant(r: ValueAfter) -> int:
        """The constant part of the value before: all of it for the first writer, else 0."""
        return r.previous_value if r.previous is None else 0
