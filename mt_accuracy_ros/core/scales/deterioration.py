"""Deterioration detection and command compensation (Kidani sections 2.1 and 3.3.2).

The systematic error measured now, e_N, is compared with the master data e_1
kept from when the machine was accurate: de = e_N - e_1 (Kidani eq. 2.1). Where
|de| >= de_TOL the accuracy has changed and the command p1 is modified to
p2 = p1 - de (Kidani eq. 2.2). For yaw of the Y axis with the tool offset d in X the
TCP change is de_y = dE_CY * d (Kidani eqs. 3.11-3.16).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError, ParameterError
from ..validation import finite_array, same_length


@dataclass(frozen=True)
class DeteriorationReport:
    """Result of comparing a profile with its baseline at common positions.

    Attributes
    ----------
    positions : ndarray, shape (n,)
    change : ndarray, shape (n,)      de = current - baseline (Kidani eq. 2.1 / 3.11)
    flagged : ndarray of bool, shape (n,)   |de| >= tolerance
    tolerance : float
    """

    positions: NDArray[np.float64]
    change: NDArray[np.float64]
    flagged: NDArray[np.bool_]
    tolerance: float

    @property
    def deteriorated(self) -> bool:
        """True when compensation is needed (Kidani Step 2)."""
        return bool(self.flagged.any())

    @property
    def max_abs_change(self) -> float:
        return float(np.max(np.abs(self.change))) if self.change.size else 0.0

    def flagged_ranges(self) -> list[tuple[float, float]]:
        """Contiguous position ranges where the change exceeds the tolerance."""
        ranges: list[tuple[float, float]] = []
        start = previous = None
        for position, flag in zip(self.positions, self.flagged):
            if flag and start is None:
                start = position
            if not flag and start is not None:
                ranges.append((float(start), float(previous)))
                start = None
            previous = position
        if start is not None:
            ranges.append((float(start), float(self.positions[-1])))
        return ranges


def detect_deterioration(positions: ArrayLike, baseline: ArrayLike, current: ArrayLike,
                         tolerance: float) -> DeteriorationReport:
    """Flag positions where |current - baseline| >= tolerance (Kidani eq. 2.1, Step 2).

    Parameters
    ----------
    positions : array_like, shape (n,)
        Positions at which both profiles are given [m], ascending.
    baseline, current : array_like, shape (n,)
        Systematic error e_1 and e_N [unit].
    tolerance : float
        de_TOL [unit], > 0.

    Returns
    -------
    DeteriorationReport
        The change de = current - baseline (n,) [unit] and where |de| >= tolerance.

    Raises
    ------
    ParameterError
        A tolerance that is not finite and > 0.
    """
    x = finite_array(positions, "positions", ndim=1)
    base = finite_array(baseline, "baseline", ndim=1)
    now = finite_array(current, "current", ndim=1)
    same_length("positions", x, "baseline", base)
    same_length("positions", x, "current", now)
    tol = float(tolerance)
    if not np.isfinite(tol) or tol <= 0:
        raise ParameterError(f"tolerance must be finite and > 0, got {tolerance!r}")
    change = now - base
    return DeteriorationReport(positions=x, change=change, flagged=np.abs(change) >= tol,
                               tolerance=tol)


def resample_profile(positions: ArrayLike, values: ArrayLike, at: ArrayLike) -> NDArray[np.float64]:
    """Linear interpolation of a profile at other positions (flat beyond its ends).

    Parameters
    ----------
    positions : array_like, shape (n,)
        The profile's positions, strictly ascending [m].
    values : array_like, shape (n,)
        The profile's values there (any unit; returned in the same).
    at : array_like, shape (m,)
        Positions to evaluate the profile at [m].

    Returns
    -------
    ndarray, shape (m,)
        The profile at ``at``, in the unit of ``values``.
    """
    x = finite_array(positions, "positions", ndim=1)
    y = finite_array(values, "values", ndim=1)
    same_length("positions", x, "values", y)
    if np.any(np.diff(x) <= 0):
        raise InputDataError("profile positions must be strictly ascending")
    return np.interp(finite_array(at, "at", ndim=1), x, y)


def compensated_command(command_m: ArrayLike, error_change_m: ArrayLike) -> NDArray[np.float64]:
    """Modified command p2 = p1 - de (Kidani eq. 2.2), element-wise.

    Parameters
    ----------
    command_m : array_like, shape (n,) or (n, 3)
        Commands p1 [m].
    error_change_m : array_like, same shape
        TCP error change de at each command [m].

    Returns
    -------
    ndarray, the shape of ``command_m``
        Modified commands p2 [m].
    """
    p1 = finite_array(command_m, "command_m")
    de = finite_array(error_change_m, "error_change_m")
    if p1.shape != de.shape:
        raise InputDataError(f"command_m {p1.shape} and error_change_m {de.shape} differ in shape")
    return p1 - de


def tcp_change_from_yaw(yaw_change_rad: ArrayLike, tool_offset_m: float) -> NDArray[np.float64]:
    """TCP change of the yaw-only model, de_y = dE_CY * d (Kidani eqs. 3.13-3.16).

    Parameters
    ----------
    yaw_change_rad : array_like, shape (n,)
        Yaw change dE_CY at each position [rad].
    tool_offset_m : float
        Abbe offset d of the tool from the axis' line [m].

    Returns
    -------
    ndarray, shape (n,)
        TCP change de_y [m].
    """
    change = finite_array(yaw_change_rad, "yaw_change_rad", ndim=1)
    offset = float(tool_offset_m)
    if not np.isfinite(offset):
        raise ParameterError(f"tool_offset_m must be finite, got {tool_offset_m!r}")
    return change * offset  # Kidani eq. 3.14
