"""Regimes found from a log's data, and how far inputs leave their training range."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.workbench.regimes import (find_regimes, range_excess,
                                                    sensors_leaving_range, smoothed)


def _first_order(drive: np.ndarray, tau_s: float, step_s: float) -> np.ndarray:
    """A first-order lag of ``drive`` (exact for a drive held over each step)."""
    a = np.exp(-step_s / tau_s)
    out = np.zeros_like(drive)
    for k in range(1, drive.size):
        out[k] = a * out[k - 1] + (1.0 - a) * drive[k]
    return out


def _heat_dwell_cool(rows: int = 900, step_s: float = 60.0, seed: int = 0):
    """A spindle on at full power for a third, at a power that holds the reached temperature
    for a third (dwell), then off: two sensors lagging it."""
    rng = np.random.default_rng(seed)
    t = np.arange(rows) * step_s
    third = rows // 3
    tau = 3 * 3600.0                                  # still rising when the power drops
    power = np.zeros(rows)
    power[:third] = 1.0
    reached = 1.0 - np.exp(-third * step_s / tau)
    power[third:2 * third] = reached                 # holds the level: a dwell
    sensors = {"t_spindle": 20.0 + 12.0 * _first_order(power, tau, step_s),
               "t_column": 20.0 + 6.0 * _first_order(power, tau, step_s)}
    for name in sensors:
        sensors[name] = sensors[name] + rng.normal(0.0, 0.02, rows)
    return t, sensors, third


def test_heating_dwell_and_cooling_are_found_where_the_power_changes():
    t, sensors, third = _heat_dwell_cool()
    regimes = find_regimes(t, sensors)
    assert [s.kind for s in regimes.stretches] == ["heating", "dwell", "cooling"]
    (heating, dwell, cooling) = regimes.stretches
    # The boundaries within the trend's window (a fiftieth of the run, and the slope's
    # threshold: a tenth of the largest rate) of where the power changed.
    assert heating.start == 0 and cooling.stop == t.size
    assert abs(dwell.start - third) <= 0.1 * third
    assert abs(cooling.start - 2 * third) <= 0.05 * third
    assert regimes.by == "trend" and regimes.group_names == ["heating", "dwell", "cooling"]
    assert regimes.group_of_row[0] == 0 and regimes.group_of_row[-1] == 2
    assert regimes.text().startswith("heating rows 1-")


def test_runs_are_the_groups_and_the_trend_restarts_in_each():
    t, sensors, third = _heat_dwell_cool(rows=300)
    both = {k: np.concatenate([v, v]) for k, v in sensors.items()}
    runs = np.repeat([0, 1], 300)
    regimes = find_regimes(np.concatenate([t, t + t[-1] + 60.0]), both, runs, ["mon", "tue"])
    assert regimes.by == "runs" and regimes.group_names == ["run 'mon'", "run 'tue'"]
    assert np.array_equal(regimes.group_of_row, runs)
    assert [(s.kind, s.run) for s in regimes.stretches] == \
        [("heating", 0), ("dwell", 0), ("cooling", 0), ("heating", 1), ("dwell", 1),
         ("cooling", 1)]


def test_spindle_programs_split_the_stretches_and_a_still_log_is_one_regime():
    t, sensors, third = _heat_dwell_cool()
    speed = np.where(np.arange(t.size) < third // 2, 3000.0, 6000.0) * 2 * np.pi / 60
    regimes = find_regimes(t, sensors, speed=speed)
    assert regimes.by == "program"
    assert regimes.kinds[:2] == ["heating at 3000 rpm", "heating at 6000 rpm"]
    still = find_regimes(t, {"a": np.full(t.size, 21.0)})
    assert still.by == "one regime" and still.kinds == ["dwell"]


def test_the_smoothing_is_a_centred_mean_over_the_rows_there_are():
    values = np.arange(10.0) ** 2
    out = smoothed(values, 3)
    assert out[5] == pytest.approx(np.mean(values[4:7]), rel=1e-12)
    assert out[0] == pytest.approx(np.mean(values[0:2]), rel=1e-12)
    assert out[-1] == pytest.approx(np.mean(values[8:10]), rel=1e-12)


def test_range_excess_is_the_share_of_the_span_beyond_it():
    fit = np.column_stack([np.ones(50), np.linspace(0.0, 2.0, 50)])
    inside = np.column_stack([np.ones(20), np.linspace(0.5, 1.5, 20)])
    assert range_excess(fit, inside) == 0.0
    beyond = np.column_stack([np.ones(20), np.full(20, 3.0)])       # 1.0 above a span of 2
    assert range_excess(fit, beyond) == pytest.approx(0.5, rel=1e-12)


def test_sensors_leaving_their_training_range_are_named_farthest_first():
    n = 100
    train = np.arange(n) < 60
    temperatures = {"a": np.linspace(20.0, 30.0, n),           # goes 4 K beyond 20..26
                    "b": np.concatenate([np.linspace(20, 25, 60), np.full(40, 22.0)])}
    (a,) = sensors_leaving_range(temperatures, train, ~train)
    assert a.sensor == "a" and a.reached_c == pytest.approx(30.0)
    assert a.share == pytest.approx((30.0 - a.high_c) / (a.high_c - 20.0), rel=1e-12)
    assert a.text().startswith("a reached 30 degC, trained on 20-25.9")
