"""Walk-forward judgement of a thermal model: the log replayed in time as the package runs.

Live, the monitor refits its model with every reference reading it has so far and
compensates what comes next. Walk-forward plays that on a recorded log: at the end of each
period the model is made again from every row so far, then predicts the next period, which
no decision saw. The figure is what a user running the package in-process gets; one split
of the log (fit on the leading part, judge the rest) is its worst case.

The periods are stretches of data time (``PERIOD`` seconds: the rows whose time falls in
``[t0 + k PERIOD, t0 + (k + 1) PERIOD)``) or the log's runs. A period is predicted once the
rows before it hold at least ``min_train_rows``; the pooled figure is the root mean square
over every predicted row.
"""
from __future__ import annotations

import dataclasses
from typing import Callable, Mapping

import numpy as np
from numpy.typing import NDArray

from ..errors import InputDataError


@dataclasses.dataclass(frozen=True)
class Period:
    """One period a walk-forward predicts.

    Attributes
    ----------
    start, stop : int
        Its rows, ``start`` to ``stop - 1`` (every row before ``start`` is fitted on).
    time_start_s, time_stop_s : float
        Its first and last row's time [s].
    label : str
        "run 'day 4'" or "12.0-16.0 h".
    """

    start: int
    stop: int
    time_start_s: float
    time_stop_s: float
    label: str


@dataclasses.dataclass
class PeriodFigures:
    """What each method did on one period.

    Attributes
    ----------
    period : Period
        The period.
    trained_rows : int
        Rows fitted on (every row before the period).
    rmse_m : dict of str to float
        Method -> RMS error over the period's rows [m].
    described : dict of str to str
        Method -> what it was this period (the workbench's chosen model).
    """

    period: Period
    trained_rows: int
    rmse_m: dict[str, float]
    described: dict[str, str]


@dataclasses.dataclass
class WalkForward:
    """A walk-forward of a log.

    Attributes
    ----------
    period_text : str
        The period as asked ("4 h", "each run").
    methods : list of str
        The methods, in the order given.
    periods : list of PeriodFigures
        Each predicted period, in time order.
    pooled_m : dict of str to float
        Method -> RMS error over every predicted row [m].
    judged_rows : int
        Rows predicted.
    first_fit_rows : int
        Rows the first prediction was fitted on.
    """

    period_text: str
    methods: list[str]
    periods: list[PeriodFigures]
    pooled_m: dict[str, float]
    judged_rows: int
    first_fit_rows: int

    def wins_over(self, method: str, others: list[str]) -> bool:
        """Whether one method beat others, pooled.

        Parameters
        ----------
        method : str
            The method judged.
        others : list of str
            The methods it must beat.

        Returns
        -------
        bool
            ``method``'s pooled error is below every one of ``others``'.
        """
        return all(self.pooled_m[method] < self.pooled_m[o] for o in others)


def parse_period(text: str) -> float | None:
    """A walk-forward period in seconds.

    Parameters
    ----------
    text : str
        ``"4h"``, ``"30 min"``, ``"900"`` (seconds), ``"2d"``, or ``"run"``.

    Returns
    -------
    float or None
        The period [s]; None for ``"run"`` (each run a period).

    Raises
    ------
    InputDataError
        Anything else, or a period not above zero.
    """
    words = text.strip().lower().replace(" ", "")
    if words in ("run", "runs"):
        return None
    units = (("min", 60.0), ("ms", 1e-3), ("s", 1.0), ("h", 3600.0), ("d", 86400.0))
    scale, number = 1.0, words
    for suffix, factor in units:
        if words.endswith(suffix):
            scale, number = factor, words[: -len(suffix)]
            break
    try:
        value = float(number) * scale
    except ValueError:
        value = float("nan")
    if not (np.isfinite(value) and value > 0):
        raise InputDataError(f"--walk-forward {text!r}: give a period of data time (4h, 30min, "
                             "900s, 1d) or 'run' (each run predicted from the runs before it)")
    return value


