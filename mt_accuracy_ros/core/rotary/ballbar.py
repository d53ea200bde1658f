"""Rotary-axis calibration with a telescopic magnetic ball bar (Zhu 2008, ch. 5).

Setup (Zhu Fig. 5.2): one ball (A) sits in a socket on the rotary table (a C
axis about z) at radius ``R_x`` and height ``R_z`` above the table centre O
(Zhu eq. 5.3); the other (B) is held by the spindle above O at height ``H``
(Zhu eq. 5.6), so that the bar stands at its nominal length L. The table indexes
through angles c; the bar reads its length change Delta_1 = |L^E| - |L|
(Zhu eq. 5.10).

Forward model
-------------
The table's actual motion is the ideal rotation (Zhu eq. 5.1) preceded by its six
error components D_x, D_y, D_z, E_x, E_y, E_z (Zhu eq. 5.2, Fig. 5.1). Two
formulations are given and cross-checked in the tests:

* :func:`length_change` - exact: the HTM product with exact rotations, the bar
  vector (Zhu eqs. 5.4-5.9) and its norm;
* :func:`squared_length_change` - Zhu's first-order closed form of
  Delta_2' = |L^E'|^2 - |L|^2 with the setup's eccentricity H_x, H_y (Zhu eq. 5.13).

A reading converts exactly to the squared change:
Delta_2' = (L + Delta_1)^2 - L^2 = 2 L Delta_1 + Delta_1^2.

Two setups cancel the eccentricity
----------------------------------
With a short (L1) and a long (L2) bar sharing the table socket (Zhu Fig. 5.3),
subtracting Zhu eq. 5.15 from Zhu eq. 5.14 leaves (Zhu eq. 5.16)

    Delta_2'(L1) - Delta_2'(L2) = 2 R_x (H2 - H1) sin(c) E_x
                                  - 2 R_x (H2 - H1) cos(c) E_y + 2 (H2 - H1) D_z

linear in (E_x, E_y, D_z) with the design J of Zhu eq. 5.19 (condition number
Zhu eq. 5.20). The radial errors D_x, D_y cancel with the eccentricity they are
coupled to (a reversal would be needed to separate them); E_z is not seen by
a ball bar at all. :func:`calibrate` estimates the three by the l2 norm (least
squares, Zhu eq. 5.17) and by the l-infinity norm (minimax, Zhu eq. 5.18, solved as a
linear programme) and compares them as Zhu's Table 5.3 does.

Units: metres, radians; angles in the data may be given in degrees where the
argument name says so.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray
from scipy.optimize import linprog

from ..errors import CalibrationError, InputDataError, ParameterError
from ..kinematics.htm import rotation_matrix_xyz
from ..validation import finite_array

#: Readings are length *changes*; anything larger is a length or a unit mistake.
MAX_PLAUSIBLE_CHANGE_M = 1e-3
ARCSEC = np.pi / (180.0 * 3600.0)


@dataclass(frozen=True)
class BallBarSetup:
    """Geometry of one ball-bar setup on a rotary table (Zhu eqs. 5.3, 5.6).

    Attributes
    ----------
    bar_length_m : float
        L, the bar's calibrated nominal length [m].
    radius_m : float
        R_x, radial distance of the table ball A from the table centre O [m].
    socket_height_m : float
        R_z, height of A above O [m].
    """

    bar_length_m: float
    radius_m: float
    socket_height_m: float = 0.0

    def __post_init__(self) -> None:
        for name in ("bar_length_m", "radius_m", "socket_height_m"):
            value = getattr(self, name)
            if not isinstance(value, (int, float, np.floating)) or not np.isfinite(value):
                raise ParameterError(f"ball bar setup: {name} must be a finite number "
                                     f"(got {value!r})")
        if self.radius_m <= 0.0:
            raise ParameterError(f"ball bar setup: radius_m (R_x) must be > 0 "
                                 f"(got {self.radius_m})")
        if self.bar_length_m <= self.radius_m:
            raise ParameterError(
                f"ball bar setup: a bar of {self.bar_length_m * 1e3:.3f} mm cannot reach a "
                f"ball {self.radius_m * 1e3:.3f} mm off the table centre (L must exceed R_x); "
                "wrong bar length or units?")

    @property
    def spindle_height_m(self) -> float:
        """H, height of the spindle ball B above O that makes |L| = L (Zhu eqs. 5.6, 5.8)."""
        return self.socket_height_m + float(np.sqrt(self.bar_length_m ** 2 - self.radius_m ** 2))

    @property
    def bar_angle_rad(self) -> float:
        """eta, the bar's angle to the table axis (Zhu: 52.26 deg for L1, 19.25 deg for L2)."""
        return float(np.arcsin(self.radius_m / self.bar_length_m))


@dataclass(frozen=True)
class RotaryAxisErrors:
    """The six error components of a C axis, constant over the turn (Zhu Fig. 5.1).

    ``radial_x_m``/``radial_y_m`` D_x, D_y; ``axial_m`` D_z [m];
    ``tilt_x_rad``/``tilt_y_rad`` E_x, E_y (wobble); ``positioning_rad`` E_z [rad].

    Attributes
    ----------
    radial_x_m, radial_y_m : float
        D_x, D_y, radial error motions [m].
    axial_m : float
        D_z, axial error motion [m].
    tilt_x_rad, tilt_y_rad : float
        E_x, E_y, tilt error motions (wobble) [rad].
    positioning_rad : float
        E_z, angular positioning error [rad].
    """

    radial_x_m: float = 0.0
    radial_y_m: float = 0.0
    axial_m: float = 0.0
    tilt_x_rad: float = 0.0
    tilt_y_rad: float = 0.0
    positioning_rad: float = 0.0


