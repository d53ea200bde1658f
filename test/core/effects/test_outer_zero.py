"""An outer rotary axis' zero error, as a sphere located at the set-up reads it (ISO 230-7).

A zero error e of B turns the B body to q + e about B's line, and with it the C line B
carries. A sphere located by a translation at the set-up then reads it exactly as C's
line turned by e about B's line: a tilt EB0C = e and an offset of C's origin,
e y x o (o = C's origin from B's line, B's frame), so EX0C = o_z e for B about y and
EY0C = -o_z e for A about x. Checked against that closed form, against the independent
generator's rigid bodies (``studies.convention_surveys``), and end to end: the check says
the zero is folded into C's line and the line's numbers are the sums it states.
"""
from __future__ import annotations

import math

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import family_named
from mt_accuracy_ros.core.effects.base import Context
from mt_accuracy_ros.core.effects.geometric import parse_inseparable
from mt_accuracy_ros.core.effects.variables import Variables
from mt_accuracy_ros.core.kinematics.machine import (machine_from_dict, outer_zeros,
                                                     with_setup_pose)
from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
from studies import convention_surveys as cs

SPHERE = np.array([0.06, -0.04, 0.05])      # the sphere, workpiece frame [m]
OUTER_OFFSET_Z = -0.08                      # C's origin below the outer axis' line [m]


def _trunnion(outer, signs, setup_deg):
    """(generator's machine, package's description) of a [w C outer X Y b Z t] trunnion."""
    work = [cs._ax("Y", 1, [0, 0, 0.1]), cs._ax("X", -1, [0, 0, 0.25]),
            cs._ax(outer, signs[0], [0.01, 0.0, OUTER_OFFSET_Z]), cs._ax("C", signs[1], [0, 0, 0])]
    tool = [cs._ax("Z", 1, [0, 0, 0.6])]
    strokes = {outer: (-100.0, 100.0), "C": (-180.0, 180.0)}
    axes = {}
    for ax in work + tool:
        if ax["rotary"]:
            low, high = strokes[ax["name"]]
            ax["stroke"] = (math.radians(low), math.radians(high))
            axes[ax["name"]] = {"stroke": {"value": [low, high], "unit": "deg"}}
        else:
            axes[ax["name"]] = {"stroke": [-0.6, 0.9]}
        axes[ax["name"]].update(offset=ax["offset"].tolist(), sign=ax["sign"])
    setup = {n: math.radians(v) for n, v in setup_deg.items()}
    generator = {"topology": "given", "work": work, "tool": tool,
                 "tool_vec": np.array([0.0, 0.0, -0.14]), "work_vec": np.zeros(3),
                 "setup": setup}
    described = machine_from_dict({"name": "given", "chain": f"[w C {outer} X Y b Z t]",
                                   "tool": [0, 0, -0.14], "workpiece": [0, 0, 0],
                                   "axes": axes})
    return generator, with_setup_pose(described, setup)


def _rows(generator, outer):
    """One sphere followed with RTCP over a grid of both rotary axes, the set-up first."""
    poses = [dict(generator["setup"])] + [
        {outer: math.radians(a), "C": math.radians(c)}
        for a in np.arange(-90, 91, 15) for c in np.arange(-180, 180, 30)]
    return {"q": [cs.solve_linear(generator, p, SPHERE) for p in poses],
            "target": np.tile(SPHERE, (len(poses), 1)), "group": [0] * len(poses),
            "setup": {0: 0}, "tool_setup": 0}


def _context(described, rows):
    positions = {a: np.array([q[a] for q in rows["q"]]) for a in described.axis_order}
    return Context(described, Variables(positions), work_point=SPHERE,
                   located_readings=True), positions


def _zero(axis, value):
    return {"iso_name": f"E{axis}0{axis}", "kind": "zero", "axis": axis, "value_si": value}


# (outer axis, the offset of C its zero draws, that offset's ratio per rad of zero)
OUTERS = [("B", "EX0C", OUTER_OFFSET_Z), ("A", "EY0C", -OUTER_OFFSET_Z)]


@pytest.mark.parametrize("outer, offset, ratio", OUTERS)
@pytest.mark.parametrize("signs", [(1, 1), (-1, 1), (1, -1)])
@pytest.mark.parametrize("setup_deg", [{"C": 0.0}, {"C": 45.0}])
def test_an_outer_zero_reads_as_the_carried_line_turned_about_the_outer_line(
        outer, offset, ratio, signs, setup_deg):
    setup = dict(setup_deg, **{outer: -60.0 if setup_deg["C"] else 0.0})
    generator, described = _trunnion(outer, signs, setup)
    rows = _rows(generator, outer)
    ctx, _ = _context(described, rows)
    zero = f"E{outer}0{outer}"
    column = ctx.located(zero)[0]
    # The closed form: C's line tilted by e about the outer direction, its origin moved by
    # e x o across it - any poses, any set-up.
    closed = ctx.located(f"E{outer}0C")[0] + ratio * ctx.located(offset)[0]
    assert np.abs(column - closed).max() < 1e-12
    # The generator's rigid bodies, 40 urad: the same to second order.
    value = 40e-6
    truth, _ = cs.located_errors(generator, cs.errs_from_effects([_zero(outer, value)]), rows)
    assert np.abs(truth).max() > 2e-6
    assert np.abs(truth - value * column).max() < 1e-10


def test_the_last_axis_zero_moves_no_located_sphere():
    generator, described = _trunnion("B", (1, 1), {"B": 0.0, "C": 0.0})
    rows = _rows(generator, "B")
    ctx, _ = _context(described, rows)
    assert np.abs(ctx.located("EC0C")[0]).max() < 1e-15
    truth, _ = cs.located_errors(generator, cs.errs_from_effects([_zero("C", 40e-6)]), rows)
    assert np.abs(truth).max() < 1e-15


