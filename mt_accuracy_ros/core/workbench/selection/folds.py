"""Time-blocked cross-validation: the readings cut into contiguous blocks in time order."""
from __future__ import annotations

import numpy as np
from numpy.typing import NDArray


def time_blocks(n: int, count: int) -> NDArray[np.intp]:
    """Block number 0..count-1 of each of n readings in time order (contiguous, near equal)."""
    sizes = np.full(count, n // count)
    sizes[: n % count] += 1
    return np.repeat(np.arange(count), sizes)


def _train(per_fold: NDArray[np.float64]) -> NDArray[np.float64]:
    """Per-fold sums -> sums over every other fold (the training blocks)."""
    return per_fold.sum(axis=0, keepdims=True) - per_fold
