"""The virtual five-axis machine: rotary effects against closed forms, rotary encoders."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import ScenarioError
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.sim.machine_tool import (ENCODER_NOISE_RAD, ENCODER_RESOLUTION_RAD,
                                              simulate)
from mt_accuracy_ros.sim.scenario import scenario_from_yaml

PROGRAM = ("{type: random_points, axes: [X, Y, Z, A, B], points: 8, seed: 2, dwell_s: 0.2, "
           "feed_m_per_min: 30, limits: {A: [-1.0, 1.0], B: [-0.7, 0.7]}}")


def _run(effects: str, duration: float = 12.0, extra: str = ""):
    return simulate(scenario_from_yaml(
        f"machine: khan_chen_rpppr\nseed: 4\nduration_s: {duration}\nsample_rate_hz: 500\n"
        f"program: {PROGRAM}\neffects: {effects}\n{extra}"))


def test_an_offset_rotary_axis_line_turns_the_work_about_the_real_line():
    """EY0A, EZ0A: the A axis line displaced by d (ISO 230-7). The table turns about the
    real line from where the work was set up (A = 0), so the material moves by
    (I - R_A) d: e = -(I - R_A) d, zero at A = 0 (ISO 10791-6's circle)."""
    result = _run("{geometric: false, rotary_location: {errors: {EY0A: 2.5e-5, EZ0A: -2.0e-5}}}")
    rows = np.arange(0, result.time_s.size, 97)
    angle = result.command["A"][rows]
    assert np.ptp(angle) > 1.0        # the table really turned
    d = np.array([0.0, 2.5e-5, -2.0e-5])
    turned = np.stack([np.zeros_like(angle), np.cos(angle) * d[1] - np.sin(angle) * d[2],
                       np.sin(angle) * d[1] + np.cos(angle) * d[2]], axis=1)
    np.testing.assert_allclose(result.tcp_error(rows), -(d - turned), rtol=0, atol=1e-12)
    # Where the work was set up the line's offset moves nothing.
    home = int(np.argmin(np.abs(result.command["A"])))
    near = abs(result.command["A"][home])
    assert near < 1e-4
    assert np.linalg.norm(result.tcp_error(np.array([home]))) <= near * np.linalg.norm(d) * 1.01


def test_a_rotary_positioning_error_is_an_extra_turn_of_the_axis():
    """rotary_runout with no radial part: the table stands at A + p sin(A + phi) - the
    nominal chain turned by that much moves the material under the tool by the same
    amount (a second formulation: the model's nominal chain, no error terms)."""
    result = _run("{geometric: false, rotary_runout: {axis: A, radial_m: 0.0, "
                  "positioning_rad: 2.0e-5, phase_rad: 0.4}}")
    rows = np.arange(0, result.time_s.size, 53)
    model = KinematicModel(result.scenario.machine)
    q = {a: result.command[a][rows] for a in result.scenario.machine.axis_order}
    turned = dict(q)
    turned["A"] = q["A"] + 2.0e-5 * np.sin(q["A"] + 0.4)
    under_tool = model.machining_point(q)
    expected = model.nominal_relative(turned, work_point=under_tool) \
        - model.nominal_relative(q, work_point=under_tool)
    np.testing.assert_allclose(result.tcp_error(rows), expected, atol=1e-12)
    assert np.max(np.abs(expected)) > 1e-7


def test_a_radial_error_motion_turns_with_the_axis_once_per_revolution():
    """EYA, EZA = r (cos, sin)(A + phi) in the turning frame: the work point's displacement
    has magnitude r at every angle (a circle of radius r), for the A table at any X."""
    result = _run("{geometric: false, rotary_runout: {axis: A, radial_m: 6.0e-6, "
                  "positioning_rad: 0.0}}")
    rows = np.arange(0, result.time_s.size, 41)
    error = result.tcp_error(rows)
    assert np.abs(error[:, 0]).max() < 1e-15              # nothing along the axis
    np.testing.assert_allclose(np.linalg.norm(error[:, 1:], axis=1), 6.0e-6, rtol=1e-9)


def test_rotary_encoders_read_the_commanded_angle_to_their_noise_and_resolution():
    result = _run("{}")
    assert result.encoder_axes == ["A", "B"]
    deviation = result.encoder_readings - np.column_stack([result.actual["A"],
                                                           result.actual["B"]])
    assert np.std(deviation) == pytest.approx(ENCODER_NOISE_RAD, rel=0.05)
    assert np.all(np.abs(deviation) < 6 * ENCODER_NOISE_RAD + ENCODER_RESOLUTION_RAD)
    steps = result.encoder_readings / ENCODER_RESOLUTION_RAD
    np.testing.assert_allclose(steps, np.round(steps), atol=1e-6)
    # A window of the run reads exactly what the whole run read there (live streaming).
    window = simulate(result.scenario, start_index=1500, stop_index=2500)
    np.testing.assert_array_equal(window.encoder_readings, result.encoder_readings[1500:2500])
    three_axis = simulate(scenario_from_yaml("machine: kidani_hmc\nduration_s: 1\n"))
    assert three_axis.encoder_axes == [] and three_axis.encoder_readings.shape[1] == 0


@pytest.mark.parametrize("machine, effects, message", [
    ("kidani_hmc", "{rotary_location: {}}", "has no rotary axis"),
    ("khan_chen_rpppr", "{rotary_location: {errors: {EY0X: 1.0e-5}}}",
     "'EY0X' is not a location error of a rotary axis"),
    ("khan_chen_rpppr", "{rotary_location: {errors: {EY0A: 0.5}}}", "below 0.01"),
    ("khan_chen_rpppr", "{rotary_runout: {axis: X}}", "'X' is not a rotary axis"),
])
def test_rotary_effects_on_the_wrong_machine_or_axis_are_refused(machine, effects, message):
    with pytest.raises(ScenarioError, match=message):
        scenario_from_yaml(f"machine: {machine}\neffects: {effects}\n")


def test_random_points_limits_are_checked():
    with pytest.raises(ScenarioError, match="limits A high = 4 m is outside the A stroke"):
        scenario_from_yaml("machine: khan_chen_rpppr\nprogram: {type: random_points, axes: "
                           "[X, A], limits: {A: [0, 4]}}\n")
    with pytest.raises(ScenarioError, match="low must be below high"):
        scenario_from_yaml("machine: khan_chen_rpppr\nprogram: {type: random_points, axes: "
                           "[X, A], limits: {A: [0.5, 0.1]}}\n")


def test_the_error_at_a_pose_is_the_trajectorys_error_where_the_machine_stood_there():
    """SimulationResult.error_at (where an instrument zeroed at the work offset reads 0)
    against tcp_error at samples of the run: same state, same pose."""
    result = _run("{rotary_location: {errors: {EB0A: 4.0e-5, EC0B: -2.0e-5}}, "
                  "rotary_runout: {axis: A, radial_m: 6.0e-6, positioning_rad: 1.5e-5}, "
                  "structural_thermal_drift: {time_constant_s: 5, rise_k: 3.0}}")
    for row in (0, 1500, result.time_s.size - 1):
        pose = {a: float(result.actual[a][row]) for a in result.scenario.machine.axis_order}
        at_rest_same_place = result.error_at(pose, row)
        np.testing.assert_allclose(at_rest_same_place, result.tcp_error(np.array([row]))[0]
                                   - _command_shift(result, row), atol=1e-15)
    assert np.linalg.norm(result.error_at(pose, 0) - at_rest_same_place) > 1e-7  # warmed


def _command_shift(result, row):
    """The nominal displacement of the actual pose against the command (servo lag)."""
    model = KinematicModel(result.scenario.machine)
    axes = result.scenario.machine.axis_order
    actual = {a: result.actual[a][[row]] for a in axes}
    command = {a: result.command[a][[row]] for a in axes}
    return (model.nominal_relative(actual) - model.nominal_relative(command))[0]


@pytest.mark.parametrize("offset, message", [
    ("{X: 0.3, Y: 0.2, Z: 0.2, A: 0.0}", "give every axis"),
    ("{X: 0.3, Y: 0.2, Z: 0.2, A: 30.0, B: 0.0}", "outside the stroke"),
])
def test_a_bad_work_offset_is_named_with_its_line(offset, message):
    with pytest.raises(ScenarioError, match=message) as caught:
        scenario_from_yaml(f"machine: khan_chen_rpppr\nseed: 1\nwork_offset: {offset}\n")
    assert "line 3" in str(caught.value)
