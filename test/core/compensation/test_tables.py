"""CNC compensation tables (ISO 230-1 names): write, read back, rebuild the model."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.tables import (machine_with_table, read_csv,
                                                      table_from_machine, write_csv)
from mt_accuracy_ros.core.errors import MachineDescriptionError
from mt_accuracy_ros.core.kinematics.chain import KinematicModel
from mt_accuracy_ros.core.kinematics.machine import machine_from_dict


@pytest.fixture
def machine():
    return machine_from_dict({
        "name": "hmc_with_errors", "chain": "[w Z b X Y t]", "tool": [0, 0, 0.15],
        "workpiece": [0, 0.05, 0],
        "axes": {
            "X": {"stroke": [0, 0.39], "offset": [0, 0.35, -0.15],
                  "errors": {"EXX": {"polynomial": [1e-6, 2e-5, -4e-5]},
                             "ECX": {"table": {"positions": [0, 0.2, 0.39],
                                               "values": [0, 3e-6, -1e-6]}},
                             "EYX": 2e-6}},
            "Y": {"stroke": [-0.44, 0], "offset": [0.12, 0, 0.45],
                  "errors": {"EBY": {"polynomial": [0, 1e-5]}},
                  "location_errors": {"EC0Y": 1.2e-5}},
            "Z": {"stroke": [0, 0.495], "offset": [0, 0.6, 0.2],
                  "location_errors": {"EB0Z": -8e-6, "EA0Z": 3e-6}}}})


def test_csv_round_trip_is_exact(machine):
    table = table_from_machine(machine, points_per_axis=21)
    text = write_csv(table)
    assert text.splitlines()[0] == "# mt_accuracy_ros compensation table v1"
    assert "axis,position,EXX,EYX,EZX,EAX,EBX,ECX" in text
    assert "EC0Y," in text
    back = read_csv(text)
    assert back.machine == "hmc_with_errors"
    for axis in "XYZ":
        np.testing.assert_array_equal(back.grids[axis], table.grids[axis])
        for name, values in table.errors[axis].items():
            np.testing.assert_array_equal(back.errors[axis][name], values)
    assert back.location == table.location


def test_model_from_the_table_reproduces_the_model(machine):
    rebuilt = machine_with_table(machine, read_csv(write_csv(table_from_machine(machine, 201))))
    rng = np.random.default_rng(0)
    positions = {a: rng.uniform(*machine.axes[a].stroke, 300) for a in "XYZ"}
    original = KinematicModel(machine).tcp_error(positions)["position"]
    from_table = KinematicModel(rebuilt).tcp_error(positions)["position"]
    # Resampling on a ~2 mm grid: the smooth terms agree to < 0.1 nm; the ECX
    # table's kink at 0.2 m falls between grid points and costs at most
    # |slope change| * h / 4 * lever = 3.6e-5 * 1.95e-3 / 4 * 0.6 m ~ 10 nm.
    assert np.max(np.abs(original - from_table)) < 1.2e-8
    assert np.median(np.abs(original - from_table)) < 1e-10
    assert np.max(np.abs(original)) > 5e-6


@pytest.mark.parametrize("text,line", [
    ("not a table\n", "line 1"),
    ("# mt_accuracy_ros compensation table v1\naxis,position,EXX\nX,0.0,abc\n", "line 3"),
    ("# mt_accuracy_ros compensation table v1\naxis,position,EXX\nX,0.0\n", "line 3"),
    ("# mt_accuracy_ros compensation table v1\naxis,position,EXX\nX,0.0,nan\n", "line 3"),
])
def test_bad_tables_name_the_line(text, line):
    with pytest.raises(MachineDescriptionError, match=line):
        read_csv(text)
