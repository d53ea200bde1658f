"""The selection engine's shortcuts against the plain computation they replace."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.compensation.error_model import ErrorModel
from mt_accuracy_ros.core.effects import Context
from mt_accuracy_ros.core.effects.physics import (consistency_allowances, consistency_problems,
                                                  limit_problems, spread_problems)
from mt_accuracy_ros.core.kinematics.machine import load_machine
from mt_accuracy_ros.core.workbench import selection
from mt_accuracy_ros.core.workbench.diagnosis import Observations, candidate_terms, residuals
from same_steps import assert_same_steps

MACHINE = load_machine("kidani_hmc")


def _selector(mask=None):
    rng = np.random.default_rng(7)
    n = 300
    positions = {a: rng.uniform(*MACHINE.axes[a].stroke, n) for a in "XYZ"}
    truth = np.zeros((n, 3))
    truth[:, 0] = 3e-6 * np.sin(2 * np.pi * positions["X"] / 0.01)
    truth[:, 1] = 2e-5 * (positions["Y"] - positions["Y"].mean()) ** 2
    obs = Observations(positions, truth + rng.normal(0, 0.5e-6, truth.shape),
                       np.ones((n, 3), bool) if mask is None else mask, np.arange(n) * 10.0,
                       uncertainty_m=1e-6)
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
    monkeypatch.setattr(selection.designs, "DESIGN_CACHE_BYTES", 1)
    small, small_terms = _selector()
    assert small._designs.max_bytes == 1
    small_steps = small.run(small_terms, max_terms=2)
    assert_same_steps(small_steps, steps)
    assert len(small._designs._items) == 1 and len(selector._designs._items) > 1


def _partial_mask():
    """Some readings measure one or two components, some none (a laser on one axis, a
    dropped reading)."""
    mask = np.ones((300, 3), bool)
    mask[::7, 2] = False
    mask[3::11, :2] = False
    mask[5::13] = False
    return mask


@pytest.mark.parametrize("mask", [None, "partial"])
def test_separable_designs_score_as_their_rows_do(mask):
    """A candidate whose design is sensitivity x columns is scored on one value per
    reading; its fold products, held-out predictions and physics check must equal those
    of its materialised (rows, P) design."""
    selector, terms = _selector(None if mask is None else _partial_mask())
    stats = selector.base_statistics(selector.base_columns())
    q = stats.base.shape[1]
    separable = [t for t in terms if selector.basis_rows(t, t.settings[-1]) is not None]
    assert {t.family.name for t in separable} >= {"positioning", "straightness", "angular",
                                                  "positioning_periodic"}
    for term in separable:
        for setting in (term.settings[0], term.settings[-1]):
            gram, rhs, yy = selector._products_of(stats, term, setting)
            design = selector.design_rows(term, setting)
            e_gram, e_rhs, e_yy = selector._candidate_products(stats, design)
            scale = np.abs(e_gram).max()
            np.testing.assert_allclose(gram, e_gram, rtol=0, atol=1e-12 * scale)
            np.testing.assert_allclose(rhs, e_rhs, rtol=0, atol=1e-12 * np.abs(e_rhs).max())
            assert yy == pytest.approx(e_yy, rel=1e-14)
            c = np.linspace(-1.0, 1.0, design.shape[1])
            basis = selector.basis_rows(term, setting)
            for a, b in selector.fold_bounds + [(0, selector.y.size)]:
                np.testing.assert_allclose(
                    selector._separable_prediction(term, basis, c, a, b), design[a:b] @ c,
                    rtol=0, atol=1e-13 * np.abs(design).max())
            coefficients = selector._fit_products(gram, rhs, yy)[0][q:]
            flat = np.zeros(selector.mask.size)
            flat[selector.rows] = design @ coefficients
            expected = limit_problems(term.family.parameter_names(term.variant, setting),
                                      coefficients, term.family.parameter_limits(
                                          selector.ctx, term.variant, setting))
            expected += consistency_problems(flat.reshape(-1, 3), selector.residual,
                                             selector.mask, selector.noise_sigma)
            assert selector.physics_refusal(term, setting, coefficients) == "; ".join(expected)


@pytest.mark.parametrize("mask", [None, "partial"])
def test_physics_refuses_alike_with_or_without_the_spread_bound(mask):
    """A candidate's spread is bounded from its products (sqrt(c'X'Xc / rows)); where the
    bound lies within every allowance the contribution is not made. Every candidate's
    refusal - as fitted, and with coefficients 30x too large, which physics refuses - is
    the same as from the contribution itself, and the bound's sum is the contribution's."""
    selector, terms = _selector(None if mask is None else _partial_mask())
    stats = selector.base_statistics(selector.base_columns())
    q = stats.base.shape[1]
    skipped = refused = 0
    for term in terms:
        setting = term.settings[-1]
        gram, rhs, yy = selector._products_of(stats, term, setting)
        coefficients, _ = selector._fit_products(gram, rhs, yy)
        for c in (coefficients[q:], 30.0 * coefficients[q:]):
            own_sum = float(c @ gram[:, q:, q:].sum(axis=0) @ c)
            own = selector.design_rows(term, setting) @ c
            assert own_sum == pytest.approx(float(own @ own), rel=1e-9, abs=1e-30)
            plain = selector.physics_refusal(term, setting, c)
            assert selector.physics_refusal(term, setting, c, own_square_sum=own_sum) == plain
            skipped += selector._spreads_within_allowances(own_sum)
            refused += "RMS at the readings" in plain
    assert skipped > 0 and refused > 0


def test_per_reading_errors_of_every_row_are_the_rows_themselves():
    """With every component of every reading fitted the rows are already per reading:
    the shortcut equals the scatter by row index, bit for bit."""
    selector, _ = _selector()
    assert selector.all_rows
    squared = np.random.default_rng(2).random(selector.y.size)
    expected = np.bincount(selector.rows, weights=squared, minlength=selector.mask.size
                           ).reshape(selector.n, selector.width)
    np.testing.assert_array_equal(selector._per_sample(squared.copy()), expected)


def test_normal_equations_solved_in_groups_are_each_their_own_solution():
    """A candidate's settings are solved in one batched call per matrix size; each result
    is bit for bit the one its own call gives (rank-deficient ones included)."""
    from mt_accuracy_ros.core.workbench.selection import solve_normal, solve_normal_grouped

    rng = np.random.default_rng(0)
    grams, rhs = [], []
    for p in (3, 4, 4, 5, 4, 3, 7):
        x = rng.normal(size=(5, 50, p))
        if p == 5:
            x[..., 4] = x[..., 0]          # a repeated column
        grams.append(np.einsum("fni,fnj->fij", x, x))
        rhs.append(rng.normal(size=(5, p)))
    for grouped, gram, r in zip(solve_normal_grouped(grams, rhs), grams, rhs):
        np.testing.assert_array_equal(grouped, solve_normal(gram, r))


def test_held_out_fits_reused_from_the_choice_of_settings_are_the_fits_made_afresh(
        monkeypatch):
    """A candidate's folds are fitted once: the fits its settings were compared with (BIC)
    serve its held-out errors. Bit for bit what solving them again gives."""
    selector, terms = _selector()
    stats = selector.base_statistics(selector.base_columns())
    compared = [t for t in terms if len(t.settings) > 1 and not t.family.preselects
                and not getattr(t.family, "penalty_setting", None)]
    assert compared      # not vacuous: candidates whose settings BIC compares
    reused = [selector.out_of_fold(stats, term) for term in compared]
    assert any(selector._settings_and_fits(term, stats)[1] for term in compared)
    fresh_choice = selection.Selector._settings_and_fits_of
    monkeypatch.setattr(selection.Selector, "_settings_and_fits_of",
                        lambda self, terms, s: [(settings, {}) for settings, _ in
                                                fresh_choice(self, terms, s)])
    for term, (squared, settings) in zip(compared, reused):
        again, settings_again = selector.out_of_fold(stats, term)
        np.testing.assert_array_equal(squared, again)
        assert settings == settings_again


def test_a_fit_and_its_standard_errors_from_one_decomposition_are_the_two_made_apart():
    """``products_fit`` decomposes X'X once for its coefficients and their covariance:
    the same numbers, bit for bit, as :func:`solve_normal` and :func:`normal_inverse`
    (and the ridge sandwich) each on its own."""
    from mt_accuracy_ros.core.workbench.selection.linalg import (normal_inverse, penalise,
                                                                 products_fit,
                                                                 ridge_standard_errors,
                                                                 solve_normal)

    rng = np.random.default_rng(3)
    x = rng.normal(size=(5, 40, 6))
    x[..., 5] = x[..., 1]                 # a repeated column: a dropped direction
    y = rng.normal(size=(5, 40))
    gram, rhs = np.einsum("fni,fnj->fij", x, x), np.einsum("fni,fn->fi", x, y)
    yy = np.einsum("fn,fn->f", y, y)
    for penalty in ((0, 0.0), (3, 0.4)):
        coefficients, standard = products_fit(gram, rhs, yy, 200, penalty)
        whole, moment = gram.sum(axis=0), rhs.sum(axis=0)
        penalised = penalise(whole, penalty[0], 6, penalty[1])
        expected = solve_normal(penalised, moment)
        np.testing.assert_array_equal(coefficients, expected)
        rss = float(yy.sum()) - 2.0 * float(expected @ moment) + \
            float(expected @ whole @ expected)
        sigma2 = max(rss, 0.0) / (200 - 6)
        apart = ridge_standard_errors(whole, penalised, sigma2) if penalty[1] else \
            np.sqrt(sigma2 * np.clip(np.diag(normal_inverse(whole)), 0.0, None))
        np.testing.assert_array_equal(standard, apart)


def _products_fit_one_by_one(gram, rhs, yy, readings, penalty):
    """The whole record's fit of one candidate as it was made before the fits were
    batched: its own decomposition, its own solve."""
    from mt_accuracy_ros.core.workbench.selection.linalg import (normal_inverse, penalise,
                                                                 ridge_standard_errors,
                                                                 solve_normal)

    gram, rhs, yy = gram.sum(axis=0), rhs.sum(axis=0), float(yy.sum())
    penalised = penalise(gram, penalty[0], gram.shape[0], penalty[1])
    coefficients = solve_normal(penalised, rhs)
    rss = yy - 2.0 * float(coefficients @ rhs) + float(coefficients @ gram @ coefficients)
    sigma2 = max(rss, 0.0) / max(1, readings - gram.shape[0])
    inverse = normal_inverse(penalised)
    standard = ridge_standard_errors(gram, penalised, sigma2, inverse) \
        if penalised is not gram else np.sqrt(sigma2 * np.clip(np.diag(inverse), 0.0, None))
    return coefficients, standard


def test_full_data_fits_in_batches_are_each_candidates_own_fit(monkeypatch):
    """``products_fits`` decomposes the candidates' normal matrices of one size together
    (in batches of a few MB): each fit equals the one made alone (to 1e-12), ridge and
    rank-deficient ones too, whatever the batches' size."""
    from mt_accuracy_ros.core.workbench.selection import linalg

    rng = np.random.default_rng(11)
    problems = []
    for k in range(40):
        p = (3, 5, 8)[k % 3]
        x = rng.normal(size=(5, 60, p)) * np.geomspace(1e-3, 10.0, p)
        if k % 7 == 0:
            x[..., -1] = x[..., 0]          # a repeated column
        y = rng.normal(size=(5, 60))
        problems.append((np.einsum("fni,fnj->fij", x, x), np.einsum("fni,fn->fi", x, y),
                         np.einsum("fn,fn->f", y, y), (1, (0.0, 0.0, 0.3)[k % 3])))
    for limit in (linalg.BATCH_BYTES, 1000):
        monkeypatch.setattr(linalg, "BATCH_BYTES", limit)
        for batched, problem in zip(linalg.products_fits(problems, 300), problems):
            for got, alone in zip(batched, _products_fit_one_by_one(*problem[:3], 300,
                                                                      problem[3])):
                np.testing.assert_allclose(got, alone, rtol=1e-12, atol=0)


