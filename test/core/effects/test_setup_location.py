"""The machine's error where the work or the tool was located, turning with it.

A squareness read by an instrument located at the set-up: the chain's own error (its
twist sum) at the readings and at the set-up, referred as the set-up referred it (a
translation of the work frame), against the catalogue's squareness (known up to a
constant) plus the set-up location with v = the squareness' error there.
"""
from __future__ import annotations

import numpy as np

from mt_accuracy_ros.core.effects import family_named
from mt_accuracy_ros.core.effects.base import Context
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.kinematics.chain import ErrorOverrides, KinematicModel
from mt_accuracy_ros.core.kinematics.machine import load_machine, with_setup_pose

SPHERE = np.array([0.05, -0.03, 0.04])


def _readings(machine, n=40, seed=7):
    rng = np.random.default_rng(seed)
    return {a: rng.uniform(*machine.axes[a].stroke, n) for a in machine.axis_order}


def test_a_located_squareness_is_the_squareness_and_the_set_up_location():
    machine = with_setup_pose(load_machine("trunnion_ac"), {"A": np.radians(-60),
                                                            "C": np.radians(30)})
    model = KinematicModel(machine)
    q = _readings(machine)
    setup = {a: np.array([machine.setup_angle(a)]) if machine.axes[a].is_rotary
             else np.array([0.1]) for a in machine.axis_order}
    angle = 40e-6
    overrides = ErrorOverrides(location={"EB0Z": angle}, use_description=False)
    # The twist sum: first order, as the catalogue's designs are.
    error = model.tcp_error_linear(q, overrides=overrides, check_stroke=False,
                                   work_point=SPHERE)["position"]
    at_setup = model.tcp_error_linear(setup, overrides=overrides, check_stroke=False,
                                      work_point=SPHERE)["position"][0]
    turned = model.branch("workpiece", q, errors=False, check_stroke=False)[:, :3, :3]
    then = model.branch("workpiece", setup, errors=False, check_stroke=False)[0, :3, :3]
    located = error - turned @ then.T @ at_setup            # what the instrument reads
    ctx = Context(machine, Variables(q), model, work_point=SPHERE)
    squareness = family_named("squareness").design(ctx, "EB0Z", {})[:, :, 0] * angle
    family = family_named("setup_location")
    assert family.variants(ctx) == ["work"]
    set_up = family.design(ctx, "work", family.settings(ctx, "work")[0]) @ at_setup
    rest = located - squareness - set_up
    # Equal up to a constant (an instrument's own zero): the squareness' value at the set-up.
    np.testing.assert_allclose(rest - rest.mean(axis=0), 0.0, atol=1e-15)
    assert np.abs(set_up).max() > 2e-6          # not vacuous: microns that turn with A, C
    # Zero where the sphere was located.
    at = family.design(Context(machine, Variables(setup), model, work_point=SPHERE), "work",
                       {})
    np.testing.assert_allclose(at, 0.0, atol=1e-15)


def test_a_two_sphere_instrument_locates_the_tool_direction_too():
    machine = with_setup_pose(load_machine("trunnion_ac"), {"C": np.radians(90)})
    q = _readings(machine, seed=8)
    ctx = Context(machine, Variables(q), KinematicModel(machine), work_point=SPHERE,
                  orientation_lever_m=0.1)
    family = family_named("setup_location")
    setting = family.settings(ctx, "work")[0]
    assert family.parameter_names("work", setting) == ["v_x", "v_y", "v_z",
                                                       "w_x", "w_y", "w_z"]
    w = np.array([3e-6, -2e-6, 0.0])
    turn = family.orientation_design(ctx, "work", setting) @ np.concatenate([np.zeros(3), w])
    model = KinematicModel(machine)
    turned = model.branch("workpiece", q, errors=False, check_stroke=False)[:, :3, :3]
    setup = {a: np.array([machine.setup_angle(a) if machine.axes[a].is_rotary else 0.0])
             for a in machine.axis_order}
    then = model.branch("workpiece", setup, errors=False, check_stroke=False)[0, :3, :3]
    # The direction's change w at the set-up, turned with the work: -R R_s^T w, as a turn.
    change = -(turned @ then.T @ w)
    np.testing.assert_allclose(np.cross(turn, ctx.tool_axis()), np.cross(
        np.cross(ctx.tool_axis(), change), ctx.tool_axis()), atol=1e-18)
    # It moves no tip.
    position = family.design(ctx, "work", setting) @ np.concatenate([np.zeros(3), w])
    np.testing.assert_allclose(position, 0.0, atol=0)


def test_a_set_up_error_beyond_any_machines_is_refused_by_its_limits():
    """The machine's error at the set-up is bounded by the largest squareness over the
    machine's reach (10 mm per metre): a fit of 2e5 m along a direction the poses barely see
    (seed 59's trial 28 of the independent generator, before the bound) is beyond it, the
    micrometres of a real set-up far within."""
    from mt_accuracy_ros.core.effects.geometric import LARGEST_SQUARENESS_RAD, machine_reach
    from mt_accuracy_ros.core.effects.physics import limit_problems

    machine = load_machine("trunnion_ac")
    ctx = Context(machine, Variables(_readings(machine)), KinematicModel(machine),
                  work_point=SPHERE)
    family = family_named("setup_location")
    setting = {"direction": True}
    limits = family.parameter_limits(ctx, "work", setting)
    names = family.parameter_names("work", setting)
    assert set(limits) == set(names)
    bound = LARGEST_SQUARENESS_RAD * machine_reach(ctx)
    assert limits["v_x"][0] == bound and limits["w_x"][0] == LARGEST_SQUARENESS_RAD
    absurd = [208932.4, -3e-9, -7e-8, -5.2e-5, -5.7e-7, -6.9e-7]
    (problem,) = limit_problems(names, absurd, limits)
    assert problem.startswith("v_x = 2.09e+05 exceeds") and "reach" in problem
    assert limit_problems(names, [6e-7, 0.0, 7e-7, 1e-5, 0.0, 0.0], limits) == []