def _angles(angles_rad: ArrayLike) -> NDArray[np.float64]:
    return finite_array(angles_rad, "angles", ndim=1)


def length_change(angles_rad: ArrayLike, setup: BallBarSetup, errors: RotaryAxisErrors,
                  eccentricity_m: tuple[float, float] = (0.0, 0.0)) -> NDArray[np.float64]:
    """Delta_1 = |L^E'| - L at each angle, exactly (Zhu eqs. 5.2-5.10, 5.12).

    The actual table HTM is Trans(D) Rot(E_x, E_y, E_z) Rot_z(c) with exact
    rotations; B sits at (H_x, H_y, H) (Zhu eq. 5.12).

    Parameters
    ----------
    angles_rad : array_like, shape (n,)
        Table angles c [rad].
    setup : BallBarSetup
        The setup's geometry (L, R_x, R_z [m]).
    errors : RotaryAxisErrors
        The six error components (D [m], E [rad]).
    eccentricity_m : tuple of float, optional
        (H_x, H_y) of the spindle ball B from the table axis [m].

    Returns
    -------
    ndarray, shape (n,)
        Delta_1 [m].

    Raises
    ------
    InputDataError
        Angles not 1-D or not finite.
    """
    c = _angles(angles_rad)
    ideal = np.stack([np.cos(c), np.sin(c), np.zeros_like(c)], axis=1) * setup.radius_m
    ideal[:, 2] = setup.socket_height_m
    error_rotation = rotation_matrix_xyz(errors.tilt_x_rad, errors.tilt_y_rad,
                                         errors.positioning_rad)
    actual = ideal @ error_rotation.T + np.array([errors.radial_x_m, errors.radial_y_m,
                                                   errors.axial_m])
    spindle = np.array([eccentricity_m[0], eccentricity_m[1], setup.spindle_height_m])
    return np.linalg.norm(actual - spindle, axis=1) - setup.bar_length_m


def squared_length_change(angles_rad: ArrayLike, setup: BallBarSetup, errors: RotaryAxisErrors,
                          eccentricity_m: tuple[float, float] = (0.0, 0.0)
                          ) -> NDArray[np.float64]:
    """Delta_2' = |L^E'|^2 - |L|^2, Zhu's first-order closed form (Zhu eq. 5.13) [m^2].

    Parameters
    ----------
    angles_rad : array_like, shape (n,)
        Table angles c [rad].
    setup : BallBarSetup
        The setup's geometry (L, R_x, R_z [m]).
    errors : RotaryAxisErrors
        The six error components (D [m], E [rad]).
    eccentricity_m : tuple of float, optional
        (H_x, H_y) of the spindle ball B from the table axis [m].

    Returns
    -------
    ndarray, shape (n,)
        Delta_2' [m^2].

    Raises
    ------
    InputDataError
        Angles not 1-D or not finite.
    """
    c = _angles(angles_rad)
    r_x, r_z, h = setup.radius_m, setup.socket_height_m, setup.spindle_height_m
    h_x, h_y = eccentricity_m
    return (-2 * r_x * h * np.sin(c) * errors.tilt_x_rad
            + 2 * r_x * h * np.cos(c) * errors.tilt_y_rad
            + 2 * r_x * np.cos(c) * errors.radial_x_m + 2 * r_x * np.sin(c) * errors.radial_y_m
            + 2 * (r_z - h) * errors.axial_m
            - 2 * r_x * np.cos(c) * h_x - 2 * r_x * np.sin(c) * h_y + h_x ** 2 + h_y ** 2)


def squared_change_from_reading(length_change_m: ArrayLike, bar_length_m: float
                                ) -> NDArray[np.float64]:
    """Delta_2' = (L + Delta_1)^2 - L^2 = 2 L Delta_1 + Delta_1^2, exact [m^2].

    Parameters
    ----------
    length_change_m : array_like
        Readings Delta_1 [m], any shape.
    bar_length_m : float
        L [m].

    Returns
    -------
    ndarray
        Delta_2' [m^2], the readings' shape.
    """
    delta = np.asarray(length_change_m, dtype=np.float64)
    return 2.0 * bar_length_m * delta + delta ** 2


def difference_design(angles_rad: ArrayLike, short: BallBarSetup, long: BallBarSetup
                      ) -> NDArray[np.float64]:
    """J of Zhu eq. 5.19: columns for (E_x, E_y, D_z), shape (n, 3) [m^2/rad, m^2/rad, m].

    Parameters
    ----------
    angles_rad : array_like, shape (n,)
        Table angles c [rad].
    short, long : BallBarSetup
        The two setups, sharing the table ball (same R_x, R_z).

    Returns
    -------
    ndarray, shape (n, 3)
        J [m^2/rad, m^2/rad, m].

    Raises
    ------
    ParameterError
        Setups that do not share the table ball, or bars of equal length.
    InputDataError
        Angles not 1-D or not finite.
    """
    c = _angles(angles_rad)
    _check_pair(short, long)
    dh = long.spindle_height_m - short.spindle_height_m
    r_x = short.radius_m
    return np.column_stack([2 * r_x * dh * np.sin(c), -2 * r_x * dh * np.cos(c),
                            np.full_like(c, 2 * dh)])


