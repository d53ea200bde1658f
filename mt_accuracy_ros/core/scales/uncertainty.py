"""Type B uncertainty budget of dual-scale yaw and its propagation to the TCP.

Kidani Table 3.4 lists four contributors, each as an expanded (2 sigma) value
with a sensitivity coefficient to the yaw:

=============================  ==========================  ===========
contributor                    2 sigma                     sensitivity
=============================  ==========================  ===========
linear encoder accuracy        (1.5 + 1.5 L) um, L in m    1 / D
signal noise                   0.08 um                     2 / D
parallelism of the pair        L / cos(0.61e-3) - L        1 / D
timing misalignment            0.005 um                    1 / D
=============================  ==========================  ===========

and combines them by Kidani eq. 3.10, ``u = sqrt(sum u_i^2)``, with u_i = sensitivity
x sigma_i. The encoder term dominates, so 2u ~= (1.5 + 1.5 L) / D um/m, the
table's last row.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import ParameterError
from ..validation import finite_array, positive

#: Parallelism error assumed by Kidani section 3.2.1 [rad] (0.61 mm/m).
KIDANI_PARALLELISM_RAD = 0.61e-3
#: Feed of the test machine [m/s] (60 m/min, Kidani section 3.1.3).
KIDANI_MAX_FEED_M_PER_S = 1.0
#: Sampling-time misalignment of the BD200 [s] (Kidani section 3.1.3).
KIDANI_SKEW_S = 5e-9


@dataclass(frozen=True)
class ScaleSpec:
    """Accuracy data of a linear scale pair.

    Attributes
    ----------
    accuracy_constant_m, accuracy_per_length : float
        Encoder accuracy ``a + b * L`` (2 sigma) [m] with L in m:
        SQ57 (1.5 + 1.5 L) um -> a = 1.5e-6 m, b = 1.5e-6 (Kidani Table 3.2).
    noise_2sigma_m : float
        Signal noise, 2 sigma [m] (Table 3.4: 0.08 um).
    noise_sensitivity : float
        Multiplier of noise/D (Table 3.4: 2, both heads).
    parallelism_rad : float
        Parallelism error delta of the pair [rad].
    timing_2sigma_m : float
        Position error from sampling misalignment, 2 sigma [m] (0.005 um).
    """

    accuracy_constant_m: float = 1.5e-6
    accuracy_per_length: float = 1.5e-6
    noise_2sigma_m: float = 0.08e-6
    noise_sensitivity: float = 2.0
    parallelism_rad: float = KIDANI_PARALLELISM_RAD
    timing_2sigma_m: float = 5e-9


@dataclass(frozen=True)
class YawUncertainty:
    """Standard uncertainties [rad] of each contributor and combined, arrays over L."""

    encoder: NDArray[np.float64]
    noise: NDArray[np.float64]
    parallelism: NDArray[np.float64]
    timing: NDArray[np.float64]

    @property
    def combined(self) -> NDArray[np.float64]:
        """u of Kidani eq. 3.10 [rad]."""
        return np.sqrt(self.encoder ** 2 + self.noise ** 2 + self.parallelism ** 2
                       + self.timing ** 2)

    @property
    def expanded(self) -> NDArray[np.float64]:
        """2u, the band Kidani Fig. 3.16 shades [rad]."""
        return 2.0 * self.combined


def yaw_uncertainty(travel_m: ArrayLike, scale_distance_m: float,
                    spec: ScaleSpec = ScaleSpec()) -> YawUncertainty:
    """Uncertainty budget of dual-scale yaw (Kidani eq. 3.10, Table 3.4).

    Parameters
    ----------
    travel_m : array_like, shape (n,)
        Travel L from the zero reference [m] (its magnitude is used).
    scale_distance_m : float
        D [m].

    Returns
    -------
    YawUncertainty
        Standard uncertainties, shape (n,) each [rad].
    """
    travel = np.abs(finite_array(np.atleast_1d(travel_m), "travel_m", ndim=1))
    distance = positive(scale_distance_m, "scale_distance_m")
    encoder_2s = spec.accuracy_constant_m + spec.accuracy_per_length * travel
    parallel_2s = travel / np.cos(spec.parallelism_rad) - travel
    return YawUncertainty(
        encoder=encoder_2s / 2.0 / distance,
        noise=np.full(travel.shape, spec.noise_2sigma_m / 2.0 * spec.noise_sensitivity / distance),
        parallelism=parallel_2s / 2.0 / distance,
        timing=np.full(travel.shape, spec.timing_2sigma_m / 2.0 / distance),
    )


def timing_error_per_distance(feed_m_per_s: float, skew_s: float,
                              scale_distance_m: float) -> float:
    """Worst-case yaw error from sampling misalignment, F dt / D [rad] (Kidani eqs. 3.1-3.4).

    Parameters
    ----------
    feed_m_per_s : float
        Feed F [m/s] (> 0).
    skew_s : float
        Sampling skew dt [s] (its magnitude counts).
    scale_distance_m : float
        Distance D between the two scales [m] (> 0).

    Returns
    -------
    float
        Yaw error [rad].

    Raises
    ------
    ParameterError
        F or D not positive.
    """
    return positive(feed_m_per_s, "feed_m_per_s") * abs(float(skew_s)) / positive(
        scale_distance_m, "scale_distance_m")


def parallelism_error_at_stroke(stroke_m: float, parallelism_rad: float,
                                scale_distance_m: float) -> float:
    """Yaw error of Kidani eq. 3.5 at the end of the stroke [rad].

    Parameters
    ----------
    stroke_m : float
        Stroke L [m] (> 0).
    parallelism_rad : float
        Parallelism error delta [rad].
    scale_distance_m : float
        Distance D between the two scales [m] (> 0).

    Returns
    -------
    float
        (L / cos(delta) - L) / D [rad].

    Raises
    ------
    ParameterError
        L or D not positive.
    """
    stroke = positive(stroke_m, "stroke_m")
    return (stroke / np.cos(parallelism_rad) - stroke) / positive(scale_distance_m,
                                                                   "scale_distance_m")


def tolerable_scale_uncertainty(tcp_target_m: float, n_scales: int = 6) -> float:
    """Per-scale uncertainty that keeps the TCP within a target (Kidani eqs. 2.17-2.19).

    ``sigma_e = sqrt(n * sigma_x^2)`` with equal scales, so
    ``sigma_x = sigma_e / sqrt(n)``; 3.2 um over six scales gives 1.31 um.

    Parameters
    ----------
    tcp_target_m : float
        Target TCP uncertainty sigma_e [m] (> 0).
    n_scales : int, optional
        Number of equal scales n (>= 1).

    Returns
    -------
    float
        sigma_x [m].

    Raises
    ------
    ParameterError
        A target that is not positive or n below 1.
    """
    if int(n_scales) < 1:
        raise ParameterError(f"n_scales must be >= 1, got {n_scales}")
    return positive(tcp_target_m, "tcp_target_m") / np.sqrt(int(n_scales))


def tcp_uncertainty_from_yaw(sigma_yaw_bx: float, sigma_yaw_bz: float,
                             sigma_yaw_cy: float) -> NDArray[np.float64]:
    """TCP uncertainty vector from the yaw uncertainties of the three axes (Kidani eq. 2.15).

    The L_* constants of Kidani eq. 2.14 are exact, so the uncertainties add in
    quadrature per component::

        sigma_e = [sqrt(s_BX^2 + s_BZ^2 + s_CY^2), s_CY, sqrt(s_BX^2 + s_BZ^2)]

    (Units as given: Kidani eq. 2.15 treats the lever arms as folded into the sigmas.)

    Parameters
    ----------
    sigma_yaw_bx, sigma_yaw_bz, sigma_yaw_cy : float
        Yaw uncertainties of the three axes, each already times its lever arm
        (unit-agnostic: the result has their unit, [m] when so folded).

    Returns
    -------
    ndarray, shape (3,)
        sigma_e per TCP component x, y, z, the inputs' unit.
    """
    bx, bz, cy = (float(v) for v in (sigma_yaw_bx, sigma_yaw_bz, sigma_yaw_cy))
    return np.array([np.sqrt(bx ** 2 + bz ** 2 + cy ** 2), cy, np.sqrt(bx ** 2 + bz ** 2)])
