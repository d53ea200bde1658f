"""A pair of parallel linear scales on one axis of the virtual machine tool.

The moving component yaws by a smooth, non-polynomial profile of its position;
scale 2 then reads ``D * tan(yaw)`` further than scale 1 (the inverse of Kidani
eq. 2.13). Readings are quantised to the scale resolution (10 nm, SQ57, Kidani
Table 3.2) and carry white noise.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray

from ..core.validation import finite_array, positive


@dataclass(frozen=True)
class YawProfile:
    """Smooth yaw error motion E_C(x) [rad] of an axis as a sum of sines.

    ``amplitudes_rad[i] * sin(2*pi*x / wavelengths_m[i] + phases_rad[i])``.
    """

    amplitudes_rad: tuple[float, ...] = (4.0e-6, 1.5e-6, 0.6e-6)
    wavelengths_m: tuple[float, ...] = (0.9, 0.31, 0.113)
    phases_rad: tuple[float, ...] = (0.3, 1.1, 2.0)

    def __call__(self, position_m: NDArray[np.float64]) -> NDArray[np.float64]:
        x = np.asarray(position_m, dtype=np.float64)
        yaw = np.zeros_like(x)
        for amplitude, wavelength, phase in zip(self.amplitudes_rad, self.wavelengths_m,
                                                self.phases_rad):
            yaw += amplitude * np.sin(2.0 * np.pi * x / wavelength + phase)
        return yaw


def read_scale_pair(position_m: NDArray[np.float64], scale_distance_m: float,
                    yaw_profile: YawProfile, *, noise_m: float = 20e-9,
                    resolution_m: float = 10e-9,
                    rng: np.random.Generator | None = None,
                    ) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Readings of scales 1 and 2 for true axis positions.

    Parameters
    ----------
    position_m : ndarray, shape (n,)
        True position of the axis at scale 1 [m].
    scale_distance_m : float
        Distance D between the scales [m].
    yaw_profile : YawProfile
        True yaw E_C(x) of the axis.
    noise_m : float
        Standard deviation of the white reading noise of each head [m].
    resolution_m : float
        Quantisation step [m]; 0 disables quantisation.
    rng : numpy.random.Generator, optional
        Source of the noise; a fixed seed gives the same readings.

    Returns
    -------
    x1_m, x2_m : ndarray, shape (n,)
    """
    x = finite_array(position_m, "position_m", ndim=1)
    distance = positive(scale_distance_m, "scale_distance_m")
    rng = rng if rng is not None else np.random.default_rng(0)
    x1 = x + rng.normal(0.0, noise_m, x.size)
    x2 = x + distance * np.tan(yaw_profile(x)) + rng.normal(0.0, noise_m, x.size)
    if resolution_m > 0.0:
        x1 = np.round(x1 / resolution_m) * resolution_m
        x2 = np.round(x2 / resolution_m) * resolution_m
    return x1, x2