def _check_pair(short: BallBarSetup, long: BallBarSetup) -> None:
    if not np.isclose(short.radius_m, long.radius_m, rtol=0, atol=1e-9) or \
            not np.isclose(short.socket_height_m, long.socket_height_m, rtol=0, atol=1e-9):
        raise ParameterError("ball bar: both setups must share the table ball A (same R_x and "
                             "R_z, Zhu Fig. 5.3); got R_x "
                             f"{short.radius_m * 1e3:.3f}/{long.radius_m * 1e3:.3f} mm, R_z "
                             f"{short.socket_height_m * 1e3:.3f}/"
                             f"{long.socket_height_m * 1e3:.3f} mm")
    if abs(long.bar_length_m - short.bar_length_m) < 1e-3:
        raise ParameterError("ball bar: the two bars must differ in length (Zhu eq. 5.16 divides "
                             "by H2 - H1); got "
                             f"{short.bar_length_m * 1e3:.3f} and {long.bar_length_m * 1e3:.3f} mm")


# ---------------------------------------------------------------------- estimation
@dataclass(frozen=True)
class NormFit:
    """One estimate of (E_x, E_y, D_z) and its residuals e_i = y_i - J_i p (Table 5.3).

    Attributes
    ----------
    method : str
        ``"l2"`` or ``"linf"``.
    parameters : ndarray, shape (3,)
        E_x [rad], E_y [rad], D_z [m].
    residuals : ndarray, shape (n,)
        e_i = y_i - J_i p [m^2].
    uncertainties : ndarray, shape (3,), or None
        Standard (k = 1) uncertainties [rad, rad, m]; l2 only.
    """

    method: str                                 # "l2" or "linf"
    parameters: NDArray[np.float64]             # (3,) E_x [rad], E_y [rad], D_z [m]
    residuals: NDArray[np.float64]              # (n,) [m^2]
    #: (3,) standard (k = 1) uncertainties; l2 only (from sigma^2 (J^T J)^-1).
    uncertainties: NDArray[np.float64] | None = None

    @property
    def max_abs(self) -> float:
        return float(np.max(np.abs(self.residuals)))

    @property
    def range(self) -> float:
        return float(np.ptp(self.residuals))

    @property
    def rms(self) -> float:
        return float(np.sqrt(np.mean(self.residuals ** 2)))

    def as_dict(self) -> dict:
        out = {"method": self.method,
               "tilt_x_rad": float(self.parameters[0]), "tilt_y_rad": float(self.parameters[1]),
               "axial_m": float(self.parameters[2]),
               "tilt_x_arcsec": float(self.parameters[0] / ARCSEC),
               "tilt_y_arcsec": float(self.parameters[1] / ARCSEC),
               "axial_um": float(self.parameters[2] * 1e6),
               "max_abs_residual_m2": self.max_abs, "range_residual_m2": self.range,
               "rms_residual_m2": self.rms}
        if self.uncertainties is not None:
            out["uncertainty_k1"] = {"tilt_x_rad": float(self.uncertainties[0]),
                                     "tilt_y_rad": float(self.uncertainties[1]),
                                     "axial_m": float(self.uncertainties[2])}
        return out


def _column_scale(design: NDArray) -> NDArray:
    scale = np.linalg.norm(design, axis=0)
    if np.any(scale == 0):
        raise CalibrationError("ball bar: a column of the design is zero")
    return scale


def fit_l2(design: NDArray, observed: NDArray) -> NormFit:
    """Least squares (l2 norm, Zhu eq. 5.17) with the parameters' covariance.

    Parameters
    ----------
    design : ndarray, shape (n, p)
        J (Zhu eq. 5.19) [m^2 per parameter unit].
    observed : ndarray, shape (n,)
        y, the squared-change differences [m^2].

    Returns
    -------
    NormFit
        ``"l2"``: parameters (p,) [rad, rad, m], residuals (n,) [m^2] and standard (k = 1)
        uncertainties (p,).

    Raises
    ------
    CalibrationError
        n <= p, or a zero column.
    """
    n, p = design.shape
    if n <= p:
        raise CalibrationError(f"ball bar: {n} readings cannot fix {p} parameters")
    scale = _column_scale(design)
    solution, *_ = np.linalg.lstsq(design / scale, observed, rcond=None)
    parameters = solution / scale
    residuals = observed - design @ parameters
    sigma2 = float(residuals @ residuals) / (n - p)
    normal = (design / scale).T @ (design / scale)
    covariance = sigma2 * np.linalg.inv(normal) / np.outer(scale, scale)
    return NormFit("l2", parameters, residuals, np.sqrt(np.diag(covariance)))


def fit_linf(design: NDArray, observed: NDArray) -> NormFit:
    """Minimax (l-infinity norm, Zhu eq. 5.18) as a linear programme.

    minimise t  subject to  -t <= y_i - J_i p <= t; solved by HiGHS on columns
    and observations scaled to order one.

    Parameters
    ----------
    design : ndarray, shape (n, p)
        J (Zhu eq. 5.19) [m^2 per parameter unit].
    observed : ndarray, shape (n,)
        y, the squared-change differences [m^2].

    Returns
    -------
    NormFit
        ``"linf"``: parameters (p,) [rad, rad, m] and residuals (n,) [m^2], no
        uncertainties.

    Raises
    ------
    CalibrationError
        n <= p, a zero column, or a linear programme that fails.
    """
    n, p = design.shape
    if n <= p:
        raise CalibrationError(f"ball bar: {n} readings cannot fix {p} parameters")
    scale = _column_scale(design)
    y_scale = float(np.max(np.abs(observed))) or 1.0
    a = design / scale
    y = observed / y_scale
    ones = np.ones((n, 1))
    a_ub = np.vstack([np.hstack([a, -ones]), np.hstack([-a, -ones])])
    b_ub = np.concatenate([y, -y])
    cost = np.zeros(p + 1)
    cost[-1] = 1.0
    bounds = [(None, None)] * p + [(0.0, None)]
    result = linprog(cost, A_ub=a_ub, b_ub=b_ub, bounds=bounds, method="highs")
    if not result.success:
        raise CalibrationError(f"ball bar: the l-infinity programme failed ({result.message})")
    parameters = result.x[:p] * y_scale / scale
    return NormFit("linf", parameters, observed - design @ parameters)


