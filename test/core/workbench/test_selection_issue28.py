"""Issue 28's engine: forward validation, per-component tests, ridge inside the fold.

Each shortcut of the selector is checked against a plain computation written here
(a refit per block with numpy's lstsq, a naive ridge with explicit nested validation).
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import Context
from mt_accuracy_ros.core.effects.thermal import AllSensorsRidge, sensor_weights
from mt_accuracy_ros.core.kinematics.machine import generic_cartesian
from mt_accuracy_ros.core.workbench import selection
from mt_accuracy_ros.core.workbench.diagnosis import (Observations, candidate_terms, diagnose,
                                                      residuals)

TRAVEL = {"X": (0.0, 0.6), "Y": (0.0, 0.5), "Z": (0.0, 0.4)}


def _survey(n=300, seed=3, z_error=None, sensors=0, noise=0.5e-6):
    rng = np.random.default_rng(seed)
    positions = {a: rng.uniform(*TRAVEL[a], n) for a in "XYZ"}
    time_s = np.arange(n) * 20.0
    temperatures = {f"s{k}": 20 + np.cumsum(rng.normal(0, 0.05, n)) for k in range(sensors)}
    truth = np.zeros((n, 3))
    if z_error is not None:
        truth[:, 2] = z_error(positions, temperatures)
    obs = Observations(positions, truth + rng.normal(0, noise, (n, 3)), np.ones((n, 3), bool),
                       time_s, temperatures=temperatures, uncertainty_m=2 * noise)
    return obs, ErrorModel(generic_cartesian(TRAVEL), {})


def _selector(obs, model, **kwargs):
    ctx = Context(model.machine, obs.variables(model.reference_temperatures_c),
                  model._kinematics)
    chosen = selection.Selector(ctx, residuals(model, obs), obs.measured_mask,
                                obs.uncertainty_m / 2, **kwargs)
    return chosen, candidate_terms(model, ctx)


def test_forward_validation_predicts_each_block_from_the_blocks_before_it_only():
    obs, model = _survey(z_error=lambda p, t: 2e-6 * np.sin(2 * np.pi * p["X"] / 0.6))
    selector, terms = _selector(obs, model, forward=True)
    term = next(t for t in terms if t.name == "positioning:EXX")
    setting = term.settings[0]
    stats = selector.base_statistics(selector.base_columns())
    per_sample, chosen = selector.out_of_fold(stats, term)
    assert all(dict(c) == setting for c in chosen.values()) or len(term.settings) > 1
    # Plain: for every block after the first, lstsq on the rows before it.
    x = np.column_stack([selector.offsets, selector.design_rows(term, chosen[1])])
    y = selector.y
    expected = np.zeros(obs.n * 3)
    for fold, (a, b) in enumerate(selector.fold_bounds):
        if fold == 0:
            continue   # nothing precedes it: never judged
        fold_setting = chosen[fold]
        xf = np.column_stack([selector.offsets, selector.design_rows(term, fold_setting)])
        coefficients, *_ = np.linalg.lstsq(xf[:a], y[:a], rcond=None)
        expected[selector.rows[a:b]] = (xf[a:b] @ coefficients - y[a:b]) ** 2
    assert x.shape[0] == y.size
    np.testing.assert_allclose(per_sample.ravel(), expected, rtol=1e-6, atol=1e-24)
    # The first block is never judged, and the folds are the asked-for count plus it.
    first = selector.fold_bounds[0]
    assert not per_sample.ravel()[selector.rows[first[0]:first[1]]].any()
    assert len(selector.fold_bounds) == 6 and selector.judged_mask.sum() < obs.n * 3


def _weak_bow_named(level: float, seeds: range) -> int:
    """How many surveys name a straightness of X in z alone whose coefficient is ``level``
    standard errors (noise 0.5 um on every component, 300 readings)."""
    shape = lambda p: ((2 * p["X"] - 0.6) / 0.6) ** 2 - 1 / 3  # noqa: E731
    hits = 0
    for seed in seeds:
        obs, _ = _survey(seed=seed)
        norm = np.linalg.norm(shape(obs.positions))
        obs, model = _survey(seed=seed, z_error=lambda p, t: level * 0.5e-6 * shape(p) / norm)
        found = diagnose(model, obs, localise_residual=False).selected
        hits += bool(found) and found[0].name == "straightness:EZX"
    return hits


def test_an_effect_of_one_component_is_tested_on_that_component(monkeypatch):
    """Issue 28: pooled over x, y and z, a straightness that lives in z alone is diluted by
    the two components it does not move. Tested on z, it is named far more often - the
    same surveys, the same seeds, the pooled test put back by hand for the comparison."""
    obs, model = _survey(seed=11)
    selector, terms = _selector(obs, model)
    step = selector.step(terms)
    scored = {s.term.name: s for s in step.ranking}
    assert scored["straightness:EZX"].components == "z"
    assert scored["positioning:EXX"].components == "x"
    assert scored["squareness:EB0Z"].components == "x"
    seeds = range(20)
    per_component = _weak_bow_named(10.0, seeds)
    monkeypatch.setattr(selection.Selector, "components_of",
                        lambda self, term: self.mask.any(axis=0))
    pooled = _weak_bow_named(10.0, seeds)
    # docs/results.md (section "Low signal", which has the 5/7/10 sigma series too): 20 of
    # 20 against 8 of 20 - seeded, so pinned: a change of either count fails here.
    assert (per_component, pooled) == (20, 8)


def _naive_ridge(x, y, strength, penalised):
    """Ridge with strength x each penalised column's own sum of squares."""
    gram = x.T @ x
    gram[penalised, penalised] *= 1.0 + strength
    return np.linalg.solve(gram, x.T @ y)


