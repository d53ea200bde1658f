"""The tilt of a tool-side carriage that carries a turning head, read by located instruments.

A tool-side carriage that carries the head's rotary axes (a gantry's Y, X or the Z ram of a
swivel head B/C) turns by eps(q) about its pivot, and with it the head's lines and the
tool. The tool was located at the head's set-up pose (its length and position set in its
own frame, ISO 10791-6): the tilt's move there, e(q_t), went into where the tool is
believed to be, and that belief turns with the head, so the instrument reads

    e(q) - R_T(q) R_T(q_s)^T e(q_t),    e(q) = eps(q) x (r_tip(q) - p)

and the tool's direction alike, w(q) - R_T(q) R_T(q_s)^T w(q_t) (the datum takes the
constant where the work does not turn). Two further readings of the same set-up: where
the carriages stand still (a sweep of C with the tip on its line) a constant turn draws
the circle a line offset draws, and the output says so; a work-side table's tilt under a
turning head, its direction change at the set-up located into the spheres.

The readings come from ``studies.convention_surveys`` (rigid bodies written from the
physics alone), on machines described to both codes.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects.base import Context, along
from mt_accuracy_ros.core.effects.geometric import (HEAD, ComponentError, carries_head,
                                                   head_setup_row,
                                                   turns_about_carried_rotary)
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
from mt_accuracy_ros.core.workbench.selection import Selector, Term
from studies import convention_surveys as cs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "workbench"))
import test_separability as geometry  # noqa: E402  (the machines both codes are told)

#: eps(q) = c0 + c1 q + c2 q^2 [rad, rad/m, rad/m^2] of the generator's command q, and its
#: Legendre coefficients over the stroke -0.6 .. 0.9 m (q = 0.75 u + 0.15):
#: P0 = c0 + 0.15 c1 + 0.15^2 c2 + 0.75^2 c2 / 3, P1 = 0.75 c1 + 2 0.75 0.15 c2,
#: P2 = 2 0.75^2 c2 / 3 [rad].
POLY = [40e-6, 300e-6, -200e-6]
LEGENDRE = {"P0": 43.0e-6, "P1": 180.0e-6, "P2": -75.0e-6}
SPHERE = np.array([0.06, -0.04, 0.05])       # workpiece frame [m]
TOOL = [0.0, 0.0, -0.15]                     # the tool vector [m]


def _gantry_head(setup_deg):
    """A gantry swivel head B/C: Y, X and the Z ram carry C and B; nothing on the bed."""
    tool = [cs._ax("Y", -1, [0, 0, 0]), cs._ax("X", 1, [0, 0, 0.355]),
            cs._ax("Z", -1, [0, 0, 0.603]), cs._ax("C", 1, [0, 0, -0.122]),
            cs._ax("B", 1, [0, 0, -0.136])]
    return geometry._machines([], tool, TOOL, setup_deg, {"C": (-180, 180), "B": (-120, 120)})


def _tables_head(setup_deg):
    """A swivel head B/C on the Z ram over the Y and X tables."""
    work = [cs._ax("Y", -1, [0, 0, 0.13]), cs._ax("X", 1, [0, 0, 0.05])]
    tool = [cs._ax("Z", 1, [0, 0, 0.547]), cs._ax("C", -1, [0, 0, -0.106]),
            cs._ax("B", 1, [0, 0, -0.085])]
    return geometry._machines(work, tool, [0, 0, -0.088], setup_deg,
                              {"C": (0, 360), "B": (-110, 30)})


def _grid(setup_deg):
    return [{"B": math.radians(b), "C": math.radians(c)}
            for b in np.arange(-90, 31, 20) for c in np.arange(-180, 180, 30)]


def _readings(generator, described, poses, effects):
    """(context with the direction measured, located errors (N, 3) [m], located direction
    changes (N, 3)): one sphere and the tool located at the first reading, at the set-up
    pose, then followed with RTCP over ``poses``."""
    poses = [dict(generator["setup"])] + list(poses)
    rows = {"q": [cs.solve_linear(generator, p, SPHERE) for p in poses],
            "target": np.tile(SPHERE, (len(poses), 1)), "group": [0] * len(poses),
            "setup": {0: 0}, "tool_setup": 0}
    errors, directions = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    positions = {a: np.array([q[a] for q in rows["q"]]) for a in described.axis_order}
    ctx = Context(described, Variables(positions), work_point=SPHERE, orientation_lever_m=0.1,
                  located_readings=True)
    return ctx, errors, directions


def _tilt(name, poly=POLY, pivot=(0.0, 0.0, 0.0)):
    return {"iso_name": name, "kind": "table_tilt", "axis": name[2], "value_si": list(poly),
            "pivot_m": list(pivot)}


def _fit(design, errors):
    """Least squares of ``errors`` (N, 3) on the design's columns and a free zero:
    (coefficients, RMS residual [m])."""
    n, _, p = design.shape
    offsets = np.tile(np.eye(3), (n, 1, 1))
    columns = np.concatenate([design, offsets], axis=2).reshape(3 * n, -1)
    solution, *_ = np.linalg.lstsq(columns, errors.reshape(-1), rcond=None)
    residual = errors.reshape(-1) - columns @ solution
    return solution[:p], float(np.sqrt(np.mean(residual ** 2)))


def _direction(ctx, turn):
    """The tool direction's change du = w x u (N, 3) of a turn w (N, 3) [rad]."""
    return np.cross(turn, ctx.tool_axis())


