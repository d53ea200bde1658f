"""The tilt of a carriage that carries the rotary axes, read by a target located at the set-up.

A work-side carriage that carries the rotary axes (a trunnion's X or Y) turns by eps(q)
about its pivot, and with it the rotary axes, the table and the work. A sphere located
at the set-up pose (an R-test's, a probed one) took in the tilt's move there, and that
belief turns with the rotary axes (ISO 10791-6), so the instrument reads

    e(q) - R_S(q) R_S(q_s)^T e(q_s),    e(q) = eps(q) x (r(q) - p)

(the datum takes the constant). The readings come from ``studies.convention_surveys``
(rigid bodies written from the physics alone), on machines described to both codes.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects.base import Context, along
from mt_accuracy_ros.core.effects.geometric import (ComponentError, Squareness, located_tilt,
                                                   setup_rows,
                                                   turns_about_carried_rotary)
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
from studies import convention_surveys as cs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "workbench"))
import test_separability as geometry  # noqa: E402  (the machines both codes are told)

#: A tilt eps(q) = c0 + c1 q + c2 q^2 [rad, rad/m, rad/m^2] of the generator's command q.
POLY = [40e-6, 300e-6, -200e-6]
#: Its Legendre coefficients over the stroke -0.6 .. 0.9 m (q = 0.75 u + 0.15):
#: P0 = c0 + 0.15 c1 + 0.15^2 c2 + 0.75^2 c2 / 3, P1 = 0.75 c1 + 2 0.75 0.15 c2,
#: P2 = 2 0.75^2 c2 / 3 [rad].
LEGENDRE = {"P0": 43.0e-6, "P1": 180.0e-6, "P2": -75.0e-6}
#: Three probed spheres, workpiece frame [m].
SPHERES = np.array([[0.06, -0.04, 0.05], [-0.05, 0.07, 0.02], [0.02, 0.03, 0.08]])


def _trunnion_ac(setup_deg):
    work = [cs._ax("Y", -1, [0, 0, 0.092]), cs._ax("X", -1, [0, 0, 0.324]),
            cs._ax("A", -1, [0, 0, -0.049]), cs._ax("C", -1, [0, 0, 0])]
    return geometry._machines(work, [cs._ax("Z", -1, [0, 0, 0.632])], [0, 0, -0.199],
                              setup_deg, {"A": (-30, 110), "C": (-360, 360)})


def _located_readings(generator, described, poses, spheres, effects):
    """(positions, noise-free errors (N, 3) [m], targets (N, 3), groups (N,)): each sphere
    located at its own first reading, at the set-up pose, then followed over ``poses``."""
    count = len(spheres)
    setup = [dict(generator["setup"])] * count
    all_poses = setup + [p for _ in range(count) for p in poses]
    targets = [spheres[g] for g in range(count)] + \
        [spheres[g] for g in range(count) for _ in poses]
    groups = list(range(count)) + [g for g in range(count) for _ in poses]
    rows = {"q": [cs.solve_linear(generator, p, t) for p, t in zip(all_poses, targets)],
            "target": np.array(targets), "group": groups,
            "setup": {g: g for g in range(count)}, "tool_setup": 0}
    errors, _ = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    positions = {a: np.array([q[a] for q in rows["q"]]) for a in described.axis_order}
    return positions, errors, np.array(targets), np.array(groups)


def _tilt(name, pivot=(0.0, 0.0, 0.0)):
    return {"iso_name": name, "kind": "table_tilt", "axis": name[2], "value_si": POLY,
            "pivot_m": list(pivot)}


def _fit(design, errors, groups):
    """Least squares of ``errors`` on the design's columns and a zero per target:
    (coefficients, RMS residual [m])."""
    n, _, p = design.shape
    offsets = np.zeros((n, 3, 3 * (groups.max() + 1)))
    for g in range(groups.max() + 1):
        offsets[groups == g, :, 3 * g:3 * g + 3] = np.eye(3)
    columns = np.concatenate([design, offsets], axis=2).reshape(3 * n, -1)
    solution, *_ = np.linalg.lstsq(columns, errors.reshape(-1), rcond=None)
    residual = errors.reshape(-1) - columns @ solution
    return solution[:p], float(np.sqrt(np.mean(residual ** 2)))


def _grid(setup_deg):
    return [{"A": math.radians(a), "C": math.radians(c)}
            for a in np.arange(-30, 111, 20) for c in np.arange(0, 360, 30)] + \
        [{k: math.radians(v) for k, v in setup_deg.items()}]


@pytest.mark.parametrize("name", ["ECY", "EBX", "ECX"])
@pytest.mark.parametrize("setup_deg", [{"A": 0, "C": 0}, {"A": 60, "C": 45}])
def test_the_located_tilt_about_the_carriage_origin_is_the_generators_closed_form(name,
                                                                                 setup_deg):
    """The package's located tilt, at the Legendre coefficients of the generator's
    polynomial, reproduces its readings to second order (a 300 urad/m tilt over 0.75 m:
    below 0.01 um), at a set-up pose of zeros and off them; the fit returns the closed
    form's coefficients."""
    generator, described = _trunnion_ac(setup_deg)
    positions, errors, targets, groups = _located_readings(
        generator, described, _grid(setup_deg), SPHERES[:1], [_tilt(name)])
    ctx = Context(described, Variables(positions), work_point=targets[0],
                  located_readings=True)
    family = ComponentError("angular", False)
    setting = {"order": 2, "constant": True, "located": True}
    assert setting in family.settings(ctx, name)
    coefficients, rms = _fit(ctx.measured_design(family, name, setting), errors, groups)
    assert np.abs(errors).max() > 1e-6                       # the tilt is seen
    assert rms < 1e-8
    fitted = dict(zip(family.parameter_names(name, setting), coefficients))
    for key, value in LEGENDRE.items():
        assert fitted[key] == pytest.approx(value, abs=0.2e-6)


