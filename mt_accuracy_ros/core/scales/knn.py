"""Exact, fast k-nearest-neighbour regression in one dimension (Kidani section 4.2.2).

The systematic part of an error sampled at scattered positions x_i is the mean
of the errors of the k training points nearest to a query position
(Kidani eq. 4.10). Positions are one-dimensional, so after one sort the k
nearest neighbours of a query are a contiguous window of the sorted training
set, found by growing the window one point at a time from the query's
insertion point. Growing it to k_max yields the estimates for every
k = 1 ... k_max in O(k_max) vector steps, with no distance matrix.

Tie rule (documented, and reproduced by :func:`knn_brute_force`)
-----------------------------------------------------------------
Training points are ranked by a stable sort on position (equal positions
keep their input order); ``s`` is the number of training points strictly left
of the query. Neighbours are ordered by the key

    (|x - q|, x, |rank - s|)

i.e. nearer first; at equal distance the point on the left (smaller position)
first; among points at one and the same position, the one whose rank is
nearer the query's insertion point first. This is exactly the order in which
a window grown from the insertion point, taking the left candidate when the
two candidates are equally far, admits points.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError, InsufficientDataError, ParameterError
from ..validation import finite_array, same_length


@dataclass(frozen=True)
class SortedTraining:
    """A training set sorted by position, ready for repeated queries.

    Attributes
    ----------
    positions : ndarray, shape (m,)
        Training positions, ascending (stable order for equal positions).
    values : ndarray, shape (m,)
        Training values in the same order.
    order : ndarray of int, shape (m,)
        ``order[r]`` is the input index of the point of rank ``r``.
    """

    positions: NDArray[np.float64]
    values: NDArray[np.float64]
    order: NDArray[np.intp]

    @classmethod
    def build(cls, positions: ArrayLike, values: ArrayLike) -> "SortedTraining":
        """Sort a training set by position (stable).

        Parameters
        ----------
        positions : array_like, shape (m,)
            Training positions [m] (any unit, the queries' unit).
        values : array_like, shape (m,)
            Training values (any unit).

        Returns
        -------
        SortedTraining
            Positions ascending, values in the same order, and the order.

        Raises
        ------
        InputDataError
            Non-finite or non-1-D inputs, or lengths that differ.
        """
        x = finite_array(positions, "positions", ndim=1)
        y = finite_array(values, "values", ndim=1)
        same_length("positions", x, "values", y)
        order = np.argsort(x, kind="stable")
        return cls(positions=x[order], values=y[order], order=order)

    def __len__(self) -> int:
        return int(self.positions.size)


def _check_k(k: int, n_training: int, name: str = "k") -> int:
    if isinstance(k, bool) or int(k) != k or int(k) < 1:
        raise ParameterError(f"{name} must be a positive integer, got {k!r}")
    k = int(k)
    if k > n_training:
        raise InsufficientDataError(
            f"{name} = {k} neighbours requested but only {n_training} training points")
    return k


def _grow_windows(training: SortedTraining, queries: NDArray[np.float64], k_max: int,
                  each_k=None):
    """Grow the neighbour window of every query from 1 to ``k_max`` points.

    Calls ``each_k(k, running_sum, running_sum_sq, rank)`` after the k-th
    neighbour is admitted: the sums over the k neighbours of every query and
    the sorted-order rank of the neighbour just admitted, each shape (n,).
    Returns the final window bounds ``lo, hi`` (``hi - lo == k_max``).
    """
    xs = training.positions
    ys = training.values
    m = xs.size
    lo = np.searchsorted(xs, queries, side="left")
    hi = lo.copy()
    running = np.zeros(queries.size)
    running_sq = np.zeros(queries.size)
    # Sentinels make the "no candidate left/right" cases plain comparisons.
    xs_pad = np.concatenate(([-np.inf], xs, [np.inf]))
    ys_pad = np.concatenate(([0.0], ys, [0.0]))
    for k in range(1, k_max + 1):
        left_distance = queries - xs_pad[lo]          # candidate rank lo-1 is pad index lo
        right_distance = xs_pad[hi + 1] - queries     # candidate rank hi is pad index hi+1
        take_left = (left_distance <= right_distance) & (lo > 0)
        take_left |= hi >= m
        admitted = np.where(take_left, lo, hi + 1)    # pad index of the admitted point
        value = ys_pad[admitted]
        running += value
        running_sq += value * value
        lo -= take_left
        hi += ~take_left
        if each_k is not None:
            each_k(k, running, running_sq, admitted - 1)
    return lo, hi


def knn_predict(positions: ArrayLike, values: ArrayLike, queries: ArrayLike, k: int,
                *, return_sigma: bool = False):
    """kNN mean at query positions (Kidani eq. 4.10), exact, with the documented tie rule.

    Parameters
    ----------
    positions, values : array_like, shape (m,)
        Training positions [m] and error values [any unit].
    queries : array_like, shape (n,)
        Query positions [m].
    k : int
        Number of neighbours, 1 <= k <= m.
    return_sigma : bool
        Also return the sample standard deviation (Kidani eq. 2.23, ddof = 1) of the
        k neighbour values - the random error at each query; NaN when k = 1.

    Returns
    -------
    mean : ndarray, shape (n,)
    sigma : ndarray, shape (n,)   (only with ``return_sigma``)
    """
    training = SortedTraining.build(positions, values)
    q = finite_array(queries, "queries", ndim=1)
    k = _check_k(k, len(training))
    result: dict[str, NDArray] = {}

    def keep(step, running, running_sq, _rank):
        if step == k:
            result["sum"] = running.copy()
            result["sum_sq"] = running_sq.copy()

    lo, hi = _grow_windows(training, q, k, keep)
    mean = result["sum"] / k
    if not return_sigma:
        return mean
    if k == 1:
        return mean, np.full(q.size, np.nan)
    # Two-pass variance over the (contiguous) windows: exact enough for
    # values whose mean is large compared with their spread.
    offsets = np.arange(k)
    window_values = training.values[lo[:, None] + offsets[None, :]] if q.size else np.zeros((0, k))
    sigma = np.std(window_values, axis=1, ddof=1)
    return mean, sigma


def knn_predict_all_k(training: SortedTraining, queries: ArrayLike,
                      k_max: int) -> NDArray[np.float64]:
    """kNN means for every k = 1 ... k_max at once.

    Parameters
    ----------
    training : SortedTraining
        The sorted training set (m points).
    queries : array_like, shape (n,)
        Query positions, the training positions' unit.
    k_max : int
        Largest k, 1 <= k_max <= m.

    Returns
    -------
    ndarray, shape (k_max, n)
        Row ``k - 1`` holds the k-NN mean at every query, the values' unit.

    Raises
    ------
    ParameterError
        ``k`` not a positive integer.
    InsufficientDataError
        ``k`` larger than the training set.
    """
    q = finite_array(queries, "queries", ndim=1, allow_empty=True)
    k_max = _check_k(k_max, len(training), "k_max")
    out = np.empty((k_max, q.size))

    def store(step, running, _sq, _rank):
        out[step - 1] = running / step

    _grow_windows(training, q, k_max, store)
    return out


def knn_neighbour_indices(positions: ArrayLike, queries: ArrayLike, k: int) -> NDArray[np.intp]:
    """Input indices of the k nearest neighbours of each query, nearest first.

    Parameters
    ----------
    positions : array_like, shape (m,)
        Training positions (any unit).
    queries : array_like, shape (n,)
        Query positions, same unit.
    k : int
        Neighbours, 1 <= k <= m.

    Returns
    -------
    ndarray of int, shape (n, k)

    Raises
    ------
    ParameterError
        ``k`` not a positive integer.
    InsufficientDataError
        ``k`` larger than the training set.
    """
    x = finite_array(positions, "positions", ndim=1)
    training = SortedTraining.build(x, np.zeros_like(x))
    q = finite_array(queries, "queries", ndim=1)
    k = _check_k(k, len(training))
    out = np.empty((q.size, k), dtype=np.intp)

    def record(step, _sum, _sq, rank):
        out[:, step - 1] = training.order[rank]

    _grow_windows(training, q, k, record)
    return out


def knn_brute_force_indices(positions: ArrayLike, queries: ArrayLike,
                            k: int) -> NDArray[np.intp]:
    """Reference neighbour indices, nearest first, by a full sort per query.

    Applies the module's tie rule literally - key (distance, position,
    |rank - insertion point|) - with no windows; the tests' independent
    formulation.

    Parameters
    ----------
    positions : array_like, shape (m,)
        Training positions (any unit).
    queries : array_like, shape (n,)
        Query positions, same unit.
    k : int
        Neighbours, 1 <= k <= m.

    Returns
    -------
    ndarray of int, shape (n, k)
        Input indices.

    Raises
    ------
    ParameterError
        ``k`` not a positive integer.
    InsufficientDataError
        ``k`` larger than the training set.
    """
    x = finite_array(positions, "positions", ndim=1)
    q = finite_array(queries, "queries", ndim=1)
    k = _check_k(k, x.size)
    rank = np.empty(x.size, dtype=np.intp)
    rank[np.argsort(x, kind="stable")] = np.arange(x.size)
    sorted_x = np.sort(x)
    out = np.empty((q.size, k), dtype=np.intp)
    for j, query in enumerate(q):
        insertion = np.searchsorted(sorted_x, query, side="left")
        out[j] = np.lexsort((np.abs(rank - insertion), x, np.abs(x - query)))[:k]
    return out


def knn_brute_force(positions: ArrayLike, values: ArrayLike, queries: ArrayLike,
                    k: int) -> NDArray[np.float64]:
    """Reference kNN mean by sorting all distances per query (O(n m log m)).

    Applies the module's tie rule literally; used by the tests as the
    independent formulation.

    Parameters
    ----------
    positions, values : array_like, shape (m,)
        Training positions (any unit) and values (any unit).
    queries : array_like, shape (n,)
        Query positions, the positions' unit.
    k : int
        Neighbours, 1 <= k <= m.

    Returns
    -------
    ndarray, shape (n,)
        kNN mean, the values' unit.

    Raises
    ------
    ParameterError
        ``k`` not a positive integer.
    InsufficientDataError
        ``k`` larger than the training set.
    """
    y = finite_array(values, "values", ndim=1)
    x = finite_array(positions, "positions", ndim=1)
    same_length("positions", x, "values", y)
    return y[knn_brute_force_indices(x, queries, k)].mean(axis=1)


@dataclass(frozen=True)
class CrossValidationResult:
    """Outcome of choosing k by K-fold cross-validation (Kidani eqs. 4.10-4.12).

    Attributes
    ----------
    k : int
        Chosen number of neighbours (smallest mean fold RMSE; the smaller k
        wins an exact tie).
    cv_rmse : float
        Mean of the K fold RMSEs at the chosen k [value unit].
    k_values : ndarray, shape (k_lim,)
        1 ... k_lim.
    rmse_by_k : ndarray, shape (k_lim,)
        Mean fold RMSE for each k.
    fold_rmse : ndarray, shape (n_folds, k_lim)
        RMSE(k) of every fold (Kidani eq. 4.11).
    folds : ndarray of int, shape (N,)
        Fold number of every input sample.
    """

    k: int
    cv_rmse: float
    k_values: NDArray[np.intp]
    rmse_by_k: NDArray[np.float64]
    fold_rmse: NDArray[np.float64]
    folds: NDArray[np.intp]


def shuffled_folds(n_samples: int, n_folds: int, seed: int | None = 0) -> NDArray[np.intp]:
    """Fold number of each sample: shuffled, then split into near-equal parts.

    The partition matches ``sklearn.model_selection.KFold(n_folds, shuffle=True)``
    in structure (the first ``n % K`` folds get one extra sample); the
    permutation comes from ``numpy.random.default_rng(seed)``.

    Parameters
    ----------
    n_samples : int
        N.
    n_folds : int
        K >= 2, at most N.
    seed : int or None, optional
        Seed of the permutation.

    Returns
    -------
    ndarray of int, shape (N,)
        Fold 0 ... K-1 of each sample.

    Raises
    ------
    ParameterError
        ``n_folds`` below 2.
    InsufficientDataError
        Fewer samples than folds.
    """
    if n_folds < 2:
        raise ParameterError(f"n_folds must be >= 2, got {n_folds}")
    if n_samples < n_folds:
        raise InsufficientDataError(f"{n_samples} samples cannot be split into {n_folds} folds")
    permutation = np.random.default_rng(seed).permutation(n_samples)
    sizes = np.full(n_folds, n_samples // n_folds)
    sizes[: n_samples % n_folds] += 1
    folds = np.empty(n_samples, dtype=np.intp)
    folds[permutation] = np.repeat(np.arange(n_folds), sizes)
    return folds


def cross_validate_k(positions: ArrayLike, values: ArrayLike, k_lim: int = 100,
                     n_folds: int = 5, seed: int | None = 0,
                     folds: ArrayLike | None = None) -> CrossValidationResult:
    """Choose k by K-fold cross-validation over k = 1 ... k_lim (Kidani 4.2.2.1).

    Each fold is held out once; the other folds are the training set; the kNN
    mean (Kidani eq. 4.10) at each held-out position is compared with its value,
    giving RMSE(k) per fold (Kidani eq. 4.11).

    Kidani eq. 4.12 as printed takes the square root of the mean of the K RMSEs, which
    is not an RMSE (its unit is the square root of the value's unit). This
    implementation uses the **plain mean of the K fold RMSEs**, the reading the
    surrounding text describes ("take the average of the K RMSE(k)s") and the
    one scikit-learn's ``GridSearchCV`` reports as ``mean_test_score``.

    Parameters
    ----------
    positions, values : array_like, shape (N,)
    k_lim : int
        Largest k tried; must leave every training set at least k_lim points.
    n_folds : int
        K >= 2.
    seed : int or None
        Seed of the shuffle (ignored when ``folds`` is given).
    folds : array_like of int, shape (N,), optional
        Explicit fold number 0 ... K-1 of each sample (e.g. time-blocked).

    Returns
    -------
    CrossValidationResult
        The chosen k, its mean fold RMSE [value unit] and the RMSE of every k and fold.

    Raises
    ------
    ParameterError
        k_lim < 1, or fewer than 2 folds.
    InputDataError
        Positions or values not finite, 1-D and of one length.
    InsufficientDataError
        Too few samples for the folds, an empty fold, or a training set smaller than
        k_lim.
    """
    x = finite_array(positions, "positions", ndim=1)
    y = finite_array(values, "values", ndim=1)
    same_length("positions", x, "values", y)
    if folds is None:
        fold_of = shuffled_folds(x.size, n_folds, seed)
    else:
        fold_of = np.asarray(folds, dtype=np.intp)
        same_length("folds", fold_of, "positions", x)
        n_folds = int(fold_of.max()) + 1
    k_lim = int(k_lim)
    if k_lim < 1:
        raise ParameterError(f"k_lim must be >= 1, got {k_lim}")
    return _result(_fold_rmse(x, y, fold_of, n_folds, k_lim), fold_of)


def _result(fold_rmse: NDArray[np.float64], fold_of: NDArray[np.intp]) -> CrossValidationResult:
    rmse_by_k = fold_rmse.mean(axis=0)
    best = int(np.argmin(rmse_by_k))
    return CrossValidationResult(k=best + 1, cv_rmse=float(rmse_by_k[best]),
                                 k_values=np.arange(1, rmse_by_k.size + 1), rmse_by_k=rmse_by_k,
                                 fold_rmse=fold_rmse, folds=fold_of)


#: Variables x samples searched together by :func:`cross_validate_k_many`.
CACHED_SAMPLES = 15_000


def cross_validate_k_many(positions: ArrayLike, values: ArrayLike, k_lim: int = 100,
                          n_folds: int = 5, seed: int | None = 0) -> list:
    """:func:`cross_validate_k` of each of V variables against the same values, in one pass.

    Parameters
    ----------
    positions : array_like, shape (V, N)
        V candidate variables at the same N samples (e.g. which one a residual follows).
    values : array_like, shape (N,) or (N, C)
        One series, or C series measured at the same samples (their neighbours in a
        variable are the same, so they share the search).
    k_lim, n_folds, seed :
        As :func:`cross_validate_k`; every variable gets the same shuffled folds, so
        result v (v, c) equals ``cross_validate_k(positions[v], values[:, c], ...)``.

    Returns
    -------
    list of V :class:`CrossValidationResult` (1-D values), or V lists of C of them.
    """
    y = np.asarray(values, dtype=np.float64)
    if y.ndim not in (1, 2):
        raise InputDataError(f"values must be (N,) or (N, C), got shape {y.shape}")
    y = finite_array(y, "values", ndim=y.ndim)
    if np.shape(positions)[:1] == (0,):
        return []
    x = finite_array(positions, "positions", ndim=2)
    if x.shape[1] != y.shape[0]:
        raise InputDataError(f"positions hold {x.shape[1]} samples per variable, "
                             f"values {y.shape[0]}")
    k_lim = int(k_lim)
    if k_lim < 1:
        raise ParameterError(f"k_lim must be >= 1, got {k_lim}")
    fold_of = shuffled_folds(y.shape[0], n_folds, seed)
    # A few variables at a time: the search makes ~25 passes over its padded arrays per
    # k, and arrays that stay in the cache make the whole search ~30 % faster (29
    # variables x 2,500 samples, docs/benchmarks.md). Every variable's numbers are its own.
    chunk = max(1, CACHED_SAMPLES // max(1, x.shape[1]))
    fold_rmse = np.concatenate([_fold_rmse(x[start:start + chunk], y, fold_of, n_folds, k_lim)
                                for start in range(0, x.shape[0], chunk)])
    if y.ndim == 1:
        return [_result(per_variable, fold_of) for per_variable in fold_rmse]
    return [[_result(per_variable[..., c], fold_of) for c in range(y.shape[1])]
            for per_variable in fold_rmse]


def _fold_rmse(x: NDArray[np.float64], y: NDArray[np.float64], fold_of: NDArray[np.intp],
               n_folds: int, k_lim: int) -> NDArray[np.float64]:
    """RMSE(k) of every fold, k = 1 .. k_lim: (n_folds, k_lim) for x (N,), or
    (V, n_folds, k_lim) for V variables x (V, N) smoothing the same y; with y of
    shape (N, C) (C series on the same samples: the neighbours depend on x alone)
    a last axis of C.

    Every fold's windows grow in one pass: the folds' training sets (of every
    variable) are laid end to end, each between -inf/+inf sentinels, so a query's
    window never leaves its own segment (a sentinel is never nearer than a
    training point). One stable sort per variable serves every fold: a
    stable-sorted array restricted to a subset is that subset stable-sorted.
    """
    many = x.ndim == 2
    xs_all = x if many else x[None, :]
    xs_parts, ys_parts, query_parts, truth_parts, starts, sizes = [], [], [], [], [], []
    offset = 0
    # Series as rows (C, N): each k's admissions gather along contiguous rows.
    series = y.T.reshape(-1, y.shape[0])
    sentinel_y = np.zeros((series.shape[0], 1))
    for xv in xs_all:
        order = np.argsort(xv, kind="stable")
        sorted_fold = fold_of[order]
        for fold in range(n_folds):
            held_out = sorted_fold == fold
            if not held_out.any():
                raise InsufficientDataError(f"fold {fold} holds no sample")
            training = order[~held_out]
            if training.size < k_lim:
                raise InsufficientDataError(
                    f"fold {fold}: k_lim = {k_lim} exceeds its {training.size} training points")
            xs_parts += [[-np.inf], xv[training], [np.inf]]
            ys_parts += [sentinel_y, series[:, training], sentinel_y]
            # Held-out queries in sorted order: every gather below walks memory in order.
            queries = xv[order[held_out]]
            query_parts.append(queries)
            truth_parts.append(series[:, order[held_out]])
            # Insertion point inside the segment, as a padded index of the left candidate.
            starts.append(offset + np.searchsorted(xv[training], queries, side="left"))
            sizes.append(queries.size)
            offset += training.size + 2
    xs_pad = np.concatenate(xs_parts)
    ys_pad = np.concatenate(ys_parts, axis=1)
    queries = np.concatenate(query_parts)
    truth = np.concatenate(truth_parts, axis=1)
    left = np.concatenate(starts)      # pad index of the next left candidate
    right = left + 1                   # pad index of the next right candidate
    running = np.zeros(truth.shape)
    boundaries = np.concatenate(([0], np.cumsum(sizes)[:-1]))
    squared = np.empty((len(sizes), k_lim, series.shape[0]))
    for k in range(1, k_lim + 1):
        take_left = (queries - xs_pad[left]) <= (xs_pad[right] - queries)
        admitted = np.where(take_left, left, right)
        running += np.take(ys_pad, admitted, axis=1)
        left -= take_left
        right += ~take_left
        residual = running / k - truth
        squared[:, k - 1] = np.add.reduceat(residual * residual, boundaries, axis=1).T
    rmse_by_fold = np.sqrt(squared / np.asarray(sizes, float)[:, None, None])
    if y.ndim == 1:
        rmse_by_fold = rmse_by_fold[..., 0]
    return rmse_by_fold.reshape((xs_all.shape[0], n_folds) + rmse_by_fold.shape[1:]) if many \
        else rmse_by_fold


def rmse(predicted: ArrayLike, measured: ArrayLike) -> float:
    """Root-mean-square difference (Kidani eq. 4.11).

    Parameters
    ----------
    predicted, measured : array_like, shape (n,)
        Values in one unit.

    Returns
    -------
    float
        RMS difference, the values' unit.

    Raises
    ------
    InputDataError
        Non-finite or non-1-D inputs, or lengths that differ.
    """
    a = finite_array(predicted, "predicted", ndim=1)
    b = finite_array(measured, "measured", ndim=1)
    same_length("predicted", a, "measured", b)
    return float(np.sqrt(np.mean((a - b) ** 2)))


@dataclass(frozen=True)
class SystematicExtraction:
    """kNN extraction of a systematic error profile (Kidani section 4.2.2.2).

    Attributes
    ----------
    cv : CrossValidationResult
        The choice of k.
    query_positions, systematic, random_sigma : ndarray, shape (n,)
        Profile with the chosen k over all data, at the query positions.
    new_data_rmse : float or None
        RMSE of the profile's prediction against new data (NaN if none given).
    """

    cv: CrossValidationResult
    query_positions: NDArray[np.float64]
    systematic: NDArray[np.float64]
    random_sigma: NDArray[np.float64]
    new_data_rmse: float

    @property
    def relative_difference(self) -> float:
        """|new-data RMSE - CV RMSE| / CV RMSE (Kidani: 1.4 %)."""
        return abs(self.new_data_rmse - self.cv.cv_rmse) / self.cv.cv_rmse


def extract_systematic(positions: ArrayLike, values: ArrayLike, query_positions: ArrayLike, *,
                       k_lim: int = 100, n_folds: int = 5, seed: int | None = 0,
                       new_positions: ArrayLike | None = None,
                       new_values: ArrayLike | None = None) -> SystematicExtraction:
    """Choose k by cross-validation, extract the profile, and test it on new data.

    Parameters
    ----------
    positions, values : array_like, shape (N,)
        Scattered positions [m] and error values (any unit, e.g. [rad] of yaw).
    query_positions : array_like, shape (n,)
        Where the profile is wanted [m].
    k_lim : int, optional
        Largest k tried.
    n_folds : int, optional
        K of the K-fold cross-validation.
    seed : int or None, optional
        Seed of the fold shuffle.
    new_positions, new_values : array_like, shape (M,), optional
        New data the profile is tested on.

    Returns
    -------
    SystematicExtraction
        The choice of k, the systematic profile and random sigma at the queries (the
        values' unit), and the RMSE against new data (NaN without it).

    Raises
    ------
    InputDataError
        Non-finite or mismatched inputs.
    InsufficientDataError
        Too few samples for ``n_folds`` folds of ``k_lim`` training points.
    """
    cv = cross_validate_k(positions, values, k_lim, n_folds, seed)
    systematic, sigma = knn_predict(positions, values, query_positions, cv.k, return_sigma=True)
    new_rmse = float("nan")
    if new_positions is not None and new_values is not None:
        predicted = knn_predict(positions, values, new_positions, cv.k)
        new_rmse = rmse(predicted, new_values)
    return SystematicExtraction(cv=cv, query_positions=np.asarray(query_positions, float),
                                systematic=systematic, random_sigma=sigma,
                                new_data_rmse=new_rmse)
