"""kNN regression: exact agreement with brute force, cross-validation, bad input."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InputDataError, InsufficientDataError, ParameterError
from mt_accuracy_ros.core.scales.knn import (SortedTraining, cross_validate_k,
                                      cross_validate_k_many, extract_systematic,
                                      knn_brute_force, knn_brute_force_indices,
                                      knn_neighbour_indices, knn_predict, knn_predict_all_k,
                                      shuffled_folds)


def _tied_data(seed: int, n: int = 400, n_queries: int = 150):
    rng = np.random.default_rng(seed)
    # Positions on a coarse grid: many duplicates and equidistant pairs.
    x = np.round(rng.uniform(0.0, 1.0, n), 2)
    y = rng.normal(size=n)
    q = np.concatenate([np.round(rng.uniform(-0.1, 1.1, n_queries), 3), x[:20]])
    return x, y, q


@pytest.mark.parametrize("seed", [0, 1, 2])
@pytest.mark.parametrize("k", [1, 2, 3, 7, 40, 400])
def test_neighbours_identical_to_brute_force_with_ties(seed, k):
    x, _, q = _tied_data(seed)
    fast = knn_neighbour_indices(x, q, k)
    slow = knn_brute_force_indices(x, q, k)
    np.testing.assert_array_equal(fast, slow)


@pytest.mark.parametrize("seed", [3, 4])
def test_means_for_all_k_agree_with_brute_force(seed):
    x, y, q = _tied_data(seed)
    all_k = knn_predict_all_k(SortedTraining.build(x, y), q, 60)
    for k in (1, 5, 33, 60):
        np.testing.assert_allclose(all_k[k - 1], knn_brute_force(x, y, q, k), rtol=0, atol=1e-12)
        np.testing.assert_allclose(knn_predict(x, y, q, k), all_k[k - 1], rtol=0, atol=1e-15)


def test_kidani_figure_4_5_example():
    # x0 = 2: 1-NN is 1.6, then 1.0, 3.1, 3.9 (Kidani section 4.2.2).
    x = np.array([1.0, 1.6, 3.1, 3.9, 5.0])
    y = np.array([10.0, 20.0, 30.0, 40.0, 50.0])
    means = [knn_predict(x, y, [2.0], k)[0] for k in (1, 2, 3, 4)]
    assert means == pytest.approx([20.0, 15.0, 20.0, 25.0])


def test_sigma_is_the_sample_standard_deviation_of_the_neighbours():
    x, y, q = _tied_data(5)
    mean, sigma = knn_predict(x, y, q, 9, return_sigma=True)
    neighbours = knn_brute_force_indices(x, q, 9)
    np.testing.assert_allclose(sigma, y[neighbours].std(axis=1, ddof=1), atol=1e-12)
    np.testing.assert_allclose(mean, y[neighbours].mean(axis=1), atol=1e-12)


def test_cross_validation_equals_an_explicit_per_fold_brute_force():
    rng = np.random.default_rng(7)
    x = rng.uniform(0, 0.39, 600)
    y = 2e-6 * np.sin(20 * x) + rng.normal(0, 3e-7, x.size)
    result = cross_validate_k(x, y, k_lim=30, n_folds=5, seed=11)
    folds = shuffled_folds(x.size, 5, 11)
    np.testing.assert_array_equal(result.folds, folds)
    for k in (1, 12, 30):
        fold_rmse = []
        for fold in range(5):
            held = folds == fold
            predicted = knn_brute_force(x[~held], y[~held], x[held], k)
            fold_rmse.append(np.sqrt(np.mean((predicted - y[held]) ** 2)))
        assert result.rmse_by_k[k - 1] == pytest.approx(np.mean(fold_rmse), rel=1e-10)
    assert result.k == int(np.argmin(result.rmse_by_k)) + 1
    assert result.cv_rmse == pytest.approx(result.rmse_by_k.min())



@pytest.mark.parametrize("cached_samples", [1, 1400, 15_000])
def test_many_variables_searched_in_any_blocks_equal_one_at_a_time(monkeypatch, cached_samples):
    """The variables are searched a few at a time (``CACHED_SAMPLES``): one, two or all
    four per block, every variable's fold errors are bit for bit its own call's."""
    from mt_accuracy_ros.core.scales import knn

    monkeypatch.setattr(knn, "CACHED_SAMPLES", cached_samples)
    rng = np.random.default_rng(5)
    n = 700
    y = rng.normal(0, 1e-6, (n, 2))
    variables = np.stack([rng.uniform(0, 0.4, n), np.repeat(np.arange(7.0), n // 7),
                          -np.linspace(0, 1, n), y[:, 0] * 1e5])
    many = cross_validate_k_many(variables, y, k_lim=25, n_folds=5, seed=2)
    for v, per_series in zip(variables, many):
        for c, result in enumerate(per_series):
            alone = cross_validate_k(v, y[:, c], k_lim=25, n_folds=5, seed=2)
            np.testing.assert_array_equal(result.fold_rmse, alone.fold_rmse)


def test_many_variables_in_one_pass_equal_one_at_a_time():
    """The batched cross-validation (every variable's folds as segments of one array)
    gives each variable exactly what its own call gives, ties and steps included."""
    rng = np.random.default_rng(3)
    n = 700
    y = rng.normal(0, 1e-6, n)
    variables = np.stack([rng.uniform(0, 0.4, n),                 # smooth
                          np.repeat(np.arange(7.0), n // 7),      # stepped: ties everywhere
                          -np.linspace(0, 1, n),                  # sorted the other way
                          y * 1e5])                               # follows y exactly
    many = cross_validate_k_many(variables, y, k_lim=25, n_folds=5, seed=2)
    assert len(many) == variables.shape[0]
    for v, result in zip(variables, many):
        alone = cross_validate_k(v, y, k_lim=25, n_folds=5, seed=2)
        np.testing.assert_array_equal(result.fold_rmse, alone.fold_rmse)
        assert (result.k, result.cv_rmse) == (alone.k, alone.cv_rmse)
    assert many[3].cv_rmse < 0.5 * many[0].cv_rmse   # the variable y follows is found
    assert cross_validate_k_many(np.empty((0, n)), y) == []
    with pytest.raises(InputDataError, match="samples per variable"):
        cross_validate_k_many(variables[:, :-1], y)

def test_cross_validation_picks_a_moderate_k_and_predicts_new_data_as_well_as_it_claims():
    rng = np.random.default_rng(8)
    def sample(n):
        x = rng.uniform(0, 0.39, n)
        return x, 3e-6 * np.sin(2 * np.pi * x / 0.13) + rng.normal(0, 4e-7, n)
    x, y = sample(5000)
    x_new, y_new = sample(5000)
    result = extract_systematic(x, y, np.linspace(0, 0.39, 50), k_lim=100, seed=0,
                                new_positions=x_new, new_values=y_new)
    assert 5 < result.cv.k < 100
    # The noise floor is 0.4 urad; both RMSEs sit just above it and agree.
    assert 3.8e-7 < result.cv.cv_rmse < 4.6e-7
    assert result.relative_difference < 0.03
    truth = 3e-6 * np.sin(2 * np.pi * result.query_positions / 0.13)
    assert np.max(np.abs(result.systematic - truth)[2:-2]) < 3e-7


def test_folds_are_balanced_and_seeded():
    folds = shuffled_folds(103, 5, seed=1)
    assert sorted(np.bincount(folds)) == [20, 20, 21, 21, 21]
    np.testing.assert_array_equal(folds, shuffled_folds(103, 5, seed=1))
    assert not np.array_equal(folds, shuffled_folds(103, 5, seed=2))


@pytest.mark.parametrize("call,error", [
    (lambda: knn_predict([0.0, np.nan], [1.0, 2.0], [0.5], 1), InputDataError),
    (lambda: knn_predict([0.0, 1.0], [1.0, np.inf], [0.5], 1), InputDataError),
    (lambda: knn_predict([0.0, 1.0], [1.0, 2.0], [np.nan], 1), InputDataError),
    (lambda: knn_predict([0.0, 1.0], [1.0, 2.0], [0.5], 3), InsufficientDataError),
    (lambda: knn_predict([], [], [0.5], 1), InputDataError),
    (lambda: knn_predict([0.0, 1.0], [1.0], [0.5], 1), InputDataError),
    (lambda: knn_predict([0.0, 1.0], [1.0, 2.0], [0.5], 0), ParameterError),
    (lambda: knn_predict([0.0, 1.0], [1.0, 2.0], [0.5], 1.5), ParameterError),
    (lambda: cross_validate_k(np.arange(20.0), np.arange(20.0), k_lim=30), InsufficientDataError),
    (lambda: shuffled_folds(3, 5), InsufficientDataError),
    (lambda: shuffled_folds(30, 1), ParameterError),
])
def test_bad_input_raises_the_documented_error(call, error):
    with pytest.raises(error) as info:
        call()
    assert str(info.value)  # a message, naming the problem
    assert isinstance(info.value, ValueError)
