"""What a calibrated model knows of its own error at the datum.

A reference instrument zeroed at the datum (an R-test touched off at the work offset)
reads the machine's error relative to the datum, e(q) - e(datum); a model with a datum
refers its error to the same pose (:meth:`.error_model.ErrorModel.tcp_error`). What the
model computes at the datum comes from its calibrated tables at that one pose, each
known to the calibration's uncertainty: a laser calibration's stated accuracy at each
table point, carried to the tool through the chain. :func:`calibration_uncertainty_at`
gives that uncertainty at the datum - first order, the table errors uncorrelated (GUM,
JCGM 100 eq. 10):

    u_c^2(e_k) = sum_i (s_ki u_i)^2

with s_ki the TCP's sensitivity to error i at the datum (the error's frame and Abbe
lever, :meth:`..kinematics.chain.KinematicModel.error_frames`: a translation moves the
TCP by R d, a rotation by (R eps) x lever) and u_i the standard uncertainty of table i
there. A refit from the datum fits the model's error at the datum within it
(:mod:`..workbench.refit`).
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from numpy.typing import NDArray

from ..errors import ParameterError
from ..kinematics.chain import KinematicModel
from ..kinematics.machine import COMPONENTS, MachineDescription, checked_datum

#: table_uncertainty(error name, the axis' position at the datum [m]) -> the table's
#: expanded (k = 2) uncertainty there [m for E<X|Y|Z>, rad for E<A|B|C>], 0 if exact.
TableUncertainty = Callable[[str, float], float]


def calibration_uncertainty_at(machine: MachineDescription, datum: dict[str, float],
                               table_uncertainty: TableUncertainty,
                               squareness_uncertainty_rad: float = 0.0
                               ) -> NDArray[np.float64]:
    """(3,) [m] expanded (k = 2) uncertainty of the model's TCP error at ``datum``.

    Parameters
    ----------
    machine : the calibrated machine description (its non-zero motion-error tables are
        the calibration's; a zero table was not measured and adds nothing).
    datum : axis -> command [m or rad], every axis of ``machine``.
    table_uncertainty : see :data:`TableUncertainty`.
    squareness_uncertainty_rad : expanded (k = 2) uncertainty of each calibrated
        squareness (a linear axis' declared angular location error) [rad].

    Returns
    -------
    (3,) [m] U (k = 2) of e(datum), x, y, z: 2 sqrt(sum_i (s_i U_i / 2)^2).

    Raises
    ------
    ParameterError : a datum that is not a pose of ``machine``, or an uncertainty that is
        negative or not finite.
    """
    pose = checked_datum(datum, machine)
    if not pose:
        raise ParameterError("calibration uncertainty at the datum: give the datum")
    frames = KinematicModel(machine).error_frames({a: np.array([v]) for a, v in pose.items()})
    variance = np.zeros(3)
    for axis in machine.axis_order:
        spec = machine.axes[axis]
        if spec.is_rotary:
            continue
        measured = [(f"E{c}{axis}", c, float(table_uncertainty(f"E{c}{axis}", pose[axis])))
                    for c, function in spec.motion_errors.items() if not function.is_zero]
        measured += [(f"E{c}0{axis}", c, float(squareness_uncertainty_rad))
                     for c in spec.location_errors if c in "ABC"]
        for name, component, expanded in measured:
            if not (np.isfinite(expanded) and expanded >= 0):
                raise ParameterError(f"the calibration's uncertainty of {name}: {expanded!r}; "
                                     "expected a finite non-negative value (k = 2)")
            sign, rotation, lever = frames[name]
            index = COMPONENTS.index(component)
            if index < 3:
                sensitivity = sign * rotation[0, :, index]                    # R d
            else:
                sensitivity = sign * np.cross(rotation[0, :, index - 3], lever[0])  # (R eps) x r
            variance += (sensitivity * expanded / 2.0) ** 2        # GUM, JCGM 100 eq. 10
    return 2.0 * np.sqrt(variance)


__all__ = ["TableUncertainty", "calibration_uncertainty_at"]