@pytest.mark.parametrize("name", ["EAZ", "EBX", "EAY"])
@pytest.mark.parametrize("setup_deg", [{"C": 0, "B": 0}, {"C": 90, "B": -30}])
def test_the_head_located_tilt_is_the_generators_closed_form(name, setup_deg):
    """The package's tilt with the tool located at the head's set-up, at the Legendre
    coefficients of the generator's polynomial, reproduces its tip readings (a 300 urad/m
    tilt over 0.75 m: to 0.01 um) and its direction changes (to 0.1 % of them), at a set-up
    of zeros and off them; the fit returns the closed form's coefficients."""
    generator, described = _gantry_head(setup_deg)
    ctx, errors, directions = _readings(generator, described, _grid(setup_deg), [_tilt(name)])
    family = ComponentError("angular", False)
    setting = {"order": 2, "constant": True, "located": HEAD}
    assert carries_head(described, name[2])
    assert setting in family.settings(ctx, name)
    assert head_setup_row(ctx) == 0
    coefficients, rms = _fit(family.design(ctx, name, setting), errors)
    assert np.abs(errors).max() > 5e-6                       # the tilt is seen
    assert rms < 1e-8
    fitted = dict(zip(family.parameter_names(name, setting), coefficients))
    for key, value in LEGENDRE.items():
        assert fitted[key] == pytest.approx(value, abs=0.2e-6)
    exact = np.array([LEGENDRE[k] for k in family.parameter_names(name, setting)])
    turn = family.orientation_design(ctx, name, setting) @ exact
    assert np.abs(directions).max() > 20e-6
    assert np.abs(_direction(ctx, turn) - directions).max() < 1e-3 * np.abs(directions).max()


def test_without_the_located_tool_the_tilt_leaves_the_set_up_turning_with_the_head():
    """The same pitch of the Z ram, unlocated (constant part and all, order 6), leaves
    micrometres: what the tool took in at the set-up, turning with C and B. Its direction
    misses the set-up's change likewise."""
    generator, described = _gantry_head({"C": 0, "B": 0})
    ctx, errors, directions = _readings(generator, described, _grid({"C": 0, "B": 0}),
                                        [_tilt("EAZ")])
    family = ComponentError("angular", False)
    sensitivity, basis = family.separable_design(ctx, "EAZ", {"order": 6})
    plain = along(sensitivity, np.column_stack([basis, np.ones(ctx.n)]))
    _, rms = _fit(plain, errors)
    assert rms > 1e-6
    setting = {"order": 2, "constant": True, "located": HEAD}
    exact = np.array([LEGENDRE[k] for k in family.parameter_names("EAZ", setting)])
    unlocated = along(ctx.orientation_jacobian("EAZ"), basis[:, :2])
    turn = unlocated @ exact[:2] + ctx.orientation_jacobian("EAZ") * exact[2]
    assert np.abs(_direction(ctx, turn) - directions).max() > 10e-6