# ------------------------------------------------------------------- data checks
#: The shortest arc a run may index [deg]: below it the tilts and the axial error cannot
#: be told apart (the design's condition number grows without bound), and an arc
#: this short is more often radians written in a degree column.
MIN_ARC_DEG = 90.0

#: A fit whose remaining scatter exceeds the readings' repeatability by this factor is
#: a misfit: the model of the setup (radius, bar lengths, units) is not these data's.
MISFIT_FACTOR = 3.0

#: Tilts of a rotary table's axis beyond this are not a table's (Zhu's Table 5.2: a few
#: arc seconds; 60" is generous) [rad].
PLAUSIBLE_TILT_RAD = 60.0 * np.pi / 648000.0


@dataclass(frozen=True)
class BallBarRun:
    """The readings of one setup: ``repetitions`` x ``angles`` (Zhu: 3 x 37).

    ``angles_rad`` (n,) in the order the table indexed them; ``readings_m``
    (r, n) the bar's length change Delta_1 [m] at each angle of each repetition.

    Attributes
    ----------
    setup : BallBarSetup
        The setup's geometry.
    angles_rad : ndarray, shape (n,)
        Table angles [rad], in the order indexed (at least 5).
    readings_m : ndarray, shape (r, n)
        Length changes Delta_1 [m] per repetition and angle (one row may be given as (n,)).
    label : str, optional
        The run's name (default from the bar length).
    """

    setup: BallBarSetup
    angles_rad: NDArray[np.float64]
    readings_m: NDArray[np.float64]
    label: str = ""

    def __post_init__(self) -> None:
        name = self.name
        angles = np.asarray(self.angles_rad, dtype=np.float64)
        readings = np.atleast_2d(np.asarray(self.readings_m, dtype=np.float64))
        if angles.ndim != 1 or angles.size < 5:
            raise InputDataError(f"{name}: at least 5 angular positions are needed "
                                 f"(got {angles.size})")
        if not np.all(np.isfinite(angles)):
            raise InputDataError(f"{name}: angle {int(np.flatnonzero(~np.isfinite(angles))[0])} "
                                 "is not a number")
        steps = np.diff(angles)
        if np.all(steps == 0):
            raise InputDataError(f"{name}: every reading is at {np.degrees(angles[0]):.3f} deg; "
                                 "a run indexes the table through an arc")
        span_deg = float(np.degrees(np.ptp(angles)))
        if span_deg <= MIN_ARC_DEG:
            hint = " - or radians in the angle_deg column" if span_deg <= 2 * np.pi * 1.01 \
                else ""
            raise InputDataError(f"{name}: the table angles span only {span_deg:.3g} deg: too "
                                 f"short an arc to separate E_x, E_y and D_z (index at least "
                                 f"{MIN_ARC_DEG:g} deg, a full turn as Zhu does){hint}")
        if not (np.all(steps > 0) or np.all(steps < 0)):
            where = int(np.flatnonzero(np.sign(steps) != np.sign(steps[0]))[0]) + 1
            raise InputDataError(
                f"{name}: the angle sequence is not monotonic at position {where} "
                f"({np.degrees(angles[where - 1]):.3f} -> {np.degrees(angles[where]):.3f} deg); "
                "one run must index the table one way")
        if readings.shape[1] != angles.size:
            raise InputDataError(f"{name}: {readings.shape[1]} readings per repetition for "
                                 f"{angles.size} angles")
        bad = ~np.isfinite(readings)
        if bad.any():
            rep, pos = (int(i) for i in np.argwhere(bad)[0])
            raise InputDataError(f"{name}: reading of repetition {rep + 1} at "
                                 f"{np.degrees(angles[pos]):.3f} deg is not a number")
        largest = float(np.max(np.abs(readings)))
        if largest > MAX_PLAUSIBLE_CHANGE_M:
            raise InputDataError(
                f"{name}: a length change of {largest * 1e3:.3f} mm is not a ball-bar reading "
                "(readings are changes from the nominal length, in metres; wrong units or "
                "absolute lengths?)")
        object.__setattr__(self, "angles_rad", angles)
        object.__setattr__(self, "readings_m", readings)

    @property
    def name(self) -> str:
        return self.label or f"{self.setup.bar_length_m * 1e3:.3f} mm bar"

    @property
    def mean_reading_m(self) -> NDArray[np.float64]:
        return self.readings_m.mean(axis=0)

    @property
    def repeatability_m(self) -> float:
        """Pooled standard deviation of the repetitions at each angle [m] (0 with one)."""
        r = self.readings_m.shape[0]
        if r < 2:
            return 0.0
        return float(np.sqrt(np.mean(self.readings_m.var(axis=0, ddof=1))))


def _match_angles(short: BallBarRun, long: BallBarRun) -> None:
    a = np.degrees(short.angles_rad)
    b = np.degrees(long.angles_rad)
    tolerance = 1e-3
    missing_long = [x for x in a if not np.any(np.abs(b - x) < tolerance)]
    missing_short = [x for x in b if not np.any(np.abs(a - x) < tolerance)]
    if missing_long or missing_short:
        which, run, other = ((missing_long, long, short) if missing_long
                             else (missing_short, short, long))
        listed = ", ".join(f"{x:.1f}" for x in which[:5]) + (" ..." if len(which) > 5 else "")
        raise InputDataError(f"ball bar: {run.name} has no reading at {listed} deg where "
                             f"{other.name} has; both setups must index the same positions")
    if a.size != b.size or np.any(np.abs(a - b) > tolerance):
        raise InputDataError(f"ball bar: {short.name} and {long.name} index the same positions "
                             "in a different order")


