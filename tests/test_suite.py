"""The suite's own tiers: what the default run keeps of a matrix of cases."""

from __future__ import annotations

import itertools

from tests.conftest import each_choice


def test_each_choice_keeps_every_value_of_every_argument_and_marks_the_rest_slow():
    cases = list(itertools.product("abc", range(4), [True, False]))
    params = each_choice(cases)
    assert [param.values for param in params] == cases
    kept = [param.values for param in params if not param.marks]
    for axis in range(3):
        assert {case[axis] for case in kept} == {case[axis] for case in cases}
    assert len(kept) == 4, "as few as the longest argument allows"
    assert {mark.name for param in params for mark in param.marks} == {"slow"}
    assert [param.marks for param in each_choice(cases)] == [param.marks for param in params]


def test_each_choice_keeps_the_cases_it_is_told_to_and_covers_the_rest_around_them():
    cases = list(itertools.product("abc", range(4)))
    kept = [
        param.values for param in each_choice(cases, keep=[("c", 0), ("c", 1)]) if not param.marks
    ]
    assert {("c", 0), ("c", 1)} <= set(kept)
    assert {case[0] for case in kept} == set("abc") and {case[1] for case in kept} == set(range(4))
    assert len(kept) == 4, "the kept cases count toward the coverage"
