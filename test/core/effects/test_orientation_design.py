"""Tool-orientation designs of the catalogue (issue 30, item 4).

Each family that turns a frame of the chain says how it turns the tool relative to
the workpiece. Checked against :meth:`KinematicModel.tcp_error_linear` - the sum of
joint error twists, a formulation independent of the designs' frames - to 1e-12,
and against the exact matrix product to first order.
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import Context, catalogue_orientation, family_named
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine


@pytest.fixture(scope="module")
def five_axis():
    machine = load_machine("khan_chen_rpppr")
    rng = np.random.default_rng(30)
    n = 40
    q = {a: rng.uniform(-0.8, 0.8, n) if machine.axes[a].is_rotary
         else rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}
    kinematics = KinematicModel(machine)
    return machine, kinematics, q, Context(machine, Variables(q), kinematics)


def _linear_orientation(kinematics, q, overrides):
    return kinematics.tcp_error_linear(q, overrides=overrides, check_stroke=False)["orientation"]


@pytest.mark.parametrize("variant", ["A", "B", "AB"])
def test_rotary_location_turns_the_tool_as_the_twist_sum_says(five_axis, variant):
    machine, kinematics, q, ctx = five_axis
    family = family_named("rotary_location")
    design = family.orientation_design(ctx, variant, {})
    for j, name in enumerate(family.parameter_names(variant, {})):
        overrides = ErrorOverrides()
        overrides.location[name] = 1.0
        expected = _linear_orientation(kinematics, q, overrides)
        np.testing.assert_allclose(design[:, :, j], expected, atol=1e-12, rtol=0)
        # A centre-line offset moves the tool's tip but never turns it.
        if name[1] in "XYZ":
            assert not np.any(design[:, :, j])


def test_rotary_error_motion_turns_the_tool_for_angular_components_only(five_axis):
    machine, kinematics, q, ctx = five_axis
    family = family_named("rotary_error")
    setting = {"harmonics": 2}
    for variant in ("EAA", "EBA", "ECB", "EYA", "EXB"):
        design = family.orientation_design(ctx, variant, setting)
        if variant[1] in "XYZ":
            assert design is None
            continue
        _, basis = family.separable_design(ctx, variant, setting)
        coefficients = np.array([0.7, -0.2, 0.4, 0.1])
        overrides = ErrorOverrides()
        overrides.motion[variant] = basis @ coefficients
        np.testing.assert_allclose(design @ coefficients,
                                   _linear_orientation(kinematics, q, overrides),
                                   atol=1e-12, rtol=0)


def test_first_harmonics_start_where_no_location_error_holds_them():
    family = family_named("rotary_error")
    setting = {"harmonics": 1}
    # Runout along and across the axis and its angular positioning: once per revolution.
    assert family.parameter_names("EAA", setting) == ["cos1", "sin1"]
    assert family.parameter_names("EYA", setting) == ["cos1", "sin1"]
    assert family.parameter_names("EXA", setting) == ["cos1", "sin1"]
    # A wobble across the axis: its first harmonic is the centre line's tilt.
    assert family.parameter_names("EBA", setting) == ["cos2", "sin2"]
    assert family.parameter_names("ECA", setting) == ["cos2", "sin2"]


def test_linear_axis_angular_errors_and_squareness_turn_the_tool():
    machine = load_machine("kidani_hmc")
    kinematics = KinematicModel(machine)
    rng = np.random.default_rng(31)
    q = {a: rng.uniform(*machine.axes[a].stroke, 30) for a in machine.axis_order}
    ctx = Context(machine, Variables(q), kinematics)
    angular = family_named("angular")
    setting = {"order": 3}
    coefficients = np.array([2e-6, -1e-6, 5e-7])
    _, basis = angular.separable_design(ctx, "ECY", setting)
    overrides = ErrorOverrides()
    overrides.motion["ECY"] = basis @ coefficients
    np.testing.assert_allclose(angular.orientation_design(ctx, "ECY", setting) @ coefficients,
                               _linear_orientation(kinematics, q, overrides), atol=1e-18)
    assert family_named("positioning").orientation_design(ctx, "EXX", setting) is None
    square = family_named("squareness")
    overrides = ErrorOverrides()
    overrides.location["EC0Y"] = 1.0
    np.testing.assert_allclose(square.orientation_design(ctx, "EC0Y", {})[:, :, 0],
                               _linear_orientation(kinematics, q, overrides), atol=1e-12)
    # The other reference is a straightness slope: a translation.
    assert square.orientation_design(ctx, "EYX", {}) is None


def test_a_fitted_rotary_location_turns_the_models_tool_as_the_chain_does(five_axis):
    """The model applies what the workbench fitted to the direction as well as to the tip:
    the exact chain with the same location errors is the second formulation."""
    machine, kinematics, q, _ = five_axis
    errors = {"EY0A": 0.0, "EZ0A": 0.0, "EB0A": 40e-6, "EC0A": -30e-6}
    entry = {"family": "rotary_location", "variant": "A", "setting": {}}
    # A zero-angle error is the set-up's: a model that still carries one is refused, named.
    with pytest.raises(ParameterError, match="EA0A is a zero-angle error"):
        ErrorModel(machine, {"rotary_location:A": {**entry, "coefficients": {
            **errors, "EA0A": 25e-6}}})
    model = ErrorModel(machine, {"rotary_location:A": {**entry, "coefficients": errors}})
    position, orientation = model.tcp_error(q)
    overrides = ErrorOverrides()
    overrides.location.update(errors)
    exact = kinematics.tcp_error(q, overrides=overrides, check_stroke=False)
    # First order in 5e-5 rad: the second-order rest is ~1e-9 rad, and ~1e-9 m through the
    # arms to the machining point (up to ~0.6 m from the A axis).
    np.testing.assert_allclose(orientation, exact["orientation"], atol=5e-9, rtol=0)
    np.testing.assert_allclose(position, exact["position"], atol=2e-9, rtol=0)
    assert np.max(np.abs(orientation)) > 2e-5


def test_a_translation_or_a_user_expression_turns_nothing(five_axis):
    machine, _, q, ctx = five_axis
    drift = {"family": "structural_thermal_drift", "variant": "t", "setting": {},
             "coefficients": {"bx": 1e-6, "by": 0.0, "bz": 0.0}}
    assert not np.any(catalogue_orientation("drift", drift, ctx))
    assert not np.any(catalogue_orientation("mine", {"expression": "k * x"}, ctx))


def test_every_rotary_axis_located_at_once_gives_each_axis_its_own_numbers(five_axis):
    """A context asks the chain for the line errors of every rotary axis in one call
    (their shared frames are most of the cost): the same numbers, bit for bit, as asking
    for one axis' four alone, and the cross products are numpy's."""
    from mt_accuracy_ros.core.kinematics.htm import cross

    machine, kinematics, q, _ = five_axis
    ctx = Context(machine, Variables(q), kinematics)
    for axis in ("A", "B"):
        along = "XYZ"["ABC".index(axis)]
        names = [f"E{c}0{axis}" for c in "XYZABC" if c not in (along, axis)]
        alone = kinematics.located_sensitivities(q, names)
        for name in names:
            for got, expected in zip(ctx.located(name), alone[name]):
                np.testing.assert_array_equal(got, expected)
    rng = np.random.default_rng(7)
    a, b = rng.normal(size=(40, 3)), rng.normal(size=(40, 3))
    np.testing.assert_array_equal(cross(a, b), np.cross(a, b))
    np.testing.assert_array_equal(cross(a, b[0]), np.cross(a, b[0]))
