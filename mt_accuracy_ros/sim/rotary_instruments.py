"""Instruments on a rotary axis of the virtual machine: a ball bar and a touch probe.

Both are written from the geometry up, sharing no code with the estimators
they feed (:mod:`..core.rotary`), so an error in an estimator's model cannot
cancel out in its own test data:

* the table's error motion is an exact rotation about the tilt vector
  (Rodrigues' formula) followed by the radial/axial shift - not the estimator's
  X-Y-Z Euler product or Zhu's first-order matrix;
* a rotary axis's location error is the axis line itself, moved and tilted:
  points rotate about that line (Rodrigues again), not through an HTM chain.

Ball bar (Zhu ch. 5 procedure): the table indexes 0-360 deg in 10 deg steps
(37 positions) for each of two bars, three repetitions each; the first
position of every repetition is reached after the table came back from the
previous run, i.e. from the other direction: the drive's lost motion and the
tilt the worm's reversed contact force gives the table (``reversal_*``) act
there only. Noise is the bar's transducer noise (white, per reading).

Touch probe (the KinematicsOpt job): a calibration sphere on the table,
probed at several rotary positions with touch points on its surface.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import NDArray

from .rigid_body import BodyErrors, body_pose, tool_against_work


def _rodrigues(vector: NDArray) -> NDArray:
    """Rotation matrix of the rotation vector ``vector`` (axis * angle), exact."""
    angle = float(np.linalg.norm(vector))
    if angle == 0.0:
        return np.eye(3)
    k = np.asarray(vector, float) / angle
    skew = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * skew + (1 - np.cos(angle)) * skew @ skew


def _about_z(angle: float) -> NDArray:
    c, s = np.cos(angle), np.sin(angle)
    return np.array([[c, -s, 0.0], [s, c, 0.0], [0.0, 0.0, 1.0]])


@dataclass
class RotaryTableTruth:
    """The table's true errors (constant over the turn, as Zhu assumes) [m, rad]."""

    radial_m: tuple[float, float] = (0.0, 0.0)       # D_x, D_y
    axial_m: float = 0.0                             # D_z
    tilt_rad: tuple[float, float] = (0.0, 0.0)       # E_x, E_y
    positioning_rad: float = 0.0                     # E_z
    reversal_lost_motion_rad: float = 0.0
    reversal_tilt_rad: tuple[float, float] = (0.0, 0.0)
    #: ISO 230-7 location errors: the line the table really turns about passes through
    #: (EX0C, EY0C) and is tilted by (EA0C, EB0C); the ball is set on the table at c = 0.
    line_offset_m: tuple[float, float] = (0.0, 0.0)
    line_tilt_rad: tuple[float, float] = (0.0, 0.0)


@dataclass
class BallBarPlan:
    """Zhu's experiment (section 5.4) by default."""

    short_bar_m: float = 0.090850
    long_bar_m: float = 0.217952
    radius_m: float = 0.071842
    socket_height_m: float = 0.0
    angles_deg: NDArray = field(default_factory=lambda: np.arange(0.0, 361.0, 10.0))
    repetitions: int = 3
    eccentricity_m: tuple[float, float] = (40e-6, -65e-6)     # H_x, H_y of the short setup
    #: How much the spindle ball's eccentricity changes when it moves up for the long bar.
    eccentricity_change_m: tuple[float, float] = (0.0, 0.0)
    noise_m: float = 0.1e-6


@dataclass
class BallBarData:
    """Readings [m] per bar: (repetitions, positions); angles [deg] as indexed."""

    angles_deg: NDArray
    short: NDArray
    long: NDArray
    plan: BallBarPlan


def _bar_reading(angle: float, plan: BallBarPlan, truth: RotaryTableTruth, bar_m: float,
                 eccentricity: tuple[float, float], reversed_approach: bool) -> float:
    lost = truth.reversal_lost_motion_rad if reversed_approach else 0.0
    tilt = np.array([truth.tilt_rad[0], truth.tilt_rad[1], truth.positioning_rad])
    if reversed_approach:
        tilt[:2] += truth.reversal_tilt_rad
    ball_at_setup = np.array([plan.radius_m, 0.0, plan.socket_height_m])
    # The turn about the actual line: through the offset point, along the tilted z.
    through = np.array([truth.line_offset_m[0], truth.line_offset_m[1], 0.0])
    direction = _rodrigues(np.array([*truth.line_tilt_rad, 0.0])) @ np.array([0.0, 0.0, 1.0])
    turned = through + _rodrigues(direction * (angle - lost)) @ (ball_at_setup - through)
    # Then Zhu's error motions, constant in the machine's frame (Zhu Fig. 5.1).
    table_ball = (_rodrigues(tilt) @ turned
                  + np.array([truth.radial_m[0], truth.radial_m[1], truth.axial_m]))
    height = plan.socket_height_m + np.sqrt(bar_m ** 2 - plan.radius_m ** 2)
    spindle_ball = np.array([eccentricity[0], eccentricity[1], height])
    return float(np.linalg.norm(table_ball - spindle_ball) - bar_m)


