"""R-test surveys of a five-axis RPPPR machine, generated without the package.

Issue 30 (item 4) asks the workbench to name a five-axis machine's rotary tilts and
zero-angle errors from the tool's direction as well as its tip. The data it is judged
on come from here: this module shares **no code** with ``mt_accuracy_ros`` (not its
chain, its machine files, its simulator or its effect bases). The machine is Khan &
Chen's RPPPR grinder written out below with exact rotations (Rodrigues' formula):

* workpiece branch from the bed: the X slide, the A axis (about x) 0.25 m above it,
  the R-test's sphere nest at ``workpiece_m`` in the A table's frame;
* tool branch from the bed: the Y and Z slides, the B axis (about y) 0.3 m below the
  ram, the sphere on the tool ``tool_m`` from the B axis.

Errors: each rotary axis' centre line tilted (the body turns about the tilted line,
ISO 230-7: a tilt about the axis' own direction is its zero error, taken out by the
set-up at A = B = 0); the A
table runs eccentric (a radial shift in the turning table's frame, once per
revolution) with a once-per-revolution angular positioning error; and a shift of the
nest on the table (set-up). An R-test zeroed at the work offset reads the sphere's
displacement from where it was there, and the tool's direction absolutely (its nest
aligned to the table), across the tool axis only.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

#: The machine's nominal geometry [m] (Khan & Chen's layout; sizes illustrative).
A_ABOVE_X_M = 0.25
B_BELOW_Z_M = 0.3
STROKES = {"X": (0.0, 0.6), "Y": (0.0, 0.4), "Z": (0.0, 0.4), "A": (-0.8, 0.8),
           "B": (-0.6, 0.6)}


def rotation(vector) -> np.ndarray:
    """Exact rotation matrix of a rotation vector (Rodrigues)."""
    vector = np.asarray(vector, dtype=float)
    angle = float(np.linalg.norm(vector))
    if angle == 0.0:
        return np.eye(3)
    k = vector / angle
    cross = np.array([[0, -k[2], k[1]], [k[2], 0, -k[0]], [-k[1], k[0], 0]])
    return np.eye(3) + np.sin(angle) * cross + (1 - np.cos(angle)) * cross @ cross


def rotation_vector(matrix) -> np.ndarray:
    """The rotation vector of a rotation matrix (small and large angles below pi)."""
    angle = np.arccos(np.clip((np.trace(matrix) - 1.0) / 2.0, -1.0, 1.0))
    axis = np.array([matrix[2, 1] - matrix[1, 2], matrix[0, 2] - matrix[2, 0],
                     matrix[1, 0] - matrix[0, 1]])
    if angle < 1e-12:
        return axis / 2.0
    return axis * angle / (2.0 * np.sin(angle))


@dataclass
class FiveAxisErrors:
    """What is wrong with the machine (SI: m, rad).

    ``a_tilt``/``b_tilt``: rotation of the axis' frame before it turns (about x, y, z
    in the bed frame: the component along the axis is its zero error);
    ``a_radial_m``/``a_phase_rad``: eccentric A bearing, in the table's frame;
    ``a_positioning_rad``: once-per-revolution angular positioning error of A;
    ``nest_shift_m``: the sphere nest's set-up shift on the A table.
    """

    a_tilt: tuple = (0.0, 0.0, 0.0)
    b_tilt: tuple = (0.0, 0.0, 0.0)
    a_radial_m: float = 0.0
    a_phase_rad: float = 0.0
    a_positioning_rad: float = 0.0
    nest_shift_m: tuple = (0.0, 0.0, 0.0)


@dataclass
class Geometry:
    workpiece_m: tuple = (0.05, 0.0, 0.02)
    tool_m: tuple = (0.0, 0.0, 0.1)


def tool_pose(x, y, z, a, b, errors: FiveAxisErrors, geometry: Geometry
              ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(tool point, tool rotation, workpiece point, workpiece rotation), bed frame."""
    # Workpiece branch: X slide, A axis above it, the nest on the A table.
    origin_a = np.array([x, 0.0, A_ABOVE_X_M])
    turn = a + errors.a_positioning_rad * np.sin(a + errors.a_phase_rad)
    # The table turns about its actual (tilted) line, set up at A = 0 (ISO 230-7): the
    # turn conjugated by the line's tilt; a tilt about A's own axis is its zero error,
    # which the set-up takes out.
    line_a = rotation(errors.a_tilt)
    table = line_a @ rotation([turn, 0.0, 0.0]) @ line_a.T
    eccentric = errors.a_radial_m * np.array([0.0, np.cos(a + errors.a_phase_rad),
                                              np.sin(a + errors.a_phase_rad)])
    work_point = origin_a + table @ (np.asarray(geometry.workpiece_m) + eccentric
                                     + np.asarray(errors.nest_shift_m))
    # Tool branch: Y and Z slides, B axis below the ram, the tool on B.
    origin_b = np.array([0.0, y, z - B_BELOW_Z_M])
    line_b = rotation(errors.b_tilt)
    spindle = line_b @ rotation([0.0, b, 0.0]) @ line_b.T
    tool_point = origin_b + spindle @ np.asarray(geometry.tool_m)
    return tool_point, spindle, work_point, table