def test_a_turn_about_the_carried_c_is_cs_zero_and_offers_no_constant_part():
    """The Z ram carries C (about z): a constant yaw ECZ of the ram is C's zero and line
    offset (ISO 230-7), so the head-located yaw has no constant part; its pitch has. No
    located setting where the head never stood at its set-up pose."""
    generator, described = _gantry_head({"C": 0, "B": 0})
    assert turns_about_carried_rotary(described, "ECZ")
    assert not turns_about_carried_rotary(described, "EAZ")
    ctx, _, _ = _readings(generator, described, _grid({"C": 0, "B": 0}), [])
    family = ComponentError("angular", False)
    assert not any(s.get("constant") and s.get("located") for s in
                   family.settings(ctx, "ECZ"))
    assert {"order": 1, "constant": True, "located": HEAD} in family.settings(ctx, "EAZ")
    away = [{"B": math.radians(b), "C": 0.3} for b in np.arange(-90, 31, 20)]
    q = [cs.solve_linear(generator, p, SPHERE) for p in away]
    positions = {a: np.array([row[a] for row in q]) for a in described.axis_order}
    elsewhere = Context(described, Variables(positions), work_point=SPHERE,
                        located_readings=True)
    assert head_setup_row(elsewhere) is None
    assert not any(s.get("located") for s in family.settings(elsewhere, "EAZ"))


def test_a_tables_tilt_under_a_turning_head_reads_its_direction_located_at_the_set_up():
    """A pitch EAX of the X table under a swivel head: the spheres were located at the
    set-up with the direction's change there, -eps(x_s) x u(q_s), which the work (not
    turning) keeps. The located turn reproduces the generator's direction changes; the
    plain turn misses that constant by eps(x_s) |u x e_x|."""
    generator, described = _tables_head({"C": 90, "B": 0})
    poly = [0.0, -210e-6, -240e-6]
    ctx, _, directions = _readings(generator, described, _grid({"C": 90, "B": 0}),
                                   [_tilt("EAX", poly)])
    family = ComponentError("angular", False)
    setting = {"order": 2, "constant": True}
    x = ctx.variables.positions["X"]
    coefficients = {"P1": 0.75 * poly[1] + 2 * 0.75 * 0.15 * poly[2],
                    "P2": 2 * 0.75 ** 2 * poly[2] / 3,
                    "P0": 0.15 * poly[1] + 0.15 ** 2 * poly[2] + 0.75 ** 2 * poly[2] / 3}
    exact = np.array([coefficients[k] for k in family.parameter_names("EAX", setting)])
    # What the instrument's rows hold: the change across the tool axis, u x du (its part
    # along u, which the zeroing leaves in du at first order, no turn of the tool makes).
    seen = np.cross(ctx.tool_axis(), directions)
    turn = family.orientation_design(ctx, "EAX", setting) @ exact
    modelled = np.cross(ctx.tool_axis(), _direction(ctx, turn))
    assert np.abs(modelled - seen).max() < 1e-3 * np.abs(seen).max()
    assert family.separable_design(ctx, "EAX", setting) is None     # located: not one product
    plain = along(ctx.orientation_jacobian("EAX"), family._basis(
        x, ctx.normalised_position("X"), setting)) @ exact
    at_setup = poly[1] * x[0] + poly[2] * x[0] ** 2
    miss = np.abs(np.cross(ctx.tool_axis(), _direction(ctx, plain)) - seen).max()
    assert miss == pytest.approx(abs(at_setup), rel=0.05)


