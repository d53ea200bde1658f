"""Systematic/random error (Kidani eqs. 2.22, 2.23) and ISO 230-2 figures."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError, InsufficientDataError
from mt_accuracy_ros.core.scales.repeatability import (group_by_position, iso230_2,
                                                       systematic_and_random)


def test_mean_and_sample_sigma_per_position():
    errors = np.array([[1.0, 2.0, 3.0], [4.0, 4.0, 4.0]])
    mean, sigma = systematic_and_random(errors)
    np.testing.assert_allclose(mean, [2.0, 4.0])
    np.testing.assert_allclose(sigma, [1.0, 0.0])


def test_grouping_scattered_stop_and_measure_data():
    x = np.array([0.0, 0.04, 0.0, 0.04 + 2e-7, 0.08])
    y = np.array([1.0, 5.0, 3.0, 7.0, 9.0])
    gx, mean, sigma, count = group_by_position(x, y)
    np.testing.assert_allclose(mean, [2.0, 6.0, 9.0])
    np.testing.assert_allclose(count, [2, 2, 1])
    assert sigma[0] == pytest.approx(np.sqrt(2.0)) and np.isnan(sigma[2])
    assert gx[1] == pytest.approx(0.04 + 1e-7)


def test_iso230_2_figures_on_a_hand_worked_example():
    targets = np.array([0.0, 100.0, 200.0])
    up = np.array([[1.0, 3.0], [2.0, 2.0], [5.0, 7.0]])      # means 2, 2, 6; s = 1.414, 0, 1.414
    down = np.array([[0.0, 0.0], [-1.0, 1.0], [4.0, 4.0]])   # means 0, 0, 4; s = 0, 1.414, 0
    r = iso230_2(targets, up, down)
    s = np.sqrt(2.0)
    np.testing.assert_allclose(r.reversal, [2.0, 2.0, 2.0])
    assert r.reversal_value == pytest.approx(2.0)
    assert r.mean_reversal == pytest.approx(2.0)
    assert r.systematic_deviation_up == pytest.approx(4.0)
    assert r.systematic_deviation == pytest.approx(6.0)          # max 6 - min 0
    assert r.mean_deviation_range == pytest.approx(5.0 - 1.0)
    assert r.repeatability_up_axis == pytest.approx(4 * s)
    # R_i = max(2 s_up + 2 s_down + |B_i|, 4 s_up, 4 s_down)
    assert r.repeatability_bidirectional[0] == pytest.approx(max(2 * s + 0 + 2.0, 4 * s))
    assert r.repeatability == pytest.approx(4 * s)
    assert r.accuracy == pytest.approx((6 + 2 * s) - (0 - 2 * s))  # low end: down run at 100
    assert r.accuracy_up == pytest.approx((6 + 2 * s) - (2 - 2 * s))
    assert set(r.summary()) >= {"accuracy", "repeatability", "reversal_value"}


def test_iso_refuses_mismatched_or_single_runs():
    with pytest.raises(InputDataError):
        iso230_2([0.0, 1.0], np.zeros((2, 3)), np.zeros((3, 3)))
    with pytest.raises(InsufficientDataError):
        iso230_2([0.0], np.zeros((1, 1)), np.zeros((1, 1)))


def test_positioning_runs_are_found_and_evaluated_like_iso230_2():
    from mt_accuracy_ros.core.scales.repeatability import iso230_2, positioning_runs

    rng = np.random.default_rng(3)
    targets = np.linspace(0.0, 0.4, 6)
    positions, deviations, directions = [], [], []
    for run in range(3):
        for sign in (1, -1):
            for target in targets[::sign]:
                positions.append(target + rng.normal(0, 1e-6))
                deviations.append(2e-6 * target / 0.4 + sign * 1e-6 + rng.normal(0, 2e-7))
                directions.append(sign)
    found = positioning_runs(np.array(positions), np.array(deviations), np.array(directions))
    assert found is not None
    p, up, down = found
    np.testing.assert_allclose(p, targets, atol=1e-5)
    assert up.shape == down.shape == (6, 3)
    result = iso230_2(p, up, down)
    assert result.mean_reversal == pytest.approx(2e-6, abs=3e-7)  # up - down = 2 x 1 um


def test_continuous_motion_is_not_mistaken_for_positioning_runs():
    from mt_accuracy_ros.core.scales.repeatability import positioning_runs

    t = np.linspace(0, 60, 600)
    q = 0.2 + 0.2 * np.sin(t)
    assert positioning_runs(q, np.zeros_like(q), np.sign(np.cos(t))) is None
