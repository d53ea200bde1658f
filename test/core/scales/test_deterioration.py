"""Deterioration detection and command compensation (Kidani eqs. 2.1, 2.2, 3.11-3.16)."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.scales.deterioration import (compensated_command, detect_deterioration,
                                                tcp_change_from_yaw)
from mt_accuracy_ros.core.errors import InputDataError, ParameterError


def test_flags_exactly_where_the_change_reaches_the_tolerance():
    positions = np.linspace(-0.44, 0.0, 12)
    baseline = np.zeros(12)
    current = np.where(positions >= -0.16, 20e-6, 1e-6)  # Kidani Fig. 3.19: -160 .. 0 mm
    report = detect_deterioration(positions, baseline, current, tolerance=5e-6)
    assert report.deteriorated
    np.testing.assert_array_equal(report.flagged, positions >= -0.16)
    (start, end), = report.flagged_ranges()
    assert start == pytest.approx(positions[positions >= -0.16][0]) and end == pytest.approx(0.0)
    assert not detect_deterioration(positions, baseline, baseline + 4.9e-6, 5e-6).deteriorated


def test_yaw_change_times_offset_then_modified_command_cancels_it():
    yaw_change = np.array([0.0, 1e-5, 2e-5])
    change = tcp_change_from_yaw(yaw_change, tool_offset_m=1.1)
    np.testing.assert_allclose(change, [0.0, 11e-6, 22e-6])
    command = np.array([-0.44, -0.2, 0.0])
    modified = compensated_command(command, change)
    # The machine moved to p + de; commanding p - de puts it back on p.
    np.testing.assert_allclose(modified + change, command)


def test_bad_inputs():
    with pytest.raises(ParameterError):
        detect_deterioration([0.0], [0.0], [0.0], tolerance=0.0)
    with pytest.raises(InputDataError):
        detect_deterioration([0.0, 1.0], [0.0], [0.0, 1.0], tolerance=1.0)
    with pytest.raises(InputDataError):
        compensated_command([0.0, 1.0], [0.0])
