"""Rotary-axis location errors from a probed sphere, on data from the foreign chain.

The centres come from ``studies/foreign_machine.py`` - its own 4x4 chain with exact
rotation vectors, sharing no code with the kinematic model the identification uses.
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import CalibrationError, InputDataError
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.rotary.probing import (default_rotary_parameters, fit_sphere,
                                                 identify_location_errors,
                                                 observable_parameters, volumetric_error)
from studies.foreign_machine import ErrorSet, read_geometry, tcp_point

MACHINE = load_machine("khan_chen_rpppr")
SPHERE = np.array([0.05, 0.08, 0.06])          # nominal sphere centre in the A table frame
SPHERE_OFFSET = np.array([3e-4, -2e-4, 1e-4])  # where it really sits, relative to nominal
TRUTH = {"A": np.array([0, 20e-6, -15e-6, 0, 30e-6, -25e-6]),
         "B": np.array([0, 0, 0, 15e-6, 0, -20e-6])}


def _cycles():
    a = np.radians(np.r_[np.arange(-90, 91, 30), np.zeros(7), [45, -45, 45, -45]])
    b = np.radians(np.r_[np.zeros(7), np.arange(-60, 61, 20), [30, 30, -30, -30]])
    n = a.size
    return {"X": np.full(n, 0.3), "Y": np.full(n, 0.2), "Z": np.full(n, 0.2), "A": a, "B": b}


def _measured(q, truth, seed=0, noise_m=0.5e-6):
    geometry = read_geometry("khan_chen_rpppr")
    errors = ErrorSet(location_fns={axis: [lambda state, t=t: t] for axis, t in truth.items()})
    # The sphere is a fixed target on the table: the probe finds it where it really is.
    actual = tcp_point(geometry, q, errors, work_point=SPHERE + SPHERE_OFFSET)
    nominal = tcp_point(geometry, q, None, work_point=SPHERE)
    rng = np.random.default_rng(seed)
    return -(actual - nominal) + rng.normal(0.0, noise_m, actual.shape)


def test_location_errors_and_the_sphere_are_found_within_their_uncertainty():
    q = _cycles()
    result = identify_location_errors(MACHINE, q, _measured(q, TRUTH), sphere_nominal_m=SPHERE)
    expected = {"EY0A": 20e-6, "EZ0A": -15e-6, "EB0A": 30e-6, "EC0A": -25e-6,
                "EA0B": 15e-6, "EC0B": -20e-6}
    for name, value in expected.items():
        assert abs(result.parameters[name] - value) <= 3 * result.uncertainties[name], name
    np.testing.assert_allclose(result.sphere_offset_m, SPHERE_OFFSET, atol=3e-6)
    # The centre wandered by hundreds of um as the axes turned; what is left is the noise.
    assert result.dispersion_before_m > 100e-6
    assert result.rms_after_m < 1.5e-6 and result.dispersion_after_m < 3e-6
    # B turns the probe about its actual line from the set-up pose, so its offsets are
    # seen (zero here) and nothing folds; the zero-angle errors are taken out where the
    # sphere and the probe were set up - said, not guessed.
    assert abs(result.parameters["EX0B"]) <= 3 * result.uncertainties["EX0B"]
    assert abs(result.parameters["EZ0B"]) <= 3 * result.uncertainties["EZ0B"]
    assert set(result.not_observable) == {"EA0A", "EB0B"}
    assert "taken out by the set-up" in result.text()
    assert result.identified_as("EZ0A") == "EZ0A" and not result.aliases


def test_volumetric_error_falls_once_the_identified_errors_are_compensated():
    q = _cycles()
    result = identify_location_errors(MACHINE, q, _measured(q, TRUTH), sphere_nominal_m=SPHERE)
    rng = np.random.default_rng(1)
    grid = {axis: rng.uniform(*MACHINE.axes[axis].stroke, 500) for axis in MACHINE.axis_order}
    truth_named = {"EY0A": 20e-6, "EZ0A": -15e-6, "EB0A": 30e-6, "EC0A": -25e-6,
                   "EA0B": 15e-6, "EC0B": -20e-6}
    before = volumetric_error(MACHINE, truth_named, grid)
    residual = {k: truth_named[k] - result.parameters[k] for k in truth_named}
    after = volumetric_error(MACHINE, residual, grid)
    rms = lambda e: np.sqrt(np.mean(np.sum(e ** 2, axis=1)))  # noqa: E731
    assert rms(after) < 0.15 * rms(before)


def test_repeated_cycles_give_a_repeatability():
    q = _cycles()
    twice = {axis: np.r_[v, v] for axis, v in q.items()}
    measured = np.vstack([_measured(q, TRUTH, seed=0), _measured(q, TRUTH, seed=1)])
    result = identify_location_errors(MACHINE, twice, measured, sphere_nominal_m=SPHERE)
    assert result.repeatability_m == pytest.approx(0.5e-6, rel=0.3)


def test_the_default_parameters_and_what_one_sphere_can_see():
    assert default_rotary_parameters(MACHINE) == ["EY0A", "EZ0A", "EB0A", "EC0A",
                                                  "EX0B", "EZ0B", "EA0B", "EC0B",
                                                  "EA0A", "EB0B"]
    kept, dropped = observable_parameters(MACHINE, _cycles(), sphere_nominal_m=SPHERE)
    # Both zero angles are taken out where the sphere and the probe were set up; every
    # offset and tilt of both lines is seen.
    assert dropped == ["EA0A", "EB0B"]
    assert set(kept) == {"EY0A", "EZ0A", "EB0A", "EC0A", "EX0B", "EZ0B", "EA0B", "EC0B"}


def test_a_zero_angle_error_is_taken_out_by_the_set_up_and_said():
    """A B zero error of 30 urad: the probe was set up at B = 0, so from there it turns by
    the commanded increments and the centres do not see it. The fit is as good as without
    it, and the output says why EB0B is not given."""
    q = _cycles()
    truth = {"A": TRUTH["A"], "B": TRUTH["B"] + np.array([0, 0, 0, 0, 30e-6, 0])}
    with_zero = _measured(q, truth)
    # Second order only: 30 urad times the other errors.
    np.testing.assert_allclose(with_zero, _measured(q, TRUTH), rtol=0, atol=1e-10)
    result = identify_location_errors(MACHINE, q, with_zero, sphere_nominal_m=SPHERE)
    assert "EB0B" not in result.parameters and "EB0B" in result.not_observable
    assert "EB0B - a zero-angle error is taken out by the set-up" in result.text()
    with pytest.raises(CalibrationError, match="EB0B"):
        identify_location_errors(MACHINE, q, with_zero, ["EB0B", "EB0A"],
                                 sphere_nominal_m=SPHERE)


def test_sphere_fit_recovers_the_centre_and_refuses_a_stray_touch():
    rng = np.random.default_rng(4)
    directions = rng.normal(size=(9, 3))
    directions[:, 2] = np.abs(directions[:, 2])           # upper half: the probe's reach
    directions /= np.linalg.norm(directions, axis=1)[:, None]
    centre = np.array([0.1, -0.02, 0.3])
    points = centre + 0.0125 * directions + rng.normal(0, 0.2e-6, (9, 3))
    fit = fit_sphere(points, 0.0125)
    np.testing.assert_allclose(fit.centre_m, centre, atol=1e-6)
    free = fit_sphere(points)
    assert free.radius_m == pytest.approx(0.0125, abs=1e-6)
    stray = points.copy()
    stray[3] += [0.0, 0.0, 2e-3]                           # touched the fixture
    with pytest.raises(InputDataError, match="touch point 3 is"):
        fit_sphere(stray, 0.0125)
    with pytest.raises(InputDataError, match="in a plane"):
        fit_sphere(np.c_[points[:, :2], np.zeros(9)], 0.0125)


def test_bad_probing_input_is_named():
    q = _cycles()
    measured = _measured(q, TRUTH)
    with pytest.raises(InputDataError, match="axis B has 17 positions for 18"):
        identify_location_errors(MACHINE, {**q, "B": q["B"][:-1]}, measured)
    bad = measured.copy()
    bad[2, 1] = np.nan
    with pytest.raises(InputDataError, match="non-finite"):
        identify_location_errors(MACHINE, q, bad)
    with pytest.raises(CalibrationError, match="EA0A"):
        identify_location_errors(MACHINE, q, measured, ["EA0A", "EB0A"], sphere_nominal_m=SPHERE)
    still = {**q, "A": np.zeros_like(q["A"])}
    with pytest.raises(InputDataError, match="needs the A axis probed at 3 or more"):
        identify_location_errors(MACHINE, still, measured, ["EB0A"])


@pytest.mark.parametrize("truth", [{"EY0C": -15e-6}, {"EY0A": 25e-6}, {"EX0C": 20e-6},
                                   {"EX0C": 20e-6, "EZ0A": -10e-6}, {}])
def test_a_trunnion_probed_at_its_set_up_pose_gives_each_line_offset_alone(truth):
    """The trunnion VMC ([w C A X Y b Z t]), the sphere touched off at A = C = 0: the
    virtual machine (its own rigid bodies, turning about the real lines) is probed
    sweeping A, then C. A C-line offset comes back as itself (not as two cancelling
    angles), an A-line offset without a spurious C offset, the sphere's set-up where it
    is, C's zero-angle error said to be the set-up's and A's folded into C's line."""
    from mt_accuracy_ros.sim.rotary_instruments import ProbingPlan, probe_sphere

    machine = load_machine("trunnion_ac")
    plan = ProbingPlan({"A": list(np.arange(-90.0, 31.0, 30.0)),
                        "C": list(np.arange(0.0, 360.0, 45.0))},
                       {"X": 0.0, "Y": 0.0, "Z": -0.3}, sphere_m=(0.08, 0.05, 0.03),
                       sphere_radius_m=12.5e-3, repeats=2)
    data = probe_sphere(machine, plan, truth, seed=3)
    rng = np.random.default_rng(7)
    centres = data["centres_m"] + rng.normal(0.0, 0.3e-6, data["centres_m"].shape)
    result = identify_location_errors(machine, data["positions"], centres,
                                      sphere_nominal_m=np.array(plan.sphere_m))
    for name, value in result.parameters.items():
        assert abs(value - truth.get(name, 0.0)) <= 4 * result.uncertainties[name] + 1e-12, \
            (name, value, result.text())
    np.testing.assert_allclose(result.sphere_offset_m, plan.sphere_offset_m, atol=1e-6)
    assert result.not_observable == ["EA0A", "EC0C"]
    # A's zero turns C's line about A's (ISO 230-7): folded into C's tilt and, through C's
    # origin 0.1 m below A's line, its offset in y; C's zero is the set-up's.
    assert result.aliases == {"EA0C": {"EA0A": pytest.approx(1.0)},
                              "EY0C": {"EA0A": pytest.approx(0.1)}}
    assert "not observable: EC0C - a zero-angle error is taken out" in result.text()
