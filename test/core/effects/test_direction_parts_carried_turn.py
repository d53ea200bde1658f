"""A carriage's constant turn about its first carried rotary axis, read with the tool direction.

On a trunnion [w C A X Y b Z t] the Y carriage carries A (about x) and C. A constant roll
eps = c0 e_x of Y turns A, C, the table and the work about Y's origin: A's zero and an
offset of A's line by the turn's lever (ISO 230-7). A sphere located at the set-up by a
translation reads it as C's line turned about A's (EA0C = c0, the line family folds A's
zero into it), so without the tool's direction the tilt's constant part is no candidate
of its own. A two-sphere instrument locates the direction's change at the set-up too,
and it turns with the work (ISO 10791-6): the carriage's turn, which turns the work at
the set-up as well, reads

    du(q) = -[eps x u - R_W(q) R_W(q_s)^T (eps x u)]

(u the tool's unit vector: no rotary axis on the tool side), where C's tilted line reads
-(eps - R_W(q) R_W(q_s)^T eps) x u - the two differ wherever the work has turned. The
readings come from ``studies.convention_surveys`` (rigid bodies from the physics alone).
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import family_named
from mt_accuracy_ros.core.effects.base import Context
from mt_accuracy_ros.core.effects.geometric import ComponentError
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
from studies import convention_surveys as cs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "workbench"))
import test_separability as geometry  # noqa: E402  (the machines both codes are told)

SPHERE = np.array([-0.0268, -0.005, 0.0903])    # workpiece frame [m]
C0 = -58e-6                                     # the roll's constant part [rad]
#: The roll eps(y) = c0 + c1 y [rad, rad/m] about Y's origin; over the stroke -0.6 .. 0.9 m
#: (y = 0.75 u + 0.15) its Legendre coefficients are P0 = c0 + 0.15 c1, P1 = 0.75 c1.
POLY = [C0, 80e-6, 0.0]
LEGENDRE = {"P0": C0 + 0.15 * 80e-6, "P1": 0.75 * 80e-6}
LEVER_M = 0.1                                   # direction rows' scale [m/rad]
SETTING = {"order": 1, "constant": True, "located": True}


def _trunnion():
    work = [cs._ax("Y", 1, [0, 0, 0.131]), cs._ax("X", 1, [0, 0, 0.176]),
            cs._ax("A", -1, [0, 0, -0.017]), cs._ax("C", 1, [0, 0, 0])]
    return geometry._machines(work, [cs._ax("Z", -1, [0, 0, 0.753])], [0, 0, -0.165],
                              {"A": 0, "C": 0}, {"A": (-120, 120), "C": (0, 360)})


def _grid_commands(generator):
    """Commands (SI) following the sphere over a grid of A and C, the set-up first."""
    poses = [dict(generator["setup"])] + [
        {"A": math.radians(a), "C": math.radians(c)}
        for a in np.arange(-90, 91, 30) for c in np.arange(0, 360, 30)]
    return [cs.solve_linear(generator, p, SPHERE) for p in poses]


def _readings(generator, described, effects, lever=LEVER_M):
    """(context, located errors (N, 3) [m], direction changes du (N, 3) [-]) of the sphere
    followed over a grid of A and C, located at the set-up (the first reading)."""
    commands = _grid_commands(generator)
    rows = {"q": commands, "target": np.tile(SPHERE, (len(commands), 1)),
            "group": [0] * len(commands),
            "setup": {0: 0}, "tool_setup": 0}
    errors, changes = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    positions = {a: np.array([q[a] for q in rows["q"]]) for a in described.axis_order}
    ctx = Context(described, Variables(positions), work_point=SPHERE,
                  orientation_lever_m=lever, located_readings=True)
    return ctx, errors, changes


def _roll(poly=POLY):
    return {"iso_name": "EAY", "kind": "table_tilt", "axis": "Y", "value_si": list(poly),
            "pivot_m": [0.0, 0.0, 0.0]}


def _measured(ctx, errors, changes):
    """(N, 6) the readings as the workbench sees them: position, then the direction's turn
    u x du across the tool axis times the lever."""
    axis = ctx.tool_axis()
    turn = np.cross(axis, changes)
    across = turn - axis * np.einsum("nc,nc->n", turn, axis)[:, None]
    return np.concatenate([errors, ctx.orientation_lever_m * across], axis=1)


def _fit(design, measured):
    """Least squares of ``measured`` (N, 6) on the design (N, 6, P) and a free offset per
    position component (the instrument's datum; the direction is absolute): (coefficients,
    RMS residual of the position rows [m], of the direction rows [m])."""
    n = measured.shape[0]
    offsets = np.zeros((n, 6, 3))
    offsets[:, :3, :] = np.eye(3)
    columns = np.concatenate([design, offsets], axis=2).reshape(6 * n, -1)
    solution, *_ = np.linalg.lstsq(columns, measured.reshape(-1), rcond=None)
    rest = (measured.reshape(-1) - columns @ solution).reshape(n, 6)
    return (solution[:design.shape[2]], float(np.sqrt(np.mean(rest[:, :3] ** 2))),
            float(np.sqrt(np.mean(rest[:, 3:] ** 2))))


def test_the_carriages_constant_turn_reads_in_the_direction_as_the_closed_form():
    """The generator's constant roll of Y, its A zero of the same value, and the closed form
    agree in the located direction; C's line tilted by the same angle does not."""
    generator, described = _trunnion()
    ctx, _, turned = _readings(generator, described, [_roll([C0, 0.0, 0.0])])
    _, _, zero = _readings(generator, described, [{"iso_name": "EA0A", "kind": "zero",
                                                   "axis": "A", "value_si": C0}])
    _, _, line = _readings(generator, described, [{"iso_name": "EA0C", "kind":
                                                   "location_tilt", "axis": "C",
                                                   "value_si": C0}])
    eps = np.array([C0, 0.0, 0.0])
    u = generator["tool_vec"] / np.linalg.norm(generator["tool_vec"])
    commands = _grid_commands(generator)
    work = [cs.side_frame(generator["work"], q, {})[:3, :3] for q in commands]
    rotations = np.array([r @ work[0].T for r in work])     # R_W(q) R_W(q_s)^T, row 0 the set-up
    closed = -(np.cross(eps, u) - rotations @ np.cross(eps, u))
    # First order: the rigid bodies differ by c0^2 (3e-9).
    np.testing.assert_allclose(turned, closed, atol=5e-9)
    np.testing.assert_allclose(zero, closed, atol=5e-9)
    # Not the carried line's turn: tens of microradians apart where the work turned.
    assert np.abs(line - closed).max() > 40e-6


