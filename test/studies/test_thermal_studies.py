"""Robustness, placement comparison and the real-data study (issue 5).

Each seeded figure is pinned to the value docs/thermal.md records, with a tolerance
that covers only float round-off (a change of the figure fails here); the relations
the studies are about (the ranking, the extrapolation's small share of the peak) are
asserted beside the pins.
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
    # docs/thermal.md: 1.74 um RMSE over a 151 um peak (1.2 %); a 3-sensor model gave 51 um.
    assert result.test_rmse_m["second_hour"] == pytest.approx(1.7435e-6, rel=1e-4)
    assert result.peak_error_m["second_hour"] == pytest.approx(150.65e-6, rel=1e-4)
    assert result.test_rmse_m["second_hour"] < 0.02 * result.peak_error_m["second_hour"]


def test_frequency_sensitivity_20_min_training_10_and_40_min_tests():
    result = studies.robustness_frequency()
    # docs/thermal.md: 0.66 / 0.67 um over 142 / 150 um peaks (0.5 / 0.4 %).
    recorded = {"10_min": (0.6612e-6, 142.33e-6), "40_min": (0.6749e-6, 149.85e-6)}
    for key, (rmse_m, peak_m) in recorded.items():
        assert result.test_rmse_m[key] == pytest.approx(rmse_m, rel=1e-4), key
        assert result.peak_error_m[key] == pytest.approx(peak_m, rel=1e-4), key
        assert result.test_rmse_m[key] < 0.01 * result.peak_error_m[key]


def test_placement_comparison_full_and_reduced_data():
    result = studies.placement_comparison()
    np.testing.assert_array_equal(result.sensors["gaussian"], [13, 48])  # 0.211 L, 0.789 L
    full, reduced = result.mse_um2["full"], result.mse_um2["reduced"]
    # Seed 0 (docs/thermal.md gives the medians over 10 seeds: 0.13 / 0.81 / 7.9 um^2 on
    # full data, 0.36 / 4.97 / 25.1 on every 20th sample).
    assert full == pytest.approx({"statistical": 0.14433, "gaussian": 0.83060,
                                  "modal": 7.8248}, rel=1e-4)
    assert reduced == pytest.approx({"statistical": 0.48347, "statistical_full": 0.33118,
                                     "gaussian": 4.9678, "modal": 24.488}, rel=1e-4)
    np.testing.assert_array_equal(result.sensors["statistical_full"], [30, 44])
    np.testing.assert_array_equal(result.sensors["statistical_reduced"], [17, 37])
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
    # docs/thermal.md's table, to its last digit (half of it: rounding, nothing more).
    recorded = {"mean": [7.53, 6.93, 26.27, 25.97, 10.26],
                "all16": [3.78, 3.55, 6.95, 6.61, 15.67],
                "all16_ridge": [4.73, 4.50, 6.67, 6.82, 5.22]}
    for model, values in recorded.items():
        np.testing.assert_allclose([rmse[model][f"ch{i}_um"] for i in range(1, 6)], values,
                                   atol=0.005, rtol=0, err_msg=model)


def test_bad_csv_is_refused(tmp_path):
    (tmp_path / "x.csv").write_text("a,b\n1,2\n")
    with pytest.raises(InputDataError, match="needs time_s"):
        load_thermal_csv(tmp_path / "x.csv")
