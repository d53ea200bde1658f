"""The line errors of an outer rotary axis that stood still, as a located sphere reads them.

A trunnion ``[w C A X Y b Z t]`` whose cradle A stood at theta over the whole survey while C
turned (a C sweep at a tilted set-up). An offset d of A's line moves everything A carries by
the constant (I - R_A(theta)) d (ISO 230-7: the body turns about its real line), so C's line
is shifted by (R_A(theta)^T - I) d in C's frame and the sphere, located at the set-up, reads
exactly C's line offset by that:

    EY0C += (cos theta - 1) EY0A + sin theta EZ0A

(theta = the axis' sign x its reading). A's tilts tilt C's line alike. The readings cannot
part the two lines, so the output names the line that turned and says the still one folded
into it, never the still line for both. Checked against that closed form, against the
independent generator's rigid bodies (``studies.convention_surveys``), and end to end.
"""
from __future__ import annotations

import math
import sys
from pathlib import Path

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import family_named
from mt_accuracy_ros.core.effects.geometric import parse_inseparable, still_outer_lines
from mt_accuracy_ros.core.workbench.diagnosis import Observations, diagnose
from studies import convention_surveys as cs

sys.path.insert(0, str(Path(__file__).resolve().parent))
from test_outer_zero import SPHERE, _context, _trunnion  # noqa: E402  (one trunnion)

A_STILL_DEG = -30.0
LINES = ["EY0A", "EZ0A", "EB0A", "EC0A"]


def _c_sweep(generator, a_deg=A_STILL_DEG, repeats=1):
    """The sphere followed with RTCP while C turns a full circle and A stands at a_deg."""
    poses = [dict(generator["setup"])] + [
        {"A": math.radians(a_deg), "C": math.radians(c)} for c in np.arange(-180, 180, 15)]
    poses = poses * repeats
    return {"q": [cs.solve_linear(generator, p, SPHERE) for p in poses],
            "target": np.tile(SPHERE, (len(poses), 1)), "group": [0] * len(poses),
            "setup": {0: 0}, "tool_setup": 0}


def _error(name, value):
    kind = "location_offset" if name[1] in "XYZ" else "location_tilt"
    return {"iso_name": name, "kind": kind, "axis": name[-1], "value_si": value}


@pytest.mark.parametrize("signs", [(1, 1), (-1, 1), (1, -1)])
def test_a_still_cradles_offsets_read_as_cs_line_moved_by_the_closed_form(signs):
    generator, described = _trunnion("A", signs, {"A": A_STILL_DEG, "C": 0.0})
    rows = _c_sweep(generator)
    ctx, _ = _context(described, rows)
    theta = signs[0] * math.radians(A_STILL_DEG)
    closed = {"EY0A": math.cos(theta) - 1.0, "EZ0A": math.sin(theta)}
    setting = family_named("rotary_location").settings(ctx, "C")[0]
    folds = parse_inseparable(setting["inseparable"])
    for name, ratio in closed.items():
        assert folds[name] == pytest.approx({"EY0C": ratio}, abs=1e-7)
        column = ctx.located(name)[0]
        assert np.abs(column - ratio * ctx.located("EY0C")[0]).max() < 1e-12
        # The generator's rigid bodies, 20 um: the same readings.
        truth, _ = cs.located_errors(generator, cs.errs_from_effects([_error(name, 20e-6)]),
                                     rows)
        assert np.abs(truth).max() > 2e-6
        assert np.abs(truth - 20e-6 * ratio * ctx.located("EY0C")[0]).max() < 1e-15


@pytest.mark.parametrize("name", ["EB0A", "EC0A"])
def test_a_still_cradles_tilts_fold_into_cs_line_as_the_generator_reads_them(name):
    generator, described = _trunnion("A", (1, -1), {"A": A_STILL_DEG, "C": 0.0})
    rows = _c_sweep(generator)
    ctx, _ = _context(described, rows)
    folds = parse_inseparable(family_named("rotary_location").settings(ctx, "C")[0]
                              ["inseparable"])[name]
    assert set(folds) <= {"EX0C", "EY0C", "EA0C", "EB0C"} and folds
    combined = sum(ratio * ctx.located(kept)[0] for kept, ratio in folds.items())
    truth, _ = cs.located_errors(generator, cs.errs_from_effects([_error(name, 30e-6)]), rows)
    assert np.abs(truth).max() > 3e-7
    # The same to second order: (30 urad)^2 x 0.1 m, and the setting's 7 printed digits.
    assert np.abs(truth - 30e-6 * combined).max() < 1e-10


def test_still_outer_lines_are_those_of_carrying_axes_that_stood_still():
    generator, described = _trunnion("A", (1, 1), {"A": A_STILL_DEG, "C": 0.0})
    still, _ = _context(described, _c_sweep(generator))
    assert still_outer_lines(still, "C") == LINES
    assert still_outer_lines(still, "AC") == []      # A is the variant's own axis
    assert still_outer_lines(still, "A") == []       # nothing carries A
    tilted = _c_sweep(generator)
    tilted["q"] += _c_sweep(generator, a_deg=10.0)["q"]
    tilted["target"] = np.tile(SPHERE, (len(tilted["q"]), 1))
    turning, _ = _context(described, tilted)
    assert still_outer_lines(turning, "C") == []
    family = family_named("rotary_location")
    assert "EY0A" not in family.parameter_names("C", family.settings(still, "C")[0])


def test_a_still_cradles_offset_beside_cs_offset_is_named_on_c_as_their_sum():
    """EY0A 20 um with EY0C -37.7 um, A still at -30 deg: the readings are C's line at
    EY0C = -37.7 + (cos 30 deg - 1) 20 = -40.38 um. The output names C's line with that
    sum and says A's offset folded into it, not A's line with a stand-in of hundreds of
    um (which an Occam tie between the two lines, broken by the fewer parameters, gave)."""
    generator, described = _trunnion("A", (1, 1), {"A": A_STILL_DEG, "C": 0.0})
    rows = _c_sweep(generator, repeats=4)
    effects = [_error("EY0A", 20e-6), _error("EY0C", -37.7e-6)]
    errors, _ = cs.located_errors(generator, cs.errs_from_effects(effects), rows)
    _, positions = _context(described, rows)
    n = len(rows["q"])
    noise = 0.3e-6
    measured = errors + np.random.default_rng(11).normal(0.0, noise, (n, 3))
    obs = Observations(positions, measured, np.ones((n, 3), bool), np.arange(n, dtype=float),
                       {}, {}, 2 * noise, work_point=SPHERE)
    selected = diagnose(ErrorModel(described), obs).selected
    assert [s.name for s in selected] == ["rotary_location:C"]
    named = selected[0]
    assert named.parameters["EY0C"] == pytest.approx(
        -37.7e-6 + (math.cos(math.radians(30.0)) - 1.0) * 20e-6, abs=0.3e-6)
    assert "EY0A" in parse_inseparable(named.setting["inseparable"])
    assert "EY0A" not in named.parameters