def test_the_constant_part_is_offered_in_full_where_the_direction_was_located():
    """With the direction located, the roll is offered as any located tilt (its constant
    part with the lever, at orders 1 and 2); on the sphere alone its constant part only at
    order 1, without the lever (the lines' offsets are the line family's)."""
    generator, described = _trunnion()
    with_direction, _, _ = _readings(generator, described, [])
    family = ComponentError("angular", False)
    full = [s for s in family.settings(with_direction, "EAY") if s.get("constant")]
    assert SETTING in full and any(s.get("lever") for s in full)
    assert {"order": 2, "constant": True, "located": True} in full
    positions = with_direction.variables.positions
    without = Context(described, Variables(positions), work_point=SPHERE,
                      located_readings=True)
    assert [s for s in family.settings(without, "EAY") if s.get("constant")] == [SETTING]


def test_the_located_roll_with_its_constant_part_is_the_generators_readings():
    """The package's located roll, constant part and slope, fits the generator's positions
    and directions to second order, at the closed form's Legendre coefficients; C's line
    (into which the line family folds A's zero) leaves microradians in the direction."""
    generator, described = _trunnion()
    ctx, errors, changes = _readings(generator, described, [_roll()])
    measured = _measured(ctx, errors, changes)
    family = ComponentError("angular", False)
    coefficients, position, direction = _fit(ctx.measured_design(family, "EAY", SETTING),
                                             measured)
    assert np.abs(errors).max() > 5e-6 and np.abs(changes).max() > 50e-6   # seen
    assert position < 2e-9 and direction < 2e-9 * LEVER_M / 0.1
    fitted = dict(zip(family.parameter_names("EAY", SETTING), coefficients))
    for key, value in LEGENDRE.items():
        assert fitted[key] == pytest.approx(value, abs=0.3e-6)
    lines = family_named("rotary_location")
    setting = lines.settings(ctx, "AC")[0]
    _, _, left = _fit(ctx.measured_design(lines, "AC", setting), measured)
    assert left > 10e-6 * LEVER_M            # over 10 urad of direction unexplained


