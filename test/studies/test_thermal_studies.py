"""Robustness, placement comparison and the real-data study (issue 5).

Tolerances come from the figures recorded in docs/thermal.md.
"""
from __future__ import annotations

import numpy as np
import pytest

from studies import thermal_fe as studies
from mt_accuracy_ros.core.errors import InputDataError
from studies.thermal_data import load_thermal_csv, study


def test_extrapolation_first_hour_to_second():
    result = studies.robustness_extrapolation()
    assert result.sensors.size == 5  # one per dominant mode (>= 90 % of the weight)
    # Recorded: 1.74 um RMSE over a 151 um peak (1.2 %); a 3-sensor model gave 51 um.
    assert result.test_rmse_m["second_hour"] < 0.02 * result.peak_error_m["second_hour"]


def test_frequency_sensitivity_20_min_training_10_and_40_min_tests():
    result = studies.robustness_frequency()
    # Recorded: 0.66 / 0.67 um over ~145 um peaks (< 0.5 %).
    for key in ("10_min", "40_min"):
        assert result.test_rmse_m[key] < 0.01 * result.peak_error_m[key]


def test_placement_comparison_full_and_reduced_data():
    result = studies.placement_comparison()
    np.testing.assert_array_equal(result.sensors["gaussian"], [13, 48])  # 0.211 L, 0.789 L
    full, reduced = result.mse_um2["full"], result.mse_um2["reduced"]
    # Recorded (seed 0): statistical 0.14, Gaussian 0.83, modal (2 sensors) 7.8 um^2 on full data.
    assert full["statistical"] < full["gaussian"] < full["modal"]
    # Krulewich's mechanism: with every 20th sample the statistical choice changes and its
    # prediction of independent runs degrades; the Gaussian sensors do not move.
    assert not np.array_equal(result.sensors["statistical_full"],
                              result.sensors["statistical_reduced"])
    assert reduced["statistical"] > 1.2 * reduced["statistical_full"]


@pytest.fixture(scope="module")
def fl_study(request):
    from conftest import DATA

    return study(load_thermal_csv(DATA / "fl_thermal" / "fl_thermal.csv"))


def test_real_data_held_out_errors_are_the_recorded_ones(fl_study):
    rmse = fl_study.held_out_rmse_um
    assert fl_study.split_s == pytest.approx(83355.0)
    # Every temperature model beats "no model" on the spindle channels 1-4 (ch5 for ridge).
    for channel in ("ch1_um", "ch2_um", "ch3_um", "ch4_um"):
        assert rmse["all16"][channel] < 0.6 * rmse["mean"][channel]
    assert rmse["all16_ridge"]["ch5_um"] < 0.6 * rmse["mean"]["ch5_um"]
    # The plain 16-sensor fit extrapolates ch5 worse than no model at all (recorded 15.7 vs
    # 10.3 um) - the reason the ridge/CV variant exists.
    assert rmse["all16"]["ch5_um"] > rmse["mean"]["ch5_um"]
    recorded = {"all16": [3.78, 3.55, 6.95, 6.61, 15.67], "all16_ridge": [4.73, 4.50, 6.67, 6.82, 5.22]}
    for model, values in recorded.items():
        np.testing.assert_allclose([rmse[model][f"ch{i}_um"] for i in range(1, 6)], values,
                                   atol=0.01)


def test_bad_csv_is_refused(tmp_path):
    (tmp_path / "x.csv").write_text("a,b\n1,2\n")
    with pytest.raises(InputDataError, match="needs time_s"):
        load_thermal_csv(tmp_path / "x.csv")
