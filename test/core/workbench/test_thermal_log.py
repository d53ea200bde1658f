"""A thermal log as a survey of a standing machine (core.workbench.thermal_log)."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError, InsufficientDataError
from mt_accuracy_ros.core.workbench.diagnosis import add_effect, diagnose
from mt_accuracy_ros.core.workbench.thermal_log import (all_inputs_least_squares,
                                                        held_out_residual, held_out_rmse,
                                                        log_model, log_observations,
                                                        noise_from_differences)


def test_the_noise_of_a_smooth_log_is_read_off_its_successive_differences():
    rng = np.random.default_rng(1)
    t = np.linspace(0, 10, 5000)
    signal = 3.0 * np.sin(t / 3.0)            # smooth: its differences are tiny
    for sigma in (0.01, 0.1):
        noisy = signal + rng.normal(0, sigma, t.size)
        assert noise_from_differences(noisy) == pytest.approx(sigma, rel=0.05)


def _log(n=300, seed=2):
    rng = np.random.default_rng(seed)
    time_s = np.arange(n) * 60.0
    t1 = 20 + 3 * (1 - np.exp(-time_s / 4000.0)) + rng.normal(0, 0.01, n)
    t2 = 21 + 0.5 * np.sin(time_s / 2500.0) + rng.normal(0, 0.01, n)
    growth = 4e-6 * (t1 - t1[0]) + rng.normal(0, 0.1e-6, n)
    return time_s, growth, {"t1": t1, "t2": t2}


def test_a_log_is_one_measured_component_of_a_standing_machine_and_names_its_sensor():
    time_s, growth, temperatures = _log()
    obs = log_observations(time_s, growth, temperatures, component="y")
    assert obs.measured_mask[:, 1].all() and not obs.measured_mask[:, [0, 2]].any()
    assert all(np.ptp(q) == 0 for q in obs.positions.values())
    # The noise band: twice the sigma read off the differences (0.1 um here).
    assert obs.uncertainty_m == pytest.approx(0.2e-6, rel=0.15)
    model = log_model(obs)
    train = np.arange(obs.n) < obs.n // 2
    training = obs.subset(np.flatnonzero(train))
    diagnosis = diagnose(model, training, forward=True)
    assert diagnosis.selected[0].name == "structural_thermal_drift:t1"
    fitted = add_effect(model, diagnosis.selected[0], training)
    assert fitted.effects["structural_thermal_drift:t1"]["coefficients"]["by"] == \
        pytest.approx(4e-6, rel=0.03)
    # Judged on the later rows with its zero set on the training rows only.
    residual = held_out_residual(fitted, obs, train)
    assert abs(residual[train].mean()) < 1e-18
    assert held_out_rmse(fitted, obs, train) < 0.2e-6 < held_out_rmse(model, obs, train)
    # Least squares on both inputs, the plain baseline, by hand.
    x = np.column_stack([np.ones(obs.n), temperatures["t1"] - temperatures["t1"][0],
                         temperatures["t2"] - temperatures["t2"][0]])
    c, *_ = np.linalg.lstsq(x[train], growth[train], rcond=None)
    expected = np.sqrt(np.mean((growth[~train] - x[~train] @ c) ** 2))
    assert all_inputs_least_squares(obs, train) == pytest.approx(expected, rel=1e-9)


def test_equal_stamps_of_a_coarse_logger_are_taken_and_the_lags_hold_still_over_them():
    """Issue 40: a logger at 0.1 s resolution writes equal stamps; they were refused as
    'not increasing'. A lag over a zero step is the identity (closed form: decay 1)."""
    from mt_accuracy_ros.core.effects.variables import first_order_lag

    time_s, growth, temperatures = _log(n=40)
    coarse = time_s.copy()
    coarse[1::2] = coarse[0::2][:coarse[1::2].size]   # every second stamp repeats
    obs = log_observations(coarse, growth, temperatures)
    assert obs.n == 40 and np.all(np.diff(obs.time_s) >= 0)
    lagged = first_order_lag(coarse, temperatures["t1"], 600.0)
    same = np.flatnonzero(np.diff(coarse) == 0)
    # Over an equal stamp the state stays; the input's jump is not integrated.
    np.testing.assert_allclose(lagged[same + 1], lagged[same], rtol=0, atol=1e-15)


def test_bad_logs_are_refused_with_the_reason():
    time_s, growth, temperatures = _log(n=40)
    with pytest.raises(InputDataError, match="component"):
        log_observations(time_s, growth, temperatures, component="w")
    with pytest.raises(InputDataError, match=r"goes back at data row 2: .* s after"):
        log_observations(time_s[::-1], growth, temperatures)
    back = time_s.copy()
    back[17] = back[16] - 1.0
    with pytest.raises(InputDataError, match="goes back at data row 18"):
        log_observations(back, growth, temperatures)
    bad = growth.copy()
    bad[:15] = np.nan
    with pytest.raises(InsufficientDataError, match="25 complete rows"):
        log_observations(time_s, bad, temperatures)
    # A dead thermocouple's NaN rows are left out, not fatal.
    dead = dict(temperatures, t2=np.where(np.arange(40) % 10 == 0, np.nan, temperatures["t2"]))
    assert log_observations(time_s, growth, dead).n == 36
    with pytest.raises(InputDataError, match="structure length"):
        log_model(log_observations(time_s, growth, temperatures), structure_length_m=0.0)