# ------------------------------------------------------------------ calibration
@dataclass(frozen=True)
class SingleSetupFit:
    """Zhu eq. 5.13 fitted to one setup: Delta_2' = a sin c + b cos c + k.

    The coupled sums cannot be separated with one setup: a = -2 R_x H E_x +
    2 R_x (D_y - H_y), b = 2 R_x H E_y + 2 R_x (D_x - H_x). With the tilts known
    from the two-setup fit they give the radial error less the eccentricity.

    Attributes
    ----------
    run : str
        The run's name.
    coefficients : ndarray, shape (3,)
        (a, b, k) [m^2].
    residuals : ndarray, shape (n,)
        [m^2].
    radial_less_eccentricity_m : ndarray, shape (2,)
        (D_x - H_x, D_y - H_y) [m].
    """

    run: str
    coefficients: NDArray[np.float64]       # (a, b, k) [m^2]
    residuals: NDArray[np.float64]          # (n,) [m^2]
    radial_less_eccentricity_m: NDArray[np.float64]   # (D_x - H_x, D_y - H_y) [m]


@dataclass(frozen=True)
class ReversalJump:
    """The jump between two readings at the same table angle (0 and 360 deg).

    A rotary axis's lost motion shows here (Zhu Fig. 5.13): the first reading
    was approached from the other direction. ``jump`` in the residual's unit,
    ``noise`` the residuals' robust standard deviation without the two ends.

    Attributes
    ----------
    run : str
        The run's (or the difference's) name.
    jump : float
        First minus last residual, in the residual's unit ([m^2] here).
    noise : float
        Robust standard deviation of the other residuals, same unit.
    """

    run: str
    jump: float
    noise: float

    @property
    def significant(self) -> bool:
        return abs(self.jump) > 4.0 * np.sqrt(2.0) * self.noise


