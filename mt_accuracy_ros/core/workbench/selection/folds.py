"""Time-blocked cross-validation: the one way the workbench predicts readings it did not fit.

The readings, in time order, are cut into contiguous blocks (folds); each block is
predicted by a fit on the others (K-fold) or, validated forward (a log whose model will
predict the future), on the blocks before it only. Blocks, not random folds: a slow
residual (a drift, a warm-up) makes neighbouring readings alike, and a fold that held
out scattered readings would be predicted by their neighbours.

Two cuts are in use (:func:`time_blocks`): ``"even"``, K blocks of near-equal size
(numpy's ``array_split``; the selection, the refit and the yaw ranking), and
``"ceil"``, blocks of ceil(N / K) readings, the last shorter (the localisation's
check of a periodic share; fewer than K blocks when N is not a multiple).

:class:`Folds` holds the cut of R rows (a reading may give several rows, one per
measured component) and gives each fold's training set - as rows, or as sums of
per-fold products (the whole record's minus the held-out block's) - and the
held-out residuals of any fit (:meth:`Folds.held_out_residuals`); how a fold is
fitted (least squares, a ridge, a prior, products) is the caller's.
"""
from __future__ import annotations

from typing import Callable

import numpy as np
from numpy.typing import NDArray

from ...errors import ParameterError

#: The ways readings are cut into blocks (:func:`time_blocks`).
CUTS = ("even", "ceil")


