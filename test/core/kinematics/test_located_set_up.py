"""What an instrument located at the set-up reads of a rotary axis' location errors.

A sphere is located at the set-up pose by a translation of the workpiece frame (a sphere
has no orientation to find), a head's tool by a translation of the tool frame; each body
turns about its actual line by its command (ISO 230-7, ISO 10791-6).
:meth:`KinematicModel.located_sensitivities` is checked against rigid-body code written
out here (exact rotations about the actual lines, the set-up's translation taken at the
set-up pose), and against closed forms: the last axis' offset moves the work by
(I - R(q - q_s)) d, a tilt of it by the tilt times the radius from the set-up angle.
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import (load_machine, machine_from_dict,
                                                     with_setup_pose)

N = 30
SPHERE = np.array([0.05, -0.03, 0.04])     # on the work table, workpiece frame [m]
SMALL = 1e-7                               # an error small enough to be first order


def _rotation(axis: int, angle: float) -> np.ndarray:
    c, s = np.cos(angle), np.sin(angle)
    i, j = [(1, 2), (2, 0), (0, 1)][axis]
    out = np.eye(3)
    out[i, i], out[i, j], out[j, i], out[j, j] = c, -s, s, c
    return out


def _rodrigues(vector: np.ndarray) -> np.ndarray:
    angle = float(np.linalg.norm(vector))
    if angle == 0.0:
        return np.eye(3)
    k = vector / angle
    skew = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew


def _end(machine, branch: str, q: dict, error: tuple[str, float] | None):
    """(rotation, origin) of a branch's end frame, bed frame: each rotary body turned about
    its actual line (offset c, direction Rod(tilt) e_k) by its command."""
    axes = machine.tool_branch if branch == "tool" else machine.workpiece_branch
    rot, pos, mount = np.eye(3), np.zeros(3), np.zeros(3)
    for axis in axes:
        spec = machine.axes[axis]
        pos = pos + rot @ mount
        k = spec.direction
        if spec.is_rotary:
            offset, tilt = np.zeros(3), np.zeros(3)
            if error is not None and error[0][3] == axis:
                c = "XYZABC".index(error[0][1])
                (offset if c < 3 else tilt)[c % 3] = error[1]
            line = _rodrigues(tilt) @ np.eye(3)[k]
            turn = _rodrigues(line * spec.sign * q[axis])
            # x -> c + R (x - c) in this joint's frame
            pos = pos + rot @ (offset - turn @ offset)
            rot = rot @ turn
        else:
            pos = pos + rot[:, k] * spec.sign * q[axis]
        mount = np.asarray(spec.offset, float)
    return rot, pos + rot @ mount


def _located_truth(machine, q: dict, setup: dict, error: tuple[str, float]):
    """The located instrument's reading of one location error: (tool - target) actual
    minus nominal, each side's error at the set-up taken out in its own frame."""
    head = any(machine.axes[a].is_rotary for a in machine.tool_branch)

    def sides(command, err):
        tool_r, tool_o = _end(machine, "tool", command, err)
        work_r, work_o = _end(machine, "workpiece", command, err)
        tip = tool_o + tool_r @ np.asarray(machine.tool, float)
        return tip, work_o + work_r @ (machine.workpiece + SPHERE), tool_r, work_r

    def moved(command):
        tip, target, tool_r, work_r = sides(command, error)
        tip0, target0, tool_r0, work_r0 = sides(command, None)
        u0 = tool_r0 @ np.asarray(machine.tool, float) / np.linalg.norm(machine.tool)
        du = work_r0 @ work_r.T @ tool_r @ np.linalg.inv(tool_r0) @ u0 - u0
        return tip - tip0, target - target0, du, tool_r0, work_r0

    tip_s, target_s, du_s, tool_rs, work_rs = moved(setup)
    tip, target, du, tool_r, work_r = moved(q)
    if head:        # the tool located in its frame, the target in the work's
        tip = tip - tool_r @ tool_rs.T @ tip_s
        target = target - work_r @ work_rs.T @ target_s
        du = du - tool_r @ tool_rs.T @ du_s if error[0][3] in machine.tool_branch else \
            du - work_r @ work_rs.T @ du_s
        return tip - target, du
    located = work_r @ work_rs.T
    return (tip - target) - located @ (tip_s - target_s), du - located @ du_s


def _poses(machine, rng, **fixed):
    q = {a: rng.uniform(*machine.axes[a].stroke, N) for a in machine.axis_order}
    q.update({a: np.full(N, float(v)) for a, v in fixed.items()})
    return q


def _compare(machine, q, names):
    model = KinematicModel(machine)
    found = model.located_sensitivities(q, names, work_point=machine.workpiece + SPHERE)
    axis = model.tool_axis(q)
    setup = {a: machine.setup_angle(a) if machine.axes[a].is_rotary else 0.0
             for a in machine.axis_order}
    for name in names:
        position, turn = found[name]
        for i in range(N):
            row = {a: float(v[i]) for a, v in q.items()}
            here = dict(setup, **{a: row[a] for a in machine.axis_order
                                  if not machine.axes[a].is_rotary})
            truth, du = _located_truth(machine, row, here, (name, SMALL))
            np.testing.assert_allclose(position[i] * SMALL, truth, rtol=0, atol=1e-13,
                                       err_msg=name)
            # What an instrument sees of the direction: its change across the tool axis.
            across = du - axis[i] * (axis[i] @ du)
            np.testing.assert_allclose(np.cross(turn[i], axis[i]) * SMALL, across, rtol=0,
                                       atol=1e-13, err_msg=name)


