"""A table's tilt about a pivot off its origin in a CNC's per-axis tables: the component
errors the model exports, put through the HTM chain as the CNC's motion errors, move the
TCP as the fitted tilt does (two formulations: the chain's frames and error twists against
the effect's design, the pivot's move written in the bed's frame)."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import family_named
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine

PIVOT = {"order": 1, "constant": True, "lever_slope": True}


def _positions(machine, n, rng):
    return {a: rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}


@pytest.mark.parametrize("machine_name, variant", [("vmc", "EBX"), ("vmc", "EAY"),
                                                   ("kidani_hmc", "ECX")])
def test_the_tables_pivot_slope_moves_the_tcp_as_the_fitted_tilt(machine_name, variant):
    machine = load_machine(machine_name)
    family = family_named("angular")
    names = family.parameter_names(variant, PIVOT)
    coefficients = dict(zip(names, [23e-6, -8e-6, 4.5e-6, -6.0e-6]))
    model = ErrorModel(machine, {f"angular:{variant}": {
        "family": "angular", "variant": variant, "setting": dict(PIVOT),
        "coefficients": coefficients}})
    positions = _positions(machine, 40, np.random.default_rng(5))
    fitted, _ = model.tcp_error(positions, fresh=True, referred=False)

    axis = variant[2]
    tables = model.table_motion_errors(axis, positions[axis])
    # The pivot's slope is in the axis' two translations across the tilt's axis.
    across = {f"E{c.upper()}{axis}" for c in "xyz" if c != "abc"["ABC".index(variant[1])]
              .translate(str.maketrans("abc", "xyz"))}
    assert set(tables) == {variant} | across, sorted(tables)
    chain = KinematicModel(machine).tcp_error(
        positions, first_order=True, overrides=ErrorOverrides(motion=tables,
                                                              use_description=False))
    np.testing.assert_allclose(chain["position"], fitted, rtol=1e-9, atol=1e-15)
    assert np.max(np.abs(fitted)) > 5e-6


def test_a_tilt_about_its_origin_puts_nothing_in_the_translations():
    machine = load_machine("vmc")
    family = family_named("angular")
    assert family.pivot_motion_errors(KinematicModel(machine), "EBX",
                                      {"order": 1, "constant": True}, [1e-5, 2e-6],
                                      np.zeros(3)) == {}
