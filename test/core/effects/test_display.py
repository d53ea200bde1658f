"""Fitted parameters as a metrologist reads them (issue 30): units and rounding."""
from __future__ import annotations

import pytest

from mt_accuracy_ros.core.effects.display import (display_parameters, display_setting,
                                                  format_measured, parameter_unit)


@pytest.mark.parametrize("value, u, text", [
    (1.4721, 0.42, "1.47 ± 0.42"),          # U to two digits, the value to its place
    (1.4721, 0.042, "1.472 ± 0.042"),
    (27.93, 3.2, "27.9 ± 3.2"),
    (1234.5, 42.0, "1235 ± 42"),
    (12345.0, 420.0, "12350 ± 420"),
    (-0.0123456, 0.00042, "-0.01235 ± 0.00042"),
    (5.0, None, "5"),
])
def test_a_value_is_rounded_to_its_uncertainty(value, u, text):
    assert format_measured(value, u) == text


def test_each_family_speaks_its_physics_unit():
    # Issue 30's example: "bx = 1.472e-06 ± 2.1e-07" for a drift is 1.47 ± 0.42 um/K (k = 2).
    shown = display_parameters("structural_thermal_drift", "column", {"bx": 1.472e-6},
                               {"bx": 2.1e-7})
    assert shown == {"bx": "1.47 ± 0.42 µm/K"}
    assert parameter_unit("squareness", "EC0Y", "angle_rad") == ("µrad", 1e6)
    assert parameter_unit("rotary_location", "A", "EX0A")[0] == "µm"
    assert parameter_unit("rotary_location", "A", "EB0A")[0] == "µrad"
    assert parameter_unit("rotary_error", "EXA", "cos1")[0] == "µm"
    assert parameter_unit("rotary_error", "EBA", "cos1")[0] == "µrad"
    assert parameter_unit("positioning_periodic", "EXX", "cos1")[0] == "µm"
    assert parameter_unit("angular", "EBX", "P1")[0] == "µrad"
    assert parameter_unit("servo_lag", "X", "lag_s") == ("ms", 1e3)
    assert parameter_unit("heat_source", "spindle_speed", "gz")[0] == "µm/krpm"
    assert parameter_unit("position_dependent_thermal", "X:column", "alpha_per_k")[0] == \
        "µm/m/K"
    assert parameter_unit("user_thing", "", "k") == ("", 1.0)
    assert display_setting({"period_m": 0.01, "tau_s": 1200.0, "order": 3}) == \
        "period 10 mm, tau 20 min, order 3"


def test_temperatures_that_explain_alike_are_one_bar():
    from mt_accuracy_ros.core.workbench.localisation import Localisation, Share

    shares = [Share(f"T_t{k}", "z", 0.92 - 0.001 * k, 1e-6) for k in range(12)]
    shares += [Share("X", "x", 0.30, 1e-6), Share("T_t3-t5", "x", 0.05, 1e-7),
               Share("Y", "z", 0.50, 1e-6)]
    chart = Localisation(sorted(shares, key=lambda s: -s.share), []).chart()
    labels = [row["label"] for row in chart]
    assert labels[0] == "all 12 temperatures alike (best T_t0)"
    assert len(chart[0]["variables"]) == 12 and chart[0]["component"] == "z"
    assert "Y" in labels and "X" in labels and "T_t3-t5" in labels
    assert not any(label.startswith("T_t1") for label in labels)


def test_a_twists_coefficient_is_a_length():
    """cross_axis multiplies normalised positions (u_a u_b, dimensionless): its coefficient
    is the twist's size at the travel's corners, a length - not per area."""
    from mt_accuracy_ros.core.effects.display import parameter_unit

    assert parameter_unit("cross_axis", "XY", "on_z") == ("µm", 1e6)
