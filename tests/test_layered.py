"""Components solved block by block (solve/layered.py): counting, listing, sampling and the
least cost from the layered graph agree with brute-force enumeration on generated boolean
models, and sampling is uniform (a chi-square test with a fixed seed)."""
from __future__ import annotations

import itertools
import math
import random
from collections import Counter
from unittest.mock import patch

import pytest
from hypothesis import HealthCheck, assume, given, settings
from hypothesis import strategies as st

from mutrose_cp.solve import tiny
from mutrose_cp.solve.boolean_model import TRUE, BoolModel, Exactly, Lit, neg
from mutrose_cp.solve.cpsat import Component, DecompositionSpace
from mutrose_cp.solve.encoding import Encoding
from mutrose_cp.solve.layered import cut_into_blocks, layered_space
from mutrose_cp.solve.tiny import free_variables

MAX_FREE = 12  # brute force enumerates 2^free assignments


@st.composite
def sequence_models(draw) -> tuple[BoolModel, list[int]]:
    """Blocks in sequence that share one or two facts: each block chooses exactly one of 1-3
    literals; a choice may require a fact's value before the block (a clause) and set or clear a
    fact (a chain step, as the encoder writes them); sometimes a choice leaves a literal of its
    own free (so several assignments give one choice); sometimes the last values are required."""
    bm = BoolModel()
    facts: list[Lit] = [draw(st.sampled_from([TRUE, neg(TRUE)])) for _ in range(draw(st.integers(1, 2)))]
    choice_vars: list[int] = []
    for b in range(draw(st.integers(2, 5))):
        choices = [bm.new_bool(f"b{b}c{i}") for i in range(draw(st.integers(1, 3)))]
        choice_vars += choices
        bm.records.append(Exactly(tuple(choices), TRUE))
        for c in choices:
            f = draw(st.integers(0, len(facts) - 1))
            if draw(st.integers(0, 2)) == 0:
                bm.clause([-c, facts[f] if draw(st.booleans()) else neg(facts[f])])
            step = draw(st.integers(0, 3))
            if step == 0:
                facts[f] = bm.or_of([c, facts[f]], f"f{f}@{c}")
            elif step == 1:
                facts[f] = bm.and_of([-c, facts[f]], f"f{f}@{c}")
        if draw(st.integers(0, 4)) == 0:
            own = bm.new_bool(f"b{b}free")
            bm.clause([-choices[0], own])
    if draw(st.booleans()):
        bm.clause([facts[0] if draw(st.booleans()) else neg(facts[0])])
    return bm, choice_vars


def brute_force(bm: BoolModel, choice_vars: list[int]) -> list[tuple[int, ...]]:
    """Every solution's true choice literals, one entry per assignment of all variables."""
    with patch.object(tiny, "MAX_WORK", 10**9):
        found = tiny.enumerate_tiny(bm, bm.records, choice_vars)
    assert found is not None
    return [tuple(sorted(s)) for s in found[1]]


MODELS = settings(max_examples=300, deadline=None, suppress_health_check=[HealthCheck.too_slow])


@MODELS
@given(sequence_models(), st.randoms(use_true_random=False))
def test_layered_graph_agrees_with_brute_force(model, rnd):
    bm, choice_vars = model
    assume(len(free_variables(bm.records) or ()) <= MAX_FREE)
    expected = brute_force(bm, choice_vars)
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None  # a sequence over one or two facts always cuts into blocks
    assert layers.count == len(expected)
    listed = list(layers.solutions())
    assert Counter(listed) == Counter(expected)
    assert [layers.solution_at(i) for i in range(layers.count)] == listed
    cost = {v: rnd.randint(-3, 5) for v in choice_vars}
    if expected:
        best, total = layers.least_cost(cost)
        least = min(sum(cost[v] for v in s) for s in expected)
        assert total == least == sum(cost[v] for v in best)
        assert best == next(s for s in listed if sum(cost[v] for v in s) == least)  # the first listed
        rng = random.Random(rnd.randint(0, 10**6))
        assert all(layers.sample(rng) in set(expected) for _ in range(10))


@MODELS
@given(sequence_models())
def test_listing_is_the_canonical_order_when_each_solution_is_listed_once(model):
    """Blocks own increasing literals and every solution takes one choice per block: depth-first
    listing is the sorted order that enumerated components are listed in."""
    bm, choice_vars = model
    assume(len(free_variables(bm.records) or ()) <= MAX_FREE)
    expected = brute_force(bm, choice_vars)
    assume(len(set(expected)) == len(expected))
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None
    assert list(layers.solutions()) == sorted(expected)


