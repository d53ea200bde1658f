"""A plane's squareness in the forms the poses can see, against the independent generator.

ISO 230-1 books a tilt of one axis' travel against another's as their squareness (EC0Y:
Y's travel tilted toward X, e_x ~ y). The readings come from ``studies.convention_surveys``
(rigid bodies written from the physics alone: the slide moves along its tilted direction,
the sphere and a head's tool located at the set-up by a translation), on machines
described here to both codes. Closed forms:

* Y's travel tilted toward X with X standing still: e_x = s y, the slope EXY - offered on
  Y's travel alone; the location form EC0Y, which turns the table Y carries with its
  travel about a point where the tool stands, moves nothing there and an absurd fit of it
  is refused in words;
* a still carriage's roll (X carries A, and stood still): one constant turn P0 of all it
  carries, read as the located sphere reads it - P0 itself comes back;
* Z's travel tilted toward X on a swivel head: e_x = s z, with the tool located at the
  head's set-up - the value there turns with the head (ISO 10791-6);
* a table yaw's constant part beside a squareness of its plane, where the target sits at
  the tool tip: one rotation, said inseparable, P0 = the yaw's mean - the squareness.
"""
from __future__ import annotations

import math
import re
import sys
from pathlib import Path

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects.base import Context
from mt_accuracy_ros.core.effects.geometric import STILL_TURN, ComponentError, Squareness
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.workbench.diagnosis import Candidate, Observations, diagnose
from studies import convention_surveys as cs

sys.path.insert(0, str(Path(__file__).resolve().parents[1] / "workbench"))
import test_separability as geometry  # noqa: E402  (the machines both codes are told)

SPHERE = np.array([0.06, -0.04, 0.05])      # the R-test's sphere, workpiece frame [m]
SQUARENESS = 40e-6                          # a squareness [rad]
ROLL = -12e-6                               # a still carriage's roll [rad]


def _fit(design, errors):
    """Least squares of ``errors`` (N, 3) on ``design`` (N, 3, P) and a constant per
    component: (coefficients, RMS residual [m])."""
    n, _, p = design.shape
    columns = np.concatenate([design, np.tile(np.eye(3)[None], (n, 1, 1))],
                             axis=2).reshape(3 * n, -1)
    solution, *_ = np.linalg.lstsq(columns, errors.reshape(-1), rcond=None)
    residual = errors.reshape(-1) - columns @ solution
    return solution[:p], float(np.sqrt(np.mean(residual ** 2)))


def _followed(generator, described, poses, effects):
    """(context, located errors (N, 3) [m]) of one sphere followed with RTCP over ``poses``,
    the first at the set-up pose, where the sphere (and a head's tool) was located."""
    poses = [dict(generator["setup"])] + list(poses)
    rows = {"q": [cs.solve_linear(generator, p, SPHERE) for p in poses],
            "target": np.tile(SPHERE, (len(poses), 1)), "group": [0] * len(poses),
            "setup": {0: 0}, "tool_setup": 0}
    errors, _ = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    positions = {a: np.array([q[a] for q in rows["q"]]) for a in described.axis_order}
    return Context(described, Variables(positions), work_point=SPHERE,
                   located_readings=True), errors


def _trunnion_ac_sweep_of_a():
    """A trunnion [w C A X Y b Z t] swept in A alone: X and C stand still, Y and Z follow
    the sphere (seed 7's trial 024)."""
    work = [cs._ax("Y", -1, [0, 0, 0.092]), cs._ax("X", -1, [0, 0, 0.324]),
            cs._ax("A", -1, [0, 0, -0.049]), cs._ax("C", -1, [0, 0, 0])]
    generator, described = geometry._machines(work, [cs._ax("Z", -1, [0, 0, 0.632])],
                                              [0, 0, -0.199], {"A": 0, "C": 0},
                                              {"A": (-30, 110), "C": (-360, 360)})
    poses = [{"A": math.radians(a), "C": 0.0} for a in range(-30, 111, 10)]
    return generator, described, poses


def _squareness(name, axis, value):
    return {"iso_name": name, "kind": "squareness", "axis": axis, "value_si": value}


def _roll_of_x(c0):
    return {"iso_name": "EAX", "kind": "table_tilt", "axis": "X", "value_si": [c0, 0.0, 0.0],
            "pivot_m": [0.0, 0.0, 0.0]}


