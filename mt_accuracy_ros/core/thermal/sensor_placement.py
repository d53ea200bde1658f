"""Temperature sensor placement by Gaussian integration (Krulewich 1996).

A thermal deflection is the integral of the temperature field (Krulewich eq. 1),
dx = alpha int_0^L T(x) dx, approximated by a weighted sum of point
temperatures (Krulewich eqs. 2-3). If T is a polynomial of order k (Krulewich eq. 4), matching
the moments (Krulewich eqs. 6-9) gives

    sum_i w_i x_i^j = L^(j+1) / (j+1),  j = 0 ... k          (Krulewich eq. 9)

which n = (k+1)/2 points satisfy exactly (Krulewich eq. 8): the Gauss-Legendre nodes
and weights mapped to [0, L]. (Krulewich eq. 10 as printed reads sum w_i = L/2; the
j = 0 case of Krulewich eq. 9 is sum w_i = L, which is what is implemented.)

Position-dependent errors (Krulewich eqs. 13-18): the sensors are fixed, n = k + 1
(Krulewich eq. 13), and the weights become polynomials of the axis position x,
solving sum_i w_i(x) x_i^j = x^(j+1)/(j+1) for j = 0 ... k.

Multi-dimensional fields (Krulewich eqs. 19-23): a complete order-p polynomial in d
dimensions has m = (p+d)!/(p! d!) terms; a position-independent error needs
n >= m/(d+1) free sensors, a position-dependent one n >= m/d.
"""
from __future__ import annotations

from math import comb, ceil

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ParameterError


def gauss_points_needed(order: int) -> int:
    """n = (k + 1) / 2, rounded up (Krulewich eq. 8).

    Parameters
    ----------
    order : int
        Polynomial order k of the temperature field (>= 0).

    Returns
    -------
    int
        Gauss points n.

    Raises
    ------
    ParameterError
        A negative order.
    """
    if int(order) < 0:
        raise ParameterError(f"polynomial order must be >= 0, got {order}")
    return int(ceil((int(order) + 1) / 2))


def gauss_points(order: int, length_m: float) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Sensor positions x_i [m] and weights w_i [m] on [0, L] for a field of order k.

    Gauss-Legendre: exact for every polynomial up to order 2n - 1 >= k.

    Parameters
    ----------
    order : int
        Polynomial order k (>= 0).
    length_m : float
        Length L [m] (> 0).

    Returns
    -------
    positions : ndarray, shape (n,)
        x_i [m].
    weights : ndarray, shape (n,)
        w_i [m].

    Raises
    ------
    ParameterError
        A negative order or a length not positive.
    """
    if not np.isfinite(length_m) or length_m <= 0:
        raise ParameterError(f"length_m must be finite and > 0, got {length_m}")
    nodes, weights = np.polynomial.legendre.leggauss(gauss_points_needed(order))
    return 0.5 * length_m * (nodes + 1.0), 0.5 * length_m * weights


def moment_residuals(positions: ArrayLike, weights: ArrayLike, order: int,
                     length_m: float) -> NDArray[np.float64]:
    """sum_i w_i x_i^j - L^(j+1)/(j+1) for j = 0 ... k (Krulewich eq. 9); zero when exact.

    Parameters
    ----------
    positions : array_like, shape (n,)
        Sensor positions x_i [m].
    weights : array_like, shape (n,)
        Weights w_i [m].
    order : int
        Highest moment k.
    length_m : float
        Length L [m].

    Returns
    -------
    ndarray, shape (k + 1,)
        Residual of moment j [m^(j+1)].
    """
    x = np.asarray(positions, dtype=np.float64)
    w = np.asarray(weights, dtype=np.float64)
    j = np.arange(int(order) + 1)
    return (w[None, :] * x[None, :] ** j[:, None]).sum(axis=1) - length_m ** (j + 1) / (j + 1)


def position_dependent_weights(sensor_positions: ArrayLike) -> NDArray[np.float64]:
    """Coefficients c (n, n) with w_i(x) = sum_j c[i, j] x^(j+1) (Krulewich eqs. 13-18).

    n = k + 1 fixed sensors at ``sensor_positions`` integrate an order-k field
    from 0 to any x exactly: V w(x) = b(x), V[j, i] = x_i^j, b_j = x^(j+1)/(j+1).

    Parameters
    ----------
    sensor_positions : array_like, shape (n,)
        Distinct sensor positions x_i [m].

    Returns
    -------
    ndarray, shape (n, n)
        c[i, j] in [m^-j] (so that w_i(x) is in [m]).

    Raises
    ------
    ParameterError
        Not a 1-D array of at least one position, or positions not distinct.
    """
    x = np.asarray(sensor_positions, dtype=np.float64)
    if x.ndim != 1 or x.size < 1:
        raise ParameterError("sensor_positions must be a 1-D array of at least one position")
    if np.unique(x).size != x.size:
        raise ParameterError("sensor positions must be distinct")
    n = x.size
    vandermonde = x[None, :] ** np.arange(n)[:, None]  # (j, i)
    # b(x)_j = x^(j+1) / (j+1): coefficient of x^(j+1) is 1/(j+1).
    return np.linalg.solve(vandermonde, np.diag(1.0 / (np.arange(n) + 1.0)))


def evaluate_weights(coefficients: ArrayLike, x: ArrayLike) -> NDArray[np.float64]:
    """w_i(x) (len(x), n) from :func:`position_dependent_weights`.

    Parameters
    ----------
    coefficients : array_like, shape (n, n)
        c from :func:`position_dependent_weights`.
    x : array_like, shape (M,)
        Upper limits of integration [m].

    Returns
    -------
    ndarray, shape (M, n)
        Weights w_i(x) [m].
    """
    c = np.asarray(coefficients, dtype=np.float64)
    xs = np.atleast_1d(np.asarray(x, dtype=np.float64))
    powers = xs[:, None] ** (np.arange(c.shape[1]) + 1)[None, :]
    return powers @ c.T


def polynomial_terms(order: int, dimensions: int) -> int:
    """m = (p + d)! / (p! d!) (Krulewich eq. 19).

    Parameters
    ----------
    order : int
        Polynomial order p (>= 0).
    dimensions : int
        Spatial dimensions d (>= 1).

    Returns
    -------
    int
        Number of terms m.

    Raises
    ------
    ParameterError
        A negative order or fewer than one dimension.
    """
    if int(order) < 0 or int(dimensions) < 1:
        raise ParameterError("order >= 0 and dimensions >= 1 required")
    return comb(int(order) + int(dimensions), int(dimensions))


def sensors_needed(order: int, dimensions: int, position_dependent: bool = False) -> int:
    """n >= m/(d+1) (Krulewich eq. 22) or, position dependent, n >= m/d (Krulewich eq. 23).

    Parameters
    ----------
    order : int
        Polynomial order p (>= 0).
    dimensions : int
        Spatial dimensions d (>= 1).
    position_dependent : bool, optional
        Weights that depend on the position (Krulewich eq. 23) instead of fixed (Krulewich
        eq. 22).

    Returns
    -------
    int
        Fewest sensors n.

    Raises
    ------
    ParameterError
        A negative order or fewer than one dimension.
    """
    m = polynomial_terms(order, dimensions)
    d = int(dimensions)
    return int(ceil(m / d)) if position_dependent else int(ceil(m / (d + 1)))
