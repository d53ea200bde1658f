"""The open catalogue on hidden effects made outside the package (issue 16).

The data come from :mod:`studies.foreign_machine`, which shares no code with the
workbench (its own chain, ODE lags, errors in shapes outside the catalogue's forms: splines,
periodic splines, a worn screw's backlash, a lag of another order, a growth that bends
with the rise, a twist whose rate changes). A few seeded
trials per group run here; the rates over hundreds of trials are in
docs/results.md (``python -m bench.workbench_catalogue``).
"""
from __future__ import annotations

import json
import re
from pathlib import Path

import numpy as np
import pytest

from studies.catalogue_trials import run_trial
from studies.foreign_machine import ErrorSet, make_trial, read_geometry, tcp_point

DOCS = Path(__file__).resolve().parents[2] / "docs"
#: The catalogue proof's one run: every outcome and its summary
#: (``python -m bench.workbench_catalogue --seeds 5 --nulls 20 --pairs 15 --out ...``).
PROOF = DOCS / "catalogue_proof.json"


def recorded(machine: str, kinds: tuple[str, ...], seed: int) -> dict:
    """The outcome docs/catalogue_proof.json records for one trial."""
    outcomes = json.loads(PROOF.read_text())["outcomes"]
    return next(o for o in outcomes
                if (o["machine"], tuple(o["kinds"]), o["seed"]) == (machine, kinds, seed))


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
    # The names, in their order, and the share removed are the proof's own for this seed
    # (docs/catalogue_proof.json), to round-off: a change of either fails here.
    proof = recorded(machine, (kind,), seed)
    assert outcome.found == proof["found"], (outcome.found, proof["found"])
    assert outcome.removed == pytest.approx(proof["removed"], abs=1e-4)
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
    proof = recorded(machine, kinds, seed)
    assert outcome.found == proof["found"], (outcome.found, proof["found"])
    assert outcome.removed == pytest.approx(proof["removed"], abs=1e-4)


def test_the_results_table_states_the_proofs_own_summary():
    """docs/results.md's catalogue table (its bold column) is the run the JSON holds:
    the same figures, rounded as printed, and the same counts."""
    summary = json.loads(PROOF.read_text())["summary"]
    text = (DOCS / "results.md").read_text()

    def row(start: str) -> str:
        return next(line for line in text.splitlines() if line.startswith(start))

    singles = summary["single_trials"]
    first = row("| right effect named first (170 single trials) |")
    assert f"**{100 * summary['named_first']:.1f} %** " \
        f"({round(summary['named_first'] * singles)} of {singles})" in first, first
    localised = row("| right variable localised |")
    assert f"**{100 * summary['localised']:.1f} %** " \
        f"({round(summary['localised'] * singles)} of {singles}; the top variable alone: " \
        f"{100 * summary['localised_by_the_top_variable_alone']:.1f} %)" in localised, localised
    assert f"**{100 * summary['median_removed']:.1f} %**" in row("| median residual RMS removed |")
    assert f"**{100 * summary['false_alarms']:.0f} %**" in \
        row(f"| false alarms, nothing hidden ({summary['null_trials']} trials) |")
    pairs = summary["pair_trials"]
    both = row(f"| both of two simultaneous hidden effects named ({pairs} pairs) |")
    assert f"**{100 * summary['both_named']:.1f} %** ({round(summary['both_named'] * pairs)} " \
        f"of {pairs}; median {100 * summary['pair_median_removed']:.1f} % removed)" in both, both
    assert re.search(r"Not named first, (\d+) of 170", text).group(1) == \
        str(singles - round(summary["named_first"] * singles))


def test_magnitudes_are_drawn_in_the_issue_range():
    sizes = [make_trial("kidani_hmc", ("backlash",), seed, readings=60).magnitudes_m[0]
             for seed in range(20)]
    assert 2e-6 <= min(sizes) and max(sizes) <= 20e-6