def test_a_still_carriages_turn_under_a_c_sweep_is_said_inseparable_from_cs_line():
    """C swept alone, B at 0, the tip on C's line: the gantry's carriages stand still. C's
    line tilted about y (EB0C) and the Y carriage turned about x by eps(y_s) (a constant
    here) both draw circles: the turn's is the located tool's error eps x a turning with C,
    (I - R_C(q - q_s)) (eps x a) - what a line offset EY0C draws. C's line is named (EX0C
    holding EB0C folded, EY0C the turn), and the output says the turn of Y (and of X and
    Z, which these poses cannot tell from it) stands for EY0C, with its value eps(y_s)."""
    generator, described = _gantry_head({"C": 0, "B": 0})
    sweep = [{"B": 0.0, "C": math.radians(c)} for c in np.arange(-180, 180, 15)] * 4
    tilt = {"iso_name": "EB0C", "kind": "location_tilt", "axis": "C", "value_si": 56e-6}
    ctx, errors, _ = _readings(generator, described, sweep, [_tilt("EAY"), tilt])
    y = ctx.variables.positions["Y"]
    assert np.ptp(y) < 1e-12 and np.ptp(ctx.variables.positions["Z"]) < 1e-12
    eps = POLY[0] + POLY[1] * y[0] + POLY[2] * y[0] ** 2
    n = ctx.n
    measured = errors + np.random.default_rng(3).normal(0.0, geometry.NOISE, (n, 3))
    obs = Observations(ctx.variables.positions, measured, np.ones((n, 3), bool),
                       np.arange(n, dtype=float), {}, {}, 2 * geometry.NOISE,
                       work_point=SPHERE)
    diagnosis = diagnose(ErrorModel(described), obs)
    assert [s.name for s in diagnosis.selected] == ["rotary_location:C"], diagnosis.text()
    said = {alt["name"]: alt for alt in diagnosis.selected[0].inseparable}
    assert "angular:EAY" in said, diagnosis.selected[0].inseparable
    assert said["angular:EAY"]["parameters"]["P0"] == pytest.approx(eps, rel=0.05)
    assert "EY0C" in said["angular:EAY"]["reason"]
    assert "angular:ECY" not in said          # about C's own direction: its zero


def test_a_pitch_of_the_ram_under_a_turning_head_is_named_alone():
    """A swivel head's R-test over a grid of B and C, the Z ram pitched by
    eps(z) = 300 urad/m z about its origin: named as the pitch alone, its slope and
    constant part the closed form's (before: the head's lines tilted by its mean, then
    the pitch at a high order standing in for the tool's located error)."""
    generator, described = _gantry_head({"C": 0, "B": 0})
    ctx, errors, directions = _readings(generator, described, _grid({"C": 0, "B": 0}) * 2,
                                        [_tilt("EAZ", [0.0, 60e-6, 0.0])])
    n = ctx.n
    rng = np.random.default_rng(5)
    measured = errors + rng.normal(0.0, geometry.NOISE, (n, 3))
    change = directions + rng.normal(0.0, 10 * geometry.NOISE, (n, 3))
    obs = Observations(ctx.variables.positions, measured, np.ones((n, 3), bool),
                       np.arange(n, dtype=float), {}, {}, 2 * geometry.NOISE,
                       measured_orientation_rad=np.cross(ctx.tool_axis(), change),
                       orientation_measured=np.ones(n, dtype=bool),
                       orientation_uncertainty_rad=20 * geometry.NOISE, work_point=SPHERE)
    diagnosis = diagnose(ErrorModel(described), obs)
    assert [s.name for s in diagnosis.selected] == ["angular:EAZ"], diagnosis.text()
    named = diagnosis.selected[0]
    assert named.setting.get("located") == HEAD
    # Stroke -0.6 .. 0.9 m: P1 = 0.75 c1 = 45 urad, P0 = 0.15 c1 = 9 urad.
    assert named.parameters["P1"] == pytest.approx(45e-6, abs=3e-6)
    assert named.parameters.get("P0", 0.0) == pytest.approx(9e-6, abs=3e-6)
    # The ram carries only the head: its constant turn is the head's lines' - said.
    (said,) = [s for s in named.inseparable if s["name"].startswith("rotary_location:")]
    assert set(said["name"].partition(":")[2]) <= {"B", "C"}
    assert "constant part P0" in said["reason"]
    assert max(abs(v) for v in said["parameters"].values()) > 1e-6