def rtest_reading(pose: dict, errors: FiveAxisErrors, geometry: Geometry,
                  datum: dict) -> tuple[np.ndarray, np.ndarray]:
    """What a two-sphere R-test zeroed at ``datum`` reads at ``pose``: the sphere's
    displacement from where it was at the datum [m] (tool minus workpiece, actual minus
    nominal, referred to the datum's) and the tool's direction error [rad] across the
    tool axis (absolute), both in the bed frame."""
    def error(q):
        t, rt, w, rw = tool_pose(q["X"], q["Y"], q["Z"], q["A"], q["B"], errors, geometry)
        t0, rt0, w0, rw0 = tool_pose(q["X"], q["Y"], q["Z"], q["A"], q["B"],
                                     FiveAxisErrors(), geometry)
        position = (t - w) - (t0 - w0)
        relative = (rw @ rw0.T).T @ (rt @ rt0.T)
        axis = rt0 @ np.asarray(geometry.tool_m) / np.linalg.norm(geometry.tool_m)
        turn = rotation_vector(relative)
        return position, turn - axis * (turn @ axis)

    position, direction = error(pose)
    return position - error(datum)[0], direction


@dataclass
class Survey:
    positions: dict = field(default_factory=dict)   # axis -> (N,)
    position_error_m: np.ndarray = None               # (N, 3)
    direction_error_rad: np.ndarray = None            # (N, 3)
    time_s: np.ndarray = None
    work_point_m: tuple = (0.05, 0.0, 0.02)           # the sphere nest in the A table frame


def survey(errors: FiveAxisErrors, *, readings: int, seed: int, datum: dict,
           position_noise_m: float = 0.5e-6, direction_noise_rad: float = 1e-6,
           geometry: Geometry | None = None) -> Survey:
    """Random poses over the strokes, read by an R-test with Gaussian noise (k = 1 given)."""
    geometry = geometry or Geometry()
    rng = np.random.default_rng(seed)
    poses = {a: rng.uniform(*STROKES[a], readings) for a in "XYZAB"}
    position = np.zeros((readings, 3))
    direction = np.zeros((readings, 3))
    for i in range(readings):
        pose = {a: poses[a][i] for a in poses}
        position[i], direction[i] = rtest_reading(pose, errors, geometry, datum)
    position += rng.normal(0.0, position_noise_m, position.shape)
    noise = rng.normal(0.0, direction_noise_rad, direction.shape)
    # The instrument sees no turn about the tool axis: nor does its noise.
    for i in range(readings):
        axis = rotation([0.0, poses["B"][i], 0.0]) @ np.asarray(geometry.tool_m)
        axis = axis / np.linalg.norm(axis)
        noise[i] -= axis * (noise[i] @ axis)
    return Survey(poses, position, direction + noise, np.arange(readings) * 0.37,
                  tuple(geometry.workpiece_m))


def reading_fields(data: Survey, with_direction: bool = True) -> dict:
    """The survey as the workbench's ``Observations`` fields (keyword arguments), with the
    R-test's stated k = 2 uncertainties: 1 um for the tip, 2 urad for the direction;
    ``with_direction=False``: the tip alone, as a probe would give it. The R-test states
    its target: the sphere nest, fixed on the A table (``work_point``)."""
    fields = {"positions": data.positions, "measured_m": data.position_error_m,
              "measured_mask": np.ones_like(data.position_error_m, dtype=bool),
              "time_s": data.time_s, "uncertainty_m": 1e-6,
              "work_point": np.asarray(data.work_point_m, dtype=float)}
    if with_direction:
        fields.update(measured_orientation_rad=data.direction_error_rad,
                      orientation_measured=np.ones(data.time_s.size, dtype=bool),
                      orientation_uncertainty_rad=2e-6)
    return fields