@dataclass
class BallBarCalibration:
    """Result of :func:`calibrate` (Zhu section 5.4, Tables 5.2 and 5.3).

    Attributes
    ----------
    short, long : BallBarRun
        The two runs (``short`` the shorter bar).
    observed : ndarray, shape (n,)
        Delta_2'(L1) - Delta_2'(L2) [m^2].
    design : ndarray, shape (n, 3)
        J of Zhu eq. 5.19 [m^2/rad, m^2/rad, m].
    l2, linf : NormFit
        The two estimates of (E_x, E_y, D_z).
    condition_number : float
        cond(J), Zhu eq. 5.20.
    single_setups : list of SingleSetupFit
        Zhu eq. 5.13 per run.
    reversal : list of ReversalJump
        The closing jumps of the runs and of the difference.
    socket_change_m : float
        The unseen socket change allowed for [m].
    socket_u, drift_u : ndarray, shape (3,), or None
        What it and the runs' drift add to the l2 standard uncertainties [rad, rad, m].
    """

    short: BallBarRun
    long: BallBarRun
    observed: NDArray[np.float64]           # (n,) Delta_2'(L1) - Delta_2'(L2) [m^2]
    design: NDArray[np.float64]             # (n, 3), Zhu eq. 5.19
    l2: NormFit
    linf: NormFit
    condition_number: float                 # Zhu eq. 5.20
    single_setups: list[SingleSetupFit] = field(default_factory=list)
    reversal: list[ReversalJump] = field(default_factory=list)
    #: The unseen socket change allowed for, and what it and the runs' drift add to the
    #: l2 parameters' standard uncertainties (3,) [rad, rad, m] (already in l2's).
    socket_change_m: float = 0.0
    socket_u: NDArray[np.float64] | None = None
    drift_u: NDArray[np.float64] | None = None

    @property
    def angles_rad(self) -> NDArray[np.float64]:
        return self.short.angles_rad

    def as_dict(self) -> dict:
        return {
            "short_bar_m": self.short.setup.bar_length_m,
            "long_bar_m": self.long.setup.bar_length_m,
            "radius_m": self.short.setup.radius_m,
            "socket_height_m": self.short.setup.socket_height_m,
            "bar_angles_deg": [float(np.degrees(self.short.setup.bar_angle_rad)),
                               float(np.degrees(self.long.setup.bar_angle_rad))],
            "positions": int(self.angles_rad.size),
            "repetitions": [int(self.short.readings_m.shape[0]),
                            int(self.long.readings_m.shape[0])],
            "repeatability_m": [self.short.repeatability_m, self.long.repeatability_m],
            "condition_number": self.condition_number,
            "l2": self.l2.as_dict(), "linf": self.linf.as_dict(),
            "radial_less_eccentricity_m": {f.run: f.radial_less_eccentricity_m.tolist()
                                           for f in self.single_setups},
            "reversal_jumps": [{"run": j.run, "jump_m2": j.jump, "noise_m2": j.noise,
                                "significant": bool(j.significant)} for j in self.reversal],
            "scatter_m": self.scatter_m, "misfit": self.misfit,
            "implausible": self.implausible,
            "axis_line": self.axis_line().as_dict(),
        }

    def axis_line(self) -> AxisLineReading:
        """The same fit read as ISO 230-7 location errors of the C axis line."""
        return axis_line_reading(self)

    @property
    def scatter_m(self) -> float:
        """The l2 fit's remaining scatter as a bar reading [m]: the squared-change residual
        (m^2) over the derivative of the squared change, 2 L, of the longer bar (the one
        whose reading a residual of the difference resembles least)."""
        bar = max(self.short.setup.bar_length_m, self.long.setup.bar_length_m)
        return float(self.l2.rms / (2.0 * bar))

    @property
    def repeatability_m(self) -> float:
        """The readings' repeatability [m]: the larger run's pooled standard deviation."""
        return max(self.short.repeatability_m, self.long.repeatability_m)

    @property
    def implausible(self) -> str:
        """A result no rotary table gives ("" when plausible): a tilt above
        :data:`PLAUSIBLE_TILT_RAD` - what a unit slip in R_x or the socket height makes of
        a good fit (the design scales with them, the scatter does not show it)."""
        tilts = np.abs(self.l2.parameters[:2])
        if np.max(tilts) <= PLAUSIBLE_TILT_RAD:
            return ""
        return (f"implausible: a tilt of {np.max(tilts) / ARCSEC:.0f}\" (a rotary table's is "
                f"seldom above {PLAUSIBLE_TILT_RAD / ARCSEC:.0f}\") - check the units of R_x "
                f"(--radius-mm, here {self.short.setup.radius_m * 1e3:.4g} mm) and of the "
                "socket height")

    @property
    def misfit(self) -> str:
        """Why the fit does not describe the data ("" when it does): a remaining scatter
        well above the repeatability, with the likely causes."""
        floor = max(self.repeatability_m, 0.05e-6)
        if self.repeatability_m <= 0 or self.scatter_m <= MISFIT_FACTOR * floor:
            return ""
        return (f"misfit: the fit leaves {self.scatter_m * 1e6:.2f} um of scatter, "
                f"{self.scatter_m / floor:.0f} x the readings' repeatability "
                f"({self.repeatability_m * 1e6:.2f} um) - check R_x (--radius-mm) and the "
                "socket height, the bar lengths, the reading units, and that the setup did "
                "not move between the runs")

    def text(self) -> str:
        lines = [f"ball bar: {self.angles_rad.size} positions, bars "
                 f"{self.short.setup.bar_length_m * 1e3:.3f} / "
                 f"{self.long.setup.bar_length_m * 1e3:.3f} mm, R_x "
                 f"{self.short.setup.radius_m * 1e3:.3f} mm, cond(J) {self.condition_number:.1f}"]
        u = self.l2.uncertainties
        for fit in (self.l2, self.linf):
            p = fit.parameters
            spread = (f" (U, k=2: {2 * u[0] / ARCSEC:.2f}\", {2 * u[1] / ARCSEC:.2f}\", "
                      f"{2 * u[2] * 1e6:.2f} um)" if fit.uncertainties is not None else "")
            lines.append(f"  {fit.method:>4}: E_x {p[0] / ARCSEC:7.2f}\""
                         f"  E_y {p[1] / ARCSEC:7.2f}\""
                         f"  D_z {p[2] * 1e6:6.2f} um{spread}; residual max "
                         f"{fit.max_abs * 1e6:.3f} mm^2, range {fit.range * 1e6:.3f} mm^2, "
                         f"RMS {fit.rms * 1e6:.3f} mm^2")
        lines.append(f"  repeatability {self.short.repeatability_m * 1e6:.2f} / "
                     f"{self.long.repeatability_m * 1e6:.2f} um (short / long bar); the l2 fit "
                     f"leaves {self.scatter_m * 1e6:.2f} um RMS as a bar reading")
        lines += self.axis_line().lines()
        for problem in (self.misfit, self.implausible):
            if problem:
                lines.append(f"  {problem}")
        if self.condition_number > ILL_CONDITIONED:
            lines.append(f"  warning: a badly conditioned design (cond(J) "
                         f"{self.condition_number:.3g}, Zhu eq. 5.20; a full turn gives about 20): "
                         "the arc or the bar lengths barely separate E_x, E_y and D_z")
        if self.socket_u is not None and self.socket_change_m > 0:
            lines.append(f"  in U: the table ball re-seating by up to "
                         f"{self.socket_change_m * 1e6:.2g} um between the setups (two setups "
                         "cannot show it) - E_x, E_y "
                         f"+-{self.socket_u[0] * np.sqrt(3) / ARCSEC:.2f}\"")
        if self.drift_u is not None and np.any(self.drift_u > 0):
            lines.append(f"  in U: a drift over each run as large as its closing-reading jump "
                         f"- E_x {self.drift_u[0] * np.sqrt(3) / ARCSEC:.2f}\", "
                         f"E_y {self.drift_u[1] * np.sqrt(3) / ARCSEC:.2f}\", "
                         f"D_z {self.drift_u[2] * np.sqrt(3) * 1e6:.2f} um")
        for jump in self.reversal:
            if jump.significant:
                lines.append(f"  {jump.run}: a jump of {jump.jump * 1e6:.4f} mm^2 between 0 and "
                             "360 deg - lost motion (backlash) of the rotary axis, or a drift "
                             "during the run")
        return "\n".join(lines)


def _robust_sigma(values: NDArray) -> float:
    return float(1.4826 * np.median(np.abs(values - np.median(values))))


def _same_angle_ends(angles: NDArray) -> bool:
    turn = abs(angles[-1] - angles[0])
    return abs(turn - 2 * np.pi) < 1e-6


