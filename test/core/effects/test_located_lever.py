"""A roll of a carriage that carries the rotary axes, about a pivot off its origin, read by a
target located at the set-up.

A work-side carriage tilted by eps(q) = c0 + c1 q about a pivot p (carriage frame) moves
what it carries about p: x -> p + R (x - p), a turn about the origin and a move by
-eps(q) x p (ISO 230-1). The move's constant part, the lever v = -c0 x p, is a translation
of the carriage and of the rotary axes, the table and the work it carries; a target located
at the set-up took it in there, and it turns with the rotary axes (ISO 10791-6): the
reading changes by -(I - R_S(q) R_S(q_s)^T) v, across the tilt's axis. A translation of
the carriage is the offset of every rotary line it carries (ISO 230-7). The readings come
from ``studies.convention_surveys`` (rigid bodies written from the physics alone).
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects.base import Context
from mt_accuracy_ros.core.effects.display import parameter_unit
from mt_accuracy_ros.core.effects.geometric import (ComponentError, Squareness,
                                                   lever_components, lever_line_offsets,
                                                   located_lever)
from mt_accuracy_ros.core.effects.setup_location import located_design
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.workbench.diagnosis import diagnose

from test_located_tilt import (SPHERES, _fit, _grid, _located_readings, _observations,
                               _trunnion_ac)

#: A pivot off the carriage's origin, carriage frame [m] (trial 002 of seed 11's).
PIVOT = (-0.142, 0.423, -0.023)
#: The lever setting: the located tilt's P1, P0 and the lever across its axis.
LEVER = {"order": 1, "constant": True, "located": True, "lever": True}
#: The lever with its slope (the pivot's move growing with the tilt's slope).
SLOPED = dict(LEVER, lever_slope=True)


def _roll(value_si, pivot=PIVOT, name="EBY"):
    return {"iso_name": name, "kind": "table_tilt", "axis": name[2],
            "value_si": list(value_si), "pivot_m": list(pivot)}


def _ctx(effects, setup_deg=None):
    setup_deg = setup_deg or {"A": 0, "C": 0}
    generator, described = _trunnion_ac(setup_deg)
    positions, errors, targets, groups = _located_readings(
        generator, described, _grid(setup_deg), SPHERES[:1], effects)
    return (Context(described, Variables(positions), work_point=targets[0], located_readings=True),
            errors, groups)


def test_lever_components_are_across_the_tilts_axis():
    assert lever_components("EBY") == "xz"
    assert lever_components("ECX") == "xy"
    assert lever_components("EAY") == "yz"
    assert ComponentError("angular", False).parameter_names("EBY", LEVER) == \
        ["P1", "P0", "lever_x", "lever_z"]
    assert parameter_unit("angular", "EBY", "lever_x") == ("µm", 1e6)
    assert parameter_unit("angular", "EBY", "P0") == ("µrad", 1e6)


@pytest.mark.parametrize("setup_deg", [{"A": 0, "C": 0}, {"A": 60, "C": 45}])
def test_a_constant_roll_about_a_pivot_is_the_located_tilt_and_its_lever(setup_deg):
    """A constant roll c0 of the Y carriage (which carries A and C) about p: the located
    tilt with its lever reproduces the generator's readings to second order (50 urad x
    0.5 m: below 0.01 um), P0 = c0, and the lever is the closed form -c0 e_y x p =
    c0 (-p_z, 0, p_x) in x and z."""
    c0 = 50e-6
    ctx, errors, groups = _ctx([_roll([c0, 0.0, 0.0])], setup_deg)
    family = ComponentError("angular", False)
    assert LEVER in family.settings(ctx, "EBY")
    coefficients, rms = _fit(ctx.measured_design(family, "EBY", LEVER), errors, groups)
    assert np.abs(errors).max() > 5e-6
    assert rms < 1e-8
    fitted = dict(zip(family.parameter_names("EBY", LEVER), coefficients))
    assert fitted["P0"] == pytest.approx(c0, abs=0.05e-6)
    assert fitted["P1"] == pytest.approx(0.0, abs=0.05e-6)
    assert fitted["lever_x"] == pytest.approx(-c0 * PIVOT[2], abs=1e-9)
    assert fitted["lever_z"] == pytest.approx(c0 * PIVOT[0], abs=1e-9)


def test_without_the_lever_the_roll_about_a_pivot_leaves_micrometres():
    """The same roll, the located tilt alone (the pivot at the carriage's origin): the
    lever's located move is left."""
    ctx, errors, groups = _ctx([_roll([50e-6, 0.0, 0.0])])
    family = ComponentError("angular", False)
    plain = {"order": 1, "constant": True, "located": True}
    _, rms = _fit(ctx.measured_design(family, "EBY", plain), errors, groups)
    assert rms > 1e-6


def test_the_lever_is_the_located_set_up_errors_shape_across_the_axis():
    """A second formulation: the lever's columns are the located set-up error's,
    (I - R_S R_S(q_s)^T), along x and z for a roll about y, of the opposite sign (the
    carriage's move, not the reading's)."""
    ctx, _, _ = _ctx([])
    np.testing.assert_allclose(located_lever(ctx, "EBY"),
                               -located_design(ctx, "work")[:, :, [0, 2]], atol=0)


def test_the_largest_setting_holds_every_smaller_ones_columns_and_not_the_levers():
    """The nested columns of the largest located setting (order 2 with its constant part)
    hold each smaller located one's; the lever's are its own (None)."""
    ctx, _, _ = _ctx([])
    family = ComponentError("angular", False)
    settings = family.settings(ctx, "EBY")
    largest = settings[-1]
    assert largest == {"order": 2, "constant": True, "located": True}
    assert [s for s in settings if s.get("lever")] == [LEVER, SLOPED]
    assert family.nested_columns("EBY", LEVER, largest) is None
    assert family.nested_columns("EBY", SLOPED, largest) is None
    full = ctx.measured_design(family, "EBY", largest)
    for setting in settings:
        if not setting.get("located") or setting.get("lever"):
            continue
        columns = family.nested_columns("EBY", setting, largest)
        np.testing.assert_allclose(full[:, :, columns],
                                   ctx.measured_design(family, "EBY", setting), atol=1e-15)


def test_the_constant_roll_about_the_origin_is_the_located_xz_squareness_on_these_poses():
    """What the poses cannot part: a constant roll EBY of the carriage that carries X, A
    and C turns X's travel against Z's (their squareness, ISO 230-1), the rotary lines and
    the work with it; located at the set-up, the lines' tilts leave no trace and the
    readings are the squareness' alone (EB0Z = c0), to second order. The lever and the
    roll's slope are what tell a roll apart."""
    c0 = 50e-6
    ctx, errors, groups = _ctx([_roll([c0, 0.0, 0.0], pivot=(0.0, 0.0, 0.0))])
    family = Squareness()
    coefficients, rms = _fit(ctx.measured_design(family, "EB0Z", {}), errors, groups)
    assert rms < 1e-8
    assert abs(coefficients[0]) == pytest.approx(c0, rel=1e-3)


def test_a_roll_of_the_carriage_that_carries_a_and_c_about_a_pivot_is_named_as_the_roll():
    """An R-test on a trunnion A/C, the Y carriage (which carries X, A and C) rolled by
    eps(y) = -49 urad - 200 urad/m y about a pivot p off its origin: named as the roll alone,
    with its constant part, its lever and the lever's slope, the closed forms' (the pivot's
    move -eps(y) e_y x p grows along Y, ISO 230-1; before the slope, Y's travel tilted in z
    named beside the roll; before the lever, A's and C's lines, eight numbers)."""
    generator, described = _trunnion_ac({"A": 0, "C": 0})
    poses = [{"A": math.radians(a), "C": math.radians(c)}
             for a in np.arange(-30, 111, 10) for c in np.arange(0, 360, 15)]
    c0, c1 = -49e-6, -200e-6
    positions, errors, targets, _ = _located_readings(generator, described, poses,
                                                      SPHERES[:1], [_roll([c0, c1, 0.0])])
    diagnosis = diagnose(ErrorModel(described), _observations(positions, errors, targets))
    named = {s.name: s for s in diagnosis.selected}
    assert sorted(named) == ["angular:EBY"], diagnosis.text()
    roll = named["angular:EBY"]
    assert roll.setting == SLOPED
    # Y's stroke -0.6 .. 0.9 m: P0 = c0 + 0.15 c1 = -79 urad, P1 = 0.75 c1 = -150 urad.
    p0, p1 = c0 + 0.15 * c1, 0.75 * c1
    # The survey moved Y by +-72 mm of its 1.5 m stroke, so P1 (per half stroke) is read
    # from a tenth of its reach.
    assert roll.parameters["P0"] == pytest.approx(p0, abs=6e-6)
    assert roll.parameters["P1"] == pytest.approx(p1, rel=0.15)
    # The lever -P0 e_y x p = P0 (-p_z, 0, p_x) and its slope -P1 e_y x p along z, where
    # the pivot's long arm p_x = -0.142 m acts (along x, p_z = -0.023 m moves a few um,
    # which these poses share with the tilt's own numbers).
    assert roll.parameters["lever_z"] == pytest.approx(p0 * PIVOT[0], abs=0.6e-6)
    assert roll.parameters["lever_slope_z"] == pytest.approx(p1 * PIVOT[0], rel=0.1)
    assert not diagnosis.residual_above_noise, diagnosis.text()
    # Said: the lever is the offsets of the lines Y carries, and the located set-up error.
    # The lever's numbers only (no whole alternative, not its slope), and P0 as the
    # squareness of the roll's plane, which it is on these poses (one rotation, ISO 230-1).
    said, *plane = roll.inseparable
    assert plane and {p["name"] for p in plane} <= {"squareness:EB0Z", "squareness:EXZ",
                                                    "squareness:EZX"}, plane
    for form in plane:
        assert abs(form["parameters"]["angle_rad"]) == pytest.approx(
            abs(roll.parameters["P0"]), rel=0.1)
    assert said["name"] == "rotary_location:AC"
    assert said["parameters"] == pytest.approx(
        {"EZ0A": roll.parameters["lever_z"], "EX0C": roll.parameters["lever_x"]}, abs=1e-15)
    assert f"v_x {-roll.parameters['lever_x'] * 1e6:.3g} µm" in said["reason"]
    assert "lever_slope" not in said["reason"]
    assert "lever (lever_x, lever_z" in roll.explanation


def test_the_lever_is_the_offsets_of_the_lines_the_carriage_carries():
    """A second formulation, on any poses: offsets of A's line in z and of C's line in x
    (ISO 230-7, the bodies turning about the moved lines, in the generator) are read as the
    Y carriage's lever in z and x, and the lever is said back as those offsets."""
    offsets = [{"iso_name": "EZ0A", "kind": "location_offset", "axis": "A",
                "value_si": 20e-6},
               {"iso_name": "EX0C", "kind": "location_offset", "axis": "C",
                "value_si": -15e-6}]
    for setup_deg in ({"A": 0, "C": 0}, {"A": 60, "C": 45}):
        ctx, errors, groups = _ctx(offsets, setup_deg)
        coefficients, rms = _fit(located_lever(ctx, "EBY"), errors, groups)
        assert np.abs(errors).max() > 5e-6
        assert rms < 1e-9
        np.testing.assert_allclose(coefficients, [-15e-6, 20e-6], atol=1e-10)
    lever = {"lever_x": -15e-6, "lever_z": 20e-6}
    assert lever_line_offsets(ctx.machine, "EBY", lever) == {"EZ0A": 20e-6, "EX0C": -15e-6}


def test_the_lever_of_a_yaw_offsets_every_carried_line_across_it():
    """A yaw ECY's lever lies along x and y: it offsets A's line in y and C's line in x and
    y (each line keeps v's components across its own direction, ISO 230-7); readings made
    from exactly those offsets are the yaw's lever's, at two set-up poses."""
    lever = {"lever_x": 12e-6, "lever_y": -9e-6}
    offsets = {"EY0A": -9e-6, "EX0C": 12e-6, "EY0C": -9e-6}
    for setup_deg in ({"A": 0, "C": 0}, {"A": 60, "C": 45}):
        ctx, _, _ = _ctx([], setup_deg)
        assert lever_line_offsets(ctx.machine, "ECY", lever) == offsets
        truth = [{"iso_name": name, "kind": "location_offset", "axis": name[3],
                  "value_si": value} for name, value in offsets.items()]
        ctx, errors, groups = _ctx(truth, setup_deg)
        coefficients, rms = _fit(located_lever(ctx, "ECY"), errors, groups)
        assert np.abs(errors).max() > 5e-6
        assert rms < 1e-9
        np.testing.assert_allclose(coefficients, [12e-6, -9e-6], atol=1e-10)


def test_the_levers_prediction_does_not_depend_on_a_set_up_reading_in_the_batch():
    """A CNC's own commands hold no reading at the set-up pose: the lever is the machine's
    (its carried lines' offsets, referred to the machine's set-up pose), so its columns are
    the same whether or not the batch holds such a reading (before: zeros without one)."""
    generator, described = _trunnion_ac({"A": 0, "C": 0})
    poses = _grid({"A": 0, "C": 0})
    positions, _, targets, _ = _located_readings(generator, described, poses, SPHERES[:1], [])
    family = ComponentError("angular", False)
    with_setup = Context(described, Variables(positions), work_point=targets[0],
                         located_readings=True)
    moved = np.abs(positions["A"]) + np.abs(positions["C"]) > 1e-3
    without = Context(described, Variables({k: v[moved] for k, v in positions.items()}),
                      work_point=targets[0])
    full = family.design(with_setup, "EBY", LEVER)
    assert not np.all(moved) and np.any(full[moved][:, :, -2:])
    np.testing.assert_allclose(family.design(without, "EBY", LEVER)[:, :, -2:],
                               full[moved][:, :, -2:], atol=1e-15)
