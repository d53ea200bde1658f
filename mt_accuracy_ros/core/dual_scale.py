"""Yaw of a linear axis from a pair of parallel linear scales (Kidani, section 2.3.2).

Two scales on one axis, a distance ``scale_distance_m`` apart, read ``x1`` and
``x2``. A rotation of the moving component about the axis normal (yaw, E_C for
the X axis) makes the readings differ:

    E_CX = atan((x2 - x1) / D_X)  ~=  (x2 - x1) / D_X          (Kidani eq. 2.13)

The readings are relative to a zero reference taken at the start of the
measurement; any initial tilt of the component is in the reference and cancels
(Kidani section 3.2.2).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from .validation import finite_array, positive, same_length


def yaw_from_scales(x1_m: ArrayLike, x2_m: ArrayLike, scale_distance_m: float, *,
                    reference: tuple[float, float] | None = None,
                    small_angle: bool = False) -> NDArray[np.float64]:
    """Yaw angle from two parallel scale readings (Kidani eq. 2.13).

    Parameters
    ----------
    x1_m, x2_m : array_like, shape (n,)
        Readings of the primary and secondary scale [m].
    scale_distance_m : float
        Distance D between the two scales [m], > 0.
    reference : (float, float), optional
        Readings (x1, x2) at the zero reference [m]. The yaw is measured
        relative to it, so a constant initial tilt cancels. ``None`` means
        the readings are already relative.
    small_angle : bool
        Use ``(x2 - x1) / D`` instead of ``atan((x2 - x1) / D)``.

    Returns
    -------
    ndarray, shape (n,)
        Yaw [rad]; positive when scale 2 reads further than scale 1.
    """
    x1 = finite_array(x1_m, "x1_m", ndim=1)
    x2 = finite_array(x2_m, "x2_m", ndim=1)
    same_length("x1_m", x1, "x2_m", x2)
    distance = positive(scale_distance_m, "scale_distance_m")
    difference = x2 - x1
    if reference is not None:
        ref = finite_array(reference, "reference", ndim=1)
        difference = difference - (ref[1] - ref[0])
    ratio = difference / distance
    return ratio if small_angle else np.arctan(ratio)
