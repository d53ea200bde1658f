"""A thermal log's operating regimes, found from its data: runs, heating, dwell, cooling,
and the spindle's programs; and how far a model's inputs leave their training range.

A thermal model fitted while the machine heats is later used while it cools, runs another
program or starts another day. Zhu (2008) tests a model's robustness the same way: fitted
on one working condition, judged on others (ch. 3's robustness tests). The regimes found
here are what a candidate is judged on when it was not fitted on them
(:func:`leave_one_regime_out`), and what the output names when a model is used outside
what it saw (:func:`range_excess`, :func:`sensors_leaving_range`).

Rules, all on the data:

- **runs** (a run column, or the clock's jumps) are regimes of their own;
- inside a run, the **trend** of the structure's mean temperature: its rate, smoothed over
  a window of a fiftieth of the run (at least :data:`MIN_WINDOW_ROWS` rows), above a tenth
  of the run's largest rate is heating, below minus that cooling, between them dwell;
- a **spindle program** is a stretch of one speed level (levels a tenth of the largest
  speed apart);
- stretches shorter than :data:`MIN_SHARE` of the log's rows join their neighbour.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from numpy.typing import NDArray

#: A stretch shorter than this share of the rows joins the one before it.
MIN_SHARE = 0.04

#: The trend's smoothing window, at least (rows).
MIN_WINDOW_ROWS = 5

#: A rate below this share of the run's largest is a dwell.
DWELL_SHARE = 0.1

#: A run whose mean temperature moves less than this over its whole length dwells [K].
STILL_K = 0.2

#: Spindle speeds closer than this share of the largest are one program.
SPEED_LEVEL_SHARE = 0.1


@dataclasses.dataclass(frozen=True)
class Regime:
    """One stretch of a log in one regime.

    Attributes
    ----------
    kind : str
        "heating", "dwell" or "cooling", with the program when a speed was given
        ("heating at 3000 rpm").
    start, stop : int
        Its rows, ``start`` to ``stop - 1``.
    run : int
        Its run's index (0 without runs).
    """

    kind: str
    start: int
    stop: int
    run: int

    @property
    def trend(self) -> str:
        """"heating", "dwell" or "cooling"."""
        return self.kind.split(" at ")[0]

    @property
    def program(self) -> str:
        """The spindle program ("3000 rpm"), "" without a speed."""
        return self.kind.split(" at ")[1] if " at " in self.kind else ""

    def rows_text(self, data_rows: NDArray[np.intp] | None = None) -> str:
        """The stretch's rows as a user reads them.

        Parameters
        ----------
        data_rows : ndarray of int, shape (N,), optional
            Each row's number in the file (default 1..N).

        Returns
        -------
        str
            "rows 12-340".
        """
        first, last = (self.start + 1, self.stop) if data_rows is None else \
            (int(data_rows[self.start]), int(data_rows[self.stop - 1]))
        return f"rows {first}-{last}"


@dataclasses.dataclass
class Regimes:
    """A log's regimes, row by row.

    Attributes
    ----------
    stretches : list of Regime
        In row order, covering every row.
    group_of_row : ndarray of int, shape (N,)
        The validation group of each row: the run when there are several runs, else the
        kind (every heating stretch one group, every cooling one another ...).
    group_names : list of str
        The groups' names ("run 'day 3'", "heating").
    by : str
        What the groups are: "runs", "trend" (heating, dwell, cooling), "program"
        (spindle speed levels) or "one regime".
    """

    stretches: list[Regime]
    group_of_row: NDArray[np.intp]
    group_names: list[str]
    by: str

    @property
    def kinds(self) -> list[str]:
        """The kinds present, in order of first appearance."""
        return list(dict.fromkeys(s.kind for s in self.stretches))

    def labels_in(self, rows: NDArray[np.bool_], part: str) -> list[str]:
        """The labels of one part of the stretches that hold any of ``rows``.

        Parameters
        ----------
        rows : ndarray of bool, shape (N,)
            The rows asked about.
        part : {"trend", "program"}
            Which part of a stretch's kind.

        Returns
        -------
        list of str
            In order of first appearance (no empty program).
        """
        return [label for label in dict.fromkeys(getattr(s, part) for s in self.stretches
                                                 if rows[s.start:s.stop].any()) if label]

    def text(self, data_rows: NDArray[np.intp] | None = None, shown: int = 8) -> str:
        """The stretches in words.

        Parameters
        ----------
        data_rows : ndarray of int, shape (N,), optional
            Each row's number in the file (default 1..N).
        shown : int, optional
            Stretches named at most.

        Returns
        -------
        str
            "heating rows 1-300, dwell rows 301-420, ..." (the first ``shown``).
        """
        parts = [f"{s.kind} {s.rows_text(data_rows)}" for s in self.stretches[:shown]]
        more = len(self.stretches) - shown
        return ", ".join(parts) + (f" and {more} more" if more > 0 else "")


def smoothed(values: NDArray[np.float64], window: int) -> NDArray[np.float64]:
    """A centred moving average, the ends over the rows there are (no padding that would
    bend the trend at a run's ends).

    Parameters
    ----------
    values : ndarray, shape (n,)
        Any signal, any unit.
    window : int
        The average's width [rows].

    Returns
    -------
    ndarray, shape (n,)
        The smoothed signal, same unit.
    """
    window = max(1, min(int(window), values.size))
    cumulative = np.concatenate([[0.0], np.cumsum(values)])
    half = window // 2
    low = np.clip(np.arange(values.size) - half, 0, values.size)
    high = np.clip(np.arange(values.size) - half + window, 0, values.size)
    return (cumulative[high] - cumulative[low]) / (high - low)


def trend_kinds(time_s: NDArray[np.float64], mean_c: NDArray[np.float64]) -> NDArray[np.str_]:
    """Each row's trend in one run (rules in the module docstring).

    Parameters
    ----------
    time_s : ndarray, shape (n,)
        The run's time [s].
    mean_c : ndarray, shape (n,)
        The structure's mean temperature [degC].

    Returns
    -------
    ndarray of str, shape (n,)
        "heating", "dwell" or "cooling".
    """
    n = mean_c.size
    kinds = np.full(n, "dwell", dtype=object)
    if n < 3 or np.ptp(mean_c) < STILL_K:
        return kinds
    window = max(MIN_WINDOW_ROWS, n // 50)
    level = smoothed(mean_c, window)
    step = max(1, window // 4)
    # The rate over ``2 step`` rows of the smoothed mean: steadier than row-to-row
    # differences of a noisy mean, and a boundary found within ``step`` rows of where the
    # trend turns.
    ahead = np.minimum(np.arange(n) + step, n - 1)
    behind = np.maximum(np.arange(n) - step, 0)
    span = time_s[ahead] - time_s[behind]
    rate = np.where(span > 0, (level[ahead] - level[behind]) / np.where(span > 0, span, 1.0),
                    0.0)
    threshold = DWELL_SHARE * float(np.max(np.abs(rate)))
    kinds[rate > threshold] = "heating"
    kinds[rate < -threshold] = "cooling"
    return kinds


def speed_levels(speed: NDArray[np.float64]) -> NDArray[np.float64]:
    """Each row's spindle program: its speed rounded to levels :data:`SPEED_LEVEL_SHARE` of
    the largest speed apart.

    Parameters
    ----------
    speed : ndarray, shape (n,)
        The spindle speed, any unit.

    Returns
    -------
    ndarray, shape (n,)
        Each row's level, the speed's unit.
    """
    top = float(np.nanmax(np.abs(speed))) if np.isfinite(speed).any() else 0.0
    if top <= 0.0:
        return np.zeros(speed.size)
    quantum = SPEED_LEVEL_SHARE * top
    return np.round(np.nan_to_num(speed) / quantum) * quantum


def _stretches_of(labels: list[str], run_of_row: NDArray[np.intp], min_rows: int
                  ) -> list[Regime]:
    """Contiguous stretches of equal label and run; those shorter than ``min_rows`` join
    the stretch before them in their run (or after, at a run's start)."""
    out: list[Regime] = []
    start = 0
    n = len(labels)
    for k in range(1, n + 1):
        if k == n or labels[k] != labels[start] or run_of_row[k] != run_of_row[start]:
            out.append(Regime(labels[start], start, k, int(run_of_row[start])))
            start = k
    merged: list[Regime] = []
    for stretch in out:
        short = stretch.stop - stretch.start < min_rows
        if merged and merged[-1].run == stretch.run and \
                (short or merged[-1].kind == stretch.kind):
            last = merged.pop()
            merged.append(dataclasses.replace(last, stop=stretch.stop))
        else:
            merged.append(stretch)
    # A short first stretch of a run joins the one after it.
    final: list[Regime] = []
    for stretch in merged:
        if final and final[-1].run == stretch.run and \
                final[-1].stop - final[-1].start < min_rows:
            last = final.pop()
            final.append(Regime(stretch.kind, last.start, stretch.stop, stretch.run))
        else:
            final.append(stretch)
    return final


def find_regimes(time_s: NDArray[np.float64], temperatures: dict[str, NDArray[np.float64]],
                 run_of_row: NDArray[np.intp] | None = None,
                 run_names: list[str] | None = None,
                 speed: NDArray[np.float64] | None = None, speed_unit: str = "rad/s"
                 ) -> Regimes:
    """The regimes of a log (rules in the module docstring).

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        Time of each row [s] (may restart at each run).
    temperatures : dict of str to ndarray, shape (N,)
        The live sensors [degC] (NaN where a reading is missing).
    run_of_row : ndarray of int, shape (N,), optional
        Run index of each row (runs contiguous, from 0); None for one run.
    run_names : list of str, optional
        The runs' names.
    speed : ndarray, shape (N,), optional
        The spindle speed (its programs split the trend's stretches).
    speed_unit : str, optional
        The speed's unit, for the kinds' names.

    Returns
    -------
    Regimes
        The stretches and the validation groups.
    """
    n = time_s.size
    runs = np.zeros(n, dtype=np.intp) if run_of_row is None else np.asarray(run_of_row)
    stacked = np.array([v for v in temperatures.values()]) if temperatures else np.zeros((1, n))
    finite = np.isfinite(stacked)
    mean_c = np.where(finite, stacked, 0.0).sum(axis=0) / np.maximum(finite.sum(axis=0), 1)
    labels = np.full(n, "dwell", dtype=object)
    for run in np.unique(runs):
        rows = np.flatnonzero(runs == run)
        labels[rows] = trend_kinds(np.asarray(time_s[rows], float), mean_c[rows])
    programs = speed_levels(np.asarray(speed, float)) if speed is not None else None
    if programs is not None and np.unique(programs).size >= 2:
        to_rpm = 60.0 / (2.0 * np.pi) if speed_unit == "rad/s" else 1.0
        labels = np.array([f"{kind} at {level * to_rpm:.0f} rpm"
                           for kind, level in zip(labels, programs)], dtype=object)
    stretches = _stretches_of(list(labels), runs, max(3, int(MIN_SHARE * n)))
    return _grouped(stretches, runs, run_names, n, programs is not None and
                    np.unique(programs).size >= 2)


def _grouped(stretches: list[Regime], runs: NDArray[np.intp], run_names: list[str] | None,
             n: int, with_programs: bool) -> Regimes:
    """The validation groups of ``stretches``: runs when there are several, else kinds."""
    group_of_row = np.zeros(n, dtype=np.intp)
    if np.unique(runs).size >= 2:
        names = [f"run {run_names[k]!r}" if run_names else f"run {k + 1}"
                 for k in range(int(runs.max()) + 1)]
        return Regimes(stretches, runs.astype(np.intp).copy(), names, "runs")
    kinds = list(dict.fromkeys(s.kind for s in stretches))
    for stretch in stretches:
        group_of_row[stretch.start:stretch.stop] = kinds.index(stretch.kind)
    by = "one regime" if len(kinds) < 2 else ("program" if with_programs else "trend")
    return Regimes(stretches, group_of_row, kinds, by)


def range_excess(fit: NDArray[np.float64], judged: NDArray[np.float64]) -> float:
    """How far ``judged`` (m, P) rows leave the range of ``fit`` (n, P) rows, as a share
    of that range: the 95th percentile over the judged rows of each row's largest excess
    over a column's [min, max] divided by the column's span (0 inside the range; 1.0 a
    whole span beyond it). Constant fitted columns (an offset) are not inputs: skipped.

    Parameters
    ----------
    fit : ndarray, shape (n, P)
        The inputs the model was fitted on.
    judged : ndarray, shape (m, P)
        The inputs it is used on.

    Returns
    -------
    float
        The excess, a share of the span (0 when ``judged`` is empty).
    """
    if judged.shape[0] == 0 or fit.shape[0] == 0:
        return 0.0
    low, high = np.nanmin(fit, axis=0), np.nanmax(fit, axis=0)
    span = high - low
    moving = span > 1e-12 * np.maximum(np.abs(high), 1.0)
    if not moving.any():
        return 0.0
    beyond = np.maximum(judged[:, moving] - high[moving], low[moving] - judged[:, moving])
    excess = np.max(np.maximum(beyond, 0.0) / span[moving], axis=1)
    return float(np.nanpercentile(excess, 95))


@dataclasses.dataclass(frozen=True)
class SensorExcess:
    """A sensor read beyond its training range on the judged rows.

    Attributes
    ----------
    sensor : str
        Its name.
    low_c, high_c : float
        Its training range [degC].
    reached_c : float
        The reading farthest outside it on the judged rows [degC].
    share : float
        How far beyond, a share of the training range's span.
    """

    sensor: str
    low_c: float
    high_c: float
    reached_c: float
    share: float

    def text(self) -> str:
        """"t3 reached 41.2 degC, trained on 22.0-35.1 (0.47 of that span beyond)"."""
        return (f"{self.sensor} reached {self.reached_c:.4g} degC, trained on "
                f"{self.low_c:.4g}-{self.high_c:.4g} ({self.share:.2g} of that span beyond)")


def sensors_leaving_range(temperatures: dict[str, NDArray[np.float64]],
                          train: NDArray[np.bool_], judged: NDArray[np.bool_],
                          least: float = 0.1) -> list[SensorExcess]:
    """The sensors whose readings on ``judged`` rows leave their range on ``train`` rows by
    ``least`` of its span or more, farthest first.

    Parameters
    ----------
    temperatures : dict of str to ndarray, shape (N,)
        The sensors [degC].
    train, judged : ndarray of bool, shape (N,)
        The rows fitted on, the rows judged.
    least : float, optional
        The smallest excess named (a share of the span).

    Returns
    -------
    list of SensorExcess
        Farthest first.
    """
    out = []
    for name, values in temperatures.items():
        fitted, used = values[train], values[judged]
        fitted, used = fitted[np.isfinite(fitted)], used[np.isfinite(used)]
        if fitted.size < 2 or used.size == 0:
            continue
        low, high = float(fitted.min()), float(fitted.max())
        span = max(high - low, 1e-9)
        above, below = float(used.max()) - high, low - float(used.min())
        share = max(above, below) / span
        if share >= least:
            reached = float(used.max()) if above >= below else float(used.min())
            out.append(SensorExcess(name, low, high, reached, share))
    return sorted(out, key=lambda e: -e.share)
