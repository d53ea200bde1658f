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

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError, ParameterError
from ..validation import finite_array, positive, same_length


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


#: Coefficient of thermal expansion of the SQ57 steel scale [1/K] (Kidani Table 3.2).
SQ57_EXPANSION_PER_K = 12e-6

#: The rotation each axis' scale pair measures: the pair of an axis lies in a
#: plane, and the yaw is the rotation about that plane's normal (Kidani Fig. 2.3).
#: A real machine's scale pairs and the simulator's share this convention.
YAW_COMPONENT = {"X": "C", "Y": "C", "Z": "B"}


def scale_expansion(travel_m: ArrayLike, temperature_rise_k: ArrayLike | float,
                    expansion_per_k: float = SQ57_EXPANSION_PER_K, *,
                    sensor_positions_m: ArrayLike | None = None) -> NDArray[np.float64]:
    """Thermal expansion of a scale over the travel from its zero reference (Kidani eq. 3.17).

    ``dL = C * L0 * dT`` for a uniform temperature rise; for a temperature
    profile measured by thermocouples along the scale (every 110 mm in Kidani
    section 3.3.3) the expansion is the integral ``C * int_0^L0 dT(s) ds`` of the
    piecewise-linear interpolated rise (constant beyond the end sensors).

    Parameters
    ----------
    travel_m : array_like, shape (n,)
        Signed travel L0 from the zero reference [m].
    temperature_rise_k : float or array_like
        Uniform rise T - T0 [K]; or, with ``sensor_positions_m``, the rise at each
        sensor, shape (n_sensors,) for one instant or (n, n_sensors) per sample.
    expansion_per_k : float
        C [1/K], > 0.
    sensor_positions_m : array_like, shape (n_sensors,), optional
        Sensor positions along the scale measured from the zero reference [m],
        ascending.

    Returns
    -------
    ndarray, shape (n,)
        Expansion dL of the scale between the reference and each position [m].
    """
    travel = finite_array(travel_m, "travel_m", ndim=1)
    coefficient = positive(expansion_per_k, "expansion_per_k")
    if sensor_positions_m is None:
        rise = finite_array(temperature_rise_k, "temperature_rise_k", allow_empty=False)
        return coefficient * travel * rise
    return ExpansionProfile(sensor_positions_m, temperature_rise_k, coefficient)(travel)


