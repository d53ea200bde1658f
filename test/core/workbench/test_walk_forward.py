"""The walk-forward's periods and arithmetic against a plain loop."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.core.workbench.walk_forward import (parse_period, walk_forward,
                                                         walk_periods)


@pytest.mark.parametrize("text, seconds", [("4h", 14400.0), ("30 min", 1800.0), ("900", 900.0),
                                           ("900s", 900.0), ("1d", 86400.0), ("run", None)])
def test_a_period_is_read_in_its_unit(text, seconds):
    assert parse_period(text) == seconds


@pytest.mark.parametrize("text", ["", "-4h", "0", "four hours", "nan"])
def test_a_period_that_is_no_time_is_refused_naming_the_flag(text):
    with pytest.raises(InputDataError, match="--walk-forward"):
        parse_period(text)


def test_periods_are_stretches_of_data_time_after_the_rows_a_fit_needs():
    t = np.arange(100) * 60.0                       # 100 min
    periods = walk_periods(t, 1200.0, None, 20)     # 20 min: 20 rows each
    assert [(p.start, p.stop) for p in periods] == [(20, 40), (40, 60), (60, 80), (80, 100)]
    assert periods[0].label == "20 min-40 min"
    runs = np.repeat([0, 1, 2], [30, 30, 40])
    by_run = walk_periods(t, None, runs, 20, ["a", "b", "c"])
    assert [(p.start, p.stop, p.label) for p in by_run] == [(30, 60, "run 'b'"),
                                                            (60, 100, "run 'c'")]
    with pytest.raises(InputDataError, match="needs runs"):
        walk_periods(t, None, None, 20)
    with pytest.raises(InputDataError, match="give a shorter period"):
        walk_periods(t, 3600.0, None, 20)


def test_the_walk_fits_on_every_row_before_each_period_as_a_plain_loop_does():
    rng = np.random.default_rng(5)
    n = 120
    t = np.arange(n) * 30.0
    x = np.cumsum(rng.normal(0, 1, n))
    y = 3.0 * x + rng.normal(0, 0.5, n) + 0.01 * t
    periods = walk_periods(t, 600.0, None, 20)

    def line(train):
        design = np.column_stack([np.ones(n), x])
        coefficients, *_ = np.linalg.lstsq(design[train], y[train], rcond=None)
        return y - design @ coefficients, ""

    def mean(train):
        return y - y[train].mean(), ""

    walk = walk_forward(n, periods, {"line": line, "mean": mean}, "10 min")
    squared, count = {"line": 0.0, "mean": 0.0}, 0
    for figures, period in zip(walk.periods, periods):
        a, b = period.start, period.stop
        design = np.column_stack([np.ones(a), x[:a]])
        gains = np.linalg.solve(design.T @ design, design.T @ y[:a])
        line_error = y[a:b] - (gains[0] + gains[1] * x[a:b])
        mean_error = y[a:b] - np.mean(y[:a])
        assert figures.trained_rows == a
        assert figures.rmse_m["line"] == pytest.approx(np.sqrt(np.mean(line_error ** 2)),
                                                       rel=1e-9)
        assert figures.rmse_m["mean"] == pytest.approx(np.sqrt(np.mean(mean_error ** 2)),
                                                       rel=1e-9)
        squared["line"] += np.sum(line_error ** 2)
        squared["mean"] += np.sum(mean_error ** 2)
        count += b - a
    assert walk.judged_rows == count == n - 20
    for name in ("line", "mean"):
        assert walk.pooled_m[name] == pytest.approx(np.sqrt(squared[name] / count), rel=1e-9)
    assert walk.wins_over("line", ["mean"])