def test_a_tilted_travel_whose_partner_stood_still_is_its_slope():
    """Y's travel tilted toward X (EC0Y) with X still: e_x = s y, the slope EXY on Y's
    travel alone, to 1e-10 m; EYX (e_y ~ x) needs X to move and is not offered."""
    generator, described, poses = _trunnion_ac_sweep_of_a()
    ctx, errors = _followed(generator, described, poses,
                            [_squareness("EC0Y", "Y", SQUARENESS)])
    assert not ctx.moves("X") and ctx.moves("Y")
    family = Squareness()
    assert "EXY" in family.variants(ctx) and "EYX" not in family.variants(ctx)
    assert np.abs(errors).max() > 1e-6                          # the squareness is seen
    (angle,), rms = _fit(ctx.measured_design(family, "EXY", {}), errors)
    assert rms < 1e-10
    # The package's slope of Y's travel in x per metre of Y (Y's sign -1 here).
    assert angle == pytest.approx(SQUARENESS, rel=1e-6)


def test_the_location_form_moves_nothing_there_and_its_absurd_fit_is_refused_in_words():
    """EC0Y as a location error turns the table Y carries with its travel about a point
    where the tool stands: the located sphere reads nothing (below 1e-15 m per rad). A fit
    of it beyond any machine's squareness is refused in a sentence with no number of the
    fit, and the candidate's display reports no value; a real one is not refused."""
    generator, described, poses = _trunnion_ac_sweep_of_a()
    ctx, _ = _followed(generator, described, poses, [])
    family = Squareness()
    assert np.abs(ctx.measured_design(family, "EC0Y", {})).max() < 1e-15
    refused = family.fit_problems(ctx, "EC0Y", {}, [1.8e11])
    assert len(refused) == 1 and "no machine tool" in refused[0]
    assert "1.8" not in refused[0]
    assert family.fit_problems(ctx, "EC0Y", {}, [SQUARENESS]) == []
    assert family.fit_problems(ctx, "EC0Y", {}, [float("nan")])
    candidate = Candidate("squareness", {"angle_rad": 1.8e11}, 1e-6, 0.1, False, "",
                          variant="EC0Y", parameter_uncertainties={"angle_rad": 2.6e10},
                          refusal=refused[0])
    shown = candidate.as_dict()["display"]["angle_rad"]
    assert not re.search(r"\d", shown), shown


def test_a_still_carriages_roll_is_one_constant_turn_read_located():
    """X carries A and stood still: its roll EAX is the constant turn P0 alone
    (``STILL_TURN``), read as the located sphere reads it; the fit returns the roll, to
    1e-10 m. Together with Y's tilted travel (seed 7's trial 024) both come back."""
    generator, described, poses = _trunnion_ac_sweep_of_a()
    family = ComponentError("angular", False)
    ctx, errors = _followed(generator, described, poses, [_roll_of_x(ROLL)])
    assert "EAX" in family.variants(ctx)
    assert family.settings(ctx, "EAX") == [STILL_TURN]
    assert family.parameter_names("EAX", STILL_TURN) == ["P0"]
    assert np.abs(errors).max() > 1e-6
    (p0,), rms = _fit(ctx.measured_design(family, "EAX", STILL_TURN), errors)
    assert rms < 1e-10
    assert p0 == pytest.approx(ROLL, rel=1e-4)
    # No motion of the axis beyond the constant (a CNC table's entry).
    np.testing.assert_allclose(family.motion_error(described, "EAX", STILL_TURN, [p0],
                                                   [-0.1, 0.0, 0.2]), [p0] * 3)
    ctx, errors = _followed(generator, described, poses,
                            [_squareness("EC0Y", "Y", SQUARENESS), _roll_of_x(ROLL)])
    design = np.concatenate([ctx.measured_design(Squareness(), "EXY", {}),
                             ctx.measured_design(family, "EAX", STILL_TURN)], axis=2)
    (angle, p0), rms = _fit(design, errors)
    assert rms < 1e-10
    assert angle == pytest.approx(SQUARENESS, rel=1e-4)
    assert p0 == pytest.approx(ROLL, rel=1e-3)


