"""Thermal-link HTMs (Zhu section 4.2, eq. 4.2, Table 4.2) in the kinematic chain."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.kinematics.htm import thermal_link_htm
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine

ARCSEC = np.pi / 180 / 3600


def test_link_htm_holds_expansion_deflection_and_slope():
    # Zhu Table 4.2, link M_0^T: eps = 27.14 um, delta = 47.87 um, theta = -20.43 arcsec.
    m = thermal_link_htm(27.14e-6, 47.87e-6, -20.43 * ARCSEC)
    np.testing.assert_allclose(m[:3, 3], [27.14e-6, 47.87e-6, 0.0])
    angle = np.arctan2(m[1, 0], m[0, 0])
    assert angle == pytest.approx(-20.43 * ARCSEC)
    # A point 0.3 m along the link moves by the expansion plus slope x length.
    end = m @ np.array([0.3, 0.0, 0.0, 1.0])
    assert end[1] - 0.0 == pytest.approx(47.87e-6 + 0.3 * np.sin(-20.43 * ARCSEC))


def test_link_htm_rejects_degenerate_axes():
    with pytest.raises(ValueError):
        thermal_link_htm(1e-6, 0, 0, length_axis="x", deflection_axis="x")


def test_thermal_link_in_the_chain_moves_the_tcp_by_its_twist():
    model = KinematicModel(load_machine("kidani_hmc"))
    pos = {"X": np.array([0.2]), "Y": np.array([-0.1]), "Z": np.array([0.3])}
    # Column (X body) grows 12 um in y and tilts 5 urad about x.
    twist = np.array([0.0, 12e-6, 0.0, 5e-6, 0.0, 0.0])
    out = model.tcp_error(pos, overrides=ErrorOverrides(thermal={"X": twist}))
    lever = np.array([0.0, -0.1, 0.0]) + model.machine.axes["X"].offset \
        + model.machine.axes["Y"].offset + model.machine.tool
    expected = twist[:3] + np.cross(twist[3:], lever)
    np.testing.assert_allclose(out["position"][0], expected, atol=1e-10)
    linear = model.tcp_error_linear(pos, overrides=ErrorOverrides(thermal={"X": twist}))
    np.testing.assert_allclose(linear["position"][0], expected, atol=1e-16)
    # The bed under the workpiece table expanding moves the work, so e has the opposite sign.
    bed = model.tcp_error(pos, overrides=ErrorOverrides(
        thermal={"bed_work": [0, 0, 20e-6, 0, 0, 0]}))
    np.testing.assert_allclose(bed["position"][0], [0, 0, -20e-6], atol=1e-15)
