"""The selection engine's shortcuts against the plain computation they replace."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import Context
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench import selection
from mt_accuracy_ros.core.workbench.diagnosis import Observations, candidate_terms, residuals

MACHINE = load_machine("kidani_hmc")


def _selector():
    rng = np.random.default_rng(7)
    n = 300
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    truth = np.zeros((n, 3))
    truth[:, 0] = 3e-6 * np.sin(2 * np.pi * positions["X"] / 0.01)
    truth[:, 1] = 2e-5 * (positions["Y"] - positions["Y"].mean()) ** 2
    obs = Observations(positions, truth + rng.normal(0, 0.5e-6, truth.shape),
                       np.ones((n, 3), bool), np.arange(n) * 10.0, uncertainty_m=1e-6)
    model = ErrorModel(MACHINE, {})
    ctx = Context(MACHINE, obs.variables(model.reference_temperatures_c), model._kinematics,
                  model.tcp_error(obs.positions, fresh=True)[1])
    chosen = selection.Selector(ctx, residuals(model, obs), obs.measured_mask, 0.5e-6)
    return chosen, candidate_terms(model, ctx, None)


def test_candidates_full_fit_from_fold_products_equals_the_fit_of_the_columns():
    selector, terms = _selector()
    stats = selector.base_statistics(selector.base_columns())
    q = stats.base.shape[1]
    for term in terms[:40]:
        setting = term.settings[-1]
        coefficients, standard = selector._fit_products(
            *selector._products_of(stats, term, setting))
        expected_c, expected_s, _ = selector.fit_full([(term, setting)])
        np.testing.assert_allclose(coefficients[q:], expected_c[-1], rtol=1e-7,
                                   atol=1e-9 * np.abs(expected_c[-1]).max(initial=1e-30))
        np.testing.assert_allclose(standard[q:], expected_s[-1], rtol=1e-5)


def test_a_design_cache_that_evicts_everything_gives_the_same_steps(monkeypatch):
    """The LRU bound (1e5 readings) must change only the cost, never a choice or a score."""
    selector, terms = _selector()
    steps = selector.run(terms, max_terms=2)
    monkeypatch.setattr(selection, "DESIGN_CACHE_BYTES", 1)
    small, small_terms = _selector()
    assert small._designs.max_bytes == 1
    small_steps = small.run(small_terms, max_terms=2)
    assert [s.added and s.added.term.name for s in small_steps] == \
        [s.added and s.added.term.name for s in steps]
    for a, b in zip(steps, small_steps):
        assert [s.term.name for s in a.ranking] == [s.term.name for s in b.ranking]
        assert [s.cv_rmse for s in a.ranking] == pytest.approx([s.cv_rmse for s in b.ranking],
                                                               rel=1e-12)
    assert len(small._designs._items) == 1 and len(selector._designs._items) > 1