def test_a_moving_carriage_offers_no_still_turn():
    """On a grid where X moves, its roll is offered at its orders as before, never as
    the still turn."""
    work = [cs._ax("Y", -1, [0, 0, 0.092]), cs._ax("X", -1, [0, 0, 0.324]),
            cs._ax("A", -1, [0, 0, -0.049]), cs._ax("C", -1, [0, 0, 0])]
    generator, described = geometry._machines(work, [cs._ax("Z", -1, [0, 0, 0.632])],
                                              [0, 0, -0.199], {"A": 0, "C": 0},
                                              {"A": (-30, 110), "C": (-360, 360)})
    poses = [{"A": math.radians(a), "C": math.radians(c)}
             for a in range(-30, 111, 20) for c in range(0, 360, 45)]
    ctx, _ = _followed(generator, described, poses, [])
    assert ctx.moves("X")
    assert STILL_TURN not in ComponentError("angular", False).settings(ctx, "EAX")


def test_a_heads_slide_tilted_is_read_with_the_tool_located_at_the_heads_set_up():
    """A swivel head [w X Y b Z C B t] set up at C = 90 deg, Z's travel tilted toward X
    (EB0Z, seed 13's trial 016): e_x = s z, and the tool located at the head's set-up
    took s z_t in, which turns with the head (ISO 10791-6). The slope EXZ read so fits to
    1e-10 m with the squareness itself; the slope as the machine makes it leaves 0.1 um."""
    work = [cs._ax("Y", -1, [0, 0, 0.1]), cs._ax("X", 1, [0, 0, 0.05])]
    tool = [cs._ax("Z", 1, [0, 0, 0.6]), cs._ax("C", 1, [0, 0, -0.2]),
            cs._ax("B", 1, [0, 0, -0.127])]
    generator, described = geometry._machines(work, tool, [0, 0, -0.093],
                                              {"C": 90, "B": 0},
                                              {"C": (-180, 180), "B": (-30, 110)})
    poses = [{"C": math.radians(c), "B": math.radians(b)}
             for c in range(-180, 180, 45) for b in range(-30, 111, 20)]
    square = 28e-6
    ctx, errors = _followed(generator, described, poses, [_squareness("EB0Z", "Z", square)])
    family = Squareness()
    (angle,), rms = _fit(ctx.measured_design(family, "EXZ", {}), errors)
    assert rms < 1e-10
    assert angle == pytest.approx(square, rel=1e-6)
    plain = (ctx.jacobian("EXZ") * ctx.variables.positions["Z"][:, None])[:, :, None]
    assert _fit(plain, errors)[1] > 0.1e-6


def test_a_yaws_constant_part_and_the_squareness_of_its_plane_are_said_one_rotation():
    """A three-axis VMC [w X Y b Z t], a laser tracker on the tool tip (seed 13's trial
    023): a constant yaw of Y turns the work about Y's origin, which moves with Y, so the
    tip's point is moved by P0 e_z x (tip - origin): e_x grows with y as Y's tilted travel
    (EC0Y) makes it. The yaw is named; its P0 holds the yaw's mean over the stroke minus
    the squareness, and the output says the squareness EXY stands for it, with that value."""
    work = [cs._ax("Y", 1, [0.036, -0.036, 0.044]), cs._ax("X", 1, [0.045, 0.005, -0.015])]
    generator, described = geometry._machines(work, [cs._ax("Z", -1, [-0.015, -0.048, 0.486])],
                                              [0, 0, -0.095], {}, {})
    rng = np.random.default_rng(3)
    targets = rng.uniform([-0.3, -0.2, 0.02], [0.3, 0.2, 0.35], size=(400, 3))
    rows = {"q": [cs.solve_linear(generator, {}, t) for t in targets], "target": targets,
            "group": [0] * len(targets), "setup": {0: 0}, "tool_setup": 0}
    square, yaw = 22e-6, [30e-6, 120e-6, 0.0]
    effects = [_squareness("EC0Y", "Y", square),
               {"iso_name": "ECY", "kind": "table_tilt", "axis": "Y", "value_si": yaw,
                "pivot_m": [0.0, 0.0, 0.0]}]
    errors, _ = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    n, noise = len(targets), 0.3e-6
    positions = {a: np.array([q[a] for q in rows["q"]]) for a in described.axis_order}
    obs = Observations(positions, errors + rng.normal(0.0, noise, (n, 3)),
                       np.ones((n, 3), bool), np.arange(n, dtype=float), {}, {}, 2 * noise,
                       work_point=targets)
    diagnosis = diagnose(ErrorModel(described), obs)
    named = diagnosis.selected[0]
    assert named.name == "angular:ECY" and named.setting.get("constant"), diagnosis.text()
    mean = yaw[0] + yaw[1] * 0.15                   # over the stroke -0.6 .. 0.9 m
    assert named.parameters["P0"] == pytest.approx(mean - square, abs=1.5e-6)
    alike = {a["name"]: a for a in named.inseparable}
    assert "squareness:EXY" in alike, named.inseparable
    assert alike["squareness:EXY"]["parameters"]["angle_rad"] == pytest.approx(
        named.parameters["P0"], rel=1e-6)
    assert "cannot part angular:ECY from squareness:EXY" in named.explanation


