"""Thermal regression (Zhu 3.12-3.15, 3.17) against known coefficients on synthetic data."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import CalibrationError, InputDataError, InsufficientDataError
from mt_accuracy_ros.core.thermal.links import fit_link
from mt_accuracy_ros.core.thermal.regression import (fit_linear, fit_time_constants, lag_features,
                                                     position_dependent_design)
from mt_accuracy_ros.core.kinematics.htm import thermal_link_htm


def _temperatures(n=500, sensors=3, seed=0):
    rng = np.random.default_rng(seed)
    t = np.linspace(0, 7200, n)
    return np.column_stack([20 + a * (1 - np.exp(-t / tau)) + 0.3 * np.sin(t / p)
                            for a, tau, p in zip(rng.uniform(1, 5, sensors),
                                                 rng.uniform(600, 5000, sensors),
                                                 rng.uniform(300, 900, sensors))])


def test_position_independent_fit_recovers_known_coefficients():
    temps = _temperatures()
    beta = np.array([2e-6, -1.5e-6, 0.7e-6])
    error = temps @ beta + 3e-6
    model = fit_linear(temps, error)
    np.testing.assert_allclose(model.coefficients, beta, rtol=1e-8)
    assert model.intercept == pytest.approx(3e-6, rel=1e-6)
    # Same answer as the textbook normal equations (eq. 3.15) where those are safe.
    design = np.column_stack([temps, np.ones(len(temps))])
    normal = np.linalg.solve(design.T @ design, design.T @ error)
    np.testing.assert_allclose(model.coefficients, normal[:3], rtol=1e-6)


def test_position_dependent_fit_recovers_known_coefficients():
    temps = _temperatures(sensors=2)
    x = np.random.default_rng(1).uniform(0, 0.4, len(temps))
    design, names = position_dependent_design(temps - 20, x, degree=2)
    assert names == ["T1", "T2", "T1*x^1", "T2*x^1", "T1*x^2", "T2*x^2"]
    truth = np.array([1e-6, 2e-6, -3e-6, 4e-6, 5e-6, -6e-6])
    model = fit_linear(design, design @ truth, intercept=False)
    np.testing.assert_allclose(model.coefficients, truth, rtol=1e-8)


def test_bad_fits_raise_clear_errors():
    temps = _temperatures()
    y = temps[:, 0]
    with pytest.raises(InsufficientDataError, match="under-determined"):
        fit_linear(temps[:3], y[:3])
    dead = temps.copy()
    dead[:, 1] = 21.0
    with pytest.raises(InputDataError, match="T2 are constant"):
        fit_linear(dead, y, ["T1", "T2", "T3"])
    holes = temps.copy()
    holes[5, 2] = np.nan
    with pytest.raises(InputDataError, match="NaN"):
        fit_linear(holes, y, ["T1", "T2", "T3"])
    twin = np.column_stack([temps, 2 * temps[:, 0] - temps[:, 1]])
    with pytest.raises(CalibrationError, match="singular"):
        fit_linear(twin, y)
    ridged = fit_linear(twin, y, ridge=1e-3)  # ridge makes it solvable
    assert ridged.train_rmse < 0.05 * np.std(y)


def test_time_constant_fit_recovers_three_modes():
    t = np.arange(0, 20 * 3600, 60.0)
    truth = (2.0, 1.0, 0.5), (363.6 * 60, 61.7 * 60, 27.0 * 60)  # Zhu's taus
    temperature = 22.0 + sum(a * (1 - np.exp(-t / tau)) for a, tau in zip(*truth))
    fit = fit_time_constants(t, temperature)
    np.testing.assert_allclose(fit.time_constants_s, truth[1], rtol=1e-4)
    np.testing.assert_allclose(fit.amplitudes, truth[0], rtol=1e-4)
    assert fit.offset == pytest.approx(22.0, abs=1e-6)


def test_lag_features_are_first_order_step_responses():
    t = np.arange(0, 3600, 15.0)
    u = (t >= 0).astype(float)
    features = lag_features(t, u, [600.0, 60.0])
    # u held over each step from t = 0: h(t_n) = 1 - exp(-t_n / tau) exactly (eq. 3.10 form).
    expected = 1 - np.exp(-t / np.array([[600.0], [60.0]]))
    np.testing.assert_allclose(features, expected.T, atol=1e-12)
    with pytest.raises(InputDataError, match="uniformly"):
        lag_features(np.array([0, 1, 3.0]), np.ones(3), [10.0])


def test_lag_of_a_temperature_starts_in_steady_state():
    """A constant 22 degC has a constant lag: no start-up ramp from zero."""
    t = np.arange(0, 3600, 15.0)
    features = lag_features(t, np.full(t.size, 22.0), [600.0, 1800.0], initial="steady")
    np.testing.assert_allclose(features, 22.0, atol=1e-12)
    # A step of 1 K on top of 22 degC at t = 0+ behaves as the step response from rest.
    u = np.where(t > 0, 23.0, 22.0)
    steady = lag_features(t, u, [600.0], initial="steady")[:, 0]
    rest = lag_features(t, u - 22.0, [600.0])[:, 0]
    np.testing.assert_allclose(steady, 22.0 + rest, atol=1e-12)


def test_thermal_link_twist_is_the_first_order_link_htm():
    temps = _temperatures(sensors=2)
    named = {"col_top": temps[:, 0], "col_base": temps[:, 1]}
    expansion = 1e-6 * (temps[:, 0] - 20) + 0.5e-6 * (temps[:, 1] - 20)
    deflection = 0.3e-6 * (temps[:, 0] - temps[:, 1])
    slope = 0.2e-6 * (temps[:, 0] - temps[:, 1])
    link = fit_link("column", ["col_top", "col_base"], named, expansion, deflection, slope,
                    length_axis="z", deflection_axis="x")
    twist = link.twist(named)
    htm = thermal_link_htm(expansion, deflection, slope, length_axis="z", deflection_axis="x")
    np.testing.assert_allclose(twist[:, :3], htm[:, :3, 3], atol=1e-15)
    # Rotation about y (normal of z, x): small-angle part of the HTM's rotation.
    np.testing.assert_allclose(twist[:, 4], htm[:, 0, 2], atol=1e-15)
    with pytest.raises(InputDataError, match="no temperature for col_base"):
        link.twist({"col_top": temps[:, 0]})