def test_without_the_located_part_the_tilt_leaves_the_set_up_turning_with_the_rotaries():
    """The same tilt, unlocated (the plain angular design, constant part and all), leaves
    micrometres: what the sphere took in at the set-up, turning with A and C."""
    generator, described = _trunnion_ac({"A": 0, "C": 0})
    positions, errors, targets, groups = _located_readings(
        generator, described, _grid({"A": 0, "C": 0}), SPHERES[:1], [_tilt("EBX")])
    ctx = Context(described, Variables(positions), work_point=targets[0],
                  located_readings=True)
    family = ComponentError("angular", False)
    plain = along(*family.separable_design(ctx, "EBX", {"order": 2, "constant": True}))
    _, rms = _fit(plain, errors, groups)
    assert rms > 0.5e-6


def test_three_probed_spheres_each_located_on_its_own_read_the_same_tilt():
    """Three spheres, each found at the set-up at its own reading, each its own zero: the
    located tilt takes each sphere's own value at the set-up and fits the closed form."""
    generator, described = geometry._trunnion_bc({"B": 0, "C": 0})
    poses = [{"B": math.radians(b), "C": math.radians(c)}
             for b in np.arange(-90, 91, 30) for c in np.arange(-180, 180, 45)]
    positions, errors, targets, groups = _located_readings(
        generator, described, poses, SPHERES, [_tilt("ECY")])
    ctx = Context(described, Variables(positions), work_point=targets,
                  located_readings=True)
    np.testing.assert_array_equal(np.unique(setup_rows(ctx)), [0, 1, 2])
    family = ComponentError("angular", False)
    setting = {"order": 2, "constant": True, "located": True}
    coefficients, rms = _fit(ctx.measured_design(family, "ECY", setting), errors, groups)
    assert rms < 1e-8
    fitted = dict(zip(family.parameter_names("ECY", setting), coefficients))
    assert fitted["P1"] == pytest.approx(LEGENDRE["P1"], abs=0.2e-6)


