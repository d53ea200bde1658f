"""Dual-scale yaw, Kidani eq. 2.13."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.scales.dual_scale import (SQ57_EXPANSION_PER_K, YawCorrections,
                                                    corrected_yaw, parallelism_yaw_error,
                                                    scale_expansion, thermal_yaw_error,
                                                    timing_yaw_error, yaw_from_scales)
from mt_accuracy_ros.core.errors import InputDataError, ParameterError


def test_yaw_is_arctan_of_difference_over_distance():
    x1 = np.array([0.0, 0.1, 0.2])
    x2 = x1 + np.array([0.0, 2.4e-6, -4.8e-6])
    yaw = yaw_from_scales(x1, x2, 0.24)
    np.testing.assert_allclose(yaw, np.arctan([0.0, 1e-5, -2e-5]), rtol=1e-9, atol=0)
    np.testing.assert_allclose(yaw_from_scales(x1, x2, 0.24, small_angle=True),
                               [0.0, 1e-5, -2e-5], rtol=1e-9)


@pytest.mark.parametrize("bad,error", [
    (dict(x1_m=[np.nan], x2_m=[0.0], scale_distance_m=0.24), InputDataError),
    (dict(x1_m=[0.0, 1.0], x2_m=[0.0], scale_distance_m=0.24), InputDataError),
    (dict(x1_m=[], x2_m=[], scale_distance_m=0.24), InputDataError),
    (dict(x1_m=[0.0], x2_m=[0.0], scale_distance_m=0.0), ParameterError),
    (dict(x1_m=[0.0], x2_m=[0.0], scale_distance_m=-1.0), ParameterError),
])
def test_bad_input_raises_a_named_error(bad, error):
    with pytest.raises(error):
        yaw_from_scales(**bad)



def test_initial_tilt_cancels_against_the_zero_reference():
    # Kidani eqs. 3.6-3.8: component tilted by delta at the reference, then
    # yawing by alpha; the scale-2 reading moves by D(sin(delta+alpha) - sin delta).
    distance = 0.6
    delta = 40e-6
    alpha = np.array([0.0, 5e-6, -12e-6, 30e-6])
    x1 = np.zeros(4)
    x2 = distance * np.sin(delta + alpha)
    reference = (0.0, distance * np.sin(delta))
    measured = yaw_from_scales(x1, x2, distance, reference=reference)
    np.testing.assert_allclose(measured, alpha, rtol=0, atol=1e-12 * 1 + abs(delta) * 3e-5)
    # Without the reference the tilt would be all there is at alpha = 0.
    assert yaw_from_scales(x1, x2, distance)[0] == pytest.approx(delta, rel=1e-6)


def test_uniform_expansion_is_c_l0_dt():
    travel = np.array([0.0, 0.1, 0.44])
    np.testing.assert_allclose(scale_expansion(travel, 2.0), 12e-6 * travel * 2.0)
    assert SQ57_EXPANSION_PER_K == 12e-6


def test_profile_expansion_integrates_the_interpolated_rise():
    sensors = np.arange(5) * 0.11  # every 110 mm (Kidani section 3.3.3)
    rises = np.array([1.0, 2.0, 3.0, 4.0, 5.0])  # linear in position: 1 + x/0.11
    travel = np.array([0.0, 0.05, 0.22, 0.44, 0.5])
    expected = 12e-6 * (travel + travel ** 2 / 0.22)
    expected[-1] = 12e-6 * (0.44 + 0.44 ** 2 / 0.22 + 0.06 * 5.0)  # flat beyond the last sensor
    np.testing.assert_allclose(scale_expansion(travel, rises, sensor_positions_m=sensors),
                               expected, rtol=1e-12)
    # A uniform profile reproduces the uniform formula.
    np.testing.assert_allclose(scale_expansion(travel, np.full(5, 2.0), sensor_positions_m=sensors),
                               scale_expansion(travel, 2.0), rtol=1e-12)


def test_a_prepared_profile_gives_the_integral_for_every_batch_of_travels():
    """The estimator integrates one temperature reading's rises once and corrects the
    batches until the next with it: the closed form of the linear profile above, and
    the numbers scale_expansion gives each batch."""
    from mt_accuracy_ros.core.scales.dual_scale import ExpansionProfile

    sensors = np.arange(5) * 0.11
    rises = np.array([1.0, 2.0, 3.0, 4.0, 5.0])
    profile = ExpansionProfile(sensors, rises, 12e-6)
    rng = np.random.default_rng(2)
    for _ in range(20):
        travel = rng.uniform(0.0, 0.44, 10)
        np.testing.assert_allclose(profile(travel), 12e-6 * (travel + travel ** 2 / 0.22),
                                   rtol=1e-12)
        np.testing.assert_array_equal(
            profile(travel), scale_expansion(travel, rises, sensor_positions_m=sensors))
    # Beyond the last sensor (a wider span than the one prepared): flat, as before.
    np.testing.assert_allclose(profile(np.array([1.5])),
                               12e-6 * (0.44 + 0.44 ** 2 / 0.22 + (1.5 - 0.44) * 5.0),
                               rtol=1e-12)
    # One row of rises per travel; a row count that fits neither is refused.
    per_sample = np.vstack([rises, 2.0 * rises])
    np.testing.assert_allclose(ExpansionProfile(sensors, per_sample, 12e-6)(
        np.array([0.22, 0.22])), [12e-6 * 0.44, 24e-6 * 0.44], rtol=1e-12)
    with pytest.raises(InputDataError):
        ExpansionProfile(sensors, per_sample, 12e-6)(np.zeros(3))
    with pytest.raises(InputDataError):
        ExpansionProfile(sensors, rises[:4], 12e-6)


def test_thermal_term_is_relative_expansion_over_distance():
    travel = np.array([0.1, 0.2])
    dl1 = scale_expansion(travel, 3.0)
    dl2 = scale_expansion(travel, 1.0)
    # Scale 1 warmer: it under-reads more, so x2 - x1 grows: apparent yaw > 0.
    apparent = thermal_yaw_error(travel, dl1, dl2, 0.6)
    np.testing.assert_allclose(apparent, 12e-6 * travel * 2.0 / 0.6)


def test_parallelism_and_timing_terms():
    np.testing.assert_allclose(parallelism_yaw_error([0.39], 0.61e-3, 0.24),
                               [(0.39 / np.cos(0.61e-3) - 0.39) / 0.24])
    np.testing.assert_allclose(timing_yaw_error([1.0, -1.0], 5e-9, 0.24),
                               [5e-9 / 0.24, -5e-9 / 0.24])


def test_corrected_yaw_removes_each_switched_on_term_and_only_those():
    distance = 0.6
    position = np.linspace(0.0, 0.44, 200)
    velocity = np.where(np.arange(200) % 2 == 0, 0.5, -0.5)
    true_yaw = 3e-6 * np.sin(position * 20)
    rise_1, rise_2 = 2.5, 0.5
    dl1 = scale_expansion(position, rise_1)
    dl2 = scale_expansion(position, rise_2)
    skew = 2e-6
    delta = 1e-3
    x1 = position - dl1
    x2 = (position + distance * np.tan(true_yaw) - dl2 + velocity * skew
          + (position / np.cos(delta) - position))
    everything = YawCorrections(thermal=True, parallelism=True, timing=True,
                                parallelism_rad=delta, skew_s=skew)
    out = corrected_yaw(x1, x2, distance, reference=(0.0, 0.0), corrections=everything,
                        temperature_rise_1_k=rise_1, temperature_rise_2_k=rise_2,
                        velocity_m_per_s=velocity)
    # Residual: the travel is taken from the (expanded) reading, and atan is
    # not additive; both are below 1e-3 urad here.
    np.testing.assert_allclose(out["yaw"], true_yaw, rtol=0, atol=1e-9)
    assert set(out) == {"yaw", "raw", "thermal", "parallelism", "timing"}
    only_thermal = corrected_yaw(x1, x2, distance, reference=(0.0, 0.0),
                                 corrections=YawCorrections(),
                                 temperature_rise_1_k=rise_1, temperature_rise_2_k=rise_2)
    assert set(only_thermal) == {"yaw", "raw", "thermal"}
    np.testing.assert_allclose(only_thermal["yaw"],
                               out["yaw"] + out["parallelism"] + out["timing"], atol=1e-15)


def test_thermal_correction_without_temperatures_is_refused():
    with pytest.raises(InputDataError, match="temperature"):
        corrected_yaw([0.0], [0.0], 0.6, reference=(0.0, 0.0))