def _single_setup(run: BallBarRun, tilts: NDArray) -> SingleSetupFit:
    c = run.angles_rad
    y = squared_change_from_reading(run.mean_reading_m, run.setup.bar_length_m)
    design = np.column_stack([np.sin(c), np.cos(c), np.ones_like(c)])
    coefficients, *_ = np.linalg.lstsq(design, y, rcond=None)
    r_x, h = run.setup.radius_m, run.setup.spindle_height_m
    a, b, _ = coefficients
    radial_y = (a + 2 * r_x * h * tilts[0]) / (2 * r_x)
    radial_x = (b - 2 * r_x * h * tilts[1]) / (2 * r_x)
    return SingleSetupFit(run.name, coefficients, y - design @ coefficients,
                          np.array([radial_x, radial_y]))


def reversal_jump(run_name: str, angles_rad: NDArray, residuals: NDArray) -> ReversalJump | None:
    """The 0/360 deg jump of a residual, or None when the run is not a full turn.

    Parameters
    ----------
    run_name : str
        The run, named in the result.
    angles_rad : ndarray, shape (n,)
        Table angles [rad], in the order indexed.
    residuals : ndarray, shape (n,)
        A fit's residuals, any unit (here [m^2]).

    Returns
    -------
    ReversalJump or None
        First minus last residual and the robust noise of the others (the residuals'
        unit); None unless the last angle is a full turn from the first and n >= 5.
    """
    if not _same_angle_ends(angles_rad) or residuals.size < 5:
        return None
    return ReversalJump(run_name, float(residuals[0] - residuals[-1]),
                        _robust_sigma(residuals[1:-1]))


#: cond(J) (Zhu eq. 5.20) above which the design is called badly conditioned: a full turn
#: with Zhu's bars gives about 20.
ILL_CONDITIONED = 100.0

#: How far the table ball may re-seat between the two setups unseen [m] (a kinematic
#: socket's repeatability): two setups cannot show it (see :func:`calibrate`).
SOCKET_CHANGE_M = 1e-6


def calibrate(short: BallBarRun, long: BallBarRun, *,
              socket_change_m: float = SOCKET_CHANGE_M) -> BallBarCalibration:
    """E_x, E_y, D_z from a short- and a long-bar run (Zhu eqs. 5.14-5.19), l2 and l-infinity.

    The l2 uncertainties also carry two effects the fit itself cannot see:

    * a **change of the table ball's position** (eccentricity H) between the setups by up
      to ``socket_change_m``: it enters the difference (Zhu eq. 5.19) as 2 R_x dH (sin, cos)
      c - the tilts' own columns over the spindle-height difference - so it shifts E_x,
      E_y by dH / dh, and the two single-setup fits agree whatever dH is (four harmonic
      coefficients, four unknowns): only a third setup would show it. Taken as a
      rectangular bound;
    * a **drift during a run**, read at its closing reading (a full turn reads the start
      angle twice): the jump between them as a linear ramp over the run's readings,
      propagated through the fit, also a rectangular bound (a lost motion of the axis
      makes the same jump; either way the result is that uncertain).

    Parameters
    ----------
    short, long : BallBarRun
        The two runs, indexing the same angles (swapped if ``long`` has the shorter bar).
    socket_change_m : float, optional
        Largest unseen re-seat of the table ball between the setups [m].

    Returns
    -------
    BallBarCalibration
        The l2 and l-infinity fits of (E_x [rad], E_y [rad], D_z [m]), the design (n, 3)
        and observations (n,) [m^2], cond(J), the single-setup fits and the runs'
        closing jumps.

    Raises
    ------
    ParameterError
        Setups that do not share the table ball, or bars of equal length.
    InputDataError
        Runs that index different positions.
    CalibrationError
        A singular design (Zhu eq. 5.20).
    """
    _check_pair(short.setup, long.setup)
    _match_angles(short, long)
    if long.setup.bar_length_m < short.setup.bar_length_m:
        short, long = long, short
    angles = short.angles_rad
    observed = (squared_change_from_reading(short.mean_reading_m, short.setup.bar_length_m)
                - squared_change_from_reading(long.mean_reading_m, long.setup.bar_length_m))
    design = difference_design(angles, short.setup, long.setup)
    singular = np.linalg.svd(design, compute_uv=False)
    if singular[-1] <= singular[0] * 1e-12:
        raise CalibrationError("ball bar: the positions do not separate E_x, E_y and D_z "
                               "(singular design, Zhu eq. 5.20); index the table over a wider arc")
    l2 = fit_l2(design, observed)
    linf = fit_linf(design, observed)
    singles = [_single_setup(run, l2.parameters[:2]) for run in (short, long)]
    jumps = [j for j in (reversal_jump(f.run, angles, f.residuals) for f in singles) if j]
    difference_jump = reversal_jump("two-setup difference", angles, l2.residuals)
    if difference_jump:
        jumps.append(difference_jump)
    # What the fit cannot see, carried into U (rectangular bounds, as standard deviations).
    dh = long.setup.spindle_height_m - short.setup.spindle_height_m
    socket = np.array([socket_change_m / abs(dh), socket_change_m / abs(dh), 0.0]) / np.sqrt(3)
    ramp = np.linspace(0.0, 1.0, angles.size)
    drift = np.zeros(3)
    for jump in jumps[:2]:                 # the two runs' own closing readings
        shift, *_ = np.linalg.lstsq(design, jump.jump * ramp, rcond=None)
        drift = np.hypot(drift, np.abs(shift) / np.sqrt(3))
    if l2.uncertainties is not None:
        l2 = NormFit(l2.method, l2.parameters, l2.residuals,
                     np.sqrt(l2.uncertainties ** 2 + socket ** 2 + drift ** 2))
    return BallBarCalibration(short, long, observed, design, l2, linf,
                              float(singular[0] / singular[-1]), singles, jumps,
                              socket_change_m=socket_change_m, socket_u=socket, drift_u=drift)


