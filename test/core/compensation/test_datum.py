"""The model's datum: position errors referred to the work offset (issue 30, item 4).

An R-test is zeroed on the part at the work offset; the compensation must never
move that datum, and a fitted effect's constant (which a fit against a zeroed
instrument cannot know) must be referred to it.
"""
from __future__ import annotations

import numpy as np
import pytest
import yaml

from mt_accuracy_ros.core.compensation.error_model import (ErrorModel, model_from_dict,
                                                           model_to_dict)
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.machine import load_machine

# Rotaries away from the set-up pose (0): their location errors act at the datum.
DATUM = {"X": 0.3, "Y": 0.2, "Z": 0.2, "A": 0.3, "B": -0.2}
EFFECTS = {
    "rotary_location:AB": {"family": "rotary_location", "variant": "AB", "setting": {},
                           "coefficients": {"EY0A": 2e-6, "EZ0A": -1e-6, "EB0A": 40e-6,
                                            "EC0A": -30e-6, "EX0B": 1e-6,
                                            "EZ0B": 0.0, "EA0B": 30e-6, "EC0B": -20e-6}},
    "structural_thermal_drift:column": {
        "family": "structural_thermal_drift", "variant": "column", "setting": {},
        "coefficients": {"bx": 1e-6, "by": 2e-6, "bz": 3e-6}},
}


def _poses(n: int = 25):
    rng = np.random.default_rng(4)
    machine = load_machine("khan_chen_rpppr")
    return {a: rng.uniform(-0.8, 0.8, n) if machine.axes[a].is_rotary
            else rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}


def _models():
    machine = load_machine("khan_chen_rpppr")
    absolute = ErrorModel(machine, dict(EFFECTS), {"column": 20.0})
    referred = ErrorModel(machine, dict(EFFECTS), {"column": 20.0}, datum=dict(DATUM))
    return absolute, referred


def test_the_datum_error_is_the_absolute_error_at_the_work_offset_at_reference_conditions():
    absolute, referred = _models()
    q = _poses()
    warm = {"column": np.full(q["X"].size, 21.5)}
    at_datum = absolute.tcp_error({a: np.array([v]) for a, v in DATUM.items()},
                                  {"column": np.array([20.0])})[0][0]
    assert np.linalg.norm(at_datum) > 1e-6   # the tilts' levers: there is something to refer
    position, orientation = referred.tcp_error(q, warm)
    expected, expected_orientation = absolute.tcp_error(q, warm)
    np.testing.assert_allclose(position, expected - at_datum, atol=1e-15, rtol=0)
    # A touch-off does not take out a tilt: the direction stays absolute.
    np.testing.assert_allclose(orientation, expected_orientation, atol=0, rtol=0)


def test_the_compensation_never_moves_the_datum_but_follows_its_thermal_drift():
    _, referred = _models()
    pose = {a: np.array([v]) for a, v in DATUM.items()}
    cold, _ = referred.tcp_error(pose, {"column": np.array([20.0])})
    np.testing.assert_allclose(cold, 0.0, atol=1e-18)
    # Warmed by 2 K the structure moved the tool off the datum: that is compensated.
    warm, _ = referred.tcp_error(pose, {"column": np.array([22.0])})
    np.testing.assert_allclose(warm[0], [2e-6, 4e-6, 6e-6], atol=1e-15)


def test_the_datum_survives_yaml_and_new_versions():
    _, referred = _models()
    text = yaml.safe_dump(model_to_dict(referred))
    again = model_from_dict(yaml.safe_load(text))
    assert again.datum == DATUM
    assert referred.with_effect("squareness", {"errors_rad": {"EC0Y": 1e-6}}).datum == DATUM
    assert referred.without_effect("structural_thermal_drift:column").datum == DATUM


@pytest.mark.parametrize("datum, message", [
    ({"X": 0.3, "Y": 0.2, "Z": 0.2, "A": 0.0}, "give every axis"),
    ({**DATUM, "A": 45.0}, "outside the stroke"),      # degrees for radians
    ({**DATUM, "X": 300.0}, "outside the stroke"),     # millimetres for metres
    ({**DATUM, "Y": float("nan")}, "finite number"),
    ([0.3, 0.2], "axis -> position"),
])
def test_a_bad_datum_is_one_clear_error(datum, message):
    with pytest.raises(ParameterError, match=message):
        model_from_dict({"machine": "khan_chen_rpppr", "effects": {}, "datum": datum})


def test_live_profiles_change_the_datum_error():
    """The datum's error is the model's as it stands: a new live profile changes it."""
    machine = load_machine("kidani_hmc")
    datum = {a: float(np.mean(machine.axes[a].stroke)) for a in machine.axis_order}
    model = ErrorModel(machine, {"geometric": {}}, datum=datum)
    pose = {a: np.array([v]) for a, v in datum.items()}
    before = model.datum_error()
    low, high = machine.axes["Y"].stroke
    grid = np.linspace(low, high, 11)
    model.set_profile("ECY", grid, 5e-6 * (grid - low) / (high - low))
    after = model.datum_error()
    assert np.linalg.norm(after - before) > 1e-8
    np.testing.assert_allclose(model.tcp_error(pose)[0], 0.0, atol=1e-18)
