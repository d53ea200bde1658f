"""Kidani's headline results on the virtual machine tool (issue 6 (a)-(d)).

Tolerances are the thesis' own figures; the values these seeds give are in
docs/results.md.
"""
from __future__ import annotations

import numpy as np

from studies import thesis


def test_a_scale_yaw_agrees_with_the_laser_within_2u():
    result = thesis.yaw_vs_laser()
    assert result.positions_m.size == 12  # y_0 = -440 mm ... y_11 = 0, every 40 mm
    np.testing.assert_allclose(np.diff(result.positions_m), 0.04, atol=1e-6)
    assert result.count_inside >= 10  # of the 11 compared positions (Fig. 3.16)
    # Not vacuous: the yaw itself is several times the band's width apart end to end.
    assert np.ptp(result.laser_yaw_rad) > 2 * result.band_2u_rad.max()


def test_b_scale_thermal_compensation_of_a_20h_warmup():
    result = thesis.warmup_compensation()
    assert result.hours[-1] == 20.0
    # The uneven heating is there (Fig. 3.23: Y1 warmer than Y2) and it moves the yaw.
    assert result.scale_rise_k[-1, 0] > result.scale_rise_k[-1, 1] + 0.5
    assert np.max(np.abs(result.raw_change_rad)) > 3e-6
    assert result.removed_fraction >= 0.903  # section 3.3.3


def test_c_deterioration_detected_and_compensated():
    result = thesis.deterioration_compensation()
    assert 20e-6 <= np.max(np.abs(result.tcp_change_true_m)) <= 24e-6  # ~22 um (Fig. 3.20)
    flagged = result.positions_m[result.flagged]
    assert flagged.size and flagged.min() > -0.2 and flagged.max() >= -0.01  # -160 mm ... 0
    assert not result.flagged[result.positions_m < -0.2].any()
    assert result.removed_fraction >= 0.86  # 22 -> 3 um


def test_d_knn_cv_rmse_predicts_new_data_rmse():
    result = thesis.knn_cv_vs_new_data()
    assert result.samples > 10_000  # five passes at 100 Hz
    assert 1 < result.k <= 100
    assert result.relative_difference <= 0.014  # 0.3962 vs 0.3907 um/m
