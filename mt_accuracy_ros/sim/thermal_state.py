"""Temperatures of the virtual machine tool: lumped first-order thermal responses.

Each temperature rise is the response of a first-order lag to a heat input u(t)
in [0, 1] (axis motion |v|/v_max, spindle speed / max speed):

    tau dh/dt = K u(t) - h        ->  h_n = a h_{n-1} + (1 - a) K u_{n-1},  a = exp(-dt/tau)

i.e. one thermal mode of Zhu eq. 3.9 (time constant tau = 1/lambda, eq. 3.3),
discretised exactly for a piecewise-constant input and run with
``scipy.signal.lfilter`` (vectorised). Along a scale the rise has a fixed
shape g(s) (warmer at the drive end), so the expansion integral of Kidani
eq. 3.17 has the closed form used by :func:`scale_expansion_m`.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray
from scipy.signal import lfilter

from ..core.dual_scale import THERMOCOUPLE_SPACING_M, thermocouple_positions  # noqa: F401


def first_order_response(u: NDArray[np.float64], dt_s: float, tau_s: float,
                         gain: float) -> NDArray[np.float64]:
    """h_n of a first-order lag (gain ``gain``, time constant ``tau_s``) to input u."""
    u = np.asarray(u, dtype=np.float64)
    if tau_s <= 0:
        return gain * u
    a = float(np.exp(-dt_s / tau_s))
    # h_n = a h_{n-1} + (1 - a) K u_{n-1}: the input acts one step later.
    shifted = np.concatenate([[0.0], u[:-1]]) if u.size else u
    return lfilter([1.0 - a], [1.0, -a], gain * shifted)


def scale_shape(s_m: NDArray[np.float64], length_m: float) -> NDArray[np.float64]:
    """g(s) = 0.6 + 0.4 cos(pi s / L): relative rise along a scale, 1 at the drive end."""
    return 0.6 + 0.4 * np.cos(np.pi * np.asarray(s_m, dtype=np.float64) / length_m)


def scale_shape_integral(s_m: NDArray[np.float64], length_m: float) -> NDArray[np.float64]:
    """G(s) = int_0^s g = 0.6 s + 0.4 L / pi sin(pi s / L) [m]."""
    s = np.asarray(s_m, dtype=np.float64)
    return 0.6 * s + 0.4 * length_m / np.pi * np.sin(np.pi * s / length_m)


def scale_expansion_m(travel_m: NDArray[np.float64], length_m: float, shaped_rise_k,
                      uniform_rise_k, expansion_per_k: float) -> NDArray[np.float64]:
    """dL(x, t) = C int_0^x [r(t) g(s) + a(t)] ds = C [r(t) G(x) + a(t) x] (Kidani eq. 3.17)."""
    # G is smooth (one half cosine over the scale): a 0.1 mm table is exact to ~1e-9 m.
    grid = np.linspace(-0.01 * length_m, 1.01 * length_m, 10_001)
    shape = np.interp(travel_m, grid, scale_shape_integral(grid, length_m))
    return expansion_per_k * (np.asarray(shaped_rise_k) * shape
                              + np.asarray(uniform_rise_k) * travel_m)
