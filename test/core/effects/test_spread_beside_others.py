"""An effect fitted beside others may move a component by more than the residual there
shows, by what the others move it the other way (triangle inequality), by at most the
allowance itself: two stand-ins that cancel each other beyond it are still refused."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.effects.physics import consistency_allowances, spread_problems

ALLOWED = {"x": 3e-6, "y": 2e-6}


def test_alone_a_spread_beyond_the_allowance_is_refused_in_words():
    (problem,) = spread_problems({"x": 3.5e-6, "y": 1e-6}, ALLOWED)
    assert problem == ("it would move x by 3.5 um RMS at the readings, more than the 3 um "
                       "the residual there allows")


@pytest.mark.parametrize("carried, refused", [
    (0.4e-6, True),    # 3.5 > 3 + 0.4
    (0.6e-6, False),   # 3.5 <= 3 + 0.6
    (50e-6, False),    # 3.5 <= 3 + min(50, 3)
])
def test_beside_others_the_allowance_grows_by_what_they_move(carried, refused):
    problems = spread_problems({"x": 3.5e-6}, ALLOWED, carried={"x": carried})
    assert bool(problems) is refused
    if refused:
        assert problems[0].endswith("the residual there allows beside what the other named "
                                    "effects move there"), problems
        assert "more than the 3.4 um" in problems[0]


def test_what_the_others_move_counts_at_most_once_more_the_allowance():
    """Two stand-ins cancelling each other by more than twice the allowance: refused
    however much the other moves; another component's motion lends nothing."""
    assert spread_problems({"x": 6.01e-6}, ALLOWED, carried={"x": 1.0})
    assert not spread_problems({"x": 6.0e-6}, ALLOWED, carried={"x": 1.0})
    assert spread_problems({"y": 2.5e-6}, ALLOWED, carried={"x": 1.0})


def test_a_pair_that_sums_to_the_residual_passes_where_each_alone_would_not():
    """Second formulation: two contributions whose sum is the residual, each beyond the
    residual's allowance alone, each within it beside the other."""
    rng = np.random.default_rng(5)
    n = 400
    q = rng.uniform(-1.0, 1.0, n)
    first = np.column_stack([4e-6 * q, np.zeros(n)])
    second = np.column_stack([-3e-6 * q + 1e-6 * q ** 2, np.zeros(n)])
    noise = 0.2e-6
    residual = first + second + rng.normal(0.0, noise, first.shape)
    allowances = consistency_allowances(residual, np.ones_like(residual, bool), noise)

    def spread(rows):
        return {c: float(np.std(rows[:, k])) for k, c in enumerate("xy")}

    assert spread_problems(spread(first), allowances)
    assert spread_problems(spread(second), allowances)
    assert not spread_problems(spread(first), allowances, carried=spread(second))
    assert not spread_problems(spread(second), allowances, carried=spread(first))