def test_a_pivot_off_the_carriage_origin_adds_columns_of_the_tilts_own_shape():
    """eps(q) x (r - p) = eps(q) x r - eps(q) x p: a pivot p off the origin adds, across the
    tilt's axis, the tilt's own shape along two fixed directions (what a straightness and a
    positioning error of the same axis with the same shape would be), located alike. The
    located tilt alone leaves micrometres; with those columns, the closed form."""
    generator, described = _trunnion_ac({"A": 0, "C": 0})
    pivot = (0.2, -0.3, 0.1)
    positions, errors, targets, groups = _located_readings(
        generator, described, _grid({"A": 0, "C": 0}), SPHERES[:1], [_tilt("ECY", pivot)])
    ctx = Context(described, Variables(positions), work_point=targets[0],
                  located_readings=True)
    family = ComponentError("angular", False)
    setting = {"order": 2, "constant": True, "located": True}
    tilt = ctx.measured_design(family, "ECY", setting)
    _, alone = _fit(tilt, errors, groups)
    assert alone > 1e-6
    basis = family.separable_design(ctx, "ECY", dict(setting, located=False))[1]
    across = [located_tilt(ctx, along(np.tile(np.eye(3)[j], (ctx.n, 1)), basis))
              for j in (0, 1)]
    _, with_pivot = _fit(np.concatenate([tilt] + across, axis=2), errors, groups)
    assert with_pivot < 1e-8


def test_the_constant_turn_about_the_first_carried_rotary_axis_is_offered_at_order_one():
    """On a trunnion B/C, X carries B (about y): a constant pitch EBX of X is B's zero and
    line offset, so the located tilt takes its constant part at order 1 only, without a
    lever (the lines' offsets are the line family's); a yaw ECY of Y has them all."""
    generator, described = geometry._trunnion_bc({"B": 0, "C": 0})
    assert turns_about_carried_rotary(described, "EBX")
    assert turns_about_carried_rotary(described, "EBY")
    assert not turns_about_carried_rotary(described, "ECY")
    poses = [{"B": math.radians(b), "C": 0.0} for b in np.arange(-90, 91, 30)]
    positions, _, targets, _ = _located_readings(generator, described, poses, SPHERES[:1],
                                                 [])
    ctx = Context(described, Variables(positions), work_point=targets[0],
                  located_readings=True)
    family = ComponentError("angular", False)
    constant = [s for s in family.settings(ctx, "EBX") if s.get("constant")]
    assert constant == [{"order": 1, "constant": True, "located": True}]
    assert any(s.get("constant") and s.get("lever") for s in family.settings(ctx, "ECY"))


def test_a_slope_of_a_tilt_about_the_carried_axis_keeps_its_mean_over_the_stroke():
    """Trunnion B/C probed at three spheres, B swept alone: Y pitched about B's direction
    by eps(y) = 85 urad/m y about its origin. Over the stroke -0.6 .. 0.9 m the tilt's mean
    P0 = 0.15 c1 is no part of the Legendre slope: the slope alone leaves it (B's line
    offset by its lever), the order-1 setting with the constant part fits the generator's
    readings to second order at P1 = 0.75 c1, P0 = 0.15 c1. Without it a yaw of the same
    carriage with its constant part fitted these readings better than the pitch did."""
    generator, described = geometry._trunnion_bc({"B": 0, "C": 0})
    poses = [{"B": math.radians(b), "C": 0.0} for b in np.arange(-110, 31, 10)] * 4
    slope = 85e-6
    tilt = {"iso_name": "EBY", "kind": "table_tilt", "axis": "Y",
            "value_si": [0.0, slope, 0.0], "pivot_m": [0.0, 0.0, 0.0]}
    positions, errors, targets, groups = _located_readings(generator, described, poses,
                                                           SPHERES, [tilt])
    ctx = Context(described, Variables(positions), work_point=targets,
                  located_readings=True)
    family = ComponentError("angular", False)
    setting = {"order": 1, "constant": True, "located": True}
    assert setting in family.settings(ctx, "EBY")
    coefficients, rms = _fit(ctx.measured_design(family, "EBY", setting), errors, groups)
    assert np.abs(errors).max() > 0.3e-6 and rms < 1e-10
    fitted = dict(zip(family.parameter_names("EBY", setting), coefficients))
    assert fitted["P1"] == pytest.approx(0.75 * slope, abs=0.05e-6)
    assert fitted["P0"] == pytest.approx(0.15 * slope, abs=0.05e-6)
    _, alone = _fit(ctx.measured_design(family, "EBY", {"order": 1, "located": True}),
                    errors, groups)
    assert alone > 20 * rms and alone > 0.05e-6