def _trunnion_bc():
    return machine_from_dict({
        "name": "bc", "chain": "[w C B X Y b Z t]", "tool": [0, 0, -0.12],
        "workpiece": [0.02, -0.01, 0.0],
        "axes": {"Y": {"stroke": [-0.3, 0.3], "offset": [0, 0, 0.1]},
                 "X": {"stroke": [-0.3, 0.3], "offset": [0, 0, 0.25], "sign": -1},
                 "B": {"stroke": [-2.0, 2.0], "offset": [0.01, 0, -0.08]},
                 "C": {"stroke": [-3.2, 3.2], "offset": [0, 0, 0]},
                 "Z": {"stroke": [-0.1, 0.6], "offset": [0, 0, 0.6]}}})


def test_an_outer_axis_read_from_a_set_up_at_a_rotary_pose_is_the_rigid_bodies():
    """B carries C, the sphere located at B = 30, C = 45 deg: B's tilt and offset turn the
    C table, whose later turns carry what the set-up located (not the per-axis form)."""
    machine = with_setup_pose(_trunnion_bc(), {"B": np.radians(30), "C": np.radians(45)})
    q = _poses(machine, np.random.default_rng(11))
    _compare(machine, q, ["EX0B", "EZ0B", "EA0B", "EC0B", "EX0C", "EY0C", "EA0C", "EB0C"])
    # Not the per-axis reference: with C turning, B's tilt reads otherwise there.
    model = KinematicModel(machine)
    located = model.located_sensitivities(q, ["EA0B"], work_point=SPHERE)["EA0B"][0]
    sign, rotation, lever = model.error_frames(q, work_point=SPHERE)["EA0B"]
    per_axis = sign * np.cross(rotation[:, :, 0], lever)
    assert np.abs(located - per_axis).max() > 0.005      # m per rad: 5 um at 1 mrad


def test_a_head_is_read_with_its_tool_located_in_its_own_frame():
    head = machine_from_dict({
        "name": "head", "chain": "[w X Y b Z C B t]", "tool": [0, 0, -0.15],
        "workpiece": [0, 0, 0],
        "axes": {"Y": {"stroke": [-0.3, 0.3], "offset": [0, 0, 0.05], "sign": -1},
                 "X": {"stroke": [-0.3, 0.3], "offset": [0, 0, 0.05], "sign": -1},
                 "Z": {"stroke": [-0.2, 0.5], "offset": [0, 0, 0.7]},
                 "C": {"stroke": [-3.2, 3.2], "offset": [0, 0, -0.2]},
                 "B": {"stroke": [-2.0, 2.0], "offset": [0, 0, -0.1]}}})
    head = with_setup_pose(head, {"C": np.radians(90), "B": np.radians(-30)})
    q = _poses(head, np.random.default_rng(12))
    _compare(head, q, ["EX0C", "EY0C", "EA0C", "EB0C", "EX0B", "EZ0B", "EA0B", "EC0B"])


@pytest.mark.parametrize("setup_c", [0.0, np.radians(45.0)])
def test_the_last_axis_reads_as_its_closed_forms(setup_c):
    machine = with_setup_pose(load_machine("trunnion_ac"), {"C": setup_c})
    model = KinematicModel(machine)
    q = _poses(machine, np.random.default_rng(13), A=0.0)
    radius, phase = 0.08, 0.6
    point = np.array([radius * np.cos(phase), radius * np.sin(phase), 0.0])
    found = model.located_sensitivities(q, ["EX0C", "EY0C", "EA0C"], work_point=point)
    d = np.array([20e-6, -12e-6, 0.0])
    offset = d[0] * found["EX0C"][0] + d[1] * found["EY0C"][0]
    turn = np.stack([np.array([[np.cos(a), -np.sin(a), 0], [np.sin(a), np.cos(a), 0],
                               [0, 0, 1]]) for a in q["C"] - setup_c])
    # An offset C line: the work moves by (I - R_C(q - q_s)) d, the tool sees minus that.
    np.testing.assert_allclose(offset, -(d - turn @ d), rtol=0, atol=1e-18)
    # A tilt about x: a point of the table rises by tilt * r (sin(phase + C) -
    # sin(phase + C_s)) against where it was set up.
    lift = radius * (np.sin(phase + q["C"]) - np.sin(phase + setup_c))
    np.testing.assert_allclose(found["EA0C"][0][:, 2], -lift, rtol=0, atol=1e-15)
    np.testing.assert_allclose(found["EA0C"][0][:, :2], 0.0, atol=1e-15)


def test_at_a_set_up_where_nothing_moves_the_lines_the_chain_reads_the_same():
    """Every bundled set-up is at 0: there the located reading is the chain's own."""
    machine = load_machine("trunnion_ac")
    model = KinematicModel(machine)
    q = _poses(machine, np.random.default_rng(14))
    names = ["EY0A", "EZ0A", "EB0A", "EC0A", "EX0C", "EY0C", "EA0C", "EB0C"]
    found = model.located_sensitivities(q, names, work_point=SPHERE)
    frames = model.error_frames(q, work_point=SPHERE)
    for name in names:
        sign, rotation, lever = frames[name]
        c = "XYZABC".index(name[1])
        expected = sign * (rotation[:, :, c] if c < 3 else
                           np.cross(rotation[:, :, c - 3], lever))
        np.testing.assert_allclose(found[name][0], expected, rtol=0, atol=1e-15)
        turn = np.zeros_like(expected) if c < 3 else sign * rotation[:, :, c - 3]
        np.testing.assert_allclose(found[name][1], turn, rtol=0, atol=1e-15)