def test_ridge_strength_is_chosen_inside_each_fold_and_fits_as_closed_form_ridge():
    # Eight weak sensors that carry a drift together.
    obs, model = _survey(n=400, seed=5, sensors=8,
                         z_error=lambda p, t: 0.8e-6 * sum(v - v[0] for v in t.values()))
    selector, terms = _selector(obs, model)
    (term,) = [t for t in terms if isinstance(t.family, AllSensorsRidge)]
    assert term.variant == "+".join(f"s{k}" for k in range(8))
    stats = selector.base_statistics(selector.base_columns())
    chosen = selector.choose_settings(term, stats)
    # Plain nested validation: fold f chooses by the blocks g != f, fitting on the others.
    design = selector.design_rows(term, term.settings[0])
    x = np.column_stack([selector.offsets, design])
    keep = np.flatnonzero(np.abs(x).sum(axis=0) > 0)          # x, y columns of a z-only log
    x, penalised = x[:, keep], np.flatnonzero(keep >= 3)
    y = selector.y
    bounds = selector.fold_bounds
    for f in range(len(bounds)):
        errors = []
        for setting in term.settings:
            total = 0.0
            for g, (a, b) in enumerate(bounds):
                if g == f:
                    continue
                train = np.ones(y.size, bool)
                for h in (f, g):
                    train[bounds[h][0]:bounds[h][1]] = False
                c = _naive_ridge(x[train], y[train], setting["ridge"], penalised)
                total += float(np.sum((x[a:b] @ c - y[a:b]) ** 2))
            errors.append(total)
        assert chosen[f] == term.settings[int(np.argmin(errors))]
    # The full fit at a strength is closed-form ridge.
    setting = term.settings[2]
    coefficients, _, _ = selector.fit_full([(term, setting)])
    expected = _naive_ridge(x, y, setting["ridge"], penalised)
    got = np.concatenate([np.zeros(3), coefficients[0]])[keep]
    np.testing.assert_allclose(got[3:], expected[3:], rtol=1e-6)
    # And which sensors carry it: every sensor about alike here.
    names = term.family.parameter_names(term.variant, setting)
    shares = dict(sensor_weights(dict(zip(names, coefficients[0])), obs.temperatures))
    assert set(shares) == set(obs.temperatures) and sum(shares.values()) == pytest.approx(1.0)


def test_squareness_with_the_other_reference_is_a_candidate_and_a_table_motion_error():
    """e_y = angle x (X's travel tilted, Y the reference): no straightness holds a slope,
    so before issue 28 nothing named it."""
    obs, model = _survey(seed=8, z_error=None)
    obs.measured_m[:, 1] += 20e-6 * obs.positions["X"]
    diagnosis = diagnose(model, obs)
    assert diagnosis.selected[0].name == "squareness:EYX"
    assert diagnosis.selected[0].parameters["angle_rad"] == pytest.approx(20e-6, rel=0.02)
    from mt_accuracy_ros.core.workbench.diagnosis import add_effect

    fitted = add_effect(model, diagnosis.selected[0], obs)
    grid = np.linspace(0.0, 0.6, 7)
    table = fitted.component_errors("X", grid)
    np.testing.assert_allclose(table["EYX"], diagnosis.selected[0].parameters["angle_rad"] * grid,
                               rtol=1e-12)
    assert "EYX" not in fitted.location_table()


def test_max_t_controls_the_family_error_and_does_not_pay_for_copies():
    """The adjustment for the best of many candidates (Westfall-Young max-T over sign
    flips of whole blocks) against what it replaces: Bonferroni's M x p."""
    from mt_accuracy_ros.core.workbench.selection import max_t_adjusted

    rng = np.random.default_rng(3)
    # Nothing helps: the smallest adjusted p of 20 candidates falls below 5 % in about
    # 5 % of the data sets (the family-wise error), not in 64 % as unadjusted.
    hits = sum(max_t_adjusted(rng.normal(0, 1, (20, 20)), draws=1000).min() < 0.05
               for _ in range(200))
    assert hits <= 18                       # 5 % of 200 is 10; binomial 99 % bound ~18
    # Twenty copies of one candidate are one test: no 20 x penalty.
    one = rng.normal(0.6, 1, 20)
    copies = max_t_adjusted(np.tile(one, (20, 1)), draws=4000)
    assert copies[0] == pytest.approx(max_t_adjusted(one[None, :], draws=4000)[0], abs=1e-12)
    assert copies[0] < 0.5 * min(1.0, 20 * _t_p(one))
    # Independent candidates: about Bonferroni's (never far above it).
    independent = np.vstack([one, rng.normal(0, 1, (19, 20))])
    assert max_t_adjusted(independent, draws=4000)[0] <= 1.5 * min(1.0, 20 * _t_p(one))


def _t_p(gains):
    from mt_accuracy_ros.core.workbench.distributions import t_sf

    b = gains.size
    return t_sf(gains.mean() / (gains.std(ddof=1) / np.sqrt(b)), b - 1)
