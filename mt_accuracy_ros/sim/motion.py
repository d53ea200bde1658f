"""Motion programs of the virtual machine tool as closed-form position functions of time."""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..core.validation import finite_array, positive


def back_and_forth(time_s: ArrayLike, stroke_m: float, feed_m_per_s: float,
                   start_m: float = 0.0) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Full-stroke back-and-forth run at constant feed (a triangle wave).

    Parameters
    ----------
    time_s : array_like, shape (n,)
        Sample times [s] from the program start.
    stroke_m : float
        Travel [m], > 0.
    feed_m_per_s : float
        Feed speed [m/s], > 0.
    start_m : float
        Position at t = 0, the negative end of the stroke [m].

    Returns
    -------
    position_m, velocity_m_per_s : ndarray, shape (n,)
    """
    t = finite_array(time_s, "time_s", ndim=1)
    stroke = positive(stroke_m, "stroke_m")
    feed = positive(feed_m_per_s, "feed_m_per_s")
    half_period = stroke / feed
    phase = np.mod(t, 2.0 * half_period)
    going_out = phase < half_period
    position = np.where(going_out, phase * feed, (2.0 * half_period - phase) * feed)
    velocity = np.where(going_out, feed, -feed)
    return start_m + position, velocity
