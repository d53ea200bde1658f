"""Streaming extraction of the systematic error for a live node (Kidani section 4.2.2).

Memory stays bounded however long the machine runs:

* a **per-position summary**: the stroke is cut into fine bins; each bin keeps
  a (forgetting) weight, the weighted sum and the weighted sum of squares of
  the values that fell in it. Adding a batch costs O(batch).
* a **ring buffer** of the most recent raw samples, on which k is re-selected
  by K-fold cross-validation (:func:`cross_validate_k`) every
  ``reselect_every`` samples.

The profile at query positions is the kNN mean over the summary: bins are
admitted nearest first (by bin centre, the left one on a tie) until their weight
reaches k; the last bin counts with the fraction that completes k. With a bin
width far below the feature size of the error this equals the kNN mean of the
raw samples up to the position resolution of one bin; no pass over the raw
history is needed.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InsufficientDataError, ParameterError
from .knn import CrossValidationResult, cross_validate_k


@dataclass(frozen=True)
class StreamingProfile:
    """The current systematic profile.

    Attributes (arrays of shape (n,) over the query positions)
    ----------
    positions, systematic, random_sigma, weight : ndarray
    k : int
    cv_rmse : float   (NaN until the first selection)
    sample_count : int   samples added so far
    """

    positions: NDArray[np.float64]
    systematic: NDArray[np.float64]
    random_sigma: NDArray[np.float64]
    weight: NDArray[np.float64]
    k: int
    cv_rmse: float
    sample_count: int


class StreamingSystematic:
    """Incremental kNN systematic-error estimator with periodic re-selection of k.

    Parameters
    ----------
    lower_m, upper_m : float
        Stroke of the axis [m]; samples outside are counted and dropped.
    bin_width_m : float
        Position resolution of the summary [m].
    k_lim, n_folds : int
        Cross-validation range and folds.
    window : int
        Raw samples kept for re-selecting k.
    reselect_every : int
        Samples between two re-selections.
    memory_samples : float
        Forgetting horizon: every sample added multiplies the old weights by
        ``exp(-1 / memory_samples)``; ``inf`` never forgets.
    initial_k : int
        k used before the first cross-validation.
    seed : int
        Seed of the cross-validation shuffles.
    """

    def __init__(self, lower_m: float, upper_m: float, *, bin_width_m: float = 0.5e-3,
                 k_lim: int = 100, n_folds: int = 5, window: int = 20000,
                 reselect_every: int = 5000, memory_samples: float = np.inf,
                 initial_k: int = 20, seed: int = 0) -> None:
        if not (np.isfinite(lower_m) and np.isfinite(upper_m) and upper_m > lower_m):
            raise ParameterError(f"stroke [{lower_m}, {upper_m}] must be finite and ascending")
        if not (np.isfinite(bin_width_m) and 0 < bin_width_m <= upper_m - lower_m):
            raise ParameterError(f"bin_width_m must be in (0, stroke], got {bin_width_m}")
        if window < n_folds * (k_lim + 1):
            raise ParameterError(f"window = {window} too small for k_lim = {k_lim} and "
                                 f"{n_folds} folds (needs >= {n_folds * (k_lim + 1)})")
        if not memory_samples > 0:
            raise ParameterError(f"memory_samples must be > 0, got {memory_samples}")
        self.lower_m, self.upper_m = float(lower_m), float(upper_m)
        self.bin_width_m = float(bin_width_m)
        n_bins = int(np.ceil((self.upper_m - self.lower_m) / self.bin_width_m))
        self.centres = self.lower_m + (np.arange(n_bins) + 0.5) * self.bin_width_m
        self.weight = np.zeros(n_bins)
        self.sum = np.zeros(n_bins)
        self.sum_sq = np.zeros(n_bins)
        self.k_lim, self.n_folds = int(k_lim), int(n_folds)
        self.reselect_every = int(reselect_every)
        self.memory_samples = float(memory_samples)
        self.k = int(initial_k)
        self.seed = int(seed)
        self.cv: CrossValidationResult | None = None
        self._ring_x = np.zeros(int(window))
        self._ring_y = np.zeros(int(window))
        self._ring_fill = 0
        self._ring_next = 0
        self.sample_count = 0
        self.dropped_count = 0
        self._since_selection = 0
        self._shift: float | None = None  # values are stored minus this, for precision

    def add(self, positions: ArrayLike, values: ArrayLike) -> int:
        """Add samples; returns how many were dropped (non-finite or outside the stroke).

        Parameters
        ----------
        positions : array_like, shape (n,)
            Axis positions [m].
        values : array_like, shape (n,)
            Errors at them (any unit, e.g. yaw [rad]).

        Returns
        -------
        int
            Samples dropped (non-finite or outside [lower_m, upper_m]).

        Raises
        ------
        ParameterError
            Lengths that differ.
        """
        x = np.asarray(positions, dtype=np.float64).ravel()
        y = np.asarray(values, dtype=np.float64).ravel()
        if x.size != y.size:
            raise ParameterError(f"positions has {x.size} values but values has {y.size}")
        good = np.isfinite(x) & np.isfinite(y) & (x >= self.lower_m) & (x <= self.upper_m)
        dropped = int(x.size - good.sum())
        self.dropped_count += dropped
        x, y = x[good], y[good]
        if x.size == 0:
            return dropped
        if self._shift is None:
            self._shift = float(y[0])
        if np.isfinite(self.memory_samples):
            self._decay(x.size)
        index = np.minimum(((x - self.lower_m) / self.bin_width_m).astype(np.intp),
                           self.weight.size - 1)
        shifted = y - self._shift
        self.weight += np.bincount(index, minlength=self.weight.size)
        self.sum += np.bincount(index, weights=shifted, minlength=self.weight.size)
        self.sum_sq += np.bincount(index, weights=shifted * shifted, minlength=self.weight.size)
        self._push_ring(x, y)
        self.sample_count += x.size
        self._since_selection += x.size
        if self._since_selection >= self.reselect_every and self._ring_fill >= self._ring_x.size:
            self.reselect_k()
        return dropped

    def forget(self) -> None:
        """Drop every sample so far: the profile restarts from the samples that follow.

        After a detected deterioration the old guideway state is no longer the
        machine's; a forgetting horizon would mix both for several horizons. The
        chosen k and the shift are kept.
        """
        self.weight[:] = 0.0
        self.sum[:] = 0.0
        self.sum_sq[:] = 0.0
        self._ring_fill = 0
        self._ring_next = 0
        self._since_selection = 0

    def _decay(self, n_new: int) -> None:
        factor = np.exp(-n_new / self.memory_samples)
        self.weight *= factor
        self.sum *= factor
        self.sum_sq *= factor

    def _push_ring(self, x: NDArray, y: NDArray) -> None:
        size = self._ring_x.size
        if x.size >= size:
            x, y = x[-size:], y[-size:]
        slots = (self._ring_next + np.arange(x.size)) % size
        self._ring_x[slots] = x
        self._ring_y[slots] = y
        self._ring_next = int((self._ring_next + x.size) % size)
        self._ring_fill = min(size, self._ring_fill + x.size)

    def reselect_k(self) -> CrossValidationResult:
        """Choose k again by cross-validation on the raw-sample window."""
        n = self._ring_fill
        if n < self.n_folds * (self.k_lim + 1):
            raise InsufficientDataError(f"only {n} samples in the window for k selection")
        result = cross_validate_k(self._ring_x[:n], self._ring_y[:n], self.k_lim, self.n_folds,
                                  seed=self.seed)
        self.cv = result
        self.k = result.k
        self._since_selection = 0
        return result

    def profile(self, query_positions: ArrayLike | None = None) -> StreamingProfile:
        """Current kNN systematic error and random sigma at the query positions.

        ``None`` queries every occupied bin centre.

        Parameters
        ----------
        query_positions : array_like, shape (n,), optional
            Positions [m].

        Returns
        -------
        StreamingProfile
            Systematic error and random sigma at the queries, the values' unit.

        Raises
        ------
        InsufficientDataError
            No samples added yet.
        """
        occupied = self.weight > 1e-12
        if not occupied.any():
            raise InsufficientDataError("no samples added yet")
        centres = self.centres[occupied]
        weights = self.weight[occupied]
        sums = self.sum[occupied]
        sums_sq = self.sum_sq[occupied]
        q = centres.copy() if query_positions is None else np.asarray(query_positions, float)
        k = float(min(self.k, weights.sum()))
        n_bins = centres.size
        lo = np.searchsorted(centres, q, side="left")
        hi = lo.copy()
        taken = np.zeros(q.size)
        acc_sum = np.zeros(q.size)
        acc_sq = np.zeros(q.size)
        pad_c = np.concatenate(([-np.inf], centres, [np.inf]))
        pad_w = np.concatenate(([0.0], weights, [0.0]))
        pad_s = np.concatenate(([0.0], sums, [0.0]))
        pad_q = np.concatenate(([0.0], sums_sq, [0.0]))
        active = taken < k
        while active.any():
            take_left = ((q - pad_c[lo]) <= (pad_c[hi + 1] - q)) & (lo > 0)
            take_left |= hi >= n_bins
            admitted = np.where(take_left, lo, hi + 1)
            fraction = np.clip((k - taken) / np.maximum(pad_w[admitted], 1e-300), 0.0, 1.0)
            fraction = np.where(active, fraction, 0.0)
            taken += fraction * pad_w[admitted]
            acc_sum += fraction * pad_s[admitted]
            acc_sq += fraction * pad_q[admitted]
            lo -= take_left & active
            hi += ~take_left & active
            active = (taken < k * (1 - 1e-12)) & ((lo > 0) | (hi < n_bins))
        mean_shifted = acc_sum / taken
        with np.errstate(invalid="ignore", divide="ignore"):
            variance = (acc_sq - taken * mean_shifted ** 2) / (taken - 1.0)
        sigma = np.sqrt(np.clip(variance, 0.0, None))
        return StreamingProfile(
            positions=q, systematic=mean_shifted + (self._shift or 0.0), random_sigma=sigma,
            weight=taken, k=self.k, cv_rmse=self.cv.cv_rmse if self.cv else float("nan"),
            sample_count=self.sample_count)
