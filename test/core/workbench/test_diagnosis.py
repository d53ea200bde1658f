"""The workbench on synthetic surveys with closed-form truths: names, parameters within
their uncertainty, honest verdicts, bad input."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel, model_from_dict
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench.diagnosis import Observations, add_effects, diagnose

MACHINE = load_machine("kidani_hmc")
NOISE = 0.7e-6


def _survey(truth_fn, seed, n=400, temperatures=None):
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    t = np.arange(n) * 15.0
    truth = truth_fn(positions, t)
    measured = truth + rng.normal(0, NOISE, truth.shape)
    return Observations(positions, measured, np.ones((n, 3), bool), t,
                        temperatures=temperatures or {}, uncertainty_m=2 * NOISE), truth


def _pitch(positions, t, amplitude=4e-6, pitch=0.01):
    out = np.zeros((t.size, 3))
    out[:, 0] = amplitude * np.sin(2 * np.pi * positions["X"] / pitch)   # tool side: +x
    return out


def test_a_ball_screw_pitch_error_is_named_and_located():
    obs, truth = _survey(_pitch, 1)
    diagnosis = diagnose(ErrorModel(MACHINE, {}), obs)
    assert [c.name for c in diagnosis.selected] == ["positioning_periodic:EXX"]
    found = diagnosis.selected[0]
    assert found.setting["period_m"] == pytest.approx(0.01, abs=2e-5)
    assert found.confidence > 0.99
    # The fitted amplitude (sin1) within 3 standard uncertainties of the truth.
    assert abs(found.parameters["sin1"] - 4e-6) < 3 * found.parameter_uncertainties["sin1"] \
        + 0.05e-6   # + the period's grid step
    peak = diagnosis.localisation.peaks[0]
    assert (peak.axis, peak.component) == ("X", "x")
    assert peak.period_m == pytest.approx(0.01, abs=5e-5)
    assert peak.amplitude == pytest.approx(4e-6, rel=0.1)
    sentence = diagnosis.localisation.sentence()
    assert "repeats every 10.0 mm of X travel with 4.0 um amplitude" in sentence
    assert "ball-screw pitch" in sentence
    # Adding it leaves the instrument's noise.
    model = add_effects(ErrorModel(MACHINE, {}), diagnosis.selected, obs)
    after = obs.measured_m - model.tcp_error(obs.positions)[0]
    assert np.std(after[:, 0]) < 1.2 * NOISE


def test_more_readings_give_a_sharper_period_and_leave_only_noise():
    """Issue 27: 10,000 readings of a 10.000 mm pitch - the period is refined between the
    grid's points (9.99 mm on the grid alone) and nothing above the noise is left."""
    obs, truth = _survey(_pitch, 2, n=10000)
    diagnosis = diagnose(ErrorModel(MACHINE, {}), obs)
    assert [c.name for c in diagnosis.selected] == ["positioning_periodic:EXX"]
    assert diagnosis.selected[0].setting["period_m"] == pytest.approx(0.01, abs=2e-6)
    assert not diagnosis.residual_above_noise
    assert diagnosis.verdict() == ""
    # The localisation's kNN shares come from an evenly spread subset at this size: the
    # residual still lives in x along X.
    top = diagnosis.localisation.top()
    assert (top.variable, top.component) == ("x", "x") and top.share > 0.5
    model = add_effects(ErrorModel(MACHINE, {}), diagnosis.selected, obs)
    after = obs.measured_m - model.tcp_error(obs.positions)[0]
    assert np.std(after[:, 0]) < 1.02 * NOISE