def test_same_shape_batches_hold_every_index_once_by_shape_and_size():
    from mt_accuracy_ros.core.workbench.selection.linalg import same_shape_batches

    shapes = [(5, 3, 3), (5, 4, 4), (5, 3, 3), (5, 3, 3), (5, 4, 4), (5, 3, 3)]
    batches = same_shape_batches(shapes, limit_bytes=2 * 5 * 9 * 8)
    assert sorted(i for b in batches for i in b) == list(range(len(shapes)))
    # Two 3x3 stacks fit the limit, one 4x4 stack only.
    assert batches == [[0, 2], [3, 5], [1], [4]]
    assert all(len({shapes[i] for i in b}) == 1 for b in batches)


def _fold_fits_one_by_one(selector, term, stats):
    """A candidate's in-fold settings and fold fits as they were made before a step's
    candidates were batched: its settings compared by BIC with a solve per setting, each
    chosen setting's folds solved alone."""
    from mt_accuracy_ros.core.workbench.selection.designs import penalty_of
    from mt_accuracy_ros.core.workbench.selection.linalg import penalise, solve_normal

    q = stats.base.shape[1]
    chosen, trained = selector._settings_before_bic(term, stats)
    compared = {}
    if trained is not None:
        counts = np.array([selector.y.size - (b - a) for a, b in selector.fold_bounds], float)
        best_bic, best = np.full(selector.folds, np.inf), [term.settings[0]] * selector.folds
        for setting, (gram, rhs, yy) in zip(term.settings, trained):
            coefficients = solve_normal(gram, rhs)
            rss = np.maximum(yy - np.einsum("fi,fi->f", coefficients, rhs), 1e-300)
            bic = counts * np.log(rss / counts) + gram.shape[1] * np.log(counts)
            for fold in np.flatnonzero(bic < best_bic):
                best_bic[fold], best[fold] = bic[fold], setting
            if penalty_of(term, setting) <= 0:
                compared[tuple(sorted(setting.items()))] = coefficients
        chosen = [c if c is not None else b for c, b in zip(chosen, best)]
    fits = {}
    for key in dict.fromkeys(tuple(sorted(s.items())) for s in chosen):
        fits[key] = compared.get(key)
        if fits[key] is None:
            gram, rhs, _ = selector._products_of(stats, term, dict(key))
            fits[key] = solve_normal(penalise(selector._train(gram), q, gram.shape[1],
                                              penalty_of(term, dict(key))),
                                     selector._train(rhs))
    return chosen, fits


