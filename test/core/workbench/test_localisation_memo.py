"""`LocalisationMemo`: a residual seen again (to rounding) is not localised again.

`check --auto` localises what the named effects leave in its first look and again in
the look at the model with them added; the memo serves the second from the first. A
residual that differs (beyond rounding), other rows or other settings are localised
afresh."""
from __future__ import annotations

import numpy as np

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench.diagnosis import Observations, add_effects, diagnose
from mt_accuracy_ros.core.workbench.diagnosis import residual_frame
from mt_accuracy_ros.core.workbench.localisation import LocalisationMemo, localise

MACHINE = load_machine("kidani_hmc")
NOISE = 0.7e-6


def _pitch_survey(seed: int = 3, n: int = 400) -> Observations:
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    truth = np.zeros((n, 3))
    truth[:, 0] = 4e-6 * np.sin(2 * np.pi * positions["X"] / 0.01)
    # No catalogue effect has this shape: something above noise stays after the pitch.
    truth[:, 2] = 3e-6 * np.sign(np.sin(2 * np.pi * np.arange(n) / 37.0))
    measured = truth + rng.normal(0, NOISE, truth.shape)
    return Observations(positions, measured, np.ones((n, 3), bool), np.arange(n) * 15.0,
                        uncertainty_m=2 * NOISE)


def _shares(localisation):
    return [(s.variable, s.component, s.share) for s in localisation.shares]


def test_an_equal_residual_is_served_and_a_changed_one_is_localised_afresh():
    obs = _pitch_survey()
    frame = residual_frame(ErrorModel(MACHINE, {}), obs)
    variables, mask = frame.ctx.variables, obs.measured_mask
    args = (variables, frame.ctx.structure_sensors(), NOISE, None, 5, None)
    memo = LocalisationMemo()
    first = memo.localise(frame.position_residual, mask, *args)
    assert memo.reused == 0
    assert _shares(first) == _shares(localise(frame.position_residual, mask, *args))
    # The same residual with another mean per component, and rounding on top: served.
    again = frame.position_residual + np.array([1e-6, -2e-6, 5e-7]) + \
        np.random.default_rng(0).normal(0, 1e-20, frame.position_residual.shape)
    assert memo.localise(again, mask, *args) is first and memo.reused == 1
    # A residual that differs by more than rounding: localised afresh.
    changed = frame.position_residual.copy()
    changed[:, 0] *= 0.5
    fresh = memo.localise(changed, mask, *args)
    assert fresh is not first and memo.reused == 1
    assert _shares(fresh) == _shares(localise(changed, mask, *args))
    # Other rows, or other settings: localised afresh.
    fewer = mask.copy()
    fewer[::2, 2] = False
    assert memo.localise(frame.position_residual, fewer, *args) is not first
    assert memo.localise(frame.position_residual, mask, variables,
                         frame.ctx.structure_sensors(), NOISE, None, 4, None) is not first
    assert memo.reused == 1


def test_the_look_after_adding_reuses_the_first_looks_localisation_of_what_remains():
    """The first look's localisation of what the named effects leave (their joint fit)
    serves the look at the model with them added: the same residual to rounding, so the
    same shares as a fresh localisation of the final model's residual, to 1e-9."""
    obs = _pitch_survey()
    memo = LocalisationMemo()
    first = diagnose(ErrorModel(MACHINE, {}), obs, localisations=memo)
    assert [c.name for c in first.selected][:1] == ["positioning_periodic:EXX"]
    assert first.localisation_after is not first.localisation
    model = add_effects(ErrorModel(MACHINE, {}), first.selected, obs)
    final = diagnose(model, obs, pair_lookahead=False, localisations=memo)
    assert memo.reused == 1 and final.localisation is first.localisation_after
    frame = residual_frame(model, obs)
    fresh = localise(frame.position_residual, obs.measured_mask, frame.ctx.variables,
                     frame.ctx.structure_sensors(), NOISE,
                     {a: MACHINE.axes[a].stroke for a in MACHINE.axis_order}, 5, None)
    kept = {(v, c): s for v, c, s in _shares(final.localisation)}
    assert {(v, c) for v, c, _ in _shares(fresh)} == set(kept)
    for variable, component, share in _shares(fresh):
        assert abs(kept[(variable, component)] - share) < 1e-9
