"""Uncertainty budget (Kidani Table 3.4, eq. 3.10) against the thesis's own numbers."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.scales.uncertainty import (KIDANI_MAX_FEED_M_PER_S,
                                                     KIDANI_PARALLELISM_RAD, KIDANI_SKEW_S,
                                                     parallelism_error_at_stroke,
                                                     tcp_uncertainty_from_yaw,
                                                     timing_error_per_distance,
                                                     tolerable_scale_uncertainty, yaw_uncertainty)

# Kidani Table 3.1: scale distances and strokes of X, Y, Z [m].
DISTANCE = {"x": 0.24, "y": 0.60, "z": 0.87}
STROKE = {"x": 0.39, "y": 0.44, "z": 0.495}


@pytest.mark.parametrize("axis,um_per_m", [("x", 0.021), ("y", 0.008), ("z", 0.006)])
def test_timing_error_matches_eqs_3_2_to_3_4(axis, um_per_m):
    value = timing_error_per_distance(KIDANI_MAX_FEED_M_PER_S, KIDANI_SKEW_S, DISTANCE[axis])
    assert value * 1e6 == pytest.approx(um_per_m, abs=0.0005)


@pytest.mark.parametrize("axis,um_per_m", [("x", 0.30), ("y", 0.14), ("z", 0.11)])
def test_parallelism_error_matches_section_3_2_1(axis, um_per_m):
    value = parallelism_error_at_stroke(STROKE[axis], KIDANI_PARALLELISM_RAD, DISTANCE[axis])
    assert value * 1e6 == pytest.approx(um_per_m, abs=0.005)


def test_tolerable_scale_uncertainty_is_1_31_um():
    assert tolerable_scale_uncertainty(3.2e-6, 6) * 1e6 == pytest.approx(1.31, abs=0.005)
    # eq. 2.17 backwards: six equal scales add up to the target again.
    sigma = tolerable_scale_uncertainty(3.2e-6, 6)
    assert np.sqrt(6 * sigma ** 2) == pytest.approx(3.2e-6)


def test_combined_band_is_dominated_by_the_encoder_as_table_3_4_says():
    travel = np.linspace(0.0, 0.44, 12)
    budget = yaw_uncertainty(travel, 0.6)
    table_row = (1.5 + 1.5 * travel) * 1e-6 / 0.6  # the table's last row, 2u
    np.testing.assert_allclose(budget.expanded, table_row, rtol=0.01)
    assert np.all(budget.expanded >= table_row)  # the other terms only add
    # Quadrature sum, eq. 3.10, term by term.
    manual = np.sqrt(budget.encoder ** 2 + budget.noise ** 2 + budget.parallelism ** 2
                     + budget.timing ** 2)
    np.testing.assert_allclose(budget.combined, manual)
    assert budget.noise[0] == pytest.approx(0.08e-6 / 2 * 2 / 0.6)


def test_band_shrinks_with_scale_distance_and_grows_with_travel():
    near = yaw_uncertainty([0.1, 0.4], 0.24).expanded
    far = yaw_uncertainty([0.1, 0.4], 0.87).expanded
    assert np.all(far < near) and near[1] > near[0]


def test_tcp_propagation_is_quadrature_per_component():
    np.testing.assert_allclose(tcp_uncertainty_from_yaw(3.0, 4.0, 12.0), [13.0, 12.0, 5.0])
