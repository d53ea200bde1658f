"""What the scale pair's own effects do to its yaw, for a diagnosis against a reference yaw.

The yaw of a dual-scale axis, E_C = (x2 - x1)/D (Kidani eq. 2.13), is corrected by the
estimator for the scales' known effects. Held against a reference yaw (a laser's) at
the same readings, what the corrections miss is one of the scales' effects left out:
each moves the yaw along its own column (:func:`yaw_regressors`), which the workbench
ranks by time-blocked cross-validation (``core.workbench.diagnosis.diagnose_yaw``).
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import NDArray


@dataclass
class YawObservations:
    """Scale-pair yaw against a reference (laser) yaw at N readings of one axis.

    ``thermal_per_c`` is (dL1 - dL2)/D computed from the thermocouples with C = 1
    (Kidani eq. 3.17): the relative-expansion term per unit expansion coefficient.
    All yaws relative to the same zero reference [rad].
    """

    axis: str
    scale_yaw: NDArray[np.float64]
    reference_yaw: NDArray[np.float64]
    travel_m: NDArray[np.float64]
    velocity: NDArray[np.float64]
    thermal_per_c: NDArray[np.float64]
    time_s: NDArray[np.float64]
    distance_m: float
    uncertainty_rad: float


YAW_EXPLANATIONS = {
    "scale_thermal_expansion": "the scale yaw drifts from the reference as the two scales' "
                               "temperatures part - one scale expands more than the other "
                               "(Kidani eq. 3.17); parameter: C [1/K]",
    "timing_skew": "the difference is proportional to the feed - the two heads are sampled at "
                   "different instants (Kidani eq. 2.20); parameter: skew [s]",
    "scale_parallelism": "the difference grows linearly with travel - the scales are not "
                         "parallel (Kidani eq. 3.5); parameter: 1/cos(delta) - 1",
}


def yaw_corrections(included: dict[str, float], obs: YawObservations) -> NDArray[np.float64]:
    """The apparent yaw the estimator's corrections remove, for the included effects.

    Parameters
    ----------
    included : dict
        Effect name -> its value: ``installation_slope`` [1], ``scale_thermal_expansion``
        C [1/K], ``timing_skew`` [s], ``scale_parallelism`` [1].
    obs : YawObservations
        The N readings.

    Returns
    -------
    ndarray, shape (N,)
        The yaw they remove [rad].
    """
    out = np.zeros_like(obs.scale_yaw)
    # The pair's linear difference from the laser found at installation (Kidani 3.3.1):
    # relative graduation slope, indistinguishable from parallelism in one run.
    out += included.get("installation_slope", 0.0) * obs.travel_m / obs.distance_m
    if "scale_thermal_expansion" in included:
        out += included["scale_thermal_expansion"] * obs.thermal_per_c   # Kidani eq. 3.17
    if "timing_skew" in included:
        out += included["timing_skew"] * obs.velocity / obs.distance_m   # Kidani eq. 2.20
    if "scale_parallelism" in included:
        out += included["scale_parallelism"] * obs.travel_m / obs.distance_m  # Kidani eq. 3.5
    return out


def yaw_regressors(obs: YawObservations) -> dict[str, NDArray[np.float64]]:
    """Each scale effect's yaw per unit of its parameter at the readings.

    Parameters
    ----------
    obs : YawObservations
        The N readings.

    Returns
    -------
    dict
        Effect name -> its column (N,) [rad per unit parameter], in the order the
        diagnosis ranks them: ``scale_thermal_expansion`` [rad K],
        ``timing_skew`` [rad/s], ``scale_parallelism`` [rad].
    """
    return {"scale_thermal_expansion": obs.thermal_per_c,               # Kidani eq. 3.17
            "timing_skew": obs.velocity / obs.distance_m,               # Kidani eq. 2.20
            "scale_parallelism": obs.travel_m / obs.distance_m}         # Kidani eq. 3.5
