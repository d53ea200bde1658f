"""Systematic and random error at repeated positions; ISO 230-2 evaluation.

Kidani section 2.4.1: with m repeated measurements E_ir at position i, the
systematic error is their mean (Kidani eq. 2.22) and the random error their sample
standard deviation (Kidani eq. 2.23). ISO 230-2 judges bidirectional positioning
runs of a reference instrument (laser interferometer) by the same statistics
per direction of approach.
"""
from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError, InsufficientDataError
from ..validation import finite_array, same_length


def systematic_and_random(errors: ArrayLike) -> tuple[NDArray[np.float64], NDArray[np.float64]]:
    """Mean (Kidani eq. 2.22) and sample standard deviation (Kidani eq. 2.23) per position.

    Parameters
    ----------
    errors : array_like, shape (n_positions, m)
        Error E_ir at position i in repetition r [any unit], m >= 2.

    Returns
    -------
    systematic, random : ndarray, shape (n_positions,)
    """
    e = finite_array(errors, "errors", ndim=2)
    if e.shape[1] < 2:
        raise InsufficientDataError(
            f"random error (Kidani eq. 2.23) needs >= 2 repetitions per position, got {e.shape[1]}")
    return e.mean(axis=1), e.std(axis=1, ddof=1)


def group_by_position(positions: ArrayLike, values: ArrayLike,
                      tolerance_m: float = 1e-6) -> tuple[NDArray, NDArray, NDArray, NDArray]:
    """Kidani eqs. 2.22/2.23 for data recorded at (nearly) repeated positions, e.g.
    stop-and-measure.

    Positions within ``tolerance_m`` of the previous one (after sorting) form one
    group. Returns ``(group_position, systematic, random, count)``; ``random`` is
    NaN for groups of one sample.

    Parameters
    ----------
    positions : array_like, shape (N,)
        Positions [m].
    values : array_like, shape (N,)
        Errors (any unit).
    tolerance_m : float, optional
        Largest gap [m] between sorted positions of one group.

    Returns
    -------
    group_position : ndarray, shape (G,)
        Mean position of each group [m].
    systematic : ndarray, shape (G,)
        Mean error (Kidani eq. 2.22), the values' unit.
    random : ndarray, shape (G,)
        Sample standard deviation, ddof = 1 (Kidani eq. 2.23), the values' unit.
    count : ndarray of int, shape (G,)
        Samples per group.

    Raises
    ------
    InputDataError
        Non-finite values or lengths that differ.
    """
    x = finite_array(positions, "positions", ndim=1)
    y = finite_array(values, "values", ndim=1)
    if x.size != y.size:
        raise InputDataError(f"positions has {x.size} values but values has {y.size}")
    order = np.argsort(x, kind="stable")
    xs, ys = x[order], y[order]
    starts = np.concatenate(([0], np.nonzero(np.diff(xs) > tolerance_m)[0] + 1))
    counts = np.diff(np.concatenate((starts, [xs.size])))
    sums = np.add.reduceat(ys, starts)
    means = sums / counts
    group_x = np.add.reduceat(xs, starts) / counts
    deviations = ys - np.repeat(means, counts)
    squares = np.add.reduceat(deviations ** 2, starts)
    with np.errstate(invalid="ignore", divide="ignore"):
        sigma = np.where(counts > 1, np.sqrt(squares / np.maximum(counts - 1, 1)), np.nan)
    return group_x, means, sigma, counts


@dataclass(frozen=True)
class Iso2302Result:
    """ISO 230-2 evaluation of bidirectional positioning runs (all lengths in the input unit).

    Per target position (arrays, shape (m,)): ``mean_up``, ``mean_down`` (mean
    unidirectional positional deviations), ``mean_bidirectional``, ``reversal``
    (B_i), ``s_up``, ``s_down`` (estimators of unidirectional repeatability),
    ``repeatability_up``, ``repeatability_down`` (4 s), ``repeatability_bidirectional``.
    Axis figures (floats): ``reversal_value`` B = max |B_i|, ``mean_reversal``,
    ``repeatability`` R, ``repeatability_up``/``_down`` maxima,
    ``systematic_deviation`` E (bidirectional), ``systematic_deviation_up``/``_down``,
    ``mean_deviation_range`` M, ``accuracy`` A, ``accuracy_up``/``_down``.
    """

    targets: NDArray[np.float64]
    mean_up: NDArray[np.float64]
    mean_down: NDArray[np.float64]
    mean_bidirectional: NDArray[np.float64]
    reversal: NDArray[np.float64]
    s_up: NDArray[np.float64]
    s_down: NDArray[np.float64]
    repeatability_bidirectional: NDArray[np.float64]
    reversal_value: float
    mean_reversal: float
    repeatability: float
    repeatability_up_axis: float
    repeatability_down_axis: float
    systematic_deviation: float
    systematic_deviation_up: float
    systematic_deviation_down: float
    mean_deviation_range: float
    accuracy: float
    accuracy_up: float
    accuracy_down: float

    def summary(self) -> dict[str, float]:
        """The axis figures as a plain dict."""
        return {name: getattr(self, name) for name in (
            "accuracy", "accuracy_up", "accuracy_down", "repeatability",
            "repeatability_up_axis", "repeatability_down_axis", "reversal_value",
            "mean_reversal", "systematic_deviation", "systematic_deviation_up",
            "systematic_deviation_down", "mean_deviation_range")}