def _duration(seconds: float) -> str:
    """"4 h", "30 min", "45 s", "2 d"."""
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def walk_periods(time_s: NDArray[np.float64], period_s: float | None,
                 run_of_row: NDArray[np.intp] | None, min_train_rows: int,
                 run_names: list[str] | None = None) -> list[Period]:
    """The periods to predict: stretches of ``period_s`` of data time, or each run
    (``period_s`` None), from the first one with ``min_train_rows`` rows before it.

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        Non-decreasing time [s] (runs laid end to end).
    period_s : float or None
        The period [s]; None: each run.
    run_of_row : ndarray of int, shape (N,), or None
        Run index of each row (needed when ``period_s`` is None).
    min_train_rows : int
        Rows a fit needs.
    run_names : list of str, optional
        The runs' names.

    Returns
    -------
    list of Period
        In time order.

    Raises
    ------
    InputDataError
        Each run a period without runs; fewer than two periods to predict.
    """
    n = time_s.size
    if period_s is None:
        if run_of_row is None:
            raise InputDataError("--walk-forward run needs runs (--run COLUMN, or a clock "
                                 "that jumps between them): give a period of time instead")
        index = np.asarray(run_of_row, dtype=np.intp)
        labels = [f"run {run_names[k]!r}" if run_names else f"run {k + 1}"
                  for k in range(int(index.max()) + 1)]
    else:
        index = np.floor((time_s - time_s[0]) / period_s).astype(np.intp)
        labels = [f"{_duration(k * period_s)}-{_duration((k + 1) * period_s)}"
                  for k in range(int(index.max()) + 1)]
    edges = np.flatnonzero(np.diff(index) != 0) + 1
    starts, stops = np.concatenate(([0], edges)), np.concatenate((edges, [n]))
    periods = [Period(int(a), int(b), float(time_s[a]), float(time_s[b - 1]),
                      labels[int(index[a])])
               for a, b in zip(starts, stops) if a >= min_train_rows]
    if len(periods) < 2:
        raise InputDataError(
            f"--walk-forward: {len(periods)} period{'s' if len(periods) != 1 else ''} to "
            f"predict after the first {min_train_rows} rows a fit needs ({n} rows over "
            f"{_duration(float(time_s[-1] - time_s[0]))}): give a shorter period")
    return periods


#: A method's residual on every row, given the rows it may fit on: (residual (N,) [m], what
#: it was - the chosen model, "" when always the same).
ResidualOf = Callable[[NDArray[np.bool_]], tuple[NDArray[np.float64], str]]


def walk_forward(n: int, periods: list[Period], methods: Mapping[str, ResidualOf],
                 period_text: str, progress: Callable[[str], None] | None = None
                 ) -> WalkForward:
    """Each period predicted by each method fitted on every row before it.

    Parameters
    ----------
    n : int
        The log's rows.
    periods : list of Period
        The periods (:func:`walk_periods`).
    methods : mapping of str to callable
        Method name -> its residual on every row given the training rows (N,) bool
        (:data:`ResidualOf`).
    period_text : str
        The period as asked, for the output.
    progress : callable, optional
        Called with a line per period (a long walk says where it is).

    Returns
    -------
    WalkForward
        Per period and pooled.
    """
    figures, squared = [], {name: 0.0 for name in methods}
    judged = 0
    for k, period in enumerate(periods):
        train = np.arange(n) < period.start
        rmse, described = {}, {}
        for name, residual_of in methods.items():
            residual, what = residual_of(train)
            part = residual[period.start:period.stop]
            rmse[name] = float(np.sqrt(np.mean(part ** 2)))
            squared[name] += float(np.sum(part ** 2))
            described[name] = what
        judged += period.stop - period.start
        figures.append(PeriodFigures(period, period.start, rmse, described))
        if progress is not None:
            progress(f"walk-forward {k + 1}/{len(periods)}: {period.label} predicted from "
                     f"{period.start} rows")
    pooled = {name: float(np.sqrt(total / max(judged, 1))) for name, total in squared.items()}
    return WalkForward(period_text, list(methods), figures, pooled, judged,
                       periods[0].start if periods else 0)
