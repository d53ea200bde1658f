"""Rotary axes turn about their real lines from the set-up pose (ISO 230-7): closed forms.

The trunnion VMC (``[w C A X Y b Z t]``) and the generic Cartesian machine a survey's
``work_axes`` builds, against formulas written out here: an offset C line moves the work
by (I - R_C) d, a tilted line by the tilt times the radius, the A pivot's offset reaches
everything the cradle carries, a zero error is taken out by the set-up, a table's pitch
with a constant part acts through the spindle's height. Each is checked on the exact
chain, the first-order twist sum and the error frames the workbench's designs use.
"""
from __future__ import annotations

from dataclasses import replace

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import MachineDescriptionError
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import (generic_cartesian, load_machine,
                                                     machine_from_dict, with_setup_pose)

N = 40
SPHERE = np.array([0.06, -0.04, 0.03])      # a fixed target on the C table [m]


def _rz(angle):
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((np.size(angle), 3, 3))
    out[:, 0, 0], out[:, 0, 1], out[:, 1, 0], out[:, 1, 1], out[:, 2, 2] = c, -s, s, c, 1.0
    return out


def _rx(angle):
    c, s = np.cos(angle), np.sin(angle)
    out = np.zeros((np.size(angle), 3, 3))
    out[:, 0, 0], out[:, 1, 1], out[:, 1, 2], out[:, 2, 1], out[:, 2, 2] = 1.0, c, -s, s, c
    return out


def _poses(machine, rng, **fixed):
    q = {a: rng.uniform(*machine.axes[a].stroke, N) for a in machine.axis_order}
    q.update({a: np.full(N, float(v)) for a, v in fixed.items()})
    return q


def _three_ways(model, q, location=None, motion=None, work_point=SPHERE):
    """Exact chain, first-order twist sum and error frames: (exact, linear, frames)."""
    overrides = ErrorOverrides(location=dict(location or {}), motion=dict(motion or {}),
                               use_description=False)
    exact = model.tcp_error(q, overrides=overrides, check_stroke=False,
                            work_point=work_point)["position"]
    linear = model.tcp_error_linear(q, overrides=overrides, check_stroke=False,
                                    work_point=work_point)["position"]
    frames = model.error_frames(q, work_point=work_point)
    summed = np.zeros_like(linear)
    for name, value in (location or {}).items():
        sign, rotation, lever = frames[name]
        c = "XYZABC".index(name[1])
        summed += value * sign * (rotation[:, :, c] if c < 3 else
                                  np.cross(rotation[:, :, c - 3], lever))
    return exact, linear, summed


@pytest.mark.parametrize("setup_c", [0.0, np.radians(45.0)])
def test_an_offset_c_line_moves_the_work_by_i_minus_r_d(setup_c):
    machine = with_setup_pose(load_machine("trunnion_ac"), {"C": setup_c})
    model = KinematicModel(machine)
    q = _poses(machine, np.random.default_rng(1), A=0.0)
    d = np.array([20e-6, -12e-6, 0.0])
    exact, linear, frames = _three_ways(model, q, {"EX0C": d[0], "EY0C": d[1]})
    # The work turns about the real line: the sphere moves by (I - R_C(q - q_s)) d, so the
    # tool relative to it is off by minus that; zero where the work was set up.
    expected = -(d - np.einsum("nij,j->ni", _rz(q["C"] - setup_c), d))
    for got in (exact, linear, frames):
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)
    at_setup = _three_ways(model, dict(q, C=np.full(N, setup_c)), {"EX0C": d[0],
                                                                   "EY0C": d[1]})[0]
    np.testing.assert_allclose(at_setup, 0.0, atol=1e-18)


