"""Thermal links of the kinematic chain (Zhu eq. 4.2, chapter 4, Table 4.2).

A link (a column, a spindle head, a bed segment) deforms with its own
temperatures: its end moves by the expansion epsilon along the link, by the
deflection delta across it and turns by the slope theta about the third axis.
Each of the three is a linear model of the link's temperatures (Zhu eq. 3.12,
fitted with :func:`~.regression.fit_linear`); :meth:`ThermalLink.twist`
turns them into the small-displacement twist (dx, dy, dz, ex, ey, ez) that
:class:`~.kinematics.ErrorOverrides` ``thermal[axis]`` applies as the link HTM
(the first-order form of :func:`~.htm.thermal_link_htm`).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError, ParameterError
from .regression import LinearThermalModel, fit_linear

AXES = "xyz"


@dataclass
class ThermalLink:
    """One thermal link: which sensors drive it, its axes, and its three models.

    ``length_axis`` / ``deflection_axis`` as in :func:`~.htm.thermal_link_htm`;
    a model left None contributes zero.
    """

    name: str
    sensors: list[str]
    length_axis: str = "z"
    deflection_axis: str = "y"
    expansion: LinearThermalModel | None = None
    deflection: LinearThermalModel | None = None
    slope: LinearThermalModel | None = None

    def __post_init__(self) -> None:
        if self.length_axis not in AXES or self.deflection_axis not in AXES or \
                self.length_axis == self.deflection_axis:
            raise ParameterError(f"link {self.name}: length_axis and deflection_axis must be two "
                                 f"different of x, y, z")

    @property
    def normal_axis(self) -> str:
        return next(a for a in AXES if a not in (self.length_axis, self.deflection_axis))

    def _columns(self, temperatures: dict[str, ArrayLike]) -> NDArray[np.float64]:
        missing = [s for s in self.sensors if s not in temperatures]
        if missing:
            raise InputDataError(f"link {self.name}: no temperature for {', '.join(missing)}")
        return np.column_stack([np.atleast_1d(np.asarray(temperatures[s], float))
                                for s in self.sensors])

    def deformation(self, temperatures: dict[str, ArrayLike]) -> dict[str, NDArray[np.float64]]:
        """epsilon [m], delta [m], theta [rad] per sample (Zhu Table 4.2).

        Parameters
        ----------
        temperatures : dict of str to array_like, shape (N,)
            Sensor -> temperature, in the unit the models were fitted in ([degC] or [K]).

        Returns
        -------
        dict of str to ndarray, shape (N,)
            ``expansion`` [m], ``deflection`` [m], ``slope`` [rad] (zero where no model).

        Raises
        ------
        InputDataError
            A sensor of the link without temperatures.
        """
        x = self._columns(temperatures)
        zero = np.zeros(x.shape[0])
        return {key: (model.predict(x) if model is not None else zero)
                for key, model in (("expansion", self.expansion), ("deflection", self.deflection),
                                   ("slope", self.slope))}

    def twist(self, temperatures: dict[str, ArrayLike]) -> NDArray[np.float64]:
        """(N, 6) twist (dx, dy, dz, ex, ey, ez) for ``ErrorOverrides.thermal``.

        Parameters
        ----------
        temperatures : dict of str to array_like, shape (N,)
            Sensor -> temperature, in the unit the models were fitted in ([degC] or [K]).

        Returns
        -------
        ndarray, shape (N, 6)
            Translations [m] and rotations [rad] of the link's end.

        Raises
        ------
        InputDataError
            A sensor of the link without temperatures.
        """
        parts = self.deformation(temperatures)
        out = np.zeros((parts["expansion"].size, 6))
        order = [AXES.index(a) for a in (self.length_axis, self.deflection_axis, self.normal_axis)]
        handed = 1.0 if (order[1] - order[0]) % 3 == 1 else -1.0
        out[:, order[0]] = parts["expansion"]
        out[:, order[1]] = parts["deflection"]
        out[:, 3 + order[2]] = handed * parts["slope"]
        return out


def fit_link(name: str, sensors: list[str], temperatures: dict[str, ArrayLike],
             expansion_m: ArrayLike | None = None, deflection_m: ArrayLike | None = None,
             slope_rad: ArrayLike | None = None, *, length_axis: str = "z",
             deflection_axis: str = "y", ridge: float = 0.0) -> ThermalLink:
    """Fit a link's epsilon / delta / theta models (Zhu eq. 3.12 with intercept) from records.

    Parameters
    ----------
    name : str
        Link name.
    sensors : list of str
        Sensors used as regressors.
    temperatures : dict of str to array_like, shape (N,)
        Sensor -> temperatures [degC] (or rises [K]).
    expansion_m, deflection_m : array_like, shape (N,), optional
        Measured expansion and deflection of the link's end [m].
    slope_rad : array_like, shape (N,), optional
        Measured slope [rad].
    length_axis, deflection_axis : {"x", "y", "z"}
        The link's length and deflection axes (different).
    ridge : float, optional
        Ridge strength (see :func:`fit_linear`).

    Returns
    -------
    ThermalLink
        With a model for each quantity given.

    Raises
    ------
    ParameterError
        Axes not two different of x, y, z.
    InputDataError, InsufficientDataError, CalibrationError
        As :func:`fit_linear`.
    """
    link = ThermalLink(name, list(sensors), length_axis, deflection_axis)
    x = link._columns(temperatures)
    for key, target in (("expansion", expansion_m), ("deflection", deflection_m),
                        ("slope", slope_rad)):
        if target is not None:
            setattr(link, key, fit_linear(x, target, list(sensors), ridge=ridge))
    return link