def iso230_2(targets: ArrayLike, deviations_up: ArrayLike,
             deviations_down: ArrayLike) -> Iso2302Result:
    """Evaluate bidirectional positioning runs per ISO 230-2.

    Parameters
    ----------
    targets : array_like, shape (m,)
        Target positions P_i.
    deviations_up, deviations_down : array_like, shape (m, n)
        Positional deviations x_ij (actual - target) approached in the positive
        and negative direction in n >= 2 runs.

    Returns
    -------
    Iso2302Result
        Per-target and axis figures, in the input's length unit.

    Raises
    ------
    InputDataError
        Shapes that do not agree.
    """
    p = finite_array(targets, "targets", ndim=1)
    up = finite_array(deviations_up, "deviations_up", ndim=2)
    down = finite_array(deviations_down, "deviations_down", ndim=2)
    if up.shape != down.shape or up.shape[0] != p.size:
        raise InputDataError(
            f"targets {p.shape}, deviations_up {up.shape} and deviations_down {down.shape} "
            "must agree: (m,), (m, n), (m, n)")
    mean_up, s_up = systematic_and_random(up)
    mean_down, s_down = systematic_and_random(down)
    reversal = mean_up - mean_down
    r_up, r_down = 4.0 * s_up, 4.0 * s_down
    r_bi = np.maximum.reduce([2 * s_up + 2 * s_down + np.abs(reversal), r_up, r_down])
    mean_bi = 0.5 * (mean_up + mean_down)
    both_means = np.concatenate((mean_up, mean_down))
    return Iso2302Result(
        targets=p, mean_up=mean_up, mean_down=mean_down, mean_bidirectional=mean_bi,
        reversal=reversal, s_up=s_up, s_down=s_down, repeatability_bidirectional=r_bi,
        reversal_value=float(np.max(np.abs(reversal))),
        mean_reversal=float(np.mean(reversal)),
        repeatability=float(np.max(r_bi)),
        repeatability_up_axis=float(np.max(r_up)),
        repeatability_down_axis=float(np.max(r_down)),
        systematic_deviation=float(np.ptp(both_means)),
        systematic_deviation_up=float(np.ptp(mean_up)),
        systematic_deviation_down=float(np.ptp(mean_down)),
        mean_deviation_range=float(np.ptp(mean_bi)),
        accuracy=float(max(np.max(mean_up + 2 * s_up), np.max(mean_down + 2 * s_down))
                       - min(np.min(mean_up - 2 * s_up), np.min(mean_down - 2 * s_down))),
        accuracy_up=float(np.max(mean_up + 2 * s_up) - np.min(mean_up - 2 * s_up)),
        accuracy_down=float(np.max(mean_down + 2 * s_down) - np.min(mean_down - 2 * s_down)),
    )


def positioning_runs(positions: ArrayLike, deviations: ArrayLike, directions: ArrayLike, *,
                     resolution_m: float = 1e-4, min_targets: int = 5, min_runs: int = 2,
                     min_share: float = 0.8):
    """Find ISO 230-2 positioning runs in readings of one axis, or None.

    Readings at the same target (positions equal within ``resolution_m``)
    approached from each direction are runs. The data holds positioning runs
    when at least ``min_targets`` targets each have ``min_runs`` approaches
    from both sides and at least ``min_share`` of the readings sit on such
    targets (a continuous motion that crosses a position twice does not).

    Parameters
    ----------
    positions : array_like, shape (N,)
        Axis positions [m].
    deviations : array_like, shape (N,)
        Positioning deviations [m].
    directions : array_like, shape (N,)
        Approach direction: > 0 rising, < 0 falling.
    resolution_m : float, optional
        Positions within this [m] are one target.
    min_targets, min_runs : int, optional
        Fewest targets, and fewest approaches per side of each.
    min_share : float, optional
        Fewest fraction of readings on such targets (dimensionless).

    Returns
    -------
    (targets (m,), up (m, n), down (m, n)) ready for :func:`iso230_2`, with n
    the smallest run count (the first n of each target), or None.

    Raises
    ------
    InputDataError
        Non-finite values or lengths that differ.
    """
    q = finite_array(positions, "positions", ndim=1)
    e = finite_array(deviations, "deviations", ndim=1)
    d = finite_array(directions, "directions", ndim=1)
    same_length("positions", q, "deviations", e)
    same_length("positions", q, "directions", d)
    keys = np.round(q / resolution_m).astype(np.int64)
    targets, up, down, used = [], [], [], 0
    for key in np.unique(keys):
        on = keys == key
        rising, falling = e[on & (d > 0)], e[on & (d < 0)]
        if rising.size >= min_runs and falling.size >= min_runs:
            targets.append(float(np.mean(q[on])))
            up.append(rising)
            down.append(falling)
            used += int(on.sum())
    if len(targets) < min_targets or used < min_share * q.size:
        return None
    runs = min(min(a.size for a in up), min(a.size for a in down))
    return (np.asarray(targets), np.array([a[:runs] for a in up]),
            np.array([a[:runs] for a in down]))