def test_an_axis_that_moved_only_between_probed_spheres_shows_no_squareness():
    """Two spheres probed on a swivel head while C turns with the tool's tip on C's line
    (seed 13's trial 018): the linear axes move only from one sphere to the other, and
    each sphere reads from its own zero, which takes in a squareness' move where it
    stands. No squareness is offered there (before, Z's slope read with the tool located
    at the head's set-up stood in for C's tilted line); with a sweep that moves Z at one
    sphere, it is."""
    work = [cs._ax("Y", -1, [0, 0, 0.1]), cs._ax("X", 1, [0, 0, 0.05])]
    tool = [cs._ax("Z", 1, [0, 0, 0.6]), cs._ax("C", 1, [0, 0, -0.2]),
            cs._ax("B", 1, [0, 0, -0.127])]
    generator, described = geometry._machines(work, tool, [0, 0, -0.093], {"C": 0, "B": 0},
                                              {"C": (-180, 180), "B": (-30, 110)})
    spheres = np.array([[-0.0556, 0.0312, 0.0604], [0.0435, 0.0169, 0.069]])

    def context(poses):
        rows = [(p, s) for s in spheres for p in [{"C": 0.0, "B": 0.0}] + poses]
        q = [cs.solve_linear(generator, p, s) for p, s in rows]
        positions = {a: np.array([row[a] for row in q]) for a in described.axis_order}
        return Context(described, Variables(positions),
                       work_point=np.array([s for _, s in rows]), located_readings=True)

    sweep_of_c = [{"C": math.radians(c), "B": 0.0} for c in range(-180, 180, 10)]
    ctx = context(sweep_of_c)
    assert ctx.target_groups is not None and ctx.moves("Z") and ctx.moves("Y")
    assert Squareness().variants(ctx) == []
    ctx = context(sweep_of_c + [{"C": 0.0, "B": math.radians(b)} for b in (-30, 30, 60)])
    assert "EXZ" in Squareness().variants(ctx)


def test_a_still_carriages_turn_and_the_carried_lines_are_said_one_another():
    """The roll of a still X that carries A, read by a sphere located at the set-up, is
    exactly a line offset of A (the turn about X's origin moves A's line by its lever, ISO
    230-7): A's line errors fit it to 1e-10 m. So where the workbench names
    rotary_location:A it says the still turn beside it, with the turn's value."""
    from mt_accuracy_ros.core.effects.geometric import RotaryLocation
    from mt_accuracy_ros.core.workbench.separability import _still_turn_pair
    from mt_accuracy_ros.core.workbench.selection import Term

    generator, described, poses = _trunnion_ac_sweep_of_a()
    ctx, errors = _followed(generator, described, poses, [_roll_of_x(ROLL)])
    lines = RotaryLocation()
    setting = {"inseparable": ""}
    design = ctx.measured_design(lines, "A", setting)
    _, rms = _fit(design, errors)
    assert np.abs(errors).max() > 1e-6 and rms < 1e-10
    family = ComponentError("angular", False)
    still = Term(family, "EAX", [STILL_TURN])
    named = Term(lines, "A", [setting])
    assert _still_turn_pair(named, still) and _still_turn_pair(still, named)
    moving = Term(family, "EAX", [{"order": 1}])
    assert not _still_turn_pair(named, moving)
