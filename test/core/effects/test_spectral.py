"""The grid periodogram against the exact one, and the normal-equation solver against
``lstsq``: two formulations of the same numbers."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.effects import spectral
from mt_accuracy_ros.core.effects.spectral import (direct_basis, frequency_grid,
                                                   grid_periodogram, periodogram,
                                                   strongest_frequencies, weight_sums)
from mt_accuracy_ros.core.workbench.selection import solve_normal


def _readings(seed: int, n: int = 3000):
    rng = np.random.default_rng(seed)
    # Readings also beyond the nominal travel: positions are taken modulo the grid's period.
    q = rng.uniform(-0.1, 0.5, n)
    weight = rng.uniform(0.5, 1.5, n)
    weight[rng.random(n) < 0.2] = 0.0          # held-out readings: zero weight
    target = weight * (3e-6 * np.sin(2 * np.pi * q / 0.01 + 0.3) + rng.normal(0, 1e-6, n))
    return q, target, weight


def test_frequency_grid_spans_2_to_50_mm_a_quarter_cycle_apart():
    f = frequency_grid(0.4)
    assert np.allclose(np.diff(f), 1.0 / 1.6)
    assert 1.0 / f[0] <= 0.05 and 1.0 / f[-1] >= 0.002
    assert 1.0 / f[0] > 0.05 - 0.0002 and 1.0 / f[-1] < 0.002 + 1e-6


@pytest.mark.parametrize("seed", [1, 2])
def test_grid_periodogram_equals_the_exact_one(seed):
    q, target, weight = _readings(seed)
    f = frequency_grid(0.39)
    exact, exact_amplitude = periodogram(q, target, weight, 1.0 / f)
    fast, fast_amplitude = grid_periodogram(q, target, weight, f)
    assert np.max(np.abs(fast - exact)) < 1e-5 * exact.max()
    assert np.max(np.abs(fast_amplitude - exact_amplitude)) < 1e-4 * exact_amplitude.max()
    assert np.argmax(fast) == np.argmax(exact)
    assert 1.0 / f[np.argmax(fast)] == pytest.approx(0.01, abs=1e-4)


def test_a_shared_basis_gives_the_same_periodogram_and_the_exact_one():
    # Few readings: the direct sums. A basis made once per axis and passed to every
    # periodogram of it must change nothing - not a bit - and still be the exact one.
    q, target, weight = _readings(3, n=150)
    f = frequency_grid(0.39)
    basis = direct_basis(q, f)
    assert basis is not None and basis.shape == (f.size, q.size)
    plain = grid_periodogram(q, target, weight, f)
    shared = grid_periodogram(q, target, weight, f, basis=basis)
    cached = grid_periodogram(q, target, None, f, basis=basis,
                              weights=weight_sums(q, weight, f, basis=basis))
    for a, b, c in zip(plain, shared, cached):
        assert np.array_equal(a, b) and np.array_equal(a, c)
    exact, _ = periodogram(q, target, weight, 1.0 / f)
    assert np.max(np.abs(shared[0] - exact)) < 1e-9 * exact.max()
    # Many readings: the lattice, no basis.
    assert direct_basis(*_readings(3)[:1], f) is None


def test_exact_periodogram_is_the_least_squares_fit():
    q, target, weight = _readings(3, 500)
    period = 0.0123
    explained, amplitude = periodogram(q, target, weight, [period])
    phase = 2 * np.pi * q / period
    basis = np.column_stack([np.ones_like(q), np.cos(phase), np.sin(phase)])
    root = np.sqrt(weight)
    keep = weight > 0
    # target = w * model, fitted in the weighted sense: minimise sum (t/sqrt(w) - sqrt(w) b.c)^2
    x = basis[keep] * root[keep, None]
    y = target[keep] / root[keep]
    c, *_ = np.linalg.lstsq(x, y, rcond=None)
    total = float(c @ (x.T @ y)) - float(target.sum()) ** 2 / float(weight.sum())
    assert explained[0] == pytest.approx(total, rel=1e-9)
    assert amplitude[0] == pytest.approx(np.hypot(c[1], c[2]), rel=1e-9)


def test_solve_normal_equals_lstsq_full_rank_and_rank_deficient():
    rng = np.random.default_rng(4)
    x = rng.normal(size=(200, 6)) * np.array([1e-6, 1.0, 1e3, 1.0, 1e-3, 1.0])
    y = rng.normal(size=200)
    expected, *_ = np.linalg.lstsq(x, y, rcond=None)
    got = solve_normal(x.T @ x, x.T @ y)
    assert np.allclose(x @ got, x @ expected, rtol=0, atol=1e-12 * np.abs(x @ expected).max())
    # A zero column and a duplicated one: the same fit as lstsq's, and the minimum-norm
    # coefficients (0 for the zero column, the duplicate's share split evenly) - where
    # lstsq itself, at its default cut-off, splits by rounding.
    x[:, 3] = 0.0
    x[:, 5] = x[:, 1]
    expected, *_ = np.linalg.lstsq(x, y, rcond=None)
    got = solve_normal(x.T @ x, x.T @ y)
    assert got[3] == 0.0
    assert got[1] == pytest.approx(got[5], rel=1e-9)
    assert got[1] + got[5] == pytest.approx(expected[1] + expected[5], rel=1e-6)
    assert np.allclose(x @ got, x @ expected, rtol=0, atol=1e-9 * np.abs(x @ expected).max())
    # Batched over a leading axis.
    stacked = solve_normal(np.stack([x.T @ x] * 3), np.stack([x.T @ y] * 3))
    assert np.allclose(stacked, got[None, :], rtol=1e-12, atol=0)


def test_legendre_columns_by_recurrence_equal_numpy_legval():
    from numpy.polynomial import legendre

    from mt_accuracy_ros.core.effects.geometric import _legendre_columns

    u = np.linspace(-1.0, 1.0, 101)
    expected = np.column_stack([legendre.legval(u, np.eye(8)[k]) for k in range(2, 8)])
    np.testing.assert_allclose(_legendre_columns(u, 2, 7), expected, rtol=0, atol=1e-14)
    assert _legendre_columns(u, 1, 1).shape == (101, 1)


def test_a_basis_asked_again_is_the_kept_one_and_equals_a_fresh_one():
    """The process keeps an axis' exponentials by its positions' and frequencies' bytes:
    asked again (a check's second localisation, a selection's preselection) the kept
    array comes back, read-only, equal to exp(-2 pi i f q) made afresh; other positions
    get their own."""
    rng = np.random.default_rng(4)
    q = rng.uniform(0.0, 0.3, 200)
    frequencies = frequency_grid(0.3)
    first = direct_basis(q, frequencies)
    again = direct_basis(q.copy(), frequencies.copy())
    assert again is first and not first.flags.writeable
    np.testing.assert_array_equal(first, np.exp(-2j * np.pi * frequencies[:, None] * q[None, :]))
    moved = q.copy()
    moved[0] += 1e-9
    other = direct_basis(moved, frequencies)
    assert other is not first
    np.testing.assert_array_equal(other[:, 1:], first[:, 1:])
    assert not np.array_equal(other[:, 0], first[:, 0])


def _fold_columns(seed: int, n: int, folds: int = 5):
    """A preselection's columns: each fold's training readings weighted, the rest zero; one
    column of zeros (a component the error does not reach)."""
    rng = np.random.default_rng(seed)
    q = rng.uniform(0.0, 0.4, n)
    sensitivity = rng.uniform(0.5, 1.5, n)
    signal = 3e-6 * np.sin(2 * np.pi * q / 0.0123 + 0.4) + rng.normal(0, 2e-6, n)
    trains = np.ones((folds, n), dtype=bool)
    for fold, rows in enumerate(np.array_split(np.arange(n), folds)):
        trains[fold, rows] = False
    weights = np.where(trains, sensitivity ** 2, 0.0).T
    targets = np.where(trains, sensitivity * signal, 0.0).T
    targets[:, -1] = 0.0
    return q, targets, weights


@pytest.mark.parametrize("n", [150, 3000])
def test_the_strongest_frequencies_are_the_periodograms_argmax(n):
    """The cheaper choice (the 3 x 3 solved in closed form for every column, a bound on
    each value's rounding) is the index the periodogram's argmax gives, column by column
    - by the direct sums (150 readings) and by the lattice (3,000); a column of zeros
    chooses the first frequency, as the argmax of its all-zero periodogram does."""
    for seed in range(6):
        q, targets, weights = _fold_columns(seed + 10 * n, n)
        f = frequency_grid(float(np.ptp(q)))
        basis = direct_basis(q, f)
        assert (basis is None) == (n == 3000)
        sums = weight_sums(q, weights, f, basis=basis)
        exact, _ = grid_periodogram(q, targets, None, f, weights=sums, basis=basis)
        chosen = strongest_frequencies(q, targets, f, weights=sums, basis=basis)
        np.testing.assert_array_equal(chosen, np.argmax(exact, axis=0))
        assert chosen[-1] == 0 and not exact[:, -1].any()


def test_the_closed_form_explained_is_the_solves_within_its_bound():
    """Adjugate over determinant against LAPACK's solve (the formulation it replaces, kept
    here): equal to 1e-12 of the column's largest value, and each difference inside the
    bound the choice trusts."""
    q, targets, weights = _fold_columns(5, 150)
    targets, weights = targets[:, :-1], weights[:, :-1]
    f = frequency_grid(float(np.ptp(q)))
    basis = direct_basis(q, f)
    sum_w, zw1, zw2 = weight_sums(q, weights, f, basis=basis)
    zt1 = basis @ targets
    explained, bound = spectral._closed_form_explained(sum_w, zw1, zw2, targets, zt1.real,
                                                       zt1.imag)
    for j in range(targets.shape[1]):
        solved, _ = spectral._solve(float(sum_w[j]), zw1[:, j], zw2[:, j],
                                    float(targets[:, j].sum()), zt1[:, j])
        difference = np.abs(explained[:, j] - solved)
        assert difference.max() <= 1e-12 * np.abs(solved).max()
        assert np.all(difference <= bound[:, j])


def test_an_unclear_choice_is_made_by_the_periodogram_itself(monkeypatch):
    """A tie (the same frequency listed twice, its two values equal to the bit in either
    computation) is not clear by any bound: that column is computed again as
    grid_periodogram does, whose argmax takes the first of the two; the clear columns
    are not."""
    q, targets, weights = _fold_columns(7, 150)
    # Column 1 another period: its choice is clear.
    targets[:, 1] = np.where(weights[:, 1] > 0, 5e-6 * np.sin(2 * np.pi * q / 0.031), 0.0)
    f = frequency_grid(float(np.ptp(q)))
    sums = weight_sums(q, weights, f)
    exact, _ = grid_periodogram(q, targets, None, f, weights=sums)
    strongest = int(np.argmax(exact[:, 0]))
    doubled = np.insert(f, strongest, f[strongest])
    basis = direct_basis(q, doubled)
    sums = weight_sums(q, weights, doubled, basis=basis)
    asked = []

    def counted(q_, target, weight, frequencies, **kwargs):
        asked.append(target.shape[1])
        return grid_periodogram(q_, target, weight, frequencies, **kwargs)

    monkeypatch.setattr(spectral, "grid_periodogram", counted)
    chosen = strongest_frequencies(q, targets, doubled, weights=sums, basis=basis)
    exact, _ = grid_periodogram(q, targets, None, doubled, weights=sums, basis=basis)
    np.testing.assert_array_equal(chosen, np.argmax(exact, axis=0))
    assert chosen[0] == strongest and chosen[1] != strongest
    assert asked == [int(np.sum(chosen == strongest))]