def test_a_roll_of_the_carriage_seen_with_the_tool_direction_is_named_as_the_roll():
    """End to end, a two-sphere R-test with 0.3 um and 3 urad noise: the roll is named
    alone with its constant part and slope at the closed form's values (before: the roll at
    order 2 without its constant part, P1 109 urad for 60, beside a yaw EAZ of order 3)."""
    generator, described = _trunnion()
    ctx, errors, changes = _readings(generator, described, [_roll()])
    rng = np.random.default_rng(11)
    n = ctx.n
    noise = 0.3e-6
    obs = Observations(ctx.variables.positions, errors + rng.normal(0.0, noise, (n, 3)),
                       np.ones((n, 3), bool), np.arange(n, dtype=float), {}, {}, 2 * noise,
                       measured_orientation_rad=np.cross(
                           ctx.tool_axis(), changes + rng.normal(0.0, 3e-6, (n, 3))),
                       orientation_measured=np.ones(n, dtype=bool),
                       orientation_uncertainty_rad=6e-6, work_point=SPHERE)
    diagnosis = diagnose(ErrorModel(described), obs)
    assert [s.name for s in diagnosis.selected] == ["angular:EAY"], diagnosis.text()
    named = diagnosis.selected[0]
    assert named.parameters["P0"] == pytest.approx(LEGENDRE["P0"], abs=5e-6)
    assert named.parameters["P1"] == pytest.approx(LEGENDRE["P1"], abs=5e-6)


def test_an_outer_zero_seen_with_the_tool_direction_is_said_as_a_carriages_turn_and_the_zero():
    """A's zero of -40 urad, read with the tool's direction: C's line (into which the line
    family folds it) cannot make the direction, a carriage's constant turn about x can - the
    check names that turn and says it is A's zero, with P0's value (before: C's line at
    0.5 urad, X's roll at order 2 and A's line offsets)."""
    generator, described = _trunnion()
    zero = -40e-6
    ctx, errors, changes = _readings(generator, described, [
        {"iso_name": "EA0A", "kind": "zero", "axis": "A", "value_si": zero}])
    rng = np.random.default_rng(11)
    n = ctx.n
    obs = Observations(ctx.variables.positions, errors + rng.normal(0.0, 0.3e-6, (n, 3)),
                       np.ones((n, 3), bool), np.arange(n, dtype=float), {}, {}, 0.6e-6,
                       measured_orientation_rad=np.cross(
                           ctx.tool_axis(), changes + rng.normal(0.0, 3e-6, (n, 3))),
                       orientation_measured=np.ones(n, dtype=bool),
                       orientation_uncertainty_rad=6e-6, work_point=SPHERE)
    diagnosis = diagnose(ErrorModel(described), obs)
    (named,) = diagnosis.selected
    assert named.name in ("angular:EAX", "angular:EAY"), diagnosis.text()
    assert named.parameters["P0"] == pytest.approx(zero, abs=3e-6)
    said = {alt["name"]: alt for alt in named.inseparable}
    assert said["rotary_location:A"]["parameters"]["EA0A"] == pytest.approx(zero, abs=3e-6)
    assert "A's zero-angle error" in named.explanation


def test_the_zero_is_said_only_where_the_turn_leaves_the_carried_travels_as_they_are():
    """Y's roll about x on [w C A X Y b Z t] turns A's body and leaves X's travel (along x)
    as it is: P0 is A's zero with the lines moved. Y's pitch about y on [w C B X Y b Z t]
    also turns X's travel toward z (a squareness): not the zero alone, nothing said."""
    from mt_accuracy_ros.core.workbench.selection import Term
    from mt_accuracy_ros.core.workbench.separability import _carried_zero

    family = ComponentError("angular", False)
    coefficients = np.array([10e-6, -30e-6])
    _, roll = _trunnion()
    (said,) = _carried_zero(roll, Term(family, "EAY", [SETTING]), SETTING, coefficients)
    assert said["name"] == "rotary_location:A"
    assert said["parameters"] == {"EA0A": pytest.approx(-30e-6)}
    _, pitch = geometry._trunnion_bc({"B": 0, "C": 0})
    assert _carried_zero(pitch, Term(family, "EBY", [SETTING]), SETTING, coefficients) == []
