"""Headline figures of an error with their expanded uncertainty.

The RMS of N residuals r_i, each read by an instrument of standard
uncertainty u (the instrument's k = 2 figure / 2), has two contributions:
the sampling spread of the RMS over the readings - estimated by a seeded
bootstrap over the readings - and the instrument, u / sqrt(N) (uncorrelated
readings). The expanded uncertainty is U = 2 sqrt(s_boot^2 + u^2 / N)
(GUM, k = 2). For zero-mean normal residuals of sigma the bootstrap part
tends to sigma / sqrt(2 N), which the tests check.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike

from ..validation import finite_array

#: Bootstrap resamples: enough for a 2-digit uncertainty.
RESAMPLES = 400
#: The k = 2 uncertainty taken for readings that state none (0): one documented default
#: per quantity, and whatever uses it says so (a default is never silent).
DEFAULT_POSITION_UNCERTAINTY_M = 1e-6
DEFAULT_DIRECTION_UNCERTAINTY_RAD = 2e-6


def stated_uncertainty(values: ArrayLike, default: float, what: str, unit: str
                       ) -> tuple[float, str]:
    """(the median of the readings' stated k = 2 uncertainties, "") - or, when they state
    none (all zero, or none given), (``default``, the sentence that says it was assumed).

    Parameters
    ----------
    values : array_like
        The readings' stated expanded uncertainties (k = 2), any shape, in ``unit``.
    default : float
        The uncertainty assumed when none is stated, in ``unit``.
    what : str
        What was read, for the sentence.
    unit : str
        The unit, for the sentence.

    Returns
    -------
    tuple of (float, str)
        The uncertainty (k = 2) in ``unit``, and "" or the sentence saying it was assumed.
    """
    everything = np.asarray(values, dtype=np.float64).ravel()
    positive = everything[np.isfinite(everything) & (everything > 0)]
    if positive.size:
        median = float(np.median(everything))
        return (median if median > 0 else float(np.median(positive))), ""
    return default, (f"{what}: the readings state no uncertainty (0); {default:g} {unit} "
                     "(k = 2) assumed")


@dataclass(frozen=True)
class Figure:
    """RMS and max |value| of an error [unit of the input] with k = 2 uncertainties.

    Attributes
    ----------
    rms : float
        RMS, the input's unit.
    rms_u_k2 : float
        Its expanded uncertainty (k = 2), same unit.
    max_abs : float
        Largest |value|, same unit.
    count : int
        Readings N.
    """

    rms: float
    rms_u_k2: float
    max_abs: float
    count: int


def rms_with_uncertainty(values: ArrayLike, instrument_u_k2: float, *, seed: int = 0
                         ) -> Figure:
    """Figures of ``values`` (shape (N,)) read with an instrument of ``instrument_u_k2`` (k = 2).

    Parameters
    ----------
    values : array_like, shape (N,)
        The error at N readings, any unit (the figures keep it).
    instrument_u_k2 : float
        The instrument's expanded uncertainty per reading (k = 2), same unit.
    seed : int, optional
        Seed of the bootstrap (the figures are reproducible).

    Returns
    -------
    Figure
        RMS, its U (k = 2), max |value| (the values' unit) and N.

    Raises
    ------
    InputDataError
        Values not 1-D, empty or not finite.
    """
    r = finite_array(values, "values", ndim=1)
    n = r.size
    rms = float(np.sqrt(np.mean(r ** 2)))
    if n < 2:
        spread = 0.0
    else:
        rng = np.random.default_rng(seed)
        picks = rng.integers(0, n, size=(RESAMPLES, n))
        spread = float(np.std(np.sqrt(np.mean(r[picks] ** 2, axis=1)), ddof=1))
    u = float(instrument_u_k2) / 2.0
    return Figure(rms, 2.0 * float(np.sqrt(spread ** 2 + u ** 2 / n)), float(np.max(np.abs(r))),
                  n)


def format_with_uncertainty(value: float, u_k2: float, unit: str) -> str:
    """``value ± U unit`` rounded to the uncertainty's two significant digits.

    Parameters
    ----------
    value : float
        The value, in ``unit``.
    u_k2 : float
        Its expanded uncertainty (k = 2), in ``unit`` (none shown when not > 0).
    unit : str
        The unit written.

    Returns
    -------
    str
        The text.
    """
    if not (np.isfinite(u_k2) and u_k2 > 0):
        return f"{value:.3g} {unit}"
    decimals = max(0, 1 - int(np.floor(np.log10(u_k2))))
    return f"{value:.{decimals}f} ± {u_k2:.{decimals}f} {unit} (k = 2)"