class ExpansionProfile:
    """A scale's measured temperature rises, prepared for the expansion at many travels.

    The expansion between the zero reference and a travel L0 is ``C * int_0^L0 dT(s) ds``
    of the piecewise-linear interpolated rise, constant beyond the end sensors (Kidani
    eq. 3.17). The cumulative integral over the sensors is computed once, at the first
    call (again only for a travel beyond the span it covers), so a node that corrects
    every batch with the rises of the latest temperature reading integrates them once
    per reading. :func:`scale_expansion` with ``sensor_positions_m`` is this.

    Parameters
    ----------
    sensor_positions_m : array_like, shape (K,)
        Sensor positions along the scale from the zero reference [m], strictly ascending.
    temperature_rise_k : array_like, shape (K,) or (n, K)
        The rise at each sensor [K]: for one instant, or one row per travel.
    expansion_per_k : float
        C [1/K], > 0.

    Raises
    ------
    InputDataError
        Values not finite, sensors not ascending, or a rise of the wrong shape.
    ParameterError
        ``expansion_per_k`` not positive.
    """

    def __init__(self, sensor_positions_m: ArrayLike, temperature_rise_k: ArrayLike,
                 expansion_per_k: float) -> None:
        self.coefficient = positive(expansion_per_k, "expansion_per_k")
        self.sensors = finite_array(sensor_positions_m, "sensor_positions_m", ndim=1)
        if np.any(np.diff(self.sensors) <= 0):
            raise InputDataError("sensor_positions_m must be strictly ascending")
        rise = finite_array(temperature_rise_k, "temperature_rise_k")
        if rise.ndim not in (1, 2) or rise.shape[-1] != self.sensors.size:
            raise InputDataError(f"temperature_rise_k has shape {rise.shape}, expected "
                                 f"({self.sensors.size},) or (n, {self.sensors.size})")
        #: (1, K) for one instant's rises, else (n, K).
        self.rises = rise.reshape(-1, self.sensors.size)
        #: (span [m], grid (K + 2,), values (R, K + 2), cumulative (R, K + 2)).
        self._table: tuple[float, NDArray, NDArray, NDArray] | None = None
        #: (1,) the one instant's integral from the grid's start to 0 (None: per row).
        self._to_zero: NDArray | None = None

    def __call__(self, travel_m: ArrayLike) -> NDArray[np.float64]:
        """Expansion dL (n,) [m] between the zero reference and each travel (n,) [m].

        Raises
        ------
        InputDataError
            Travels not finite, or not one per row of per-travel rises.
        """
        travel = finite_array(travel_m, "travel_m", ndim=1)
        if self.rises.shape[0] not in (1, travel.size):
            raise InputDataError(f"temperature_rise_k has shape {self.rises.shape}, expected "
                                 f"({travel.size}, {self.sensors.size})")
        # Extend the profile flat to both sides so every travel is covered.
        span = max(float(np.max(np.abs(travel), initial=0.0)),
                   float(np.max(np.abs(self.sensors)))) + 1.0
        if self._table is None or self._table[0] < span:
            grid = np.concatenate(([-span], self.sensors, [span]))
            values = np.concatenate((self.rises[:, :1], self.rises, self.rises[:, -1:]), axis=1)
            # Cumulative trapezoid from the grid start; the part up to 0 is subtracted.
            cumulative = np.concatenate(
                (np.zeros((values.shape[0], 1)),
                 np.cumsum(0.5 * (values[:, 1:] + values[:, :-1]) * np.diff(grid), axis=1)),
                axis=1)
            self._table = (span, grid, values, cumulative)
            # One instant's rises: the integral up to the zero reference is one number.
            self._to_zero = None if self.rises.shape[0] > 1 else \
                self._integral_to(np.zeros(1), np.zeros(1, dtype=np.intp))
        if self._to_zero is None:
            rows = np.arange(travel.size)
            to_zero = self._integral_to(np.zeros_like(travel), rows)
        else:
            rows, to_zero = np.zeros(travel.size, dtype=np.intp), self._to_zero
        return self.coefficient * (self._integral_to(travel, rows) - to_zero)

    def _integral_to(self, points: NDArray, rows: NDArray) -> NDArray:
        """Integral of row ``rows[i]``'s interpolant from the grid's start to ``points[i]``."""
        _, grid, values, cumulative = self._table
        index = np.clip(np.searchsorted(grid, points, side="right") - 1, 0, grid.size - 2)
        width = points - grid[index]
        slope = (values[rows, index + 1] - values[rows, index]) / (grid[index + 1] - grid[index])
        return cumulative[rows, index] + width * (values[rows, index] + 0.5 * slope * width)


def thermal_yaw_error(travel_m: ArrayLike, expansion_1_m: ArrayLike, expansion_2_m: ArrayLike,
                      scale_distance_m: float) -> NDArray[np.float64]:
    """Apparent yaw from unequal expansion of the two scales (Kidani section 3.3.3).

    A scale that expands by dL under-reads the travel by dL (its graduations
    moved apart), so the measured difference x2 - x1 changes by -(dL2 - dL1)
    and the yaw by ``-(dL2 - dL1) / D``. The thesis states the magnitude
    ``(dL2 - dL1) / D``; the sign here follows from the reading model and is
    the one the simulator uses.

    Parameters
    ----------
    travel_m : array_like, shape (n,)
        Travel from the zero reference [m] (checked for length only).
    expansion_1_m, expansion_2_m : array_like, shape (n,)
        Expansion dL of scale 1 and scale 2 over the travel [m].
    scale_distance_m : float
        Distance D between the two scales [m] (> 0).

    Returns
    -------
    ndarray, shape (n,)
        Apparent yaw [rad] to subtract from the measured yaw.

    Raises
    ------
    InputDataError
        Non-finite values or lengths that differ.
    ParameterError
        ``scale_distance_m`` not positive.
    """
    travel = finite_array(travel_m, "travel_m", ndim=1)
    dl1 = finite_array(expansion_1_m, "expansion_1_m", ndim=1)
    dl2 = finite_array(expansion_2_m, "expansion_2_m", ndim=1)
    same_length("travel_m", travel, "expansion_1_m", dl1)
    same_length("travel_m", travel, "expansion_2_m", dl2)
    return -(dl2 - dl1) / positive(scale_distance_m, "scale_distance_m")


