"""Model and machine loaders raise only the package's own errors, naming what is wrong."""
from __future__ import annotations

import pytest
import yaml

from mt_accuracy_ros.core.compensation.error_model import model_from_dict, resolve_model
from mt_accuracy_ros.core.errors import MachineDescriptionError, MtAccuracyError, ParameterError
from mt_accuracy_ros.core.kinematics.machine import load_machine, machine_from_dict


@pytest.mark.parametrize("data,words", [
    ({"machine": "kidani_hmc", "effects": ["squareness"]}, "'effects' must map"),
    ({"machine": "kidani_hmc", "version": "two"}, "'version' must be a non-negative integer"),
    ({"machine": "kidani_hmc", "version": -1}, "'version'"),
    ({"machine": ["kidani_hmc"]}, "'machine' must be"),
    ({"machine": "kidani_hmc", "effects": {"squareness": 3}}, "effects.squareness"),
    ({"machine": "kidani_hmc", "reference_temperatures_c": [1, 2]}, "reference_temperatures_c"),
    ({"machine": "kidani_hmc", "reference_temperatures_c": {"t": "warm"}}, "malformed"),
    ([1, 2, 3], "needs 'machine'"),
])
def test_malformed_models_are_refused_with_a_parameter_error(data, words):
    with pytest.raises(ParameterError, match=words):
        model_from_dict(data, "m.yaml")
    # The same through the text path the nodes take.
    with pytest.raises(ParameterError):
        resolve_model(yaml.safe_dump(data) + "\n")


def test_a_binary_machine_file_is_a_machine_description_error(tmp_path):
    binary = tmp_path / "machine.yaml"
    binary.write_bytes(bytes(range(256)) * 4)
    with pytest.raises(MachineDescriptionError, match="machine.yaml"):
        load_machine(binary)
    with pytest.raises(ParameterError):
        resolve_model(f"machine: {binary}\n")


@pytest.mark.parametrize("data", [
    {"name": "m", "chain": "WXYFZT", "axes": {"X": {"stroke": "wide", "offset": [0, 0, 0]}},
     "tool": [0, 0, 0], "workpiece": [0, 0, 0]},
    {"name": "m", "chain": "WXFT", "axes": {"X": {"stroke": [0, 1], "offset": "here"}},
     "tool": [0, 0, 0], "workpiece": [0, 0, 0]},
    {"name": "m", "chain": 42, "axes": {}, "tool": [0, 0, 0], "workpiece": [0, 0, 0]},
])
def test_malformed_machines_raise_only_package_errors(data):
    with pytest.raises(MtAccuracyError):
        machine_from_dict(data, "m.yaml")


def test_a_good_model_still_loads():
    model = model_from_dict({"machine": "kidani_hmc", "version": 3,
                             "effects": {"squareness": True}})
    assert model.version == 3 and "squareness" in model.effects