def ballbar_test(truth: RotaryTableTruth, plan: BallBarPlan | None = None, *,
                 seed: int = 0) -> BallBarData:
    """Both setups of Zhu's two-bar test on the virtual rotary table."""
    plan = plan or BallBarPlan()
    rng = np.random.default_rng(seed)
    angles = np.radians(np.asarray(plan.angles_deg, float))
    out = {}
    for which, bar, ecc in (("short", plan.short_bar_m, plan.eccentricity_m),
                            ("long", plan.long_bar_m,
                             (plan.eccentricity_m[0] + plan.eccentricity_change_m[0],
                              plan.eccentricity_m[1] + plan.eccentricity_change_m[1]))):
        readings = np.empty((plan.repetitions, angles.size))
        for r in range(plan.repetitions):
            for i, angle in enumerate(angles):
                readings[r, i] = _bar_reading(angle, plan, truth, bar, ecc,
                                              reversed_approach=i == 0)
        out[which] = readings + rng.normal(0.0, plan.noise_m, readings.shape)
    return BallBarData(np.asarray(plan.angles_deg, float), out["short"], out["long"], plan)


# ----------------------------------------------------------------- touch probe
@dataclass
class ProbingPlan:
    """A KinematicsOpt-style cycle plan for a machine with rotary axes.

    ``rotary_positions_deg``: axis -> the positions each rotary axis is probed at
    (the others at 0); ``linear_m``: where the linear axes stand; the sphere sits at
    ``sphere_m`` in the workpiece-end frame, really at ``sphere_m + sphere_offset_m``.
    """

    rotary_positions_deg: dict[str, list[float]]
    linear_m: dict[str, float]
    sphere_m: tuple[float, float, float] = (0.05, 0.08, 0.06)
    sphere_offset_m: tuple[float, float, float] = (3e-4, -2e-4, 1e-4)
    sphere_radius_m: float = 0.0125
    touches: int = 9
    noise_m: float = 0.3e-6
    repeats: int = 1


def probe_sphere(machine, plan: ProbingPlan, location_errors: dict[str, float], *,
                 seed: int = 0) -> dict:
    """Touch points of each cycle relative to where the CNC expects the sphere's centre.

    The machine's true geometry is ``machine`` with ``location_errors`` (the virtual
    machine's own kinematic chain); returns ``positions`` (axis -> (N,)),
    ``touch_points_m`` (N, touches, 3) and the truth.
    """
    rng = np.random.default_rng(seed)
    rows = []
    for axis, angles in plan.rotary_positions_deg.items():
        for angle in angles:
            q = {a: plan.linear_m.get(a, 0.0) for a in machine.axis_order}
            q[axis] = np.radians(angle)
            rows.append(q)
    rows = rows * plan.repeats
    positions = {a: np.array([r[a] for r in rows], float) for a in machine.axis_order}
    sphere = np.asarray(plan.sphere_m, float)
    # The sphere is a fixed target: the truth compares the probe's place with the
    # sphere's real place, from the simulator's own rigid bodies.
    n = positions[machine.axis_order[0]].size
    errors = BodyErrors()
    for name, value in location_errors.items():
        errors.add("location", name[-1], "XYZABC".index(name[1]), float(value), n)
    real_sphere = sphere + np.asarray(plan.sphere_offset_m, float)
    truth, _ = tool_against_work(machine, positions, positions, errors, work_point=real_sphere)
    # ... against the centre the CNC expects (the sphere where the plan puts it)
    error = truth + (_relative(machine, positions, real_sphere)
                     - _relative(machine, positions, sphere))
    centres = -error                                   # where the probe finds the centre
    n = centres.shape[0]
    directions = rng.normal(size=(n, plan.touches, 3))
    directions[..., 2] = np.abs(directions[..., 2])    # the upper half the probe can reach
    directions /= np.linalg.norm(directions, axis=2, keepdims=True)
    points = centres[:, None, :] + plan.sphere_radius_m * directions \
        + rng.normal(0.0, plan.noise_m, (n, plan.touches, 3))
    return {"positions": positions, "touch_points_m": points, "centres_m": centres}


def _relative(machine, positions, point) -> NDArray:
    """(N, 3) nominal tool point minus a workpiece point (workpiece frame), bed frame."""
    tool = body_pose(machine, "tool", positions).point(np.asarray(machine.tool, float))
    return tool - body_pose(machine, "workpiece", positions).point(point)


# ------------------------------------------------------------- from a scenario
def location_errors_of(scenario) -> dict[str, float]:
    """The rotary axes' true location errors of a scenario's virtual machine [m, rad]
    (its ``rotary_location`` effect; empty when that is off)."""
    if not scenario.ever_enabled("rotary_location"):
        return {}
    return {str(k): float(v) for k, v in scenario.parameters("rotary_location")["errors"].items()}


def table_truth(scenario, axis: str) -> RotaryTableTruth:
    """The ball bar's view of rotary ``axis`` of a scenario's machine, in Zhu's table frame.

    Zhu's table turns about its own z; for an axis turning about machine
    direction d the table frame is (d+1, d+2, d) cyclically (A: Y, Z, X). The
    location errors of the axis line map to Zhu's radial (D_x, D_y), axial (D_z)
    and tilt (E_x, E_y) errors; its zero-angle error to the positioning E_z.
    """
    machine = scenario.machine
    if axis not in machine.axes or not machine.axes[axis].is_rotary:
        raise ValueError(f"{axis!r} is not a rotary axis of {machine.name}")
    errors = location_errors_of(scenario)
    along = "ABC".index(axis)
    local_x, local_y = (along + 1) % 3, (along + 2) % 3

    def value(component: str) -> float:
        return errors.get(f"E{component}0{axis}", 0.0)

    return RotaryTableTruth(
        radial_m=(value("XYZ"[local_x]), value("XYZ"[local_y])), axial_m=value("XYZ"[along]),
        tilt_rad=(value("ABC"[local_x]), value("ABC"[local_y])),
        positioning_rad=value(axis))