def test_renamed_graph_lists_the_renamed_solutions():
    bm, choice_vars = _door_model(4)
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None
    reversing = {v: 1000 - v for v in range(1, len(bm.names))}
    renamed = layers.renamed(reversing)
    assert renamed.count == layers.count
    assert Counter(renamed.solutions()) == Counter(tuple(sorted(reversing[v] for v in s)) for s in layers.solutions())
    for block in renamed.blocks:  # in order of their renamed choices, as listing needs them
        assert [(e.source, e.choices, e.target) for e in block] == sorted((e.source, e.choices, e.target)
                                                                          for e in block)
    shifting = {v: 1000 + v for v in range(1, len(bm.names))}  # the same order: the same listing
    assert list(layers.renamed(shifting).solutions()) == [tuple(v + 1000 for v in s) for s in layers.solutions()]


def _door_model(n: int) -> tuple[BoolModel, list[int]]:
    """n tasks in sequence, each leaving a shared door as it is, opening it (only when closed)
    or closing it; keeping it requires a literal of the task's own, which is free otherwise."""
    bm = BoolModel()
    door: Lit = neg(TRUE)
    choice_vars = []
    for k in range(n):
        keep, open_, close = (bm.new_bool(f"t{k}{w}") for w in ("keep", "open", "close"))
        choice_vars += [keep, open_, close]
        bm.records.append(Exactly((keep, open_, close), TRUE))
        bm.clause([-open_, neg(door)])
        door = bm.and_of([-close, bm.or_of([open_, door], f"opened{k}")], f"door{k}")
        bm.clause([-keep, bm.new_bool(f"t{k}own")])
    return bm, choice_vars


def _chi_square_critical(df: int, z: float = 3.09) -> float:
    """The chi-square quantile at 0.999 (z of the normal), by Wilson and Hilferty."""
    return df * (1 - 2 / (9 * df) + z * math.sqrt(2 / (9 * df))) ** 3


def test_samples_are_uniform_over_the_solutions():
    """Each solution is drawn in proportion to the assignments that give it (one per
    assignment, as enumeration counts them): chi-square below its 0.999 quantile."""
    bm, choice_vars = _door_model(3)
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None
    expected = Counter(brute_force(bm, choice_vars))
    assert sum(expected.values()) == layers.count and len(expected) > 8
    assert set(expected.values()) != {1}  # some solutions weigh more than others
    draws = 200 * layers.count
    rng = random.Random(20251130)
    seen = Counter(layers.sample(rng) for _ in range(draws))
    assert set(seen) == set(expected)
    chi2 = sum((seen[s] - draws * n / layers.count) ** 2 / (draws * n / layers.count) for s, n in expected.items())
    assert chi2 < _chi_square_critical(len(expected) - 1)
    # and a skewed sampler fails the same test: the test can tell
    skewed = Counter(itertools.islice(itertools.cycle(sorted(expected)), draws))
    chi2_skewed = sum((skewed[s] - draws * n / layers.count) ** 2 / (draws * n / layers.count)
                      for s, n in expected.items())
    assert chi2_skewed > _chi_square_critical(len(expected) - 1)


@pytest.mark.parametrize("n", [2, 10, 200])
def test_blocks_follow_the_tasks(n):
    """One block per task (its exactly-one choice, its preconditions and its chain steps) and one
    for the literal of its own that a task leaves free (created after the others); the blocks pass
    on the door and the task's choice to that literal's block: linear in the number of tasks."""
    bm, choice_vars = _door_model(n)
    blocks = cut_into_blocks(bm.records)
    assert len(blocks) == 2 * n
    assert all(isinstance(block[0], Exactly) for block in blocks[::2])
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None
    assert max(len(f) for f in layers.frontiers) == 2
    # door closed: keep, open (2 ways), close (2 ways); door open: keep, close (2 ways)
    closed, opened = 1, 0
    for _ in range(n):
        closed, opened = 3 * closed + 2 * opened, 2 * closed + opened
    assert layers.count == closed + opened


@pytest.mark.parametrize("n", [3, 6, 300])
def test_a_parallel_conflict_is_passed_on_as_a_chain(n):
    """n tasks that may each set or clear one fact in parallel, never both in one mission
    (``not (OR(setters) and OR(clearers))``): each wide definition is passed from block to block
    as "some setter so far", so the component is layered.  The tasks that do not keep the fact
    all set it or all clear it: 2^n + 2^n - 1 solutions."""
    bm = BoolModel()
    setters, clearers, choice_vars = [], [], []
    for k in range(n):
        keep, set_, clear = (bm.new_bool(f"t{k}{w}") for w in ("keep", "set", "clear"))
        bm.records.append(Exactly((keep, set_, clear), TRUE))
        setters.append(set_)
        clearers.append(clear)
        choice_vars += [keep, set_, clear]
    some_set, some_cleared = bm.or_of(setters, "set"), bm.or_of(clearers, "cleared")
    bm.clause([-some_set, -some_cleared])
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None
    assert max(len(f) for f in layers.frontiers) <= 4
    assert layers.count == 2 ** (n + 1) - 1
    if n <= 6:
        assert Counter(layers.solutions()) == Counter(brute_force(bm, choice_vars))