@pytest.mark.parametrize("limit", [None, 3000])
def test_a_steps_fold_fits_in_batches_are_each_candidates_own(monkeypatch, limit):
    """``fold_fits`` solves every candidate's BIC comparisons and held-out fits in
    batched calls: each candidate's settings are those it chooses alone and each fold's
    fit equals its own solve (to 1e-12), with batches of the default size and of a few
    matrices (flushed many times in a step)."""
    from mt_accuracy_ros.core.workbench.selection import linalg

    if limit is not None:
        monkeypatch.setattr(linalg, "BATCH_BYTES", limit)
        monkeypatch.setattr(selection.selector, "BATCH_BYTES", limit)
    selector, terms = _selector()
    selector.selected = [(terms[0], terms[0].settings[0])]
    stats = selector.base_statistics(selector.base_columns())
    kinds = {(len(t.settings) > 1, t.family.preselects) for t in terms}
    assert {(True, False), (False, False)} <= kinds     # BIC and single settings both
    for (settings, fits), term in zip(selector.fold_fits(terms, stats), terms):
        alone_settings, alone_fits = _fold_fits_one_by_one(selector, term, stats)
        assert settings == alone_settings, term.name
        assert fits.keys() == alone_fits.keys(), term.name
        for key, coefficients in fits.items():
            np.testing.assert_allclose(coefficients, alone_fits[key], rtol=1e-12, atol=1e-300)


