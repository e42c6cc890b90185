"""Components equal up to renaming are solved once (``solve/cpsat.py``): their key must tell
apart everything that changes the solutions, and nothing else."""
from __future__ import annotations

from mutrose_cp.solve.boolean_model import TRUE, BoolModel, Compare, Exactly, NumericEffectKind, ValueAfter
from mutrose_cp.solve.cpsat import Component, _signature


def _numeric_component(bm: BoolModel, span: int, bound: int) -> Component:
    """Pick one of two writers of a number, then compare the value after the chosen one."""
    a, b = bm.new_bool("a"), bm.new_bool("b")
    bm.records.append(Exactly((a, b), TRUE))
    value = bm.new_int("value", -span, span)
    bm.records.append(ValueAfter(a, value, None, 0, 3, NumericEffectKind.ASSIGN))
    holds = bm.new_bool("holds")
    bm.records.append(Compare(holds, value, ">", bound))
    return Component(bm.records[-3:], [a, b])


def test_components_equal_up_to_renaming_share_a_key_and_map_variables_in_order():
    bm = BoolModel()
    first, second = _numeric_component(bm, 10, 2), _numeric_component(bm, 10, 2)
    (key1, order1), (key2, order2) = _signature(bm, first), _signature(bm, second)
    assert key1 == key2
    assert [v + 4 for v in order1] == order2  # the second's variables, in the first's roles


def test_the_key_holds_the_range_of_integer_variables_and_the_constants():
    bm = BoolModel()
    base = _signature(bm, _numeric_component(bm, 10, 2))[0]
    assert _signature(bm, _numeric_component(bm, 20, 2))[0] != base  # another range
    assert _signature(bm, _numeric_component(bm, 10, 5))[0] != base  # another bound
