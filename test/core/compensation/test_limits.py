"""The gate before a model goes live (issue 26): its corrections over the whole travel
and temperature range against the controller's limits - closed-form envelopes."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import model_from_dict
from mt_accuracy_ros.core.compensation.limits import (DEFAULT_LIMITS, CorrectionLimits,
                                                      correction_envelope, gate_problem)
from mt_accuracy_ros.core.errors import MachineDescriptionError
from mt_accuracy_ros.core.kinematics.machine import load_machine, machine_from_dict


def _drift(by_m_per_k: float):
    return model_from_dict({"machine": "kidani_hmc", "reference_temperatures_c": {"bed": 20.0},
                            "effects": {"structural_thermal_drift:bed": {
                                "family": "structural_thermal_drift", "variant": "bed",
                                "coefficients": {"bx": 0.0, "by": by_m_per_k, "bz": 0.0}}}})


def test_a_thermal_gain_is_bounded_over_the_temperature_range():
    limits = CorrectionLimits.of(load_machine("kidani_hmc"))
    envelope = correction_envelope(_drift(4e-6), limits)
    # Closed form: |by| x the range (15 K) on y, nothing on x and z; rate |by| x 0.01 K/s.
    assert envelope.max_abs_m == pytest.approx([0.0, 4e-6 * 15.0, 0.0], abs=1e-15)
    assert envelope.max_rate_m_per_s[1] == pytest.approx(4e-6 * 0.01, rel=1e-9)
    assert gate_problem(_drift(4e-6)) == ""


def test_the_demo_run_two_fit_is_refused_before_it_goes_live():
    # The fit once broadcast: -5.48 mm/K on the bed sensor.
    problem = gate_problem(_drift(-5.48e-3))
    assert "its y correction reaches 8.22e+04 um" in problem
    assert "beyond the controller's 1000 um" in problem


def test_a_slope_too_steep_for_the_controller_is_refused():
    # A 5 um, 2 mm pitch on X: slope 2 pi 5 um / 2 mm = 15.7e-3, at 0.5 m/s -> 7.9 mm/s.
    entry = {"family": "positioning_periodic", "variant": "EXX",
             "setting": {"period_m": 0.002},
             "coefficients": {"cos1": 0.0, "sin1": 5e-6, "cos2": 0.0, "sin2": 0.0}}
    model = model_from_dict({"machine": "kidani_hmc", "effects": {"p": entry}})
    limits = CorrectionLimits.of(model.machine)
    rate = correction_envelope(model, limits).max_rate_m_per_s[0]
    assert rate == pytest.approx(2 * np.pi * 5e-6 / 0.002 * 0.5, rel=0.02)
    assert gate_problem(model) == ""   # under the default 10 mm/s
    strict = CorrectionLimits(limits.max_correction_m, 5e-3, limits.max_feed_m_per_s,
                              limits.temperature_range_k, limits.max_temperature_rate_k_per_s,
                              limits.max_spindle_speed_rpm)
    assert "mm/s, beyond the controller's 5 mm/s" in gate_problem(model, strict)


def test_limits_are_machine_configuration():
    data = {"name": "m", "chain": "[w b X t]", "tool": [0, 0, 0.1], "workpiece": [0, 0, 0],
            "axes": {"X": {"stroke": [0, 0.5], "offset": [0, 0, 0]}},
            "cnc": {"max_correction_m": {"X": 2e-4}, "max_feed_m_per_s": 0.2}}
    limits = CorrectionLimits.of(machine_from_dict(data))
    assert limits.max_correction_m == (2e-4, DEFAULT_LIMITS["max_correction_m"],
                                       DEFAULT_LIMITS["max_correction_m"])
    assert limits.max_feed_m_per_s == 0.2
    for bad in ({"max_feed_m_per_s": -1}, {"max_correction_m": "1 mm"}, {"speed": 1.0}):
        with pytest.raises(MachineDescriptionError, match="cnc"):
            machine_from_dict({**data, "cnc": bad})
