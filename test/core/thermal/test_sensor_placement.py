"""Gaussian-integration sensor placement (Krulewich eqs. 4-23) against closed forms."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.thermal.sensor_placement import (evaluate_weights, gauss_points,
                                                  gauss_points_needed, moment_residuals,
                                                  polynomial_terms, position_dependent_weights,
                                                  sensors_needed)


@pytest.mark.parametrize("order, n", [(0, 1), (1, 1), (2, 2), (3, 2), (4, 3), (5, 3), (9, 5)])
def test_number_of_points_is_k_plus_one_over_two(order, n):
    assert gauss_points_needed(order) == n  # eq. 8


def test_two_points_for_a_cubic_field_are_the_closed_form():
    positions, weights = gauss_points(3, 0.305)
    # Two-point Gauss-Legendre on [0, L]: L/2 (1 -+ 1/sqrt(3)), weights L/2.
    np.testing.assert_allclose(positions, 0.305 / 2 * (1 + np.array([-1, 1]) / np.sqrt(3)),
                               rtol=1e-15)
    np.testing.assert_allclose(weights, [0.305 / 2] * 2, rtol=1e-15)


@pytest.mark.parametrize("order", [1, 3, 5, 7])
def test_moment_equations_hold_and_integrate_any_polynomial_of_that_order(order):
    length = 1.7
    x, w = gauss_points(order, length)
    np.testing.assert_allclose(moment_residuals(x, w, order, length), 0.0, atol=1e-13)  # eq. 9
    coefficients = np.random.default_rng(order).normal(size=order + 1)
    field = np.polynomial.Polynomial(coefficients)
    exact = field.integ()(length) - field.integ()(0.0)
    assert w @ field(x) == pytest.approx(exact, rel=1e-12)  # eq. 3 with alpha = 1


def test_position_dependent_weights_match_eqs_17_18():
    x1, x2 = 0.05, 0.24
    c = position_dependent_weights([x1, x2])
    # w1 = (x^2 - 2 x2 x) / (2 (x1 - x2)), w2 = (-x^2 + 2 x1 x) / (2 (x1 - x2))
    np.testing.assert_allclose(c[0], [-2 * x2 / (2 * (x1 - x2)), 1 / (2 * (x1 - x2))], rtol=1e-12)
    np.testing.assert_allclose(c[1], [2 * x1 / (2 * (x1 - x2)), -1 / (2 * (x1 - x2))], rtol=1e-12)


def test_position_dependent_weights_integrate_to_any_position():
    sensors = np.array([0.0, 0.1, 0.25, 0.3])  # n = k + 1 = 4: a cubic field (eq. 13)
    c = position_dependent_weights(sensors)
    field = np.polynomial.Polynomial([1.0, -2.0, 0.5, 3.0])
    positions = np.linspace(0, 0.3, 7)
    estimate = evaluate_weights(c, positions) @ field(sensors)
    np.testing.assert_allclose(estimate, field.integ()(positions) - field.integ()(0.0),
                               atol=1e-14)


def test_multidimensional_counts_of_eqs_19_to_23():
    assert polynomial_terms(2, 3) == 10                 # eqs. 20-21
    assert sensors_needed(2, 3) == 3                    # eq. 22: 10/4 -> 3
    assert sensors_needed(2, 3, position_dependent=True) == 4  # eq. 23: 10/3 -> 4
    assert polynomial_terms(3, 1) == 4 and sensors_needed(3, 1) == 2  # 1-D agrees with eq. 8


def test_bad_inputs():
    with pytest.raises(ParameterError):
        gauss_points(3, 0.0)
    with pytest.raises(ParameterError, match="distinct"):
        position_dependent_weights([0.1, 0.1])
    with pytest.raises(ParameterError):
        gauss_points_needed(-1)
