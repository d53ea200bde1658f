"""Fleet trends: the slope and its standard error against scipy's regression, the drift
rules, the ranking and the shared effects."""
from __future__ import annotations

import numpy as np
import pytest
from scipy import stats

from mt_accuracy_ros.core.fleet.trends import (DRIFT_T, TWO_DAY_RATIO, common_effects,
                                               error_trend, rank_by_drift)


def test_slope_and_standard_error_equal_scipys_linear_regression():
    rng = np.random.default_rng(5)
    days = np.array([739000.0, 739001, 739003, 739004, 739008, 739009])
    error = 3e-6 + 0.4e-6 * (days - days[0]) + rng.normal(0, 0.2e-6, days.size)
    trend = error_trend(days, error)
    reference = stats.linregress(days, error)
    assert trend.slope_m_per_day == pytest.approx(reference.slope, rel=1e-12)
    assert trend.slope_standard_error_m_per_day == pytest.approx(reference.stderr, rel=1e-10)
    assert trend.drifting and trend.days == 6
    assert trend.first_m == error[0] and trend.last_m == error[-1]


def test_the_days_order_does_not_matter():
    days = np.array([3.0, 1.0, 2.0, 5.0])
    error = np.array([5.0, 3.0, 4.1, 7.0]) * 1e-6
    shuffled = error_trend(days, error)
    order = np.argsort(days)
    ordered = error_trend(days[order], error[order])
    assert shuffled == ordered
    assert shuffled.first_m == 3e-6 and shuffled.last_m == 7e-6


def test_a_steady_machine_with_scatter_is_not_drifting():
    rng = np.random.default_rng(1)
    days = np.arange(10.0)
    trend = error_trend(days, 4e-6 + rng.normal(0, 0.3e-6, 10))
    assert not trend.drifting
    assert abs(trend.slope_m_per_day) < DRIFT_T * trend.slope_standard_error_m_per_day


def test_a_falling_error_is_never_a_drift():
    trend = error_trend([0, 1, 2, 3], [8e-6, 6e-6, 4e-6, 2e-6])
    assert trend.slope_m_per_day == pytest.approx(-2e-6) and not trend.drifting


def test_one_and_two_days():
    one = error_trend([10.0], [3e-6])
    assert one.slope_m_per_day == 0.0 and not one.drifting
    assert one.as_dict()["slope_standard_error_m_per_day"] is None
    grew = error_trend([0, 1], [2e-6, 2e-6 * TWO_DAY_RATIO * 1.01])
    kept = error_trend([0, 1], [2e-6, 2e-6 * TWO_DAY_RATIO * 0.99])
    assert grew.drifting and not kept.drifting
    assert grew.slope_m_per_day == pytest.approx(2e-6 * (TWO_DAY_RATIO * 1.01 - 1))


@pytest.mark.parametrize("days, error, message", [
    ([], [], "at least one day"), ([0, 1], [1e-6], "one value each"),
    ([0, 1], [1e-6, np.nan], "finite")])
def test_bad_input_is_refused(days, error, message):
    with pytest.raises(ValueError, match=message):
        error_trend(days, error)


def test_ranking_puts_drifting_machines_first_by_slope():
    trends = {"a": error_trend([0, 1, 2], [1e-6, 1.1e-6, 0.9e-6]),
              "b": error_trend([0, 1, 2, 3], [1e-6, 2e-6, 3.1e-6, 3.9e-6]),
              "c": error_trend([0, 1, 2, 3], [1e-6, 3e-6, 5.1e-6, 6.9e-6]),
              "d": error_trend([0, 1], [1e-6, 1.2e-6])}
    assert [n for n in trends if trends[n].drifting] == ["b", "c"]
    assert rank_by_drift(trends) == ["c", "b", "d", "a"]


def test_common_effects_count_each_machine_once():
    shared = common_effects({"m1": ["drift", "pitch", "drift"], "m2": ["drift", "yaw"],
                             "m3": ["pitch", "drift"], "m4": []})
    assert shared == [("drift", ["m1", "m2", "m3"]), ("pitch", ["m1", "m3"])]
    assert common_effects({"m1": ["x"], "m2": ["x"]}, least=3) == []
