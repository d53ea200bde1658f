"""Position-dependent error functions of an axis: constant, table, polynomial, profile.

A machine description gives each of an axis' six error motions (positioning,
two straightness, roll, pitch, yaw) as one of these; all evaluate vectorised
over positions in metres (linear axes) or radians (rotary axes) and return
metres or radians.
"""
from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import MachineDescriptionError


@dataclass(frozen=True)
class ErrorFunction:
    """One error motion as a function of the axis position.

    kind : ``"constant"``, ``"table"`` (piecewise-linear, flat beyond the ends),
    ``"polynomial"`` (coefficients c0, c1, ... of position^i) or ``"profile"``
    (a measured profile, e.g. a kNN systematic profile: same as a table).

    Calling it with positions, shape ``S``, [m] (linear axis) or [rad] (rotary
    axis) returns the error, shape ``S``, [m] (translational motion) or [rad]
    (angular motion).

    Parameters
    ----------
    kind : {"constant", "table", "profile", "polynomial"}
        Form of the function, as above.
    value : float
        The constant's value [m] or [rad] (``kind="constant"``).
    positions : ndarray, shape (K,)
        Strictly ascending table / profile positions [m] or [rad].
    values : ndarray, shape (K,)
        Error at ``positions`` [m] or [rad].
    coefficients : ndarray, shape (P,)
        Polynomial coefficients c0, c1, ...; ``c_i`` in [m or rad] / [position unit]^i.
    """

    kind: str = "constant"
    value: float = 0.0
    positions: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    values: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))
    coefficients: NDArray[np.float64] = field(default_factory=lambda: np.zeros(0))

    def __call__(self, position: ArrayLike) -> NDArray[np.float64]:
        q = np.asarray(position, dtype=np.float64)
        if self.kind == "constant":
            return np.full(q.shape, self.value)
        if self.kind in ("table", "profile"):
            return np.interp(q, self.positions, self.values)
        return np.polynomial.polynomial.polyval(q, self.coefficients)

    @property
    def is_zero(self) -> bool:
        if self.kind == "constant":
            return self.value == 0.0
        if self.kind in ("table", "profile"):
            return not np.any(self.values)
        return not np.any(self.coefficients)


def parse_error_function(spec, where: str) -> ErrorFunction:
    """Build an :class:`ErrorFunction` from its YAML form; errors name ``where``.

    Accepted forms: a number; ``{table: {positions: [...], values: [...]}}``;
    ``{profile: {positions: [...], values: [...]}}``; ``{polynomial: [c0, c1, ...]}``.

    Parameters
    ----------
    spec : float or dict
        The YAML value, positions in [m] / [rad], values in [m] / [rad].
    where : str
        Where ``spec`` sits in the description (e.g. ``"axes.X.errors.EXX"``),
        quoted in error messages.

    Returns
    -------
    ErrorFunction
        The parsed function.

    Raises
    ------
    MachineDescriptionError
        If the form is unknown, a value is not a finite number, a table has fewer
        than two points, unequal lengths or positions not strictly ascending.
    """
    def finite(values, name):
        try:
            array = np.asarray(values, dtype=np.float64)
        except (TypeError, ValueError) as exc:
            raise MachineDescriptionError(f"{where}.{name}: not numbers ({exc})") from exc
        if not np.all(np.isfinite(array)):
            raise MachineDescriptionError(f"{where}.{name}: non-finite value (NaN or inf)")
        return array

    if isinstance(spec, (int, float)) and not isinstance(spec, bool):
        return ErrorFunction(kind="constant", value=float(finite(spec, "value")))
    if not isinstance(spec, dict) or len(spec) != 1:
        raise MachineDescriptionError(
            f"{where}: expected a number or one of {{table, profile, polynomial}}, got {spec!r}")
    (kind, body), = spec.items()
    if kind in ("table", "profile"):
        if not isinstance(body, dict) or set(body) != {"positions", "values"}:
            raise MachineDescriptionError(f"{where}.{kind}: needs exactly 'positions' and 'values'")
        positions = finite(body["positions"], f"{kind}.positions")
        values = finite(body["values"], f"{kind}.values")
        if positions.ndim != 1 or positions.shape != values.shape or positions.size < 2:
            raise MachineDescriptionError(
                f"{where}.{kind}: positions and values must be equal-length lists of >= 2")
        if np.any(np.diff(positions) <= 0):
            raise MachineDescriptionError(f"{where}.{kind}.positions: must be strictly ascending")
        return ErrorFunction(kind=kind, positions=positions, values=values)
    if kind == "polynomial":
        coefficients = finite(body, "polynomial")
        if coefficients.ndim != 1 or coefficients.size == 0:
            raise MachineDescriptionError(f"{where}.polynomial: needs a list of coefficients")
        return ErrorFunction(kind="polynomial", coefficients=coefficients)
    raise MachineDescriptionError(f"{where}: unknown error form {kind!r}; "
                                  "use table, profile or polynomial")


def sampled(function: ErrorFunction, grid: ArrayLike) -> ErrorFunction:
    """The function as a table on ``grid`` (what a CNC compensation table holds).

    Parameters
    ----------
    function : ErrorFunction
        The error function to sample.
    grid : array_like, shape (K,)
        Ascending positions [m] (linear axis) or [rad] (rotary axis).

    Returns
    -------
    ErrorFunction
        ``kind="table"`` with ``positions=grid`` and ``values=function(grid)``.
    """
    g = np.asarray(grid, dtype=np.float64)
    return ErrorFunction(kind="table", positions=g, values=function(g))


def from_profile(positions: ArrayLike, systematic: ArrayLike) -> ErrorFunction:
    """An error function from a measured profile, e.g. the kNN systematic error
    of :func:`mt_accuracy_ros.core.scales.knn.extract_systematic` (positions ascending).

    Parameters
    ----------
    positions : array_like, shape (K,)
        Strictly ascending positions [m] (linear axis) or [rad] (rotary axis), K >= 2.
    systematic : array_like, shape (K,)
        Error at each position [m] or [rad].

    Returns
    -------
    ErrorFunction
        ``kind="profile"`` (interpolated linearly, flat beyond the ends).

    Raises
    ------
    MachineDescriptionError
        If the profile is not finite, too short or not strictly ascending.
    """
    return parse_error_function({"profile": {"positions": np.asarray(positions).tolist(),
                                             "values": np.asarray(systematic).tolist()}},
                                "profile")