def parallelism_yaw_error(travel_m: ArrayLike, parallelism_rad: float,
                          scale_distance_m: float) -> NDArray[np.float64]:
    """Apparent yaw from a parallelism error delta of the scale pair (Kidani eq. 3.5).

    ``dE_yaw = (L / cos(delta) - L) / D`` for a travel L from the zero reference;
    the sign of L carries through (travel to the negative side gives a negative
    apparent yaw), the sign of delta does not (cos is even).

    Parameters
    ----------
    travel_m : array_like, shape (n,)
        Travel L from the zero reference [m].
    parallelism_rad : float
        Parallelism error delta [rad], |delta| < pi/2.
    scale_distance_m : float
        Distance D between the two scales [m] (> 0).

    Returns
    -------
    ndarray, shape (n,)
        Apparent yaw [rad].

    Raises
    ------
    ParameterError
        delta not finite or too large, or D not positive.
    """
    travel = finite_array(travel_m, "travel_m", ndim=1)
    delta = float(parallelism_rad)
    if not np.isfinite(delta) or abs(delta) >= np.pi / 2:
        raise ParameterError(f"parallelism_rad must be finite and |delta| < pi/2, got {delta!r}")
    return (travel / np.cos(delta) - travel) / positive(scale_distance_m, "scale_distance_m")


def timing_yaw_error(velocity_m_per_s: ArrayLike, skew_s: float,
                     scale_distance_m: float) -> NDArray[np.float64]:
    """Apparent yaw from sampling head 2 ``skew_s`` later than head 1 (Kidani eq. 2.20).

    Head 2 then reads the position ``v * dt`` further along, so
    ``dE = v * dt / D`` (the thesis writes ``+-F dt / D``; the sign is the
    direction of motion).

    Parameters
    ----------
    velocity_m_per_s : array_like, shape (n,)
        Axis velocity v [m/s].
    skew_s : float
        Sampling skew dt of head 2 after head 1 [s].
    scale_distance_m : float
        Distance D between the two scales [m] (> 0).

    Returns
    -------
    ndarray, shape (n,)
        Apparent yaw [rad].

    Raises
    ------
    ParameterError
        A non-finite skew or D not positive.
    """
    velocity = finite_array(velocity_m_per_s, "velocity_m_per_s", ndim=1)
    skew = float(skew_s)
    if not np.isfinite(skew):
        raise ParameterError(f"skew_s must be finite, got {skew!r}")
    return velocity * skew / positive(scale_distance_m, "scale_distance_m")


@dataclass(frozen=True)
class YawCorrections:
    """Which correction terms :func:`corrected_yaw` removes, each switchable.

    Attributes
    ----------
    thermal : bool
        Relative thermal expansion of the two scales (Kidani eq. 3.17).
    parallelism : bool
        Parallelism error of the pair (Kidani eq. 3.5); needs ``parallelism_rad``.
    timing : bool
        Sampling-time misalignment (Kidani eq. 2.20); needs ``skew_s``.
    parallelism_rad : float
        Known parallelism error delta [rad].
    skew_s : float
        Known sampling delay of head 2 behind head 1 [s].
    expansion_per_k : float
        C of both scales [1/K].
    """

    thermal: bool = True
    parallelism: bool = False
    timing: bool = False
    parallelism_rad: float = 0.0
    skew_s: float = 0.0
    expansion_per_k: float = SQ57_EXPANSION_PER_K


