"""`mt-accuracy check LOG.csv --target COLUMN --walk-forward PERIOD`: the log replayed in time.

At each period's end the workbench makes its model again from every row so far - the same
search a check makes on its training rows (:func:`~.check_log.search_log`), as the monitor
does live with new reference readings - and the model predicts the next period, which no
decision saw. Beside it, on the same periods, the baselines a user would otherwise run:

- **constant**: the mean of every row so far;
- **least squares on every input**: every live sensor's rise, and an offset, fitted by
  least squares on every row so far;
- **no model**: nothing compensated, the displacement from the log's first reading (from
  each run's first, when the runs were zeroed).

The arithmetic of the walk is :mod:`~mt_accuracy_ros.core.workbench.walk_forward`'s.
"""
from __future__ import annotations

import dataclasses

import numpy as np

from ..core.workbench.walk_forward import WalkForward, walk_forward, walk_periods

#: The methods of a walk-forward, in the order printed.
METHODS = ("workbench", "constant", "least squares on every input", "no model")

#: Rows a period's fit needs before the walk predicts it (the selection's 8, and some).
MIN_TRAIN_ROWS = 20


def no_model_residual(obs) -> np.ndarray:
    """The displacement left with nothing compensated (N,) [m]: from the log's first reading,
    or each run's first when the runs were zeroed."""
    c = int(np.flatnonzero(obs.measured_mask[0])[0])
    measured = obs.measured_m[:, c]
    return measured if obs.zeroed_runs else measured - measured[0]


def walk_periods_of_log(log, period_s: float | None) -> list:
    """The periods a walk-forward of the read ``log`` predicts (``period_s`` [s], None:
    each run), once :data:`MIN_TRAIN_ROWS` rows (a tenth of a short log) lie before them.

    Raises
    ------
    InputDataError
        A period that leaves fewer than two periods to predict; ``run`` without runs.
    """
    obs = log.obs
    return walk_periods(obs.time_s, period_s, obs.run_of_row,
                        min(MIN_TRAIN_ROWS, max(8, obs.n // 10)), log.run_names)


def walk_forward_of_log(log, periods: list, period_text: str, options,
                        progress=None) -> WalkForward:
    """The walk-forward of a read log (:class:`~.check_log.LogData`) with the search
    ``options`` (:class:`~.check_log.SearchOptions`).

    Parameters
    ----------
    log : LogData
        The log, read and judged (:func:`~.check_log.read_log`).
    periods : list of Period
        The periods to predict (:func:`walk_periods_of_log`).
    period_text : str
        The period as asked, for the output.
    options : SearchOptions
        What the search may add.
    progress : callable, optional
        Called with one line per period.

    Returns
    -------
    WalkForward
        Per period and pooled, for :data:`METHODS`.
    """
    from ..core.workbench.thermal_log import (all_inputs_least_squares_residual,
                                              held_out_residual, log_model)
    from .check_log import search_log

    obs = log.obs
    empty = log_model(obs)
    untouched = no_model_residual(obs)

    def workbench(train):
        # A log of its own per period: the search's notes are not the check's.
        searched = search_log(dataclasses.replace(log, notes=[]), train, options)
        added = [name for step in searched.progress.steps for name in step.added or []]
        return (held_out_residual(searched.progress.model, obs, train),
                ", ".join(added) or "nothing added")

    methods = {"workbench": workbench,
               "constant": lambda train: (held_out_residual(empty, obs, train), ""),
               "least squares on every input":
                   lambda train: (all_inputs_least_squares_residual(obs, train), ""),
               "no model": lambda train: (untouched, "")}
    return walk_forward(obs.n, periods, methods, period_text, progress)


def walk_forward_lines(walk: WalkForward, unit: str, scale: float) -> list[str]:
    """The printed lines of a walk-forward: one per period, the pooled figures, and whether
    the workbench beat both the constant and least squares."""
    head = "  ".join(f"{m:>12.12s}" for m in walk.methods)
    lines = [f"walk-forward, each {walk.period_text} predicted by a fit on every row before it "
             f"(RMS, {unit}; first fit on {walk.first_fit_rows} rows):",
             f"  {'period':>18s} {'rows':>6s}  {head}"]
    for figures in walk.periods:
        period = figures.period
        row = "  ".join(f"{figures.rmse_m[m] * scale:12.4g}" for m in walk.methods)
        lines.append(f"  {period.label[:18]:>18s} {period.stop - period.start:6d}  {row}")
    pooled = "  ".join(f"{walk.pooled_m[m] * scale:12.4g}" for m in walk.methods)
    lines.append(f"  {'pooled':>18s} {walk.judged_rows:6d}  {pooled}")
    baselines = ["constant", "least squares on every input"]
    better = walk.wins_over("workbench", baselines)
    lines.append("walk-forward: the workbench " + ("beats" if better else "does not beat") +
                 " both the constant and least squares on every input, pooled "
                 f"({walk.pooled_m['workbench'] * scale:.4g} against "
                 f"{walk.pooled_m['constant'] * scale:.4g} and "
                 f"{walk.pooled_m['least squares on every input'] * scale:.4g} {unit})")
    return lines
