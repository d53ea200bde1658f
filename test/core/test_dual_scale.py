"""Dual-scale yaw, Kidani eq. 2.13."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.dual_scale import yaw_from_scales
from mt_accuracy_ros.core.errors import InputDataError, ParameterError


def test_yaw_is_arctan_of_difference_over_distance():
    x1 = np.array([0.0, 0.1, 0.2])
    x2 = x1 + np.array([0.0, 2.4e-6, -4.8e-6])
    yaw = yaw_from_scales(x1, x2, 0.24)
    np.testing.assert_allclose(yaw, np.arctan([0.0, 1e-5, -2e-5]), rtol=1e-9, atol=0)
    np.testing.assert_allclose(yaw_from_scales(x1, x2, 0.24, small_angle=True),
                               [0.0, 1e-5, -2e-5], rtol=1e-9)


@pytest.mark.parametrize("bad,error", [
    (dict(x1_m=[np.nan], x2_m=[0.0], scale_distance_m=0.24), InputDataError),
    (dict(x1_m=[0.0, 1.0], x2_m=[0.0], scale_distance_m=0.24), InputDataError),
    (dict(x1_m=[], x2_m=[], scale_distance_m=0.24), InputDataError),
    (dict(x1_m=[0.0], x2_m=[0.0], scale_distance_m=0.0), ParameterError),
    (dict(x1_m=[0.0], x2_m=[0.0], scale_distance_m=-1.0), ParameterError),
])
def test_bad_input_raises_a_named_error(bad, error):
    with pytest.raises(error):
        yaw_from_scales(**bad)
