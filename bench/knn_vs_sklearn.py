"""kNN cross-validation: this package's windowed kNN vs scikit-learn, same folds, same run.

N scattered points, k = 1 ... 100, 5 shuffled folds. scikit-learn's
``GridSearchCV(KNeighborsRegressor())`` gets exactly our folds (as explicit
train/test index pairs) and scores by RMSE; both must pick the same k and give
the same mean fold RMSEs.

Both sides are timed alike: one warm-up each, then ``--repeats`` timed runs each,
interleaved, every one reported; the speed-up is the ratio of the medians.

Usage: ``python -m bench.knn_vs_sklearn [--n 100000] [--k-lim 100] [--folds 5] [--repeats 3]``
"""
from __future__ import annotations

import argparse
import json
import platform
import time

import numpy as np

from mt_accuracy_ros.core.scales.knn import cross_validate_k, shuffled_folds


def run(n: int, k_lim: int, n_folds: int, seed: int = 0, repeats: int = 3) -> dict:
    from sklearn.model_selection import GridSearchCV
    from sklearn.neighbors import KNeighborsRegressor

    rng = np.random.default_rng(seed)
    # Continuous positions (no exact ties, where tie rules could differ), a yaw
    # profile of a few urad and 0.4 urad noise, as in Kidani Fig. 4.4.
    x = rng.uniform(0.0, 0.39, n)
    y = 3e-6 * np.sin(2 * np.pi * x / 0.13) + 1e-6 * np.sin(2 * np.pi * x / 0.031) \
        + rng.normal(0.0, 4e-7, n)
    folds = shuffled_folds(n, n_folds, seed)

    splits = [(np.nonzero(folds != f)[0], np.nonzero(folds == f)[0]) for f in range(n_folds)]

    def sklearn_search():
        search = GridSearchCV(KNeighborsRegressor(), {"n_neighbors": list(range(1, k_lim + 1))},
                              cv=splits, scoring="neg_root_mean_squared_error", refit=False)
        return search.fit(x[:, None], y)

    # Both sides alike (issue 39): one warm-up each on the same small problem, then the
    # same number of timed repetitions, every one reported; the ratio is of medians.
    cross_validate_k(x[:5000], y[:5000], 10, n_folds, seed=seed)
    GridSearchCV(KNeighborsRegressor(), {"n_neighbors": [1, 5, 10]}, cv=n_folds,
                 scoring="neg_root_mean_squared_error", refit=False).fit(x[:5000, None],
                                                                          y[:5000])
    ours_times, sklearn_times = [], []
    for _ in range(repeats):
        started = time.perf_counter()
        ours = cross_validate_k(x, y, k_lim, n_folds, folds=folds)
        ours_times.append(time.perf_counter() - started)
        started = time.perf_counter()
        search = sklearn_search()
        sklearn_times.append(time.perf_counter() - started)
    ours_s, sklearn_s = float(np.median(ours_times)), float(np.median(sklearn_times))
    sklearn_rmse = -search.cv_results_["mean_test_score"]
    sklearn_k = int(search.best_params_["n_neighbors"])
    relative = np.max(np.abs(sklearn_rmse - ours.rmse_by_k) / sklearn_rmse)
    return {
        "n": n, "k_lim": k_lim, "folds": n_folds,
        "ours_s": ours_s, "ours_repeats_s": ours_times, "sklearn_s": sklearn_s,
        "sklearn_repeats_s": sklearn_times, "speedup": sklearn_s / ours_s,
        "speedups_per_repeat": [b / a for a, b in zip(ours_times, sklearn_times)],
        "k_ours": ours.k, "k_sklearn": sklearn_k,
        "cv_rmse_ours": ours.cv_rmse, "cv_rmse_sklearn": float(sklearn_rmse[sklearn_k - 1]),
        "max_relative_rmse_difference": float(relative),
        "machine": f"{platform.machine()}, {platform.python_version()}",
    }


def main() -> int:
    parser = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    parser.add_argument("--n", type=int, default=100_000)
    parser.add_argument("--k-lim", type=int, default=100)
    parser.add_argument("--folds", type=int, default=5)
    parser.add_argument("--repeats", type=int, default=3,
                        help="timed runs of each side after one warm-up each (all reported)")
    args = parser.parse_args()
    result = run(args.n, args.k_lim, args.folds, repeats=args.repeats)
    print(json.dumps(result, indent=2))
    ok = result["k_ours"] == result["k_sklearn"] and result["max_relative_rmse_difference"] < 1e-9
    print("AGREE" if ok else "DISAGREE")
    return 0 if ok else 1


if __name__ == "__main__":
    raise SystemExit(main())
