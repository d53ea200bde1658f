"""The generic Cartesian machine a survey without --machine is checked on."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.effects import Context
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.errors import MachineDescriptionError
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import generic_cartesian


def test_strokes_chain_and_a_still_axis():
    machine = generic_cartesian({"X": (0.0, 0.6), "Y": (0.0, 0.5), "Z": (0.2, 0.2)}, 0.1)
    assert machine.chain == "[w b X Y Z t]" and machine.axis_order == ("X", "Y", "Z")
    assert machine.axes["X"].stroke == (0.0, 0.6)
    # An axis that stood still gets a nominal millimetre around where it stood.
    assert machine.axes["Z"].stroke == pytest.approx((0.1995, 0.2005))
    np.testing.assert_array_equal(machine.tool, [0.0, 0.0, 0.1])
    with pytest.raises(MachineDescriptionError, match="at least one"):
        generic_cartesian({"A": (0.0, 1.0)})


def test_an_angular_error_acts_through_the_later_axes_positions_and_the_tool():
    """E_AX (X's roll) moves the TCP by eps x (0, y, z + tool): the Abbe arm is what
    varies over the survey, closed form."""
    rng = np.random.default_rng(3)
    n, tool = 50, 0.1
    positions = {"X": rng.uniform(0, 0.6, n), "Y": rng.uniform(0, 0.5, n),
                 "Z": rng.uniform(0, 0.4, n)}
    machine = generic_cartesian({a: (0.0, 0.6) for a in "XYZ"}, tool)
    ctx = Context(machine, Variables(positions=positions, time_s=np.arange(n, dtype=float)),
                  KinematicModel(machine))
    arm = np.column_stack([np.zeros(n), positions["Y"], positions["Z"] + tool])
    expected = np.cross(np.array([1.0, 0.0, 0.0]), arm)
    sensitivity = ctx.jacobian("EAX")
    sign = np.sign(np.sum(sensitivity * expected))
    np.testing.assert_allclose(sensitivity, sign * expected, atol=1e-12)
    # Positioning of X: one to one along x, wherever the other axes are.
    np.testing.assert_allclose(np.abs(ctx.jacobian("EXX")), np.tile([1.0, 0, 0], (n, 1)),
                               atol=1e-12)