def test_a_tilted_c_line_moves_a_point_by_the_tilt_times_its_radius():
    machine = load_machine("trunnion_ac")
    model = KinematicModel(machine)
    q = _poses(machine, np.random.default_rng(2), A=0.0)
    tilt, radius, phase = 30e-6, 0.08, 0.6
    point = np.array([radius * np.cos(phase), radius * np.sin(phase), 0.0])
    exact, linear, frames = _three_ways(model, q, {"EA0C": tilt}, work_point=point)
    # A tilt about x lifts a point of the table by tilt * r (sin(phase + C) - sin(phase)):
    # the tool sees it with the opposite sign; across the table, second order only
    # (tilt^2 x the arms: below 1e-9 m).
    lift = tilt * radius * (np.sin(phase + q["C"]) - np.sin(phase))
    np.testing.assert_allclose(linear[:, 2], -lift, rtol=0, atol=1e-18)
    np.testing.assert_allclose(linear[:, :2], 0.0, atol=1e-18)
    np.testing.assert_allclose(linear, frames, rtol=0, atol=1e-18)
    np.testing.assert_allclose(exact, linear, rtol=0, atol=1e-9)


def test_the_a_pivot_offset_moves_everything_the_cradle_carries():
    machine = load_machine("trunnion_ac")
    model = KinematicModel(machine)
    q = _poses(machine, np.random.default_rng(3))
    d = np.array([0.0, 15e-6, -25e-6])
    exact, linear, frames = _three_ways(model, q, {"EY0A": d[1], "EZ0A": d[2]})
    # A's frame has the tables' orientation (X and Y only translate): the cradle, the C
    # table and the sphere move by (I - R_A) d whatever C does.
    expected = -(d - np.einsum("nij,j->ni", _rx(q["A"]), d))
    for got in (exact, linear, frames):
        np.testing.assert_allclose(got, expected, rtol=0, atol=1e-15)


def test_a_zero_error_and_an_offset_along_the_line_are_taken_out_by_the_set_up():
    machine = with_setup_pose(load_machine("trunnion_ac"), {"A": np.radians(-30.0)})
    model = KinematicModel(machine)
    q = _poses(machine, np.random.default_rng(4))
    for name in ("EC0C", "EZ0C", "EA0A", "EX0A"):
        exact, linear, frames = _three_ways(model, q, {name: 40e-6})
        for got in (exact, linear, frames):
            np.testing.assert_allclose(got, 0.0, atol=1e-16)
    # Not vacuous: the same size across the line moves the work by tens of um.
    assert np.abs(_three_ways(model, q, {"EY0A": 40e-6})[0]).max() > 30e-6


def test_the_simulated_and_the_described_set_up_pose_are_the_same_thing():
    text = load_machine("trunnion_ac")
    described = machine_from_dict({
        "name": "t", "chain": "[w C A X Y b Z t]", "tool": [0, 0, -0.15],
        "workpiece": [0, 0, 0],
        "setup_pose": {"A": {"value": -90, "unit": "deg"}, "C": {"value": 45, "unit": "deg"}},
        "axes": {a: {"stroke": list(text.axes[a].stroke), "offset": list(text.axes[a].offset),
                     "sign": text.axes[a].sign} for a in text.axis_order}})
    assert described.setup_pose == pytest.approx({"A": -np.pi / 2, "C": np.pi / 4})
    via_survey = with_setup_pose(text, {"A": -np.pi / 2, "C": np.pi / 4})
    q = _poses(text, np.random.default_rng(5))
    location = {"EX0C": 10e-6, "EB0A": 20e-6, "EZ0A": -8e-6}
    np.testing.assert_allclose(_three_ways(KinematicModel(described), q, location)[0],
                               _three_ways(KinematicModel(via_survey), q, location)[0],
                               rtol=0, atol=1e-18)


@pytest.mark.parametrize("spec, words", [
    ({"stroke": [-110, 30]}, "degrees? write {value: [-110, 30], unit: deg}"),
    ({"stroke": {"value": [-110, 30], "unit": "gon"}}, "unit 'gon' is not one of"),
])
def test_a_rotary_stroke_in_degrees_without_its_unit_is_refused(spec, words):
    with pytest.raises(MachineDescriptionError, match=words.replace("?", r"\?")
                       .replace("[", r"\[").replace("{", r"\{")):
        machine_from_dict({"name": "t", "chain": "[w A b Z t]", "tool": [0, 0, 0.1],
                           "workpiece": [0, 0, 0],
                           "axes": {"A": {**spec, "offset": [0, 0, 0]},
                                    "Z": {"stroke": [0, 0.3], "offset": [0, 0, 0]}}})


