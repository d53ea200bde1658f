"""The one time-blocked cross-validation (``selection.folds``) gives the folds and the
held-out errors the four former cross-validations gave.

Before ``folds.py`` the selection, the refit, the yaw ranking and the localisation each
cut the readings into blocks and fitted the others their own way. Each former
implementation is kept here verbatim as the reference formulation; the code that now
goes through :class:`~mt_accuracy_ros.core.workbench.selection.folds.Folds` must give
the same folds and the same errors (to 1e-12), on inputs of several sizes, folds,
cuts and masks.
"""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InsufficientDataError, ParameterError
from mt_accuracy_ros.core.workbench import diagnosis, localisation, refit
from mt_accuracy_ros.core.workbench.selection import Selector, solve_normal
from mt_accuracy_ros.core.workbench.selection.folds import Folds, time_blocks, training_sums

from test_selection_engine import _partial_mask, _selector


# ------------------------------------------------------ the former implementations
def _former_time_blocks(n, count):
    """selection.time_blocks as it was."""
    sizes = np.full(count, n // count)
    sizes[: n % count] += 1
    return np.repeat(np.arange(count), sizes)


def _former_selector_out_of_fold(selector):
    """Selector.out_of_fold(stats, None) as it was: the fold bounds from searchsorted,
    training products by subtraction (forward: cumulative), held-out errors by slice."""
    fold_of_row = selector.fold_of_sample[selector.sample_of_row]
    edges = np.searchsorted(fold_of_row, np.arange(selector.folds + 1))
    bounds = [(int(edges[f]), int(edges[f + 1])) for f in range(selector.folds)]

    def train(per_fold):
        if selector.forward:
            return np.cumsum(per_fold, axis=0) - per_fold
        return per_fold.sum(axis=0, keepdims=True) - per_fold

    base = selector.base_columns()
    with_y = np.column_stack([base, selector.y])
    products = np.stack([with_y[a:b].T @ with_y[a:b] for a, b in bounds])
    q = base.shape[1]
    coefficients = solve_normal(train(products[:, :q, :q]), train(products[:, :q, q]))
    squared = np.empty(selector.y.size)
    for fold, (a, b) in enumerate(bounds):
        squared[a:b] = (base[a:b] @ coefficients[fold] - selector.y[a:b]) ** 2
    return bounds, squared


def _former_blocked_cv_errors(x, y, fold_of_row, penalties, prior=None):
    """refit.blocked_cv_errors as it was (a boolean mask per fold)."""
    errors = np.empty_like(y)
    for fold in np.unique(fold_of_row):
        held = fold_of_row == fold
        train = ~held
        _, penalised, right = refit._normal_equations(x[train], y[train], penalties, prior)
        coefficients = solve_normal(penalised, right)
        errors[held] = y[held] - x[held] @ coefficients
    return errors


def _former_blocked_cv(x, offsets, y, sample_of_row, n_samples, k=5):
    """diagnosis.blocked_cv as it was (array_split of the readings, lstsq per fold)."""
    design = np.column_stack([offsets, x]) if x.size else offsets
    folds = np.array_split(np.arange(n_samples), k)
    squared, count = 0.0, 0
    for fold in folds:
        test = np.isin(sample_of_row, fold)
        train = ~test
        if test.sum() == 0 or train.sum() <= design.shape[1]:
            continue
        coefficients, *_ = np.linalg.lstsq(design[train], y[train], rcond=None)
        error = design[test] @ coefficients - y[test]
        squared += float(error @ error)
        count += int(test.sum())
    if count == 0:
        raise InsufficientDataError("too few reference readings for cross-validation")
    return float(np.sqrt(squared / count))


def _former_blocked_share(q, r, period_m, folds):
    """localisation._blocked_share as it was (blocks of ceil(N / folds) readings)."""
    phase = 2.0 * np.pi * q / period_m
    design = np.column_stack([np.ones(q.size), np.cos(phase), np.sin(phase)])
    size = -(-q.size // folds)
    edges = [(start, min(start + size, q.size)) for start in range(0, q.size, size)]
    grams = np.stack([design[a:b].T @ design[a:b] for a, b in edges])
    moments = np.stack([design[a:b].T @ r[a:b] for a, b in edges])
    squared = 0.0
    for fold, (a, b) in enumerate(edges):
        gram, moment = grams.sum(axis=0) - grams[fold], moments.sum(axis=0) - moments[fold]
        if np.linalg.cond(gram) < 1e10:
            coefficients = np.linalg.solve(gram, moment)
        else:
            coefficients, *_ = np.linalg.lstsq(np.delete(design, np.s_[a:b], axis=0),
                                               np.delete(r, np.s_[a:b]), rcond=None)
        squared += float(np.sum((design[a:b] @ coefficients - r[a:b]) ** 2))
    return edges, max(0.0, 1.0 - squared / float(np.sum(r ** 2)))


# ------------------------------------------------------------------ the cuts
@pytest.mark.parametrize("n, count", [(20, 5), (23, 5), (101, 7), (3, 5), (400, 3)])
def test_the_even_cut_is_the_former_selections_and_numpys_array_split(n, count):
    blocks = time_blocks(n, count)
    np.testing.assert_array_equal(blocks, _former_time_blocks(n, count))
    split = np.array_split(np.arange(n), count)
    np.testing.assert_array_equal(blocks, np.concatenate(
        [np.full(part.size, k) for k, part in enumerate(split)]).astype(int))


@pytest.mark.parametrize("n, count", [(1000, 5), (23, 5), (21, 5), (400, 3), (7, 3)])
def test_the_ceil_cut_is_the_former_localisations(n, count):
    size = -(-n // count)
    edges = [(start, min(start + size, n)) for start in range(0, n, size)]
    assert Folds.of_readings(n, count, cut="ceil").bounds == edges
    # Not vacuous: at 21 readings in 5 the cuts differ (5 blocks of 5, 4, ... against 5 of 5).
    if (n, count) == (21, 5):
        assert Folds.of_readings(n, count).bounds != edges


def test_a_cut_it_does_not_know_and_rows_out_of_time_order_are_refused():
    with pytest.raises(ParameterError, match="cut"):
        time_blocks(10, 2, cut="random")
    with pytest.raises(ParameterError, match="non-decreasing"):
        Folds(np.array([0, 1, 0, 1]))


def test_training_sums_are_every_other_fold_or_the_earlier_ones():
    per_fold = np.arange(12.0).reshape(4, 3)
    np.testing.assert_array_equal(training_sums(per_fold), per_fold.sum(axis=0) - per_fold)
    np.testing.assert_array_equal(training_sums(per_fold, forward=True)[0], 0.0)
    np.testing.assert_array_equal(training_sums(per_fold, forward=True)[3],
                                  per_fold[:3].sum(axis=0))


# ------------------------------------------------------ the four cross-validations
@pytest.mark.parametrize("mask, forward", [(None, False), ("partial", False), (None, True),
                                           ("partial", True)])
def test_the_selections_folds_and_errors_are_the_former_ones(mask, forward):
    selector, terms = _selector(None if mask is None else _partial_mask())
    if forward:
        selector = Selector(selector.ctx, selector.residual, selector.mask,
                            selector.noise_sigma, forward=True)
    bounds, squared = _former_selector_out_of_fold(selector)
    assert selector.fold_bounds == bounds
    stats = selector.base_statistics(selector.base_columns())
    now = selector._held_out_errors(stats.base, solve_normal(
        selector._train(stats.products[:, :stats.base.shape[1], :stats.base.shape[1]]),
        selector._train(stats.products[:, :stats.base.shape[1], -1])))
    np.testing.assert_allclose(now, squared, rtol=1e-12, atol=0.0)
    # Its per-reading errors are the former ones, gathered per reading and component.
    per_sample, _ = selector.out_of_fold(stats, None)
    np.testing.assert_allclose(per_sample, selector._per_sample(squared), rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("rows, folds, prior", [(60, 5, False), (97, 4, True), (300, 6, True),
                                                (41, 3, False)])
def test_the_refits_held_out_errors_are_the_former_ones(rows, folds, prior):
    rng = np.random.default_rng(rows)
    x = np.column_stack([np.ones(rows), rng.normal(size=(rows, 4))])
    y = x @ rng.normal(size=5) * 1e-6 + rng.normal(0.0, 1e-7, rows)
    fold_of_row = _former_time_blocks(rows, folds)
    penalties = [(3, 5, 0.3)]
    given = (np.array([4.0, 2.0]), np.array([1e-7, -2e-7])) if prior else None
    np.testing.assert_allclose(
        refit.blocked_cv_errors(x, y, fold_of_row, penalties, given),
        _former_blocked_cv_errors(x, y, fold_of_row, penalties, given), rtol=1e-12, atol=0.0)


@pytest.mark.parametrize("n, k, columns", [(40, 5, 1), (23, 5, 0), (57, 4, 2), (12, 5, 2)])
def test_the_yaw_rankings_cross_validation_is_the_former_one(n, k, columns):
    rng = np.random.default_rng(n + k)
    x = rng.normal(size=(n, columns))
    offsets = np.ones((n, 1))
    y = (x.sum(axis=1) if columns else 0.0) * 1e-6 + rng.normal(0.0, 1e-7, n)
    rows = np.arange(n)
    assert diagnosis.blocked_cv(x, offsets, y, rows, n, k) == pytest.approx(
        _former_blocked_cv(x, offsets, y, rows, n, k), rel=1e-12, abs=0.0)


def test_the_yaw_rankings_cross_validation_refuses_as_it_did():
    """Blocks too small to fit a column: both refuse alike."""
    x = np.ones((2, 3))
    with pytest.raises(InsufficientDataError):
        _former_blocked_cv(x, np.ones((2, 1)), np.zeros(2), np.arange(2), 2, 2)
    with pytest.raises(InsufficientDataError):
        diagnosis.blocked_cv(x, np.ones((2, 1)), np.zeros(2), np.arange(2), 2, 2)


@pytest.mark.parametrize("n, folds", [(1000, 5), (23, 5), (21, 5), (400, 3)])
def test_the_localisations_blocks_and_share_are_the_former_ones(n, folds):
    rng = np.random.default_rng(n)
    q = np.sort(rng.uniform(0.0, 0.4, n))
    for period, amplitude in ((0.01, 3e-6), (0.0237, 1e-7), (0.05, 0.0)):
        r = amplitude * np.sin(2 * np.pi * q / period + 0.3) + rng.normal(0, 1e-6, n)
        r -= r.mean()
        edges, share = _former_blocked_share(q, r, period, folds)
        assert Folds.of_readings(n, folds, cut="ceil").bounds == edges
        assert localisation._blocked_share(q, r, period, folds) == pytest.approx(
            share, rel=1e-12, abs=1e-15)
    # The singular blocks' fallback (positions a whole number of periods apart).
    q = np.arange(40) * 0.01
    r = rng.normal(0, 1e-6, 40)
    assert localisation._blocked_share(q, r, 0.01, 5) == pytest.approx(
        _former_blocked_share(q, r, 0.01, 5)[1], rel=1e-12, abs=1e-15)
