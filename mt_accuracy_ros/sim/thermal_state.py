"""Temperatures of the virtual machine tool.

* The **scales**: a finite-element model of each scale body, solved by its
  thermal modes (:class:`ScaleTemperatureField`, Zhu eqs. 3.1-3.10), heated by
  the axis' motion at the drive end and along the stroke.
* The **structure** (column, bed, spindle housing): lumped, one thermal mode
  each - the response of a first-order lag to a heat input u(t) in [0, 1]
  (axis motion |v|/v_max, spindle speed / max speed),

      tau dh/dt = K u(t) - h    ->  h_n = a h_{n-1} + (1 - a) K u_{n-1},  a = exp(-dt/tau)

  (Zhu eq. 3.9, tau = 1/lambda, Zhu eq. 3.3), exact for a piecewise-constant
  input, run as that recursion (a few thousand samples: the node processes that
  simulate need not import scipy.signal, a second of CPU each).
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray

from ..core.scales.dual_scale import THERMOCOUPLE_SPACING_M, thermocouple_positions  # noqa: F401


def first_order_response(u: NDArray[np.float64], dt_s: float, tau_s: float,
                         gain: float) -> NDArray[np.float64]:
    """h_n of a first-order lag (gain ``gain``, time constant ``tau_s``) to input u."""
    u = np.asarray(u, dtype=np.float64)
    if tau_s <= 0:
        return gain * u
    a = float(np.exp(-dt_s / tau_s))
    # h_n = a h_{n-1} + (1 - a) K u_{n-1}: the input acts one step later.
    shifted = np.concatenate([[0.0], u[:-1]]) if u.size else u
    drive = ((1.0 - a) * (gain * shifted)).tolist()
    out, state = [], 0.0
    for term in drive:
        state = term + a * state
        out.append(state)
    return np.array(out, dtype=np.float64)


#: Cross-section of a scale body for its FE model: 30 x 10 mm steel bar (SQ57-like tape
#: carrier), convection 10 W/m^2 K to the machine's air.
SCALE_AREA_M2 = 3.0e-4
SCALE_PERIMETER_M = 0.08
SCALE_CONVECTION_W_M2K = 10.0
#: Share of a scale's heat entering at the drive end (motor, bearing); the rest along
#: the stroke (guideway and nut friction).
DRIVE_END_SHARE = 0.5


class ScaleTemperatureField:
    """Temperature rise along a scale over time from the thermal FE model (so the scales'
    expansion follows the heat the axis makes, not an assumed uniform rise).

    A 1-D FE model of the scale body (:func:`~mt_accuracy_ros.core.thermal.fem.rod_model`,
    Zhu eq. 3.1) solved by its thermal modes (Zhu eqs. 3.2-3.10), heated by the axis'
    motion - ``DRIVE_END_SHARE`` at the drive end (s = 0), the rest spread along
    the stroke. The mode shapes are the model's; the time axis is scaled so that
    the slowest mode has the scenario's ``time_constant_s``, and the field is
    scaled so that the drive end reaches ``rise_k`` under continuous full-duty
    motion. Gives thermocouple readings (interpolated at their positions) and
    the expansion integral of Kidani eq. 3.17 exactly over the FE field.
    """

    def __init__(self, length_m: float, heat_input, dt_s: float, time_constant_s: float,
                 rise_k: float, n_elements: int = 44) -> None:
        from ..core.thermal.fem import ThermalModes, rod_model, thermal_modes

        model = rod_model(length_m, SCALE_AREA_M2, n_elements, SCALE_CONVECTION_W_M2K,
                          perimeter_m=SCALE_PERIMETER_M)
        modes = thermal_modes(model)
        factor = modes.time_constants_s[0] / max(float(time_constant_s), 1e-9)
        scaled = ThermalModes(modes.eigenvalues * factor, modes.shapes)
        x = model.nodes[:, 0]
        weights = np.gradient(x)  # trapezoid share of each node
        unit = DRIVE_END_SHARE * model.heat_vector(1.0) + \
            (1.0 - DRIVE_END_SHARE) * weights / weights.sum()
        steady = scaled.step_response(unit, [1e6 * float(time_constant_s)])[0]
        field = scaled.response(np.outer(np.asarray(heat_input, float), unit), dt_s)
        # Row n is the field at t_n = n dt: inputs u_0 ... u_{n-1} applied.
        field = np.vstack([np.zeros((1, x.size)), field[:-1]]) * (rise_k / steady[0])
        self.nodes_m = x
        self.dt_s = float(dt_s)
        self.field_k = field
        self.integral = np.concatenate(
            [np.zeros((field.shape[0], 1)),
             np.cumsum(0.5 * (field[:, 1:] + field[:, :-1]) * np.diff(x), axis=1)], axis=1)

    def at_sensors(self, positions_m) -> NDArray[np.float64]:
        """(M, n_sensors) rise at the thermocouples [K]."""
        return np.column_stack([self._column(p) for p in np.atleast_1d(positions_m)])

    def _column(self, position_m: float) -> NDArray[np.float64]:
        j = int(np.clip(np.searchsorted(self.nodes_m, position_m) - 1, 0, self.nodes_m.size - 2))
        w = (position_m - self.nodes_m[j]) / (self.nodes_m[j + 1] - self.nodes_m[j])
        return (1 - w) * self.field_k[:, j] + w * self.field_k[:, j + 1]

    def expansion_integral(self, time_s, travel_m) -> NDArray[np.float64]:
        """int_0^u T(s, t) ds [K m] at each (t, u) sample, bilinear in the FE results."""
        t = np.asarray(time_s, dtype=np.float64) / self.dt_s
        rows = self.field_k.shape[0]
        ti = np.clip(np.floor(t).astype(np.intp), 0, rows - 2)
        wt = np.clip(t - ti, 0.0, 1.0)
        u = np.clip(np.asarray(travel_m, dtype=np.float64), self.nodes_m[0], self.nodes_m[-1])
        step = self.nodes_m[1] - self.nodes_m[0]
        nj = np.clip(np.floor(u / step).astype(np.intp), 0, self.nodes_m.size - 2)
        # Within an element T is linear in s: integrate the partial element exactly.
        s = u - self.nodes_m[nj]

        def at(row):
            t0 = self.field_k[row, nj]
            t1 = self.field_k[row, nj + 1]
            return self.integral[row, nj] + t0 * s + 0.5 * (t1 - t0) / step * s * s

        return (1 - wt) * at(ti) + wt * at(ti + 1)