def test_a_set_up_angle_needs_its_unit_and_a_rotary_axis():
    base = {"name": "t", "chain": "[w A b Z t]", "tool": [0, 0, 0.1], "workpiece": [0, 0, 0],
            "axes": {"A": {"stroke": [-2, 2], "offset": [0, 0, 0]},
                     "Z": {"stroke": [0, 0.3], "offset": [0, 0, 0]}}}
    with pytest.raises(MachineDescriptionError, match="give the angle with its unit"):
        machine_from_dict({**base, "setup_pose": {"A": 30}})
    with pytest.raises(MachineDescriptionError, match="not a rotary axis"):
        machine_from_dict({**base, "setup_pose": {"Z": {"value": 1, "unit": "deg"}}})
    with pytest.raises(MachineDescriptionError, match="outside the stroke"):
        machine_from_dict({**base, "setup_pose": {"A": {"value": 180, "unit": "deg"}}})


def test_a_table_pitch_with_a_constant_part_acts_through_the_spindles_height():
    """The generic machine a survey's ``work_axes`` build: the tables move against the
    command (a CNC's coordinates), so a pitch eps(x) = c0 + c1 x of the X table turns the
    part under a tool h above the table's reference: e_x = -eps (z + h), e_z = eps x."""
    h = 0.1
    machine = generic_cartesian({"X": (-0.3, 0.3), "Y": (-0.2, 0.2), "Z": (-0.4, 0.0)},
                                tool_length_m=h, work_axes=("Y", "X"))
    assert [machine.axes[a].sign for a in "XYZ"] == [-1.0, -1.0, 1.0]
    model = KinematicModel(machine)
    q = _poses(machine, np.random.default_rng(6))
    c0, c1 = 20e-6, 60e-6
    pitch = c0 + c1 * q["X"]
    overrides = ErrorOverrides(motion={"EBX": pitch}, use_description=False)
    linear = model.tcp_error_linear(q, overrides=overrides, check_stroke=False)["position"]
    np.testing.assert_allclose(linear[:, 0], -pitch * (q["Z"] + h), rtol=0, atol=1e-15)
    np.testing.assert_allclose(linear[:, 2], pitch * q["X"], rtol=0, atol=1e-15)
    exact = model.tcp_error(q, overrides=overrides, check_stroke=False)["position"]
    # Second order: tilts of up to 40 urad squared times arms of up to 0.5 m.
    np.testing.assert_allclose(exact, linear, rtol=0, atol=1e-9)
    # With z = 0 the constant part alone moves the tip by c0 h: the spindle's height.
    flat = dict(q, Z=np.zeros(N), X=np.zeros(N))
    at_zero = model.tcp_error_linear(flat, overrides=ErrorOverrides(
        motion={"EBX": np.full(N, c0)}, use_description=False), check_stroke=False)
    np.testing.assert_allclose(at_zero["position"][:, 0], -c0 * h, rtol=0, atol=1e-18)


def test_a_bundled_table_machine_and_the_work_axes_machine_agree():
    """The bundled vmc (tables sign -1) and the generic machine of ``work_axes: [Y, X]``
    put a table tilt through the same arm, up to what the bundled offsets add: a
    constant and terms of the tilted axis' own position."""
    vmc = load_machine("vmc")
    generic = generic_cartesian({a: vmc.axes[a].stroke for a in "XYZ"},
                                tool_length_m=0.0, work_axes=("Y", "X"))
    q = _poses(vmc, np.random.default_rng(7))
    tilt = {"EAY": 30e-6 * q["Y"] / 0.2}
    one = KinematicModel(vmc).tcp_error_linear(
        q, overrides=ErrorOverrides(motion=tilt, use_description=False), check_stroke=False)
    two = KinematicModel(generic).tcp_error_linear(
        q, overrides=ErrorOverrides(motion=tilt, use_description=False), check_stroke=False)
    difference = one["position"] - two["position"]
    # What the generic machine cannot know (the arms of the offsets) depends on Y alone.
    for c in range(3):
        fit = np.polyfit(q["Y"], difference[:, c], 2)
        np.testing.assert_allclose(np.polyval(fit, q["Y"]), difference[:, c], atol=1e-15)
    assert replace(vmc).axes["X"].sign == -1.0
