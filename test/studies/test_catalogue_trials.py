"""The open catalogue on hidden effects made outside the package (issue 16).

The data come from :mod:`studies.foreign_machine`, which shares no code with the
workbench (its own chain, ODE lags, errors in shapes outside the catalogue's forms: splines,
periodic splines, a worn screw's backlash, a lag of another order, a growth that bends
with the rise, a twist whose rate changes). A few seeded
trials per group run here; the rates over hundreds of trials are in
docs/results.md (``python -m bench.workbench_catalogue``).
"""
from __future__ import annotations

import numpy as np
import pytest

from studies.catalogue_trials import run_trial
from studies.foreign_machine import ErrorSet, make_trial, read_geometry, tcp_point


def test_the_generator_is_a_rigid_body_chain_of_its_own():
    """A sanity check of the foreign chain against a closed form: a squareness EC0Y of
    the HMC's Y axis (tool branch after X) gives e_x = -S y at the tool."""
    geometry = read_geometry("kidani_hmc")
    q = {"X": np.array([0.1, 0.2]), "Y": np.array([-0.3, -0.1]), "Z": np.array([0.2, 0.3])}
    square = 20e-6
    errors = ErrorSet(location_fns={"Y": [lambda s: np.array([0, 0, 0, 0, 0, square])]})
    error = tcp_point(geometry, q, errors) - tcp_point(geometry, q, None)
    # Rotation about z at the Y frame: the tool point (y + offsets) swings in x.
    lever_y = q["Y"] + geometry.offsets["Y"][1] + geometry.tool[1]
    # (exact rotations: equal to first order, the rest is S^2 x lever ~ 1e-10 m)
    np.testing.assert_allclose(error[:, 0], -square * lever_y, atol=1e-9, rtol=0)
    lever_x = geometry.offsets["Y"][0] + geometry.tool[0]
    np.testing.assert_allclose(error[:, 1], square * lever_x, atol=1e-9, rtol=0)


@pytest.mark.parametrize("machine, kind, seed", [
    ("kidani_hmc", "ballscrew_pitch", 1000),
    ("kidani_hmc", "lagged_growth", 1000),
    ("kidani_hmc", "thermal_squareness", 1000),
    ("kidani_hmc", "twist", 1001),
    ("kidani_hmc", "backlash", 1000),
    ("khan_chen_rpppr", "rotary_offset", 1000),
    ("khan_chen_rpppr", "rotary_runout", 1001),
    ("khan_chen_rpppr", "spindle_heat", 1002),
])
def test_a_hidden_effect_outside_the_package_is_named_located_and_removed(machine, kind, seed):
    outcome = run_trial(machine, (kind,), seed)
    assert outcome.named_first, (outcome.found, outcome.text)
    assert outcome.localised, (outcome.top_variable, outcome.sentence)
    # Shapes outside the catalogue's forms (issue 39) leave what its family cannot hold:
    # a measured-looking pitch (a periodic spline) harmonics beyond the second (72 %
    # removed here; medians 52-94 % in the catalogue proof, docs/results.md), a twist whose
    # rate changes along the way the part p_a p_b cannot follow (79 % here; medians 81-89
    # %). Every other kind: 80 %.
    floor = {"ballscrew_pitch": 0.65, "twist": 0.75}.get(kind, 0.8)
    assert outcome.removed >= floor, (outcome.rms_before_um, outcome.rms_after_um)


@pytest.mark.parametrize("machine, seed", [("kidani_hmc", 5000), ("khan_chen_rpppr", 5001)])
def test_nothing_hidden_nothing_named(machine, seed):
    outcome = run_trial(machine, (), seed)
    assert outcome.found == [], outcome.text
    assert "nothing missing" in outcome.text


@pytest.mark.parametrize("machine, kinds, seed", [
    ("khan_chen_rpppr", ("structural_drift", "thermal_squareness"), 9007),
    ("kidani_hmc", ("ballscrew_pitch", "servo_lag"), 9004),
])
def test_two_hidden_effects_are_both_named(machine, kinds, seed):
    outcome = run_trial(machine, kinds, seed)
    assert outcome.all_named, outcome.found
    assert outcome.removed >= 0.8


def test_magnitudes_are_drawn_in_the_issue_range():
    sizes = [make_trial("kidani_hmc", ("backlash",), seed, readings=60).magnitudes_m[0]
             for seed in range(20)]
    assert 2e-6 <= min(sizes) and max(sizes) <= 20e-6
