"""Issue 41: after each addition every earlier term must still earn its place.

A survey whose z error is the product x·y on a generic machine: the selection first
reaches for simpler stand-ins (a tilt through the tool's arm, a twist of the wrong
pair) and later adds what explains them. The stand-ins are dropped, each with the
term that explains it, and the model that remains is consistent: every kept term
passes the selection's tests against all the others, every dropped one fails them
against the final model (a second pass of the same tests, made here)."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.kinematics.machine import generic_cartesian
from mt_accuracy_ros.core.workbench.diagnosis import (Observations, candidate_terms, diagnose,
                                                      residual_frame)
from mt_accuracy_ros.core.workbench.selection import Selector


def _survey(seed: int = 1, n: int = 600):
    """600 random points in 500 x 400 x 300 mm, z error 20 um (x / 500 mm) (y / 400 mm),
    0.3 um of noise; the generic machine over the surveyed travel (as ``check`` makes it
    for a survey without a machine)."""
    rng = np.random.default_rng(seed)
    x, y, z = rng.uniform(0, 0.5, n), rng.uniform(0, 0.4, n), rng.uniform(0, 0.3, n)
    measured = np.zeros((n, 3))
    measured[:, 2] = 20e-6 * (x / 0.5) * (y / 0.4) + rng.normal(0, 0.3e-6, n)
    measured[:, 0], measured[:, 1] = rng.normal(0, 0.3e-6, n), rng.normal(0, 0.3e-6, n)
    travel = {a: (float(q.min()), float(q.max())) for a, q in zip("XYZ", (x, y, z))}
    model = ErrorModel(generic_cartesian(travel), {})
    obs = Observations({"X": x, "Y": y, "Z": z}, measured, np.ones((n, 3), bool),
                       np.arange(n) * 5.0, {a: np.zeros(n) for a in "XYZ"}, {}, 0.6e-6)
    return model, obs


def test_a_term_a_later_one_explains_is_dropped_and_said():
    model, obs = _survey()
    diagnosis = diagnose(model, obs)
    named = [c.name for c in diagnosis.selected]
    assert diagnosis.dropped, "the stand-ins the product first looked like stay"
    for entry in diagnosis.dropped:
        assert entry["name"] not in named
        assert entry["sentence"] == f"dropped {entry['name']}: {entry['by']} explains it"
    assert "cross_axis:XY" in named
    # what remains explains the product down to the probe's noise
    assert diagnosis.final_cv_rmse < 0.45e-6


def test_every_kept_term_earns_its_place_and_no_dropped_one_does():
    model, obs = _survey()
    frame = residual_frame(model, obs)
    selector = Selector(frame.ctx, frame.residual, frame.mask, obs.uncertainty_m / 2)
    selector.run(candidate_terms(model, frame.ctx, None), max_terms=4)
    final = list(selector.selected)
    assert len(final) >= 2 and selector.dropped

    def passes(term, against) -> bool:
        selector.selected = against
        return selector.step([term]).added is not None

    for term, _ in final:
        assert passes(term, [s for s in final if s[0].name != term.name]), term.name
    for gone, _ in selector.dropped:
        assert not passes(gone.term, final), gone.term.name
