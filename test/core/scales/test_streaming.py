"""Streaming systematic-error estimator: bounded memory, agreement with batch kNN."""
from __future__ import annotations

import numpy as np
import pytest

from mt_accuracy_ros.core.errors import InsufficientDataError, ParameterError
from mt_accuracy_ros.core.scales.knn import cross_validate_k, knn_predict
from mt_accuracy_ros.core.scales.streaming import StreamingSystematic


def _passes(rng, n_passes=5, rate_hz=100.0, feed=1.0 / 60, stroke=0.39):
    samples_per_pass = int(stroke / feed * rate_hz)
    x = np.tile(np.linspace(0.0, stroke, samples_per_pass), n_passes)
    x = x + rng.uniform(-1e-4, 1e-4, x.size)
    x = np.clip(x, 0.0, stroke)
    y = 2e-6 * np.sin(2 * np.pi * x / 0.2) + rng.normal(0, 3e-7, x.size)
    return x, y


def test_streamed_profile_matches_batch_knn_and_reselects_k():
    rng = np.random.default_rng(0)
    x, y = _passes(rng)
    stream = StreamingSystematic(0.0, 0.39, bin_width_m=0.1e-3, k_lim=60, window=x.size,
                                 reselect_every=x.size, initial_k=10)
    for start in range(0, x.size, 500):
        stream.add(x[start:start + 500], y[start:start + 500])
    assert stream.sample_count == x.size
    batch_cv = cross_validate_k(x, y, 60, 5, seed=0)
    assert stream.k == batch_cv.k  # the window held exactly the same data
    queries = np.linspace(0.02, 0.37, 40)
    profile = stream.profile(queries)
    batch = knn_predict(x, y, queries, stream.k)
    # Differences stem from 0.1 mm binning only.
    assert np.max(np.abs(profile.systematic - batch)) < 0.1e-6
    truth = 2e-6 * np.sin(2 * np.pi * queries / 0.2)
    assert np.max(np.abs(profile.systematic - truth)) < 0.35e-6
    assert np.all(profile.weight == pytest.approx(stream.k))
    assert np.median(profile.random_sigma) == pytest.approx(3e-7, rel=0.25)


def test_memory_is_bounded_and_forgetting_follows_a_change():
    rng = np.random.default_rng(1)
    stream = StreamingSystematic(0.0, 0.39, bin_width_m=1e-3, k_lim=20, window=2000,
                                 reselect_every=10**9, memory_samples=5000, initial_k=20)
    arrays_before = (stream.weight.nbytes, stream._ring_x.nbytes)
    for _ in range(20):
        x = rng.uniform(0, 0.39, 1000)
        stream.add(x, np.zeros_like(x))
    for _ in range(20):
        x = rng.uniform(0, 0.39, 1000)
        stream.add(x, np.full_like(x, 5e-6))  # the machine changed
    assert (stream.weight.nbytes, stream._ring_x.nbytes) == arrays_before
    assert stream.profile([0.2]).systematic[0] == pytest.approx(5e-6, rel=0.05)


def test_non_finite_and_out_of_stroke_samples_are_dropped_and_counted():
    stream = StreamingSystematic(0.0, 0.39, k_lim=5, window=100, initial_k=3)
    dropped = stream.add([0.1, np.nan, 0.5, 0.2], [1.0, 1.0, 1.0, np.inf])
    assert dropped == 3 and stream.dropped_count == 3 and stream.sample_count == 1


def test_bad_parameters_and_empty_state():
    with pytest.raises(ParameterError):
        StreamingSystematic(1.0, 0.0)
    with pytest.raises(ParameterError):
        StreamingSystematic(0.0, 1.0, k_lim=100, window=50)
    with pytest.raises(InsufficientDataError):
        StreamingSystematic(0.0, 1.0, k_lim=5, window=100).profile([0.5])