def time_blocks(n: int, count: int, cut: str = "even") -> NDArray[np.intp]:
    """Block number of each of n readings in time order (contiguous blocks).

    Parameters
    ----------
    n : int
        The readings.
    count : int
        K, the blocks asked for.
    cut : {"even", "ceil"}
        ``"even"``: K blocks of n // K readings, the first n % K one longer (numpy's
        ``array_split``). ``"ceil"``: blocks of ceil(n / K) readings, the last shorter
        (ceil(n / ceil(n / K)) blocks: fewer than K when n is not a multiple).

    Returns
    -------
    ndarray of int, shape (n,)
        0, 0, ..., 1, ... non-decreasing.
    """
    if cut == "even":
        sizes = np.full(count, n // count)
        sizes[: n % count] += 1
        return np.repeat(np.arange(count), sizes)
    if cut == "ceil":
        return np.arange(n) // -(-n // count)
    raise ParameterError(f"cut {cut!r}: one of {', '.join(CUTS)}")


def training_sums(per_fold: NDArray[np.float64], forward: bool = False) -> NDArray[np.float64]:
    """Per-fold sums -> each fold's training sums.

    Parameters
    ----------
    per_fold : ndarray, shape (F, ...)
        A sum over each fold's rows (products X_f'X_f, X_f'y_f, ...).
    forward : bool
        The training blocks are the earlier folds only (forward validation), not
        every other fold.

    Returns
    -------
    ndarray, shape (F, ...)
        The sum over each fold's training blocks: the whole record's minus the fold's
        own, or (forward) the cumulative sum before it.
    """
    if forward:
        return np.cumsum(per_fold, axis=0) - per_fold
    return per_fold.sum(axis=0, keepdims=True) - per_fold


def _train(per_fold: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per-fold sums -> sums over every other fold (:func:`training_sums`, K-fold)."""
    return training_sums(per_fold)


class Folds:
    """Contiguous time blocks of R rows in time order.

    Parameters
    ----------
    fold_of_row : ndarray of int, shape (R,)
        Each row's fold, non-decreasing (rows in time order).
    count : int, optional
        F, the folds (default: the last row's fold + 1); a fold may hold no row.
    forward : bool
        Validated forward: a fold is trained on the folds before it only.
    """

    def __init__(self, fold_of_row: NDArray[np.intp], count: int | None = None,
                 forward: bool = False) -> None:
        fold_of_row = np.asarray(fold_of_row, dtype=np.intp)
        if fold_of_row.ndim != 1 or np.any(np.diff(fold_of_row) < 0):
            raise ParameterError("folds: one fold per row, non-decreasing (rows in time order)")
        self.fold_of_row = fold_of_row
        self.count = int(fold_of_row[-1]) + 1 if count is None else int(count)
        self.forward = bool(forward)
        edges = np.searchsorted(fold_of_row, np.arange(self.count + 1))
        #: Each fold's rows a:b (one slice each: the folds are contiguous).
        self.bounds = [(int(edges[f]), int(edges[f + 1])) for f in range(self.count)]

    @classmethod
    def of_readings(cls, n: int, count: int, sample_of_row: NDArray[np.intp] | None = None,
                    cut: str = "even", forward: bool = False) -> "Folds":
        """The readings 0..n-1 cut into blocks, each row in its reading's.

        Parameters
        ----------
        n : int
            The readings.
        count : int
            K, the blocks asked for (:func:`time_blocks`).
        sample_of_row : ndarray of int, shape (R,), optional
            Each row's reading, non-decreasing (default: one row per reading).
        cut : {"even", "ceil"}
            How the readings are cut (:func:`time_blocks`).
        forward : bool
            Validated forward.

        Returns
        -------
        Folds
        """
        blocks = time_blocks(n, count, cut)
        fold_of_row = blocks if sample_of_row is None else blocks[sample_of_row]
        return cls(fold_of_row, int(blocks[-1]) + 1 if n else count, forward)

    def training_sums(self, per_fold: NDArray[np.float64]) -> NDArray[np.float64]:
        """Each fold's training sums (:func:`training_sums`, forward if these folds are).

        Parameters
        ----------
        per_fold : ndarray, shape (F, ...)
            A sum over each fold's rows.

        Returns
        -------
        ndarray, shape (F, ...)
        """
        return training_sums(per_fold, self.forward)

    def block_products(self, left: NDArray[np.float64], right: NDArray[np.float64]
                       ) -> NDArray[np.float64]:
        """Each fold's left_f' right_f.

        Parameters
        ----------
        left : ndarray, shape (R, a)
        right : ndarray, shape (R, b) or (R,)

        Returns
        -------
        ndarray, shape (F, a, b) or (F, a)
        """
        return np.stack([left[a:b].T @ right[a:b] for a, b in self.bounds])

    def training_rows(self, fold: int) -> NDArray[np.bool_]:
        """The rows ``fold`` is fitted on.

        Parameters
        ----------
        fold : int
            0..F-1.

        Returns
        -------
        ndarray of bool, shape (R,)
            Every other fold's rows, or (forward) the earlier folds'.
        """
        a, b = self.bounds[fold]
        rows = np.zeros(self.fold_of_row.size, dtype=bool)
        if self.forward:
            rows[:a] = True
        else:
            rows[:a] = rows[b:] = True
        return rows

    def validation_pairs(self) -> list[tuple[int, int, NDArray[np.float64]]]:
        """The folds' inner validation, for a choice made inside each fold.

        Returns
        -------
        list of (f, g, weights (F,))
            Fold f's choice is validated on each of its training blocks g by a fit on
            the blocks ``weights`` marks (every fold but f and g; forward: the blocks
            before g, g > 0 and before f). Never on the held-out block f.
        """
        pairs = []
        for f in range(self.count):
            for g in range(self.count):
                if g == f or (self.forward and (g >= f or g == 0)):
                    continue
                weights = np.ones(self.count)
                if self.forward:
                    weights = (np.arange(self.count) < g).astype(float)
                else:
                    weights[[f, g]] = 0.0
                pairs.append((f, g, weights))
        return pairs

    def held_out_pairs(self) -> list[tuple[int, int, NDArray[np.float64]]]:
        """The outer validation as (g, g, weights (F,)): each fold g predicted by a fit on
        the blocks ``weights`` marks (every other fold; forward: the earlier ones, g > 0)."""
        pairs = []
        for g in range(1 if self.forward else 0, self.count):
            weights = (np.arange(self.count) < g).astype(float) if self.forward else \
                (np.arange(self.count) != g).astype(float)
            pairs.append((g, g, weights))
        return pairs

    def held_out_residuals(self, x: NDArray[np.float64], y: NDArray[np.float64],
                           solve: Callable[[int], NDArray[np.float64] | None]
                           ) -> tuple[NDArray[np.float64], NDArray[np.bool_]]:
        """The residual of each fold's rows under the fit on its training blocks.

        Parameters
        ----------
        x : ndarray, shape (R, p)
            The design.
        y : ndarray, shape (R,)
            The readings.
        solve : callable
            ``solve(fold)`` -> the coefficients (p,) fitted on that fold's training
            blocks (:meth:`training_rows`, or :meth:`training_sums` of per-fold
            products), or None when the fold cannot be fitted (it is then not judged).

        Returns
        -------
        residual : ndarray, shape (R,)
            y - x @ coefficients on each judged fold's rows; 0 elsewhere.
        judged : ndarray of bool, shape (R,)
        """
        residual = np.zeros(y.shape[0])
        judged = np.zeros(y.shape[0], dtype=bool)
        for fold, (a, b) in enumerate(self.bounds):
            if b == a:
                continue
            coefficients = solve(fold)
            if coefficients is None:
                continue
            residual[a:b] = y[a:b] - x[a:b] @ coefficients
            judged[a:b] = True
        return residual, judged