def test_outer_zeros_are_the_axes_that_carry_one_on_its_side():
    _, trunnion = _trunnion("B", (1, 1), {"B": 0.0, "C": 0.0})
    assert outer_zeros(trunnion, "C") == ["EB0B"]
    assert outer_zeros(trunnion, "BC") == ["EB0B"]
    assert outer_zeros(trunnion, "B") == []
    head = machine_from_dict({"name": "head", "chain": "[w X Y b Z C B t]",
                              "tool": [0, 0, -0.1], "workpiece": [0, 0, 0],
                              "axes": {a: {"stroke": [-1.0, 1.0], "offset": [0, 0, 0]}
                                        for a in "XYZBC"}})
    assert outer_zeros(head, "B") == ["EC0C"]
    mixed = machine_from_dict({"name": "mixed", "chain": "[w C X Y b Z B t]",
                               "tool": [0, 0, -0.1], "workpiece": [0, 0, 0],
                               "axes": {a: {"stroke": [-1.0, 1.0], "offset": [0, 0, 0]}
                                        for a in "XYZBC"}})
    assert outer_zeros(mixed, "BC") == []


@pytest.mark.parametrize("outer, offset, ratio", OUTERS)
def test_the_line_family_says_the_outer_zero_folded_and_never_fits_it(outer, offset, ratio):
    generator, described = _trunnion(outer, (1, -1), {outer: 0.0, "C": 0.0})
    ctx, _ = _context(described, _rows(generator, outer))
    family = family_named("rotary_location")
    setting = family.settings(ctx, "C")[0]
    folds = parse_inseparable(setting["inseparable"])
    assert folds[f"E{outer}0{outer}"] == pytest.approx({f"E{outer}0C": 1.0, offset: ratio},
                                                       abs=1e-9)
    zero = f"E{outer}0{outer}"
    assert zero not in family.parameter_names("C", setting)
    assert family.parameter_names("C", setting) == ["EX0C", "EY0C", "EA0C", "EB0C"]
    assert f"{zero} (the {outer} axis' zero error, turning the lines it carries) moves " \
        "these readings as" in family.explanation("C", setting)


def test_a_zero_and_the_carried_tilt_are_named_as_the_sums_they_make():
    """B's zero 48 urad beside C's tilt about y of -51 urad: C's line carries
    EB0C + EB0B = -3 urad and EX0C = -0.08 m x 48 urad = -3.84 um, as the output says."""
    generator, described = _trunnion("B", (1, -1), {"B": 0.0, "C": 0.0})
    rows = _rows(generator, "B")
    rows = {k: (v * 4 if isinstance(v, list) else v) for k, v in rows.items()}
    rows["target"] = np.tile(SPHERE, (len(rows["q"]), 1))
    effects = [_zero("B", 48e-6), {"iso_name": "EB0C", "kind": "location_tilt", "axis": "C",
                                   "value_si": -51e-6}]
    errors, _ = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    _, positions = _context(described, rows)
    n = len(rows["q"])
    noise = 0.3e-6
    measured = errors + np.random.default_rng(3).normal(0.0, noise, (n, 3))
    obs = Observations(positions, measured, np.ones((n, 3), bool), np.arange(n, dtype=float),
                       {}, {}, 2 * noise, work_point=SPHERE)
    named = diagnose(ErrorModel(described), obs).selected[0]
    assert named.name == "rotary_location:C"
    assert "EB0B" in parse_inseparable(named.setting["inseparable"])
    assert named.parameters["EX0C"] == pytest.approx(OUTER_OFFSET_Z * 48e-6, abs=0.3e-6)
    assert named.parameters["EB0C"] == pytest.approx(-3e-6, abs=1.5e-6)
    assert "EB0C stands for EB0C + 1 rad/rad x EB0B" in named.explanation


def test_probing_says_an_outer_zero_folded_into_the_carried_line():
    """The probing tool on a trunnion [w C A X Y b Z t], A's zero -43.7 urad: the probed
    centres see C's line turned about A's (EA0C -43.7 urad, EY0C -o_z x it), and the output
    says EA0A folded into them with those coefficients, not taken out by the set-up."""
    from mt_accuracy_ros.core.rotary.probing import identify_location_errors

    generator, described = _trunnion("A", (1, -1), {"A": 0.0, "C": 0.0})
    rows = _rows(generator, "A")
    value = -43.7e-6
    errors, _ = cs.located_errors(generator, cs.errs_from_effects([_zero("A", value)]), rows)
    _, positions = _context(described, rows)
    noise = np.random.default_rng(5).normal(0.0, 0.3e-6, errors.shape)
    # Found minus expected centres: minus the TCP error (Khan & Chen eq. 17).
    result = identify_location_errors(described, positions, -errors + noise,
                                      sphere_nominal_m=SPHERE)
    assert result.parameters["EA0C"] == pytest.approx(value, abs=1.5e-6)
    assert result.parameters["EY0C"] == pytest.approx(-OUTER_OFFSET_Z * value, abs=0.3e-6)
    assert result.aliases["EA0C"]["EA0A"] == pytest.approx(1.0, abs=1e-6)
    assert result.aliases["EY0C"]["EA0A"] == pytest.approx(-OUTER_OFFSET_Z, abs=1e-8)
    text = result.text()
    assert "EA0C + EA0A" in text and "EY0C + 0.08 m/rad x EA0A" in text
    assert "EA0A - an outer axis' zero-angle error turns" in text
    assert "not observable: EA0A" not in text