def test_no_reading_at_the_set_up_pose_offers_no_located_tilt():
    """Where no reading is at the set-up pose, where the target was located is not known:
    the tilt is offered plain, and a located setting's design is the tilt itself."""
    generator, described = geometry._trunnion_bc({"B": 0, "C": 0})
    poses = [{"B": math.radians(b), "C": 0.3} for b in np.arange(-90, 91, 30)]
    q = [cs.solve_linear(generator, p, SPHERES[0]) for p in poses]
    positions = {a: np.array([row[a] for row in q]) for a in described.axis_order}
    ctx = Context(described, Variables(positions), work_point=SPHERES[0],
                  located_readings=True)
    family = ComponentError("angular", False)
    assert setup_rows(ctx) is None
    assert not any(s.get("located") for s in family.settings(ctx, "ECY"))
    located = family.design(ctx, "ECY", {"order": 1, "located": True})
    np.testing.assert_array_equal(located, family.design(ctx, "ECY", {"order": 1}))


def _observations(positions, errors, targets, seed=0):
    n = errors.shape[0]
    measured = errors + np.random.default_rng(seed).normal(0.0, geometry.NOISE, (n, 3))
    work_point = targets[0] if np.all(targets == targets[0]) else targets
    return Observations(positions, measured, np.ones((n, 3), bool), np.arange(n, dtype=float),
                        {}, {}, 2 * geometry.NOISE, work_point=work_point)


def test_a_yaw_of_the_carriage_under_a_c_sweep_is_named_with_its_constant_part():
    """A trunnion B/C's R-test sweeping C alone, B at the set-up, the Y carriage (which
    carries B and C) yawed by eps(y) = -47 urad + 300 urad/m y about its origin: named
    as the yaw, its constant part and slope the closed form's (before: a 7th-order
    straightness EXY and C's line offsets)."""
    generator, described = geometry._trunnion_bc({"B": 0, "C": 0})
    poses = [{"B": 0.0, "C": math.radians(c)} for c in np.arange(0, 360, 15)] * 12
    yaw = {"iso_name": "ECY", "kind": "table_tilt", "axis": "Y",
           "value_si": [-47e-6, 300e-6, 0.0], "pivot_m": [0.0, 0.0, 0.0]}
    positions, errors, targets, _ = _located_readings(generator, described, poses,
                                                      SPHERES[:1], [yaw])
    diagnosis = diagnose(ErrorModel(described), _observations(positions, errors, targets))
    names = [s.name for s in diagnosis.selected]
    assert names == ["angular:ECY"], diagnosis.text()
    named = diagnosis.selected[0]
    # Stroke -0.6 .. 0.9 m: P0 = c0 + 0.15 c1 = -2 urad, P1 = 0.75 c1 = 225 urad.
    assert named.parameters["P1"] == pytest.approx(225e-6, abs=25e-6)
    assert named.parameters.get("P0", 0.0) == pytest.approx(-2e-6, abs=15e-6)