def test_a_located_tilts_sensitivity_is_made_again_from_a_separable_setting():
    """A selector that lost a tilt's sensitivity from its store makes it again from a
    setting whose design is one sensitivity times scalar columns: not from the last, the
    head-located one (not separable)."""
    generator, described = _gantry_head({"C": 0, "B": 0})
    located, _, _ = _readings(generator, described, _grid({"C": 0, "B": 0}), [])
    ctx = Context(described, located.variables, work_point=SPHERE, located_readings=True)
    family = ComponentError("angular", False)
    term = Term(family, "EAZ", family.settings(ctx, "EAZ"))
    assert term.settings[-1].get("located") == HEAD
    selector = Selector(ctx, np.zeros((ctx.n, 3)), np.ones((ctx.n, 3), dtype=bool), 1e-6)
    along_rows, squared = selector.sensitivity(term)
    np.testing.assert_array_equal(along_rows, ctx.jacobian("EAZ").reshape(-1))
    np.testing.assert_allclose(squared, np.sum(ctx.jacobian("EAZ") ** 2, axis=1))


def test_a_line_parameter_fitted_near_zero_has_no_turn_said_to_stand_for_it():
    """C's line tilted about y alone (EB0C, folded into EX0C), the carriages still: the turns
    about y are said to stand for EX0C, and none for EY0C, which carries nothing here (any
    turn would 'reproduce' a zero)."""
    generator, described = _gantry_head({"C": 0, "B": 0})
    sweep = [{"B": 0.0, "C": math.radians(c)} for c in np.arange(-180, 180, 15)] * 4
    tilt = {"iso_name": "EB0C", "kind": "location_tilt", "axis": "C", "value_si": 56e-6}
    ctx, errors, _ = _readings(generator, described, sweep, [tilt])
    n = ctx.n
    measured = errors + np.random.default_rng(4).normal(0.0, geometry.NOISE, (n, 3))
    obs = Observations(ctx.variables.positions, measured, np.ones((n, 3), bool),
                       np.arange(n, dtype=float), {}, {}, 2 * geometry.NOISE,
                       work_point=SPHERE)
    diagnosis = diagnose(ErrorModel(described), obs)
    assert [s.name for s in diagnosis.selected] == ["rotary_location:C"], diagnosis.text()
    reasons = [alt["reason"] for alt in diagnosis.selected[0].inseparable
               if alt["name"].startswith("angular:")]
    assert reasons and all(r.endswith("as EX0C does") for r in reasons), reasons


def test_the_head_located_tilts_words_say_the_tool_and_the_heads_lines():
    """The output says the tool was located at the head's set-up, and that the constant
    part turns the head's lines (not a squareness of the plane)."""
    family = ComponentError("angular", False)
    setting = {"order": 1, "constant": True, "located": HEAD}
    words = family.explanation("EAZ", setting)
    assert "the tool was located at the head's set-up" in words
    assert "rotary axes' lines tilted alike" in words and "squareness" not in words
    assert family.describe_setting(setting) == \
        "order 1, with a constant part (the head's lines tilted alike), the tool located " \
        "at the head's set-up"
    assert family.describe_setting({"order": 2, "constant": True}) == \
        "order 2, with a constant part (its plane's squareness)"


def test_a_cncs_own_commands_get_the_heads_carriage_tilt_as_the_machine_makes_it():
    """A compensation's batch of commands holds no located tool, even where the head stands
    at its set-up: a head-located tilt predicts the plain tilt there, whatever the batch."""
    generator, described = _gantry_head({"B": 0, "C": 0})
    ctx, _, _ = _readings(generator, described, _grid({"B": 0, "C": 0}), [])
    family = ComponentError("angular", False)
    setting = next(s for s in family.settings(ctx, "EAZ") if s.get("located") == "head")
    commands = Context(described, ctx.variables, work_point=SPHERE)
    plain = along(*family.separable_design(commands, "EAZ", dict(setting, located=False)))
    assert head_setup_row(commands) is None and head_setup_row(ctx) is not None
    np.testing.assert_array_equal(family.design(commands, "EAZ", setting), plain)
    assert np.abs(family.design(ctx, "EAZ", setting)
                  - family.design(commands, "EAZ", setting)).max() > 1e-3
