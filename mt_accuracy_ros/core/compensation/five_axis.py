"""Five-axis compensation: rotary-axis corrections for the tool's direction, linear for its tip.

On a machine with rotary axes the model predicts two errors at a command q
(Kidani eq. 2.10 generalised; Khan & Chen eqs. 9-16): the TCP position error
e_p (N, 3) [m] and the tool-orientation error eps (N, 3) [rad], a small
rotation of the tool relative to the workpiece in the bed frame. A controller
can cancel both, as a 5-axis CNC's volumetric compensation does, by adding

* to the rotary commands: dr = -(P J_o)^+ P eps, the least-squares turn of the
  rotary axes that brings the tool's *direction* back. P = I - t t^T removes
  the rotation about the tool axis t (a spindle's own rotation: no rotary axis
  needs to, and on most machines none can, correct it);
* to the TCP (through the linear axes): c = -(e_p + J_p dr), the position
  error plus the shift of the tool tip the rotary correction itself causes.

J_o (N, 3, R) and J_p (N, 3, R) are the derivatives of the nominal relative
orientation and position with respect to the rotary axes (central
differences of the nominal chain, exact to ~1e-10). This is the first-order
inverse of the chain: after the correction the tool's pose error is second
order in the errors (a few 1e-10 m for errors of 1e-5) - tested against the
chain evaluated exactly at the corrected command, a second formulation.

Near a kinematic singularity (a rotary axis parallel to the tool) P J_o loses
rank: the direction it cannot turn is left uncorrected (truncated
pseudo-inverse, ``rcond``) and reported in ``residual_direction_rad``, rather
than answered with a huge turn.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError
from ..kinematics.chain import KinematicModel
from ..kinematics.htm import rotation_vector

#: Central-difference step for the rotary Jacobians [rad].
JACOBIAN_STEP_RAD = 1e-6


@dataclass
class FiveAxisCorrection:
    """What to add to the commands at N positions.

    Parameters
    ----------
    position_m : ndarray, shape (N, 3)
        Correction of the TCP in the bed frame [m] (the linear axes realise it).
    rotary_rad : ndarray, shape (N, R)
        Correction of each rotary axis [rad], columns in ``rotary_axes`` order.
    rotary_axes : tuple of str
        The R rotary axis letters.
    residual_direction_rad : ndarray, shape (N, 3)
        Tool-direction error the rotary axes cannot take out (singular poses) [rad].
    """

    position_m: NDArray[np.float64]
    rotary_rad: NDArray[np.float64]
    rotary_axes: tuple[str, ...]
    residual_direction_rad: NDArray[np.float64]


def tool_direction(kinematics: KinematicModel, positions: dict[str, ArrayLike]) -> NDArray:
    """Unit vector (N, 3) of the tool axis in the bed frame, nominal chain.

    Parameters
    ----------
    kinematics : KinematicModel
        The nominal machine.
    positions : dict of str to array_like, shape (N,)
        Axis commands [m] (rotary [rad]), every axis.

    Returns
    -------
    ndarray, shape (N, 3)
        Unit vectors (dimensionless), bed frame.
    """
    return kinematics.tool_axis(positions)


def rotary_jacobians(kinematics: KinematicModel, positions: dict[str, ArrayLike],
                     step_rad: float = JACOBIAN_STEP_RAD) -> tuple[NDArray, NDArray, tuple]:
    """d(tool - workpiece)/d r and d(relative orientation)/d r of the nominal chain.

    The workpiece point is the machining point of ``positions`` (the material
    under the tool), held fixed in the workpiece frame while the axis turns.

    Parameters
    ----------
    kinematics : KinematicModel
        The nominal machine.
    positions : dict of str to array_like, shape (N,)
        Axis commands [m] (rotary [rad]), every axis.
    step_rad : float, optional
        Central-difference step [rad].

    Returns
    -------
    (J_p (N, 3, R) [m/rad], J_o (N, 3, R) [rad/rad], rotary axes)
    """
    machine = kinematics.machine
    rotary = tuple(a for a in machine.axis_order if machine.axes[a].is_rotary)
    q = {a: np.atleast_1d(np.asarray(v, dtype=np.float64)) for a, v in positions.items()}
    n = np.broadcast(*q.values()).size
    under_tool = kinematics.machining_point(q)
    jac_p = np.zeros((n, 3, len(rotary)))
    jac_o = np.zeros((n, 3, len(rotary)))
    for i, axis in enumerate(rotary):
        ends = []
        for sign in (1.0, -1.0):
            moved = dict(q)
            moved[axis] = q[axis] + sign * step_rad
            tool = kinematics.branch("tool", moved, errors=False, check_stroke=False)
            work = kinematics.branch("workpiece", moved, errors=False, check_stroke=False,
                                     end_point=under_tool)
            ends.append((tool, work))
        (tool_plus, work_plus), (tool_minus, work_minus) = ends
        jac_p[:, :, i] = ((tool_plus[:, :3, 3] - work_plus[:, :3, 3])
                          - (tool_minus[:, :3, 3] - work_minus[:, :3, 3])) / (2 * step_rad)
        # Rotation from the minus to the plus pose of each branch, in the bed frame.
        turn_tool = rotation_vector(tool_plus[:, :3, :3] @ np.swapaxes(tool_minus[:, :3, :3], 1, 2))
        turn_work = rotation_vector(work_plus[:, :3, :3] @ np.swapaxes(work_minus[:, :3, :3], 1, 2))
        jac_o[:, :, i] = (turn_tool - turn_work) / (2 * step_rad)
    return jac_p, jac_o, rotary


def five_axis_correction(kinematics: KinematicModel, positions: dict[str, ArrayLike],
                         position_error_m: ArrayLike, orientation_error_rad: ArrayLike, *,
                         rcond: float = 0.05) -> FiveAxisCorrection:
    """Rotary and TCP corrections that cancel the tool's position and direction error.

    Parameters
    ----------
    kinematics : KinematicModel
        The controller's nominal machine.
    positions : dict
        Axis -> command (N,) [m or rad], every axis of the machine.
    position_error_m, orientation_error_rad : array_like (N, 3)
        The model's TCP error [m] and tool-orientation error [rad] at the commands
        (bed frame).
    rcond : float
        Singular values of P J_o below ``rcond`` x the largest are not inverted.

    Returns
    -------
    FiveAxisCorrection
        Position [m] and rotary [rad] corrections, and the direction error left [rad].

    Raises
    ------
    InputDataError
        Errors not both (N, 3), or not finite.
    """
    e_p = np.atleast_2d(np.asarray(position_error_m, dtype=np.float64))
    eps = np.atleast_2d(np.asarray(orientation_error_rad, dtype=np.float64))
    if e_p.shape != eps.shape or e_p.shape[1:] != (3,):
        raise InputDataError(f"position error {e_p.shape} and orientation error {eps.shape} "
                             "must both be (N, 3)")
    if not (np.all(np.isfinite(e_p)) and np.all(np.isfinite(eps))):
        raise InputDataError("five-axis correction of a NaN/inf error")
    jac_p, jac_o, rotary = rotary_jacobians(kinematics, positions)
    n = e_p.shape[0]
    if not rotary:
        return FiveAxisCorrection(-e_p, np.zeros((n, 0)), (), np.zeros((n, 3)))
    t = tool_direction(kinematics, positions)
    projector = np.eye(3)[None] - t[:, :, None] * t[:, None, :]
    reachable = projector @ jac_o                                    # (N, 3, R)
    wanted = -np.einsum("nij,nj->ni", projector, eps)                # (N, 3)
    turn = np.einsum("nij,nj->ni", np.linalg.pinv(reachable, rcond=rcond), wanted)
    left = np.einsum("nij,nj->ni", reachable, turn) - wanted
    position = -(e_p + np.einsum("nij,nj->ni", jac_p, turn))
    return FiveAxisCorrection(position, turn, rotary, left)