def test_a_yaw_and_a_pitch_of_the_carriages_seen_by_three_probed_spheres_are_both_named():
    """Three spheres probed on a trunnion B/C over a grid, each located on its own: the Y
    carriage's yaw (constant, linear and quadratic) and the X carriage's pitch are named,
    nothing else (before: B's and C's lines, a squareness and stand-ins; before the located
    tilt's lever, the yaw's constant part as the XY squareness, located, 53.6 urad for 52,
    and its varying part as a straightness EXY of order 4)."""
    generator, described = geometry._trunnion_bc({"B": 0, "C": 0})
    poses = [{"B": math.radians(b), "C": math.radians(c)}
             for b in np.arange(-90, 91, 30) for c in np.arange(-180, 180, 45)] * 2
    yaw = {"iso_name": "ECY", "kind": "table_tilt", "axis": "Y",
           "value_si": [52e-6, -110e-6, -560e-6], "pivot_m": [0.0, 0.0, 0.0]}
    pitch = {"iso_name": "EBX", "kind": "table_tilt", "axis": "X",
             "value_si": [0.0, 93e-6, 0.0], "pivot_m": [0.0, 0.0, 0.0]}
    positions, errors, targets, _ = _located_readings(generator, described, poses, SPHERES,
                                                      [yaw, pitch])
    diagnosis = diagnose(ErrorModel(described), _observations(positions, errors, targets))
    assert sorted(s.name for s in diagnosis.selected) == ["angular:EBX", "angular:ECY"], \
        diagnosis.text()


@pytest.mark.parametrize("located", [True, False])
def test_a_squareness_of_a_table_slide_is_read_located_like_its_tilt(located):
    """Y's slide out of square with X (EC0Y, 50 urad) on a trunnion A/C, an R-test sphere
    located at the set-up: the squareness' move there went into the sphere and turns with
    A and C. The squareness family's design is the located one (the generator's readings
    to second order, as X's error growing with Y, EXY); the plain design leaves
    micrometres."""
    generator, described = _trunnion_ac({"A": 0, "C": 0})
    square = {"iso_name": "EC0Y", "kind": "squareness", "axis": "Y", "value_si": 50e-6}
    positions, errors, targets, groups = _located_readings(
        generator, described, _grid({"A": 0, "C": 0}), SPHERES[:1], [square])
    ctx = Context(described, Variables(positions), work_point=targets[0],
                  located_readings=True)
    family = Squareness()
    design = family.design(ctx, "EXY", {}) if located else \
        (ctx.jacobian("EXY") * positions["Y"][:, None])[:, :, None]
    coefficients, rms = _fit(design, errors, groups)
    if located:
        assert rms < 1e-8
        assert abs(coefficients[0]) == pytest.approx(50e-6, rel=0.01)
    else:
        assert rms > 0.5e-6


@pytest.mark.parametrize("name", ["ECY", "EBX"])
def test_a_cncs_own_commands_get_the_tilt_as_the_machine_makes_it_whatever_poses(name):
    """A compensation's batch of commands is no instrument's: nothing was located among
    them, so a located tilt predicts the machine's own tilt there - the plain design - even
    when the batch holds the set-up pose (before, such a row turned the batch's prediction
    into the located reading: micrometres apart for the same commands)."""
    generator, described = _trunnion_ac({"A": 0, "C": 0})
    positions, _, targets, _ = _located_readings(
        generator, described, _grid({"A": 0, "C": 0}), SPHERES[:1], [])
    family = ComponentError("angular", False)
    setting = {"order": 2, "constant": True, "located": True}
    commands = Context(described, Variables(positions), work_point=targets[0])
    readings = Context(described, Variables(positions), work_point=targets[0],
                       located_readings=True)
    plain = along(*family.separable_design(commands, name, {"order": 2, "constant": True}))
    assert setup_rows(commands) is None and setup_rows(readings) is not None
    np.testing.assert_array_equal(family.design(commands, name, setting), plain)
    assert np.abs(family.design(readings, name, setting) - plain).max() > 1e-3
