"""A refit takes as zero what the live fit could not tell from zero, unless the readings
show it.

A column drift whose x gain the early fit left within its uncertainty of zero: where the
truth has no x gain the refit takes it as zero (fitting it would only take up others'
error); where the truth has one, the whole warm-up shows it held out and the refit gives
it back. Truth written out here (first-order warm-up, closed form)."""
from __future__ import annotations

import numpy as np

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench.diagnosis import Observations
from mt_accuracy_ros.core.workbench.refit import held_parameters, refit_effects

MACHINE = load_machine("kidani_hmc")
NOISE = 0.5e-6
NAME = "structural_thermal_drift:column"


def _warm_up(beta: np.ndarray, seed: int, n: int = 300) -> Observations:
    """A column warming 3 K (tau 40 s) read every 0.4 s, an instrument zero of its own."""
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    t = np.arange(n) * 0.4
    rise = 3.0 * (1.0 - np.exp(-t / 40.0))
    measured = rise[:, None] * beta[None, :] + rng.normal(0.0, NOISE, (n, 3)) + 2e-6
    return Observations(positions, measured, np.ones((n, 3), bool), t,
                        temperatures={"column": 20.0 + rise}, uncertainty_m=2 * NOISE)


def _early(bx: float) -> ErrorModel:
    """The model as an early fit left it: an x gain within its uncertainty of zero, the
    other two identified (and right)."""
    entry = {"family": "structural_thermal_drift", "variant": "column", "setting": {},
             "coefficients": {"bx": bx, "by": 2.0e-6, "bz": 3.0e-6},
             "uncertainties": {"bx": 0.2e-6, "by": 0.05e-6, "bz": 0.05e-6}}
    return ErrorModel(MACHINE, {NAME: entry}, reference_temperatures_c={"column": 20.0})


def test_which_parameters_the_live_fit_left_unidentified():
    model = _early(0.3e-6)
    np.testing.assert_array_equal(held_parameters(model, NAME, ["bx", "by", "bz"]),
                                  [True, False, False])
    # Outside its U (k = 2) a value is identified.
    assert not held_parameters(_early(0.41e-6), NAME, ["bx"])[0]


def test_a_gain_the_truth_lacks_is_taken_as_zero():
    obs = _warm_up(np.array([0.0, 2.0e-6, 3.0e-6]), seed=1)
    refit = refit_effects(_early(0.3e-6), obs)
    assert refit.held == [f"{NAME}: bx"] and not refit.released
    drift = refit.candidates[0]
    assert drift.parameters["bx"] == 0.0
    assert drift.parameter_uncertainties["bx"] == 0.2e-6
    # The others fitted without it: the truth within 3 standard uncertainties.
    for name, truth in (("by", 2.0e-6), ("bz", 3.0e-6)):
        assert abs(drift.parameters[name] - truth) < 3 * drift.parameter_uncertainties[name]
    assert "taken as zero (not told from zero when fitted, not shown held out now): " \
        f"{NAME}: bx" in refit.sentence()


def test_a_gain_the_warm_up_shows_is_given_back():
    obs = _warm_up(np.array([1.0e-6, 2.0e-6, 3.0e-6]), seed=2)
    refit = refit_effects(_early(0.3e-6), obs)
    assert refit.released == [f"{NAME}: bx"] and not refit.held
    drift = refit.candidates[0]
    assert abs(drift.parameters["bx"] - 1.0e-6) < 3 * drift.parameter_uncertainties["bx"]
    assert refit.recommended, refit.sentence()
    assert f"{NAME}: bx refitted too (the readings now show them)" in refit.sentence()
