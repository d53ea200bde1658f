"""The two tail probabilities the workbench's tests need, without importing scipy.stats.

``scipy.stats`` takes ~0.5 s to import - longer than a whole check of a small
survey. The block test needs Student's t upper tail and the noise test the
chi-square upper tail; both are regularised incomplete functions evaluated
here by their classical series and continued fractions (Lentz's method;
Abramowitz & Stegun 6.5.29/6.5.31 and 26.5.8), to ~1e-13 relative - the
tests compare them with scipy.stats.
"""
from __future__ import annotations

import math

_TINY = 1e-300
_EPS = 1e-15


def _gamma_prefactor(a: float, x: float) -> float:
    """x^a e^-x / Gamma(a), in logs (a of 1e5 and more)."""
    return math.exp(a * math.log(x) - x - math.lgamma(a))


def regularized_gamma_q(a: float, x: float) -> float:
    """Q(a, x) = Gamma(a, x) / Gamma(a), the upper regularised incomplete gamma function.

    Parameters
    ----------
    a : float
        Shape, > 0.
    x : float
        Argument (1 for x <= 0).

    Returns
    -------
    float
        Q(a, x) in [0, 1].

    Raises
    ------
    ValueError
        a <= 0.
    """
    if a <= 0:
        raise ValueError(f"a must be > 0, got {a}")
    if x <= 0:
        return 1.0
    iterations = 100 + int(10 * math.sqrt(a))
    if x < a + 1.0:
        # Series for P(a, x) = x^a e^-x / Gamma(a + 1) * sum x^n / ((a + 1) ... (a + n)).
        term = total = 1.0 / a
        denominator = a
        for _ in range(iterations):
            denominator += 1.0
            term *= x / denominator
            total += term
            if abs(term) < abs(total) * _EPS:
                break
        return max(0.0, 1.0 - total * _gamma_prefactor(a, x))
    # Continued fraction for Q (A&S 6.5.31), modified Lentz.
    b = x + 1.0 - a
    c = 1.0 / _TINY
    d = 1.0 / b
    h = d
    for i in range(1, iterations):
        an = -i * (i - a)
        b += 2.0
        d = an * d + b
        d = _TINY if abs(d) < _TINY else d
        c = b + an / c
        c = _TINY if abs(c) < _TINY else c
        d = 1.0 / d
        delta = d * c
        h *= delta
        if abs(delta - 1.0) < _EPS:
            break
    return _gamma_prefactor(a, x) * h


def chi2_sf(value: float, dof: float) -> float:
    """P(chi-square with ``dof`` degrees of freedom > ``value``).

    Parameters
    ----------
    value : float
        The chi-square statistic, dimensionless.
    dof : float
        Degrees of freedom, > 0.

    Returns
    -------
    float
        The upper tail probability.

    Raises
    ------
    ValueError
        dof <= 0.
    """
    return regularized_gamma_q(0.5 * dof, 0.5 * value)


def _beta_fraction(a: float, b: float, x: float) -> float:
    """Continued fraction of the incomplete beta function (A&S 26.5.8), Lentz."""
    c = 1.0
    d = 1.0 - (a + b) * x / (a + 1.0)
    d = 1.0 / (_TINY if abs(d) < _TINY else d)
    h = d
    for m in range(1, 10000):
        m2 = 2 * m
        for numerator in (m * (b - m) * x / ((a + m2 - 1.0) * (a + m2)),
                          -(a + m) * (a + b + m) * x / ((a + m2) * (a + m2 + 1.0))):
            d = 1.0 + numerator * d
            d = 1.0 / (_TINY if abs(d) < _TINY else d)
            c = 1.0 + numerator / c
            c = _TINY if abs(c) < _TINY else c
            delta = d * c
            h *= delta
        if abs(delta - 1.0) < _EPS:
            break
    return h


def regularized_beta(a: float, b: float, x: float) -> float:
    """I_x(a, b), the regularised incomplete beta function, 0 <= x <= 1.

    Parameters
    ----------
    a, b : float
        Shapes, > 0.
    x : float
        Argument in [0, 1].

    Returns
    -------
    float
        I_x(a, b) in [0, 1].

    Raises
    ------
    ValueError
        x outside [0, 1].
    """
    if not 0.0 <= x <= 1.0:
        raise ValueError(f"x must be in [0, 1], got {x}")
    if x in (0.0, 1.0):
        return x
    log_front = (math.lgamma(a + b) - math.lgamma(a) - math.lgamma(b) +
                 a * math.log(x) + b * math.log1p(-x))
    if x < (a + 1.0) / (a + b + 2.0):
        return math.exp(log_front) * _beta_fraction(a, b, x) / a
    return 1.0 - math.exp(log_front) * _beta_fraction(b, a, 1.0 - x) / b


def t_sf(value: float, dof: float) -> float:
    """P(Student's t with ``dof`` degrees of freedom > ``value``).

    Parameters
    ----------
    value : float
        The t statistic, dimensionless.
    dof : float
        Degrees of freedom, > 0.

    Returns
    -------
    float
        The upper tail probability (NaN for a NaN value).
    """
    if math.isnan(value):
        return math.nan
    if math.isinf(value):
        return 0.0 if value > 0 else 1.0
    tail = 0.5 * regularized_beta(0.5 * dof, 0.5, dof / (dof + value * value))
    return tail if value >= 0 else 1.0 - tail
