"""A tilt's slope about a pivot off the carriage's origin, read by a target located at the
set-up.

A work-side carriage tilted by eps(q) = P0 + P1 L1(u) about a pivot p (carriage frame)
moves what it carries by -eps(q) (e_k x p) more than a turn about its origin (ISO 230-1).
The constant part's move is the lever (``test_located_lever.py``); the slope's,
-P1 L1(u) (e_k x p), grows along the carriage's travel: the rotary lines it carries are
offset by an amount that changes with its position. A target located at the set-up took
that move in there, and it turns with the rotary axes (ISO 10791-6). The readings come
from ``studies.convention_surveys`` (rigid bodies written from the physics alone).
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.effects.base import Context
from mt_accuracy_ros.core.effects.geometric import ComponentError, located_lever_slope
from mt_accuracy_ros.core.effects.variables import Variables

from test_located_tilt import SPHERES, _fit, _grid, _located_readings, _trunnion_ac

#: A pivot off the carriage's origin, carriage frame [m] (trial 021 of seed 43's).
PIVOT = (-0.155, 0.086, 0.179)
#: The roll's setting with its lever and the lever's slope.
SLOPED = {"order": 1, "constant": True, "located": True, "lever": True, "lever_slope": True}
#: A tilt about the first carried rotary axis' direction: no constant part, the slope alone.
SLOPE_ONLY = {"order": 1, "located": True, "lever_slope": True}


def _tilt(name, value_si, pivot=PIVOT):
    return {"iso_name": name, "kind": "table_tilt", "axis": name[2],
            "value_si": list(value_si), "pivot_m": list(pivot)}


def _ctx(effects, setup_deg):
    generator, described = _trunnion_ac(setup_deg)
    positions, errors, targets, groups = _located_readings(
        generator, described, _grid(setup_deg), SPHERES[:1], effects)
    return (Context(described, Variables(positions), work_point=targets[0], located_readings=True),
            errors, groups)


def _across(name, pivot=PIVOT):
    """e_k x p along the two directions across the tilt's axis (lever_components)."""
    axis = np.eye(3)["ABC".index(name[1])]
    moved = np.cross(axis, pivot)
    return [moved[i] for i in range(3) if i != "ABC".index(name[1])]


@pytest.mark.parametrize("setup_deg", [{"A": 0, "C": 0}, {"A": 60, "C": 45}])
def test_a_sloped_roll_about_a_pivot_is_the_located_tilt_its_lever_and_their_slope(setup_deg):
    """A roll of the Y carriage (it carries X, A and C) growing along Y about p: the located
    tilt with its lever and their slope reproduces the generator's readings to second order;
    the lever is -P0 (e_y x p) and its slope -P1 (e_y x p), in x and z, closed forms of the
    fitted P0 and P1."""
    ctx, errors, groups = _ctx([_tilt("EBY", [20e-6, 300e-6, 0.0])], setup_deg)
    family = ComponentError("angular", False)
    assert SLOPED in family.settings(ctx, "EBY")
    assert family.parameter_names("EBY", SLOPED) == \
        ["P1", "P0", "lever_x", "lever_z", "lever_slope_x", "lever_slope_z"]
    coefficients, rms = _fit(ctx.measured_design(family, "EBY", SLOPED), errors, groups)
    assert np.abs(errors).max() > 5e-6
    assert rms < 1e-8
    fitted = dict(zip(family.parameter_names("EBY", SLOPED), coefficients))
    across = _across("EBY")
    assert [fitted["lever_x"], fitted["lever_z"]] == \
        pytest.approx([-fitted["P0"] * a for a in across], abs=2e-9)
    assert [fitted["lever_slope_x"], fitted["lever_slope_z"]] == \
        pytest.approx([-fitted["P1"] * a for a in across], abs=2e-9)
    assert abs(fitted["lever_slope_x"]) > 1e-6


def test_without_the_slope_the_sloped_roll_about_a_pivot_leaves_a_micrometre():
    ctx, errors, groups = _ctx([_tilt("EBY", [20e-6, 300e-6, 0.0])], {"A": 0, "C": 0})
    family = ComponentError("angular", False)
    lever = {"order": 1, "constant": True, "located": True, "lever": True}
    _, rms = _fit(ctx.measured_design(family, "EBY", lever), errors, groups)
    assert rms > 0.5e-6     # about a micrometre RMS, against 1e-8 with the slope