def test_two_missing_effects_are_both_named_with_their_parameters():
    def truth(positions, t):
        out = _pitch(positions, t, 3e-6)
        out[:, 0] += -25e-6 * positions["Y"]          # squareness EC0Y = 25 urad (e_x = -S y)
        return out
    obs, _ = _survey(truth, 2)
    diagnosis = diagnose(ErrorModel(MACHINE, {}), obs)
    names = {c.name: c for c in diagnosis.selected}
    assert set(names) == {"positioning_periodic:EXX", "squareness:EC0Y"}
    square = names["squareness:EC0Y"]
    assert abs(square.parameters["angle_rad"] - 25e-6) < 3 * \
        square.parameter_uncertainties["angle_rad"]


@pytest.mark.parametrize("seed", [11, 12, 13])
def test_nothing_missing_nothing_named(seed):
    obs, _ = _survey(lambda p, t: np.zeros((t.size, 3)), seed,
                     temperatures={"column": 20 + 0.001 * np.arange(400),
                                   "bed": 20 + 0.5 * np.sin(np.arange(400) / 50)})
    diagnosis = diagnose(ErrorModel(MACHINE, {}), obs)
    assert diagnosis.selected == []
    assert not diagnosis.residual_above_noise
    assert "nothing missing" in diagnosis.text() and "unexplained" not in diagnosis.text()


def test_a_residual_no_effect_explains_is_called_unexplained_not_noise():
    """A square wave in time (a door opening, a coolant pump switching) is in no family:
    the verdict names the systematic residual and where it lives."""
    def truth(positions, t):
        out = np.zeros((t.size, 3))
        out[:, 0] = 3e-6 * np.sign(np.sin(2 * np.pi * t / 900.0))
        return out
    obs, _ = _survey(truth, 3)
    diagnosis = diagnose(ErrorModel(MACHINE, {}), obs)
    assert diagnosis.selected == []
    assert diagnosis.residual_above_noise
    assert diagnosis.unexplained_m["x"] == pytest.approx(3e-6, rel=0.15)
    import re

    assert re.search(r"an unexplained systematic residual of (2\.[89]|3\.[01]) um on x remains",
                     diagnosis.text()), diagnosis.text()
    assert diagnosis.localisation.top().variable == "t"
    assert "nothing beyond noise" not in diagnosis.text()


def test_a_user_effect_competes_with_the_catalogue_and_wins_when_right():
    def truth(positions, t):
        out = np.zeros((t.size, 3))
        out[:, 2] = 6e-6 * np.exp(-((positions["X"] - 0.2) / 0.05) ** 2)   # a local bump
        return out
    obs, _ = _survey(truth, 4)
    model = model_from_dict({"machine": "kidani_hmc", "effects": {"bump": {
        "expression": "k * exp(-((x - 0.2) / 0.05) ** 2)", "parameters": ["k"],
        "acts_on": "z"}}})
    diagnosis = diagnose(model, obs)
    assert diagnosis.found is not None and diagnosis.found.name == "user:bump"
    assert diagnosis.found.parameters["k"] == pytest.approx(6e-6, abs=3 * diagnosis.found.
                                                           parameter_uncertainties["k"])
    fitted = add_effects(model, [diagnosis.found], obs)
    assert fitted.effects["bump"]["values"]["k"] == diagnosis.found.parameters["k"]


def test_a_user_effect_collinear_with_the_model_is_refused_by_name():
    model = model_from_dict({"machine": "kidani_hmc", "effects": {
        "sq": {"family": "squareness", "variant": "EC0Y", "coefficients": {"angle_rad": 1e-5}},
        "again": {"expression": "k * y", "parameters": ["k"], "acts_on": "x"}}})
    obs, _ = _survey(lambda p, t: np.zeros((t.size, 3)), 5)
    with pytest.raises(ParameterError, match="user effect 'again': its design is collinear "
                                             "with sq"):
        diagnose(model, obs)
    constant = model_from_dict({"machine": "kidani_hmc", "effects": {
        "offset": {"expression": "k * 1 + k * 0", "parameters": ["k"], "acts_on": "x"}}})
    with pytest.raises(ParameterError, match="collinear with a constant offset"):
        diagnose(constant, obs)