def test_long_range_couplings_do_not_cut_into_blocks():
    """Task i constrained together with task n-1-i: the middle of the sequence would pass on
    half the tasks' choices, more than a frontier holds; left to the other solvers."""
    bm = BoolModel()
    pairs = [(bm.new_bool(f"a{k}"), bm.new_bool(f"b{k}")) for k in range(40)]
    for pair in pairs:
        bm.records.append(Exactly(pair, TRUE))
    for k in range(20):
        bm.clause([pairs[k][0], pairs[39 - k][0]])
    assert layered_space(bm, bm.records, [v for pair in pairs for v in pair]) is None


def written_paths(component: dict) -> int:
    """The solutions a written layered graph stands for (docs/formats/output.md): its paths,
    each weighted by the product of its edges' counts."""
    paths = {0: 1}
    for block in component["blocks"]:
        following: dict[int, int] = {}
        for edge in block:
            if int(edge["from"]) in paths:
                to = int(edge["to"])
                following[to] = following.get(to, 0) + paths[int(edge["from"])] * int(edge["count"])
        paths = following
    return sum(paths.values())


def test_written_graph_stands_for_every_solution():
    """The output's layered graph of a component whose solutions weigh differently: its paths,
    weighted by the edges' counts, are the component's count; its states name the door."""
    bm, choice_vars = _door_model(4)
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None
    decomposition_lit = {100 + v: v for v in choice_vars}
    encoding = Encoding(bm, decomposition_lit, {}, {}, tasks=[0])
    component = Component(list(bm.records), choice_vars, count=layers.count, layers=layers)
    space = DecompositionSpace(encoding, [component], {v: d for d, v in decomposition_lit.items()})
    (written,) = space.component_table(lambda d: f"t{d}")
    assert written["count"] == str(layers.count) and "alternatives" not in written
    assert written_paths(written) == layers.count == len(brute_force(bm, choice_vars))
    assert any(edge["count"] == "2" for block in written["blocks"] for edge in block)
    # after the first task: its choice to keep the door (its own literal's block needs it), the door
    assert sorted(written["states"][1]) == [["t0keep=0", "door0=0"], ["t0keep=0", "door0=1"], ["t0keep=1", "door0=0"]]


def test_listed_solutions_read_as_sorted_decomposition_vertices():
    """A listed component's solutions (decomposition literals) read as their sorted
    decomposition vertices, again on every pass, with the least and greatest vertex of any."""
    from mutrose_cp.solve.cpsat import Listed

    listed = Listed([frozenset({1, 2}), frozenset({3})], {1: 40, 2: 7, 3: 12})
    assert list(listed) == [(7, 40), (12,)] == list(listed) and listed.first() == (7, 40)
    assert listed.bounds() == (7, 40)
    assert Listed([frozenset()], {}).bounds() is None and list(Listed([frozenset()], {})) == [()]


@settings(max_examples=40, deadline=None, suppress_health_check=list(HealthCheck))
@given(st.integers(1, 5), st.data())
def test_verify_folds_a_layered_component_without_listing_it(n, data):
    """verify's forward pass over a layered component (solve/verify.py) gives, per atom vector,
    the number of its solutions that make those atoms true, as listing every path does; its
    witness is one of them."""
    from mutrose_cp.model.properties import Property, Uses
    from mutrose_cp.solve.property_grounding import GroundedProperty
    from mutrose_cp.solve.verify import decide

    bm, choice_vars = _door_model(n)
    layers = layered_space(bm, bm.records, choice_vars)
    assert layers is not None
    vertex = {v: 100 + v for v in choice_vars}
    encoding = Encoding(bm, {d: v for v, d in vertex.items()}, {}, {}, tasks=[0])
    space = DecompositionSpace(encoding, [Component(list(bm.records), choice_vars, count=layers.count, layers=layers)],
                               vertex)
    sets = tuple(frozenset(data.draw(st.sets(st.sampled_from(sorted(vertex.values())), min_size=1, max_size=3)))
                 for _ in range(data.draw(st.integers(1, 3))))
    formula = data.draw(st.sampled_from([("and", (0, ("not", (len(sets) - 1,)))), ("or", tuple(range(len(sets)))), 0]))
    quantifier = data.draw(st.sampled_from(["count", "always", "never", "some"]))
    prop = Property("p", quantifier, Uses(("method", "m")), "", "--property 1")
    found = decide(prop, GroundedProperty(formula, sets), space)

    def satisfies(solution: set[int], f) -> bool:
        if isinstance(f, int):
            return not sets[f].isdisjoint(solution)
        op, operands = f
        return (not satisfies(solution, operands[0]) if op == "not" else
                all(satisfies(solution, g) for g in operands) if op == "and" else
                any(satisfies(solution, g) for g in operands))

    solutions = [{vertex[v] for v in s} for s in layers.solutions()]
    count = sum(satisfies(s, formula) for s in solutions)
    assert (found.count, found.total) == (count, len(solutions) == layers.count and layers.count)
    if found.witness is not None:
        assert set(found.witness) in solutions
        assert satisfies(set(found.witness), formula) == (quantifier != "always")
