"""A set-up angle of a continuous rotary axis is modulo a full turn; others stay in stroke."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import MachineDescriptionError
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import machine_from_dict, with_setup_pose

BASE = {"name": "t", "chain": "[w C A b Z t]", "tool": [0, 0, -0.1], "workpiece": [0, 0, 0],
        "axes": {"A": {"stroke": {"value": [-110, 30], "unit": "deg"}, "offset": [0, 0, 0]},
                 "C": {"stroke": {"value": [0, 360], "unit": "deg"}, "offset": [0, 0, 0]},
                 "Z": {"stroke": [0, 0.3], "offset": [0, 0, 0.5]}}}


def test_a_continuous_axis_takes_its_set_up_angle_modulo_a_full_turn_and_says_so():
    machine = machine_from_dict({**BASE, "setup_pose": {"C": {"value": -45, "unit": "deg"}}})
    assert machine.setup_angle("C") == pytest.approx(np.radians(315.0), abs=1e-12)
    assert len(machine.setup_notes) == 1
    assert "-45 deg taken as 315 deg" in machine.setup_notes[0]
    assert "modulo 360 deg" in machine.setup_notes[0]
    # The same orientation: the located chain reads the same either way.
    q = {"A": np.zeros(5), "C": np.radians([0, 60, 120, 200, 300]), "Z": np.full(5, 0.1)}
    overrides = ErrorOverrides(location={"EX0C": 20e-6})
    taken = KinematicModel(machine).tcp_error(q, overrides=overrides, work_point=[0.05, 0, 0])
    turned = with_setup_pose(machine_from_dict(BASE), {"C": np.radians(315.0)})
    np.testing.assert_allclose(taken["position"], KinematicModel(turned).tcp_error(
        q, overrides=overrides, work_point=[0.05, 0, 0])["position"], rtol=0, atol=1e-18)
    # A map's set-up goes the same way, and says it.
    via_map = with_setup_pose(machine_from_dict(BASE), {"C": np.radians(-45.0)}, "the map")
    assert via_map.setup_angle("C") == pytest.approx(np.radians(315.0), abs=1e-12)
    assert "taken as 315 deg" in via_map.setup_notes[0]
    # An angle inside the stroke is as given, with nothing to say.
    inside = machine_from_dict({**BASE, "setup_pose": {"C": {"value": 45, "unit": "deg"}}})
    assert inside.setup_notes == ()


def test_an_axis_short_of_a_full_turn_refuses_what_lies_outside_its_stroke():
    with pytest.raises(MachineDescriptionError, match="outside the stroke"):
        machine_from_dict({**BASE, "setup_pose": {"A": {"value": 250, "unit": "deg"}}})
    with pytest.raises(MachineDescriptionError, match="outside the stroke"):
        with_setup_pose(machine_from_dict(BASE), {"A": np.radians(-120.0)})


def test_a_set_up_another_source_replaces_is_said_not_refused_when_out_of_stroke():
    """A machine file written with A set up at 90 deg, outside A's [-110, 30] deg: refused
    as the machine's own set-up, but where a survey's map gives A's set-up the file's is
    not used - said with the stroke, the rest of the file read as it is."""
    spec = {**BASE, "setup_pose": {"A": {"value": 90, "unit": "deg"},
                                   "C": {"value": 45, "unit": "deg"}}}
    with pytest.raises(MachineDescriptionError, match="outside the stroke"):
        machine_from_dict(spec)
    machine = machine_from_dict(spec, replaced_setup={"A": "the column map's setup_pose"})
    assert "A" not in machine.setup_pose
    assert machine.setup_angle("C") == pytest.approx(np.radians(45.0), abs=1e-12)
    (note,) = machine.setup_notes
    assert "90 deg is outside the stroke [-110, 30] deg" in note
    assert "not used - the column map's setup_pose gives A's set-up" in note
    # A set-up with no unit is still refused: replaced or not, the file must be readable.
    with pytest.raises(MachineDescriptionError, match="unit"):
        machine_from_dict({**BASE, "setup_pose": {"A": 90}}, replaced_setup={"A": "the map"})
