"""The held-out share of a periodogram peak (``localisation._blocked_share``) from each
time block's normal equations equals a least-squares fit of the other blocks' rows."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.workbench.localisation import _blocked_share


def _by_least_squares(q, r, period_m, folds):
    """The plain formulation: for each block, lstsq on every other row, error on it."""
    phase = 2.0 * np.pi * q / period_m
    design = np.column_stack([np.ones(q.size), np.cos(phase), np.sin(phase)])
    block = np.repeat(np.arange(folds), -(-q.size // folds))[:q.size]
    squared = 0.0
    for fold in range(folds):
        test = block == fold
        coefficients, *_ = np.linalg.lstsq(design[~test], r[~test], rcond=None)
        squared += float(np.sum((design[test] @ coefficients - r[test]) ** 2))
    return max(0.0, 1.0 - squared / float(np.sum(r ** 2)))


@pytest.mark.parametrize("n, folds", [(1000, 5), (23, 5), (21, 5), (400, 3)])
def test_the_blocks_normal_equations_give_the_least_squares_share(n, folds):
    rng = np.random.default_rng(n)
    q = np.sort(rng.uniform(0.0, 0.4, n))
    for period, amplitude in ((0.01, 3e-6), (0.0237, 1e-7), (0.05, 0.0)):
        r = amplitude * np.sin(2 * np.pi * q / period + 0.3) + rng.normal(0, 1e-6, n)
        r -= r.mean()
        assert _blocked_share(q, r, period, folds) == pytest.approx(
            _by_least_squares(q, r, period, folds), rel=1e-9, abs=1e-12)
    # A strong sinusoid is found held out; noise alone shares nothing.
    r = 3e-6 * np.sin(2 * np.pi * q / 0.01) + rng.normal(0, 1e-7, n)
    assert _blocked_share(q, r - r.mean(), 0.01, folds) > 0.9 or n < 50


def test_a_period_the_positions_do_not_sample_falls_back_to_the_minimum_norm_fit():
    """Positions a whole number of periods apart: cos is constant, the blocks' normal
    equations singular - the share is the least-squares one."""
    q = np.repeat(np.arange(50) * 0.01, 4)
    r = np.random.default_rng(1).normal(0, 1e-6, q.size)
    r -= r.mean()
    assert _blocked_share(q, r, 0.01, 5) == pytest.approx(_by_least_squares(q, r, 0.01, 5),
                                                          rel=1e-9, abs=1e-12)