@pytest.mark.parametrize("setup_deg", [{"A": 0, "C": 0}, {"A": 60, "C": 45}])
def test_a_roll_about_the_carried_a_axis_direction_is_offered_with_its_slope_alone(setup_deg):
    """The X carriage's roll EAX turns about the direction of A, the first rotary axis it
    carries: its constant part is A's zero and line offset (no lever is offered with it),
    but its slope about a pivot still offsets the carried lines along X's travel. A linear roll
    about p, zero at X's mid-stroke, is the located tilt with the slope alone, -P1 (e_x x p)
    in y and z."""
    # Zero at the stroke's middle: a constant part would be A's zero and line offset.
    low, high = _trunnion_ac(setup_deg)[1].axes["X"].stroke
    c1 = 440e-6
    ctx, errors, groups = _ctx([_tilt("EAX", [-c1 * 0.5 * (low + high), c1, 0.0])], setup_deg)
    family = ComponentError("angular", False)
    settings = family.settings(ctx, "EAX")
    assert SLOPE_ONLY in settings and not any(s.get("lever") for s in settings)
    coefficients, rms = _fit(ctx.measured_design(family, "EAX", SLOPE_ONLY), errors, groups)
    assert np.abs(errors).max() > 5e-6
    assert rms < 1e-8
    fitted = dict(zip(family.parameter_names("EAX", SLOPE_ONLY), coefficients))
    assert [fitted["lever_slope_y"], fitted["lever_slope_z"]] == \
        pytest.approx([-fitted["P1"] * a for a in _across("EAX")], rel=1e-3)
    # The plain located tilt, without the slope, leaves the pivot's move.
    _, plain = _fit(ctx.measured_design(family, "EAX", {"order": 1, "located": True}),
                    errors, groups)
    assert plain > 1e-6


def test_the_slope_on_a_cnc_batch_is_the_move_as_the_machine_makes_it():
    """A CNC's own commands hold no set-up reading: the slope's columns are then the
    carriage's move from its stroke's middle, -L1(u) across the axis, with no located part."""
    generator, described = _trunnion_ac({"A": 0, "C": 0})
    positions, _, targets, _ = _located_readings(generator, described, _grid({"A": 0, "C": 0}),
                                                 SPHERES[:1], [])
    ctx = Context(described, Variables(positions), work_point=targets[0])
    slope = np.linspace(-1.0, 1.0, ctx.n)
    columns = located_lever_slope(ctx, "EBY", slope)
    np.testing.assert_allclose(columns[:, 0, 0], -slope, atol=0)
    np.testing.assert_allclose(columns[:, 2, 1], -slope, atol=0)
    assert not np.any(columns[:, 1, :])


def test_a_pivot_beyond_the_machines_reach_is_refused_in_words():
    """The pivot a fit implies, |lever slope| / |P1|, beyond the machine's strokes, tool and
    half a metre is refused with its distance (a yaw's 40 um lever slope over a 5.5 urad
    slope: a pivot 7.3 m away); the same slope at a pivot of 0.2 m stands."""
    ctx, _, _ = _ctx([], {"A": 0, "C": 0})
    family = ComponentError("angular", False)
    names = family.parameter_names("EBY", SLOPED)
    far = dict(zip(names, [5.5e-6, 50e-6, 0.0, 0.0, 0.0, 40e-6]))
    near = dict(far, lever_slope_z=0.2 * 5.5e-6)
    (problem,) = family.fit_problems(ctx, "EBY", SLOPED, [far[n] for n in names])
    assert "7.27 m" in problem and "beyond the machine's reach" in problem
    assert family.fit_problems(ctx, "EBY", SLOPED, [near[n] for n in names]) == []


def test_a_constant_lever_beyond_the_machines_reach_is_refused_in_words():
    """The same rule for the lever of the constant part, |lever| / |P0|: a fit that divides
    a line offset of a million metres by an 11 urad turn (a direction the poses barely
    see) is refused; a pivot of 0.9 m at the same turn stands."""
    ctx, _, _ = _ctx([], {"A": 0, "C": 0})
    family = ComponentError("angular", False)
    names = family.parameter_names("EBY", SLOPED)
    far = dict(zip(names, [50e-6, 11e-6, -1e6, 0.06e-6, 0.0, 0.0]))
    near = dict(far, lever_x=0.9 * 11e-6)
    (problem,) = family.fit_problems(ctx, "EBY", SLOPED, [far[n] for n in names])
    assert "the pivot its lever puts 9.09e+10 m" in problem, problem
    assert "beyond the machine's reach" in problem
    assert family.fit_problems(ctx, "EBY", SLOPED, [near[n] for n in names]) == []