#: ISO 230-2's reference temperature [degC].
REFERENCE_TEMPERATURE_C = 20.0
#: Runs of the standard test (linear axes up to 2 m); fewer still give figures, flagged.
STANDARD_RUNS = 5


def corrected_to_20c(target_m: ArrayLike, deviation_m: ArrayLike, temperature_c: ArrayLike,
                     expansion_per_k: float) -> NDArray[np.float64]:
    """Deviations referred to 20 degC (ISO 230-2, the temperature clause: the nominal
    differential expansion of the axis' scale or the part, alpha (T - 20) P, taken out).

    Parameters
    ----------
    target_m, deviation_m, temperature_c : array_like, shape (N,)
        Target P [m] (from the axis' zero), deviation [m], material temperature [degC].
    expansion_per_k : float
        The material's expansion coefficient alpha [1/K].

    Returns
    -------
    ndarray, shape (N,)
        Deviation at 20 degC [m].

    Raises
    ------
    InputDataError
        Arrays not finite or of different lengths, or alpha not in (0, 1e-3).
    """
    p = finite_array(target_m, "targets", ndim=1)
    x = finite_array(deviation_m, "deviations", ndim=1)
    t = finite_array(temperature_c, "temperatures", ndim=1)
    same_length("targets", p, "deviations", x)
    same_length("targets", p, "temperatures", t)
    if not (np.isfinite(expansion_per_k) and 0 < expansion_per_k < 1e-3):
        raise InputDataError(f"expansion coefficient {expansion_per_k!r} /K: give alpha as a "
                             "positive number below 1e-3 (steel 11.5e-6)")
    return x - expansion_per_k * (t - REFERENCE_TEMPERATURE_C) * p


def runs_by_target(target_m: ArrayLike, deviation_m: ArrayLike, direction: ArrayLike,
                   run: ArrayLike, resolution_m: float = 1e-6
                   ) -> tuple[NDArray[np.float64], NDArray[np.float64], NDArray[np.float64]]:
    """(targets (m,), up (m, n), down (m, n)) for :func:`iso230_2` from one reading per row.

    Every target must be read once per run in each direction; a target missing from a
    run, a run read twice, or fewer than 2 runs is an :class:`InputDataError` naming it.

    Parameters
    ----------
    target_m : array_like, shape (N,)
        Target position of each reading [m].
    deviation_m : array_like, shape (N,)
        Deviation [m].
    direction : array_like, shape (N,)
        Approach direction: > 0 rising, < 0 falling.
    run : array_like of int, shape (N,)
        Run number of each reading.
    resolution_m : float, optional
        Targets within this [m] are one.

    Returns
    -------
    targets : ndarray, shape (m,)
        Target positions [m].
    up, down : ndarray, shape (m, n)
        Deviations [m] per target and run, each direction.

    Raises
    ------
    InputDataError
        Mismatched lengths, non-finite values, a target missing from a run, a run read
        twice, or fewer than 2 runs.
    """
    p = finite_array(target_m, "targets", ndim=1)
    x = finite_array(deviation_m, "deviations", ndim=1)
    d = finite_array(direction, "directions", ndim=1)
    r = np.asarray(run, dtype=np.int64)
    same_length("targets", p, "deviations", x)
    same_length("targets", p, "directions", d)
    if r.shape != p.shape:
        raise InputDataError(f"runs has {r.size} values but targets has {p.size}")
    keys = np.round(p / resolution_m).astype(np.int64)
    targets = np.unique(keys)
    runs = np.unique(r)
    if runs.size < 2:
        raise InsufficientDataError(f"too few runs: {runs.size}; ISO 230-2 needs at least 2 "
                                    f"to give a repeatability ({STANDARD_RUNS} in the standard "
                                    "test)")
    tables = {}
    for sign, name in ((1.0, "up"), (-1.0, "down")):
        table = np.full((targets.size, runs.size), np.nan)
        for k in np.flatnonzero(np.sign(d) == sign):
            i = int(np.searchsorted(targets, keys[k]))
            j = int(np.searchsorted(runs, r[k]))
            if np.isfinite(table[i, j]):
                raise InputDataError(f"target {keys[k] * resolution_m * 1e3:.4g} mm is read "
                                     f"twice in run {r[k]} going {name}")
            table[i, j] = x[k]
        missing = np.argwhere(~np.isfinite(table))
        if missing.size:
            i, j = missing[0]
            raise InputDataError(
                f"unequal target sets: target {targets[i] * resolution_m * 1e3:.4g} mm has no "
                f"reading going {name} in run {runs[j]} ({len(missing)} such gaps); every run "
                "must visit every target from both sides")
        tables[name] = table
    return targets * resolution_m, tables["up"], tables["down"]