def test_terms_fitted_jointly_are_each_judged_beside_what_the_others_move():
    """:meth:`Selector.joint_refusals` against the plain computation on full (N, 3)
    contributions: each term's spread per component judged with the allowance grown by
    the others' spread (at most once more) where the set-up was located as one sum.
    Coefficients 3x and 30x too large make some refuse."""
    selector, terms = _selector()
    selector.shared_located = True
    chosen = [t for t in terms if t.family.name in ("straightness", "angular")][:3]
    together = [(t, t.settings[-1]) for t in chosen]
    coefficients, _, _ = selector.fit_full(together)
    for scale in (1.0, 3.0, 30.0):
        scaled = [scale * c for c in coefficients]
        flats = []
        for (term, setting), c in zip(together, scaled):
            flat = np.zeros(selector.mask.size)
            flat[selector.rows] = selector.design_rows(term, setting) @ c
            flats.append(flat.reshape(-1, 3))
        allowances = consistency_allowances(selector.residual, selector.mask,
                                            selector.noise_sigma)
        expected = []
        for k, ((term, setting), c) in enumerate(zip(together, scaled)):
            others = sum(f for j, f in enumerate(flats) if j != k)
            own_spread = {a: float(np.std(flats[k][:, i])) for i, a in enumerate("xyz")}
            other_spread = {a: float(np.std(others[:, i])) for i, a in enumerate("xyz")}
            problems = limit_problems(term.family.parameter_names(term.variant, setting), c,
                                      term.family.parameter_limits(selector.ctx, term.variant,
                                                                   setting))
            problems += term.family.fit_problems(selector.ctx, term.variant, setting, c)
            problems += spread_problems(own_spread, allowances, carried=other_spread)
            expected.append("; ".join(problems))
        assert selector.joint_refusals(together, scaled) == expected
        assert selector.joint_refusals(together, scaled, [1]) == [expected[1]]
    assert any(selector.joint_refusals(together, [30.0 * c for c in coefficients]))


def test_a_term_refused_alone_stands_beside_one_that_cancels_it():
    """A contribution 1.5x its allowance where it is largest: refused alone, it stands
    beside one that moves 90 % of it the other way, and not beside one that moves 30 % -
    where the set-up was located as one sum. On a survey without located turns (this HMC's)
    each term is held to the residual alone."""
    selector, terms = _selector()
    assert not selector.shared_located
    term = next(t for t in terms if t.family.name == "straightness")
    setting = term.settings[-1]
    c = selector.fit_full([(term, setting)])[0][0]
    spreads = selector._spreads(selector.prediction_rows(term, setting, c))
    c = c * 1.5 / max(spreads[k] / selector.allowances[k] for k in spreads)
    assert selector.physics_refusal(term, setting, c)
    pair = [(term, setting), (term, setting)]
    assert selector.joint_refusals(pair, [c, -0.9 * c], [0]) == \
        [selector.physics_refusal(term, setting, c)]
    selector.shared_located = True
    assert selector.joint_refusals(pair, [c, -0.9 * c], [0]) == [""]
    assert selector.joint_refusals(pair, [c, -0.3 * c], [0])[0].endswith(
        "beside what the other named effects move there")
