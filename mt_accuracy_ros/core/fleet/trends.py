"""Trends of a fleet: each machine's model-versus-measurement error over its days.

A machine *drifts* (deteriorates) when the RMS error of its model against its
reference readings grows from day to day by more than the day-to-day scatter
explains: the least-squares slope over the days is positive and at least
``DRIFT_T`` standard errors from zero (three days or more), or, on two days only,
the error grew by more than ``TWO_DAY_RATIO``. A machine whose error is steady
(a well-kept machine, or one whose model holds its effects) is not flagged.

Pure functions on plain numbers [m, days]; no file, no ROS, no Dask.
"""
from __future__ import annotations

from collections import defaultdict
from dataclasses import dataclass

import numpy as np

#: Slope / standard error beyond which a rising error is called a drift.
DRIFT_T = 2.0
#: With two days only: the error must grow by this factor to be called a drift.
TWO_DAY_RATIO = 1.5


@dataclass(frozen=True)
class Trend:
    """A machine's error over its days.

    Attributes
    ----------
    days : int
        Days with a diagnosis.
    slope_m_per_day : float
        Least-squares slope of the day's RMS error [m/day] (0 with one day).
    slope_standard_error_m_per_day : float
        Its standard error [m/day] (inf with two days or fewer).
    first_m, last_m : float
        The first and the last day's RMS error [m].
    drifting : bool
        See the module docstring.
    """

    days: int
    slope_m_per_day: float
    slope_standard_error_m_per_day: float
    first_m: float
    last_m: float
    drifting: bool

    def as_dict(self) -> dict:
        """Plain values (JSON): an infinite standard error is None."""
        spread = self.slope_standard_error_m_per_day
        return {"days": self.days, "slope_m_per_day": self.slope_m_per_day,
                "slope_standard_error_m_per_day": spread if np.isfinite(spread) else None,
                "first_m": self.first_m, "last_m": self.last_m, "drifting": self.drifting}


def error_trend(day_numbers, rmse_m) -> Trend:
    """The :class:`Trend` of one machine.

    Parameters
    ----------
    day_numbers : array_like, shape (n,)
        Each diagnosed day as a number of days (a date's ordinal, or the order of
        undated files) [day]; need not be consecutive.
    rmse_m : array_like, shape (n,)
        That day's RMS error of the model against the readings [m].

    Returns
    -------
    Trend
        Slope [m/day] with its standard error, first and last error [m], drifting.

    Raises
    ------
    ValueError
        Lengths that differ, no day, or non-finite values.
    """
    days = np.asarray(day_numbers, dtype=np.float64)
    error = np.asarray(rmse_m, dtype=np.float64)
    if days.shape != error.shape or days.ndim != 1:
        raise ValueError(f"day_numbers {days.shape} and rmse_m {error.shape}: one value each")
    if days.size == 0:
        raise ValueError("a trend needs at least one day")
    if not (np.all(np.isfinite(days)) and np.all(np.isfinite(error))):
        raise ValueError("day numbers and errors must be finite")
    order = np.argsort(days, kind="stable")
    days, error = days[order], error[order]
    n = days.size
    if n == 1 or np.ptp(days) == 0:
        return Trend(n, 0.0, float("inf"), float(error[0]), float(error[-1]), False)
    centred = days - days.mean()
    slope = float(centred @ (error - error.mean()) / (centred @ centred))
    if n == 2:
        drifting = bool(error[1] > TWO_DAY_RATIO * error[0])
        return Trend(n, slope, float("inf"), float(error[0]), float(error[1]), drifting)
    residual = error - error.mean() - slope * centred
    sigma2 = float(residual @ residual) / (n - 2)
    standard_error = float(np.sqrt(sigma2 / (centred @ centred)))
    drifting = bool(slope > 0 and slope > DRIFT_T * standard_error)
    return Trend(n, slope, standard_error, float(error[0]), float(error[-1]), drifting)


def rank_by_drift(trends: dict[str, Trend]) -> list[str]:
    """Machine names, the drifting ones first, each group by falling slope.

    Parameters
    ----------
    trends : dict of str to Trend
        Each machine's trend (:func:`error_trend`); slopes in m/day.

    Returns
    -------
    list of str, len(trends)
        The machines' names in that order (ties by name).
    """
    return sorted(trends, key=lambda name: (not trends[name].drifting,
                                            -trends[name].slope_m_per_day, name))


def common_effects(named_by_machine: dict[str, list[str]], least: int = 2
                   ) -> list[tuple[str, list[str]]]:
    """Effects named on at least ``least`` machines, most shared first.

    Parameters
    ----------
    named_by_machine : dict of str to list of str
        Machine -> the names of the effects named on any of its days (repeats are
        counted once per machine).
    least : int
        The fewest machines an effect must be named on to be listed.

    Returns
    -------
    list of (str, list of str)
        (effect, the machines it was named on, sorted), by falling count, then name.
    """
    machines = defaultdict(set)
    for machine, names in named_by_machine.items():
        for name in names:
            machines[name].add(machine)
    shared = [(name, sorted(owners)) for name, owners in machines.items()
              if len(owners) >= least]
    return sorted(shared, key=lambda item: (-len(item[1]), item[0]))