def corrected_yaw(x1_m: ArrayLike, x2_m: ArrayLike, scale_distance_m: float, *,
                  reference: tuple[float, float],
                  corrections: YawCorrections = YawCorrections(),
                  temperature_rise_1_k: ArrayLike | float | None = None,
                  temperature_rise_2_k: ArrayLike | float | None = None,
                  sensor_positions_m: ArrayLike | None = None,
                  velocity_m_per_s: ArrayLike | None = None) -> dict[str, NDArray[np.float64]]:
    """Yaw with the switched-on corrections removed, and each term on its own.

    Parameters
    ----------
    x1_m, x2_m : array_like, shape (n,)
        Raw readings [m].
    scale_distance_m : float
        D [m].
    reference : (float, float)
        Readings at the zero reference [m].
    corrections : YawCorrections
        Which terms to remove and their constants.
    temperature_rise_1_k, temperature_rise_2_k : float or array_like
        Rise of each scale since the reference [K] (see :func:`scale_expansion`).
    sensor_positions_m : array_like, optional
        Thermocouple positions along the scales, from the reference [m].
    velocity_m_per_s : array_like, shape (n,), optional
        Axis velocity, needed for the timing term.

    Returns
    -------
    dict with keys ``yaw`` (corrected), ``raw`` and one key per applied term
    (``thermal``, ``parallelism``, ``timing``), each shape (n,) [rad].
    """
    raw = yaw_from_scales(x1_m, x2_m, scale_distance_m, reference=reference)
    x1 = np.asarray(x1_m, dtype=np.float64)
    # Travel from the zero reference along scale 1 (the feedback scale).
    travel = x1 - reference[0]
    terms: dict[str, NDArray[np.float64]] = {}
    if corrections.thermal:
        if temperature_rise_1_k is None or temperature_rise_2_k is None:
            raise InputDataError("thermal correction needs temperature_rise_1_k and _2_k")
        dl1 = scale_expansion(travel, temperature_rise_1_k, corrections.expansion_per_k,
                              sensor_positions_m=sensor_positions_m)
        dl2 = scale_expansion(travel, temperature_rise_2_k, corrections.expansion_per_k,
                              sensor_positions_m=sensor_positions_m)
        terms["thermal"] = thermal_yaw_error(travel, dl1, dl2, scale_distance_m)
    if corrections.parallelism:
        terms["parallelism"] = parallelism_yaw_error(travel, corrections.parallelism_rad,
                                                     scale_distance_m)
    if corrections.timing:
        if velocity_m_per_s is None:
            raise InputDataError("timing correction needs velocity_m_per_s")
        terms["timing"] = timing_yaw_error(velocity_m_per_s, corrections.skew_s,
                                           scale_distance_m)
    yaw = raw.copy()
    for term in terms.values():
        yaw -= term
    return {"yaw": yaw, "raw": raw, **terms}


#: Thermocouple spacing along each scale [m] (Kidani section 3.3.3).
THERMOCOUPLE_SPACING_M = 0.11


def thermocouple_positions(length_m: float, spacing_m: float = THERMOCOUPLE_SPACING_M
                           ) -> NDArray[np.float64]:
    """Positions along a scale of thermocouples every ``spacing_m``, both ends included [m].

    Parameters
    ----------
    length_m : float
        Scale length [m] (> 0).
    spacing_m : float, optional
        Thermocouple spacing [m] (> 0).

    Returns
    -------
    ndarray, shape (K,)
        Positions from 0 to ``length_m`` [m].

    Raises
    ------
    ParameterError
        A length or spacing that is not positive.
    """
    length = positive(length_m, "length_m")
    spacing = positive(spacing_m, "spacing_m")
    count = int(np.floor(length / spacing + 1e-9)) + 1
    positions = np.arange(count) * spacing
    if length - positions[-1] > 1e-6:
        positions = np.append(positions, length)
    return positions
