"""Five-axis compensation: the rotary axes turn the tool back, the linear axes its tip.

The first-order inverse (:mod:`mt_accuracy_ros.core.compensation.five_axis`) is
checked against the kinematic chain evaluated exactly at the corrected
command - a second formulation - and against closed forms on a tilting axis.
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.five_axis import (five_axis_correction, rotary_jacobians,
                                                         tool_direction)
from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.htm import rotation_vector
from mt_accuracy_ros.core.kinematics.machine import load_machine, machine_from_dict

LOCATION = {"EY0A": 25e-6, "EZ0A": -20e-6, "EB0A": 40e-6, "EC0A": -30e-6, "EX0B": 20e-6,
            "EA0B": 30e-6}


def _overrides(q):
    return ErrorOverrides(location=LOCATION, motion={"EAA": 15e-6 * np.sin(q["A"] + 0.4),
                                                     "EYA": 6e-6 * np.cos(q["A"] + 0.4),
                                                     "EXX": 4e-6 * np.sin(9 * q["X"])},
                          use_description=False)


def _pose(model: KinematicModel, q, errors: bool, under_tool):
    """Tool and the workpiece frame carried to ``under_tool`` (the machining point of the
    original command: the material to cut does not move with the correction)."""
    tool = model.branch("tool", q, errors=errors, overrides=_overrides(q), check_stroke=False)
    work = model.branch("workpiece", q, errors=errors, overrides=_overrides(q),
                        check_stroke=False, end_point=under_tool)
    return tool, work


def test_the_corrected_machine_is_right_to_second_order_at_random_poses():
    machine = load_machine("khan_chen_rpppr")
    model = KinematicModel(machine)
    rng = np.random.default_rng(3)
    n = 300
    q = {a: rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}
    q["A"], q["B"] = 0.9 * q["A"], 0.8 * q["B"]
    before = model.tcp_error(q, overrides=_overrides(q), check_stroke=False)
    fix = five_axis_correction(model, q, before["position"], before["orientation"])
    assert fix.rotary_axes == ("A", "B")
    # The corrected command, every error evaluated exactly there (not linearised).
    moved = dict(q)
    for k, axis in enumerate(fix.rotary_axes):
        moved[axis] = q[axis] + fix.rotary_rad[:, k]
    tool1, work1 = _pose(model, moved, errors=True, under_tool=model.machining_point(q))
    tool0, work0 = _pose(model, q, errors=False, under_tool=model.machining_point(q))
    tip = (tool1[:, :3, 3] - work1[:, :3, 3]) - (tool0[:, :3, 3] - work0[:, :3, 3]) \
        + fix.position_m
    turn = rotation_vector(np.swapaxes(work1[:, :3, :3] @ np.swapaxes(work0[:, :3, :3], 1, 2),
                                       1, 2) @ (tool1[:, :3, :3] @ np.swapaxes(tool0[:, :3, :3],
                                                                               1, 2)))
    axis = tool_direction(model, q)
    direction_before = np.linalg.norm(np.cross(before["orientation"], axis), axis=1)
    direction_after = np.linalg.norm(np.cross(turn, axis), axis=1)
    assert np.max(np.linalg.norm(before["position"], axis=1)) > 20e-6
    assert np.max(direction_before) > 40e-6
    # What is left is second order in errors of ~5e-5 through arms up to ~1 m (the
    # machining point is far from the A axis); a tilted line turns the body by up to twice
    # its tilt (E R E^T - R): below 3e-8 m (halving every error quarters it: 1.9e-8,
    # 4.9e-9, 1.2e-9 m) and 1e-8 rad.
    assert np.max(np.abs(tip)) < 3e-8, np.max(np.abs(tip))
    assert np.max(direction_after) < 1e-8, np.max(direction_after)
    assert np.max(np.abs(fix.residual_direction_rad)) < 1e-12


TILT_TABLE = {"name": "tilt_table", "chain": "[w A X b Y Z t]", "tool": [0.0, 0.0, 0.2],
              "workpiece": [0.0, 0.0, 0.05],
              "axes": {"X": {"stroke": [0.0, 0.5], "offset": [0.0, 0.0, 0.1]},
                       "A": {"stroke": [-1.6, 1.6], "offset": [0.0, 0.0, 0.0]},
                       "Y": {"stroke": [0.0, 0.4], "offset": [0.0, 0.0, 0.0]},
                       "Z": {"stroke": [0.0, 0.4], "offset": [0.0, 0.0, -0.3]}}}


def test_a_tilt_about_the_tilting_axis_is_taken_out_by_that_axis_closed_form():
    """Tool tilted by delta about X relative to the work on an A table: the table turns by
    +delta (turning the work by +delta turns the tool relative to it by -delta), and the
    tip moves back by the lever: J_p delta = (0, -z_w, y_w) x ... checked numerically."""
    machine = machine_from_dict(TILT_TABLE)
    model = KinematicModel(machine)
    q = {"X": np.array([0.2]), "A": np.array([0.0]), "Y": np.array([0.1]), "Z": np.array([0.2])}
    delta = 30e-6
    fix = five_axis_correction(model, q, np.zeros((1, 3)), np.array([[delta, 0.0, 0.0]]))
    assert fix.rotary_rad[0, 0] == pytest.approx(delta, rel=1e-9)
    jac_p, jac_o, axes = rotary_jacobians(model, q)
    assert axes == ("A",)
    np.testing.assert_allclose(jac_o[0, :, 0], [-1.0, 0.0, 0.0], atol=1e-9)
    # The tip's correction undoes the shift the turn causes: c = -J_p delta.
    np.testing.assert_allclose(fix.position_m[0], -jac_p[0, :, 0] * delta, atol=1e-15)
    # J_p closed form: turning the work point about the A axis line by dA moves it by
    # (0, -w_z, w_y) dA, w its position from the axis (the machining point in the A frame,
    # at A = 0: the tool (0, 0.1, 0.1) less the axis line's origin (0.2, 0, 0.1)), so the
    # tool relative to it moves by -(0, -w_z, w_y) dA.
    w = [-0.2, 0.1, 0.0]
    np.testing.assert_allclose(model.machining_point(q)[0], w, atol=1e-15)
    np.testing.assert_allclose(jac_p[0, :, 0], [0.0, w[2], -w[1]], atol=1e-9)


def test_a_direction_no_rotary_axis_can_turn_is_reported_not_forced():
    """A tilt about Y on an A-only table: no axis can take it out - it stays, reported."""
    machine = machine_from_dict(TILT_TABLE)
    model = KinematicModel(machine)
    q = {"X": np.array([0.2]), "A": np.array([0.3]), "Y": np.array([0.1]), "Z": np.array([0.2])}
    tilt = np.array([[0.0, 25e-6, 0.0]])
    fix = five_axis_correction(model, q, np.zeros((1, 3)), tilt)
    assert abs(fix.rotary_rad[0, 0]) < 1e-12
    np.testing.assert_allclose(fix.residual_direction_rad[0], [0.0, 25e-6, 0.0], atol=1e-12)
    # A rotation about the tool axis itself (a spindle's own turn) needs no correction.
    spin = five_axis_correction(model, q, np.zeros((1, 3)), np.array([[0.0, 0.0, 40e-6]]))
    assert abs(spin.rotary_rad[0, 0]) < 1e-12
    assert np.max(np.abs(spin.residual_direction_rad)) < 1e-12


def test_a_three_axis_machine_gets_minus_the_error_and_bad_input_is_refused():
    model = KinematicModel(load_machine("kidani_hmc"))
    q = {a: np.array([0.0]) for a in model.machine.axis_order}
    error = np.array([[1e-6, -2e-6, 3e-6]])
    fix = five_axis_correction(model, q, error, np.array([[1e-5, 0, 0]]))
    np.testing.assert_array_equal(fix.position_m, -error)
    assert fix.rotary_rad.shape == (1, 0)
    with pytest.raises(InputDataError, match="NaN"):
        five_axis_correction(model, q, np.array([[np.nan, 0, 0]]), np.zeros((1, 3)))
    with pytest.raises(InputDataError, match=r"\(N, 3\)"):
        five_axis_correction(model, q, np.zeros((1, 2)), np.zeros((1, 3)))