# ----------------------------------------------------- the ISO 230-7 reading
@dataclass(frozen=True)
class AxisLineReading:
    """Zhu's fit read as location errors of the C axis line (ISO 230-7).

    Zhu's model (Zhu eq. 5.2) moves the table by constant *error motions* after the ideal
    turn; ISO 230-7 instead turns the table about its actual axis line, and the table
    ball is where it was set at c = 0. To first order the two describe the same
    readings with (derived in ``docs/rotary.md``):

    * EA0C = E_x, EB0C = E_y: the line's tilts about x and y;
    * the table ball's height offset at the set-up, D_z - R_x E_y: Zhu's D_z also holds
      the rise R_x E_y that a line tilted by E_y gives the ball at c = 0, which the
      line convention books as the ball's set-up, not the axis;
    * per setup, EX0C - H_x and EY0C - H_y from the single-setup fit (Zhu eq. 5.13): the
      line's offset from the spindle ball. They are the line's location errors only
      when the spindle ball stood at the machine's nominal C centre (H = 0); the two
      setups cancel them in the difference (Zhu eq. 5.16), so they carry the single-setup
      fits' uncertainty, not the tilts' U.

    Angles [rad], lengths [m]; ``*_u_k2`` expanded uncertainties (k = 2).

    Attributes
    ----------
    ea0c_rad, eb0c_rad : float
        The C line's tilts about x and y [rad].
    ea0c_u_k2, eb0c_u_k2 : float
        Their expanded uncertainties (k = 2) [rad].
    ball_height_offset_m : float
        D_z - R_x E_y [m].
    ball_height_offset_u_k2 : float
        Its expanded uncertainty (k = 2) [m].
    line_offset_from_spindle_ball_m : dict of str to tuple of float
        Run name -> (EX0C - H_x, EY0C - H_y) [m].
    """

    ea0c_rad: float
    eb0c_rad: float
    ea0c_u_k2: float
    eb0c_u_k2: float
    ball_height_offset_m: float
    ball_height_offset_u_k2: float
    line_offset_from_spindle_ball_m: dict[str, tuple[float, float]]

    def as_dict(self) -> dict:
        return {"convention": "ISO 230-7: the table turns about its actual axis line; "
                              "the table ball set at c = 0",
                "EA0C_rad": self.ea0c_rad, "EB0C_rad": self.eb0c_rad,
                "EA0C_u_k2_rad": self.ea0c_u_k2, "EB0C_u_k2_rad": self.eb0c_u_k2,
                "ball_height_offset_m": self.ball_height_offset_m,
                "ball_height_offset_u_k2_m": self.ball_height_offset_u_k2,
                "line_offset_from_spindle_ball_m": {
                    run: list(xy) for run, xy in self.line_offset_from_spindle_ball_m.items()},
                "assumption": "EX0C, EY0C equal the line's offset from the spindle ball only "
                              "if the spindle ball stood at the machine's nominal C centre"}

    def lines(self) -> list[str]:
        """The reading in words, with what it assumes."""
        offsets = "; ".join(f"{run} {x * 1e6:+.2f} / {y * 1e6:+.2f} um"
                            for run, (x, y) in self.line_offset_from_spindle_ball_m.items())
        return [f"  as ISO 230-7 location errors of the C line (the table turns about its "
                f"actual line; the ball set at c = 0): EA0C {self.ea0c_rad * 1e6:+.2f} "
                f"+- {self.ea0c_u_k2 * 1e6:.2f} urad, EB0C {self.eb0c_rad * 1e6:+.2f} "
                f"+- {self.eb0c_u_k2 * 1e6:.2f} urad (k = 2); the ball's set-up height "
                f"offset {self.ball_height_offset_m * 1e6:+.2f} "
                f"+- {self.ball_height_offset_u_k2 * 1e6:.2f} um (D_z - R_x E_y)",
                f"  EX0C, EY0C as the line's offset from the spindle ball (x / y): {offsets}"
                " - the line's location errors if the spindle ball stood at the nominal C "
                "centre, else its set-up eccentricity (the difference of the setups "
                "cancels them, Zhu eq. 5.16)"]


def axis_line_reading(calibration: BallBarCalibration) -> AxisLineReading:
    """:class:`AxisLineReading` of a calibration (first order in the errors).

    Parameters
    ----------
    calibration : BallBarCalibration
        The result of :func:`calibrate`.

    Returns
    -------
    AxisLineReading
        EA0C, EB0C [rad], the ball's set-up height offset [m] and the line's offsets from
        the spindle ball per run [m], with expanded uncertainties (k = 2).
    """
    e_x, e_y, d_z = calibration.l2.parameters
    r_x = calibration.short.setup.radius_m
    u = (calibration.l2.uncertainties if calibration.l2.uncertainties is not None
         else np.zeros(3))
    height = d_z - r_x * e_y          # Zhu eq. 5.2 rewritten about the actual line
    # The height's variance: D_z and E_y's are correlated through the design; the l2
    # covariance is not kept, so the two are added in quadrature - a bound, not a guess.
    height_u = float(np.hypot(u[2], r_x * u[1]))
    offsets = {f.run: (float(f.radial_less_eccentricity_m[0]),
                       float(f.radial_less_eccentricity_m[1]))
               for f in calibration.single_setups}
    return AxisLineReading(float(e_x), float(e_y), float(2 * u[0]), float(2 * u[1]),
                           float(height), 2 * height_u, offsets)
