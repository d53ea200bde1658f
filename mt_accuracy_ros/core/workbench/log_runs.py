"""A log made of many runs: a day, a shift, an experiment - each a fresh start.

Shops log a machine's warm-up day after day: each day starts cold, its time
restarts (or jumps over the night), and a dial gauge is often zeroed at the
start of each run. Stitched end to end such a log lies: a lag carried over
the night, a "drift with time" across days, one zero for readings that had
eighteen. Here every run is its own record:

* :func:`run_labels` turns a run column into contiguous runs, refusing a run
  whose rows are not together, a run of one row, and a time that goes back
  inside a run (between runs it may restart);
* :func:`stitched_time` lays the runs one after the other for plotting and
  for the engine's ordering, while lags and ``t`` restart per run
  (:class:`~..effects.variables.Variables` with ``run_starts``);
* :func:`split_at_run` puts ``train_fraction`` at the nearest run boundary,
  and :func:`run_blocks` makes whole runs the blocks of forward validation;
* :func:`mixed_units_problem` names a run whose readings are in another unit
  than the others' (a day logged in mm among days in um; a sensor in degF) -
  for a sensor only when the run, converted, matches the other runs
  (:func:`unit_slip_of_run`); a run merely hotter is said (:func:`run_level_notes`);
* :func:`clock_breaks` finds a clock that jumps (a logger restarted days later: a
  break between runs) and names equal stamps with their rows;
* :func:`leave_out_dead_sensors` judges every sensor by the one rule of
  :mod:`~..inputs.sensor_health`.
"""
from __future__ import annotations

import numpy as np
from numpy.typing import ArrayLike, NDArray

from ..errors import InputDataError

#: Fewest rows of a run (a run of one row has no change to explain).
MIN_RUN_ROWS = 2

#: A run whose target spreads this many times more (or less) than the median run's
#: is taken for a unit slip: a day in mm among days in um is 1000x.
UNIT_SLIP_RATIO = 200.0

#: A run whose sensor sits this far [K] from every other run's level is taken for a
#: unit slip (degF, K), not for weather.
TEMPERATURE_SLIP_K = 40.0


def run_labels(values: ArrayLike, data_rows: ArrayLike | None = None,
               column: str = "run") -> tuple[NDArray[np.intp], list[str]]:
    """(run index per row (N,), run names in order) from a run column (N,).

    Rows of one run share a value and lie together. ``data_rows`` (N,) are the
    rows' numbers in the file, for the errors (default 1..N).

    Parameters
    ----------
    values : array_like, shape (N,)
        The run column (compared as stripped text).
    data_rows : array_like of int, shape (N,), optional
        The rows' numbers in the file, for the errors (default 1..N).
    column : str, optional
        The run column's name, for the errors.

    Returns
    -------
    tuple of (ndarray of int, shape (N,), list of str)
        Run index per row (from 0), and the runs' names in order.

    Raises
    ------
    InputDataError
        A run whose rows are not together (a gap), or a run of one row.
    """
    labels = [str(v).strip() for v in np.asarray(values, dtype=object)]
    rows = np.arange(1, len(labels) + 1) if data_rows is None else np.asarray(data_rows)
    if not labels:
        return np.zeros(0, dtype=np.intp), []
    names: list[str] = []
    first_row: dict[str, int] = {}
    index = np.empty(len(labels), dtype=np.intp)
    for i, label in enumerate(labels):
        if i == 0 or label != labels[i - 1]:
            if label in first_row:
                last = max(j for j in range(i) if labels[j] == label)
                raise InputDataError(
                    f"the {column} column has a gap: run {label!r} at data rows "
                    f"{int(rows[first_row[label]])}-{int(rows[last])}, again at data row "
                    f"{int(rows[i])} (each run's rows must lie together; sort the file by run)")
            first_row[label] = i
            names.append(label)
        index[i] = len(names) - 1
    counts = np.bincount(index, minlength=len(names))
    short = np.flatnonzero(counts < MIN_RUN_ROWS)
    if short.size:
        k = int(short[0])
        raise InputDataError(f"run {names[k]!r} of the {column} column has {int(counts[k])} row "
                             f"(data row {int(rows[first_row[names[k]]])}): a run needs at "
                             f"least {MIN_RUN_ROWS}")
    return index, names


def run_starts(run_of_row: NDArray[np.intp]) -> NDArray[np.intp]:
    """(R,) the first row of each run.

    Parameters
    ----------
    run_of_row : ndarray of int, shape (N,)
        Run index of each row (runs contiguous, from 0).

    Returns
    -------
    ndarray of int, shape (R,)
        Row index of each run's first row.
    """
    run_of_row = np.asarray(run_of_row)
    return np.concatenate(([0], np.flatnonzero(np.diff(run_of_row) != 0) + 1)).astype(np.intp)


def stitched_time(time_s: NDArray[np.float64], run_of_row: NDArray[np.intp],
                  names: list[str], data_rows: ArrayLike | None = None) -> NDArray[np.float64]:
    """Runs laid end to end (N,) [s]: each starts one of its own median steps after the
    previous run's end, its time relative to its first row. A time that goes back inside
    a run is refused, naming the row.

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        The log's time [s].
    run_of_row : ndarray of int, shape (N,)
        Run index of each row (runs contiguous, from 0).
    names : list of str
        The runs' names, in order.
    data_rows : array_like of int, shape (N,), optional
        The rows' numbers in the file, for the messages (default 1..N).

    Returns
    -------
    ndarray, shape (N,)
        Stitched time [s], from 0.

    Raises
    ------
    InputDataError
        A time that goes back inside a run.
    """
    t = np.asarray(time_s, dtype=np.float64)
    rows = np.arange(1, t.size + 1) if data_rows is None else np.asarray(data_rows)
    out = np.empty_like(t)
    starts = list(run_starts(run_of_row)) + [t.size]
    offset = 0.0
    for k, (a, b) in enumerate(zip(starts[:-1], starts[1:])):
        local = t[a:b] - t[a]
        back = np.flatnonzero(np.diff(local) < 0)
        if back.size:
            j = a + int(back[0]) + 1
            raise InputDataError(f"the time goes back inside run {names[k]!r} at data row "
                                 f"{int(rows[j])}: {t[j]:g} s after {t[j - 1]:g} s (between "
                                 "runs it may restart; inside one it must not)")
        steps = np.diff(local)
        step = float(np.median(steps[steps > 0])) if np.any(steps > 0) else 1.0
        out[a:b] = offset + local
        offset = float(out[b - 1]) + step
    return out


def split_at_run(run_of_row: NDArray[np.intp], fraction: float) -> NDArray[np.bool_]:
    """(N,) training rows: the runs before the run boundary nearest ``fraction`` of the rows,
    at least one run on each side.

    Parameters
    ----------
    run_of_row : ndarray of int, shape (N,)
        Run index of each row (runs contiguous, from 0).
    fraction : float
        Share of the rows wanted for training, in (0, 1).

    Returns
    -------
    ndarray of bool, shape (N,)
        True on the training rows.

    Raises
    ------
    InputDataError
        Fewer than two runs (nothing to judge by whole runs).
    """
    run_of_row = np.asarray(run_of_row)
    starts = run_starts(run_of_row)
    if starts.size < 2:
        raise InputDataError("one run: whole runs cannot judge one another (give a log of "
                             "several runs, or leave --run out)")
    boundaries = starts[1:]
    cut = int(boundaries[np.argmin(np.abs(boundaries - fraction * run_of_row.size))])
    return np.arange(run_of_row.size) < cut


def run_blocks(run_of_row: NDArray[np.intp], max_blocks: int) -> NDArray[np.intp] | None:
    """(N,) forward-validation block of each row: whole runs, grouped into at most
    ``max_blocks`` contiguous blocks of near-equal rows (None with one run).

    Parameters
    ----------
    run_of_row : ndarray of int, shape (N,)
        Run index of each row (runs contiguous, from 0).
    max_blocks : int
        Most blocks.

    Returns
    -------
    ndarray of int, shape (N,), or None
        Block of each row, 0, 1, ... in time order; None with one run.
    """
    run_of_row = np.asarray(run_of_row)
    starts = run_starts(run_of_row)
    runs = starts.size
    if runs < 2:
        return None
    count = min(runs, max_blocks)
    # A run joins the block its first row falls in (equal cuts of the rows), then the
    # blocks are renumbered 0, 1, ... so that none is empty.
    block_of_run = (starts * count) // run_of_row.size
    block_of_run = np.concatenate(([0], np.cumsum(np.diff(block_of_run) > 0)))
    position = np.searchsorted(starts, np.arange(run_of_row.size), side="right") - 1
    return block_of_run[position].astype(np.intp)


def mixed_units_problem(target: NDArray[np.float64], temperatures: dict[str, NDArray],
                        run_of_row: NDArray[np.intp], names: list[str],
                        zeroed: bool) -> str:
    """One line naming a run in another unit than the others', or "".

    The target: a run whose spread (its range; or, absolute, its level too) is
    :data:`UNIT_SLIP_RATIO` times the median run's or more, either way. A sensor: a run
    whose readings, mapped by a unit slip's conversion (:func:`unit_slip_of_run`), match
    the other runs' while its raw readings do not - a different process (a hotter day)
    is not a unit slip.

    Parameters
    ----------
    target : ndarray, shape (N,)
        The measured error, in the log's unit (only ratios between runs are used).
    temperatures : dict of str to ndarray, shape (N,)
        Sensor name -> readings [degC].
    run_of_row : ndarray of int, shape (N,)
        Run index of each row (runs contiguous, from 0).
    names : list of str
        The runs' names, in order.
    zeroed : bool
        Whether the target was zeroed per run (not read: each run's range is compared
        either way).

    Returns
    -------
    str
        The line, or "".
    """
    starts = list(run_starts(run_of_row)) + [run_of_row.size]
    slices = [slice(a, b) for a, b in zip(starts[:-1], starts[1:])]
    if len(slices) >= 3:
        spreads = np.array([float(np.ptp(target[s])) for s in slices])
        usual = float(np.median(spreads))
        for k, spread in enumerate(spreads):
            if usual > 0 and spread > 0 and (spread / usual >= UNIT_SLIP_RATIO or
                                              usual / spread >= UNIT_SLIP_RATIO):
                return (f"run {names[k]!r}: its target spans {spread / usual:.3g}x the median "
                        "run's - mixed units across runs? (mm among um: 1000x); convert it")
    if len(slices) >= 2:
        for sensor, values in temperatures.items():
            for k, run in enumerate(slices):
                rest = np.concatenate([values[s] for j, s in enumerate(slices) if j != k])
                slip = unit_slip_of_run(values[run], rest,
                                        [values[s] for j, s in enumerate(slices) if j != k])
                if slip:
                    unit, converted = slip
                    own = values[run][np.isfinite(values[run])]
                    return (f"run {names[k]!r}: sensor {sensor} reads {np.median(own):.4g} "
                            f"where the other runs read {np.nanmedian(rest):.4g} - mixed "
                            f"units across runs? ({unit}: converted it reads "
                            f"{converted:.4g} degC, as the others do); give every run in "
                            "degC")
    return ""


def run_level_notes(temperatures: dict[str, NDArray], run_of_row: NDArray[np.intp],
                    names: list[str]) -> list[str]:
    """One note per sensor whose level in a run lies :data:`TEMPERATURE_SLIP_K` or more
    from the other runs' while no unit slip maps it onto them (:func:`unit_slip_of_run`):
    a different process (a hotter day, a machine at work), said and kept.

    Parameters
    ----------
    temperatures : dict of str to ndarray, shape (N,)
        Sensor name -> readings [degC].
    run_of_row : ndarray of int, shape (N,)
        Run index of each row (runs contiguous, from 0).
    names : list of str
        The runs' names, in order.

    Returns
    -------
    list of str
        The notes (at most one per sensor).
    """
    starts = list(run_starts(run_of_row)) + [run_of_row.size]
    slices = [slice(a, b) for a, b in zip(starts[:-1], starts[1:])]
    notes = []
    for sensor, values in temperatures.items():
        for k, run in enumerate(slices):
            own = values[run][np.isfinite(values[run])]
            rest = np.concatenate([values[s] for j, s in enumerate(slices) if j != k])
            rest = rest[np.isfinite(rest)]
            if own.size and rest.size and \
                    abs(np.median(own) - np.median(rest)) >= TEMPERATURE_SLIP_K:
                notes.append(f"run {names[k]!r}: sensor {sensor} reads {np.median(own):.4g} "
                             f"where the other runs read {np.median(rest):.4g}; no unit slip "
                             "(K, degF) maps one onto the other: taken as a different process")
                break
    return notes


#: Unit slips of a temperature: unit -> (degC from it, where its raw readings of a
#: machine's structure lie [unit]).
TEMPERATURE_SLIPS = {"K": (lambda v: v - 273.15, (250.0, 400.0)),
                     "degF": (lambda v: (v - 32.0) / 1.8, (14.0, 248.0))}


def unit_slip_of_run(run: NDArray[np.float64], rest: NDArray[np.float64],
                     other_runs: list[NDArray[np.float64]]) -> tuple[str, float] | None:
    """(the unit, the run's median converted [degC]) when one run's readings are another
    unit's, else None.

    A unit slip is an affine map over a whole run: the run's raw readings lie outside the
    other runs' range (widened by :data:`TEMPERATURE_SLIP_K`/8), lie where only that unit
    puts a structure's temperature, and - converted - fall inside the others' range with
    a spread like theirs (when they spread by a kelvin or more) and their coolest readings
    nearer the others' coolest than the raw ones (a run that ran hotter starts where the
    others start).

    Parameters
    ----------
    run : ndarray, shape (n,)
        One run's readings of a sensor, as given (unit unknown; degC expected).
    rest : ndarray, shape (m,)
        The other runs' readings of that sensor [degC].
    other_runs : list of ndarray
        The other runs' readings, run by run [degC].

    Returns
    -------
    tuple of (str, float) or None
        (``"K"`` or ``"degF"``, the run's converted median [degC]), or None.
    """
    run, rest = run[np.isfinite(run)], rest[np.isfinite(rest)]
    if run.size < 2 or rest.size < 2:
        return None
    tolerance = TEMPERATURE_SLIP_K / 8.0
    low, high = np.percentile(rest, [1, 99])
    low, high = low - tolerance, high + tolerance
    if low <= np.median(run) <= high:
        return None
    spreads = [np.ptp(r[np.isfinite(r)]) for r in other_runs if np.isfinite(r).sum() >= 2]
    usual_spread = float(np.median(spreads)) if spreads else 0.0
    for unit, (to_celsius, (raw_low, raw_high)) in TEMPERATURE_SLIPS.items():
        if not (raw_low <= np.percentile(run, 1) and np.percentile(run, 99) <= raw_high):
            continue
        converted = to_celsius(run)
        inside = low <= np.percentile(converted, 5) and np.percentile(converted, 95) <= high
        alike = usual_spread < 1.0 or 0.5 <= np.ptp(converted) / usual_spread <= 2.0
        # The map holds over the whole run, its coolest readings too: a run that only ran
        # hotter (or cooler) starts where the others start, as read.
        coolest = float(np.percentile(rest, 5))
        starts_alike = abs(np.percentile(converted, 5) - coolest) < \
            abs(np.percentile(run, 5) - coolest)
        if inside and alike and starts_alike:
            return unit, float(np.median(converted))
    return None


#: A step of the clock this many times its median step, and at least
#: :data:`CLOCK_JUMP_MIN_S`, is a break of the record (a logger restarted days later).
CLOCK_JUMP_FACTOR = 100.0
CLOCK_JUMP_MIN_S = 3600.0


def clock_breaks(time_s: NDArray[np.float64], data_rows: ArrayLike | None = None
                 ) -> tuple[NDArray[np.bool_], list[str]]:
    """((N,) rows right after a clock jump, one note per jump and one for equal stamps).

    A jump: a forward step :data:`CLOCK_JUMP_FACTOR` times the median step and
    :data:`CLOCK_JUMP_MIN_S` or more. Equal stamps are named with their rows (a logger's
    resolution: the lags hold still over them). A step back is the caller's to refuse.

    Parameters
    ----------
    time_s : ndarray, shape (N,)
        The log's time [s].
    data_rows : array_like of int, shape (N,), optional
        The rows' numbers in the file, for the messages (default 1..N).

    Returns
    -------
    tuple of (ndarray of bool, shape (N,), list of str)
        The rows after a jump, and the notes.
    """
    t = np.asarray(time_s, dtype=np.float64)
    rows = np.arange(1, t.size + 1) if data_rows is None else np.asarray(data_rows)
    breaks = np.zeros(t.size, dtype=bool)
    notes: list[str] = []
    if t.size < 3:
        return breaks, notes
    steps = np.diff(t)
    forward = steps[np.isfinite(steps) & (steps > 0)]
    usual = float(np.median(forward)) if forward.size else 0.0
    for k in np.flatnonzero(steps >= max(CLOCK_JUMP_FACTOR * usual, CLOCK_JUMP_MIN_S)) + 1:
        breaks[k] = True
        notes.append(f"the clock jumps by {duration_text(steps[k - 1])} at data row "
                     f"{int(rows[k])} (its usual step {usual:g} s): taken as a break between "
                     "runs (lags and time restart there)")
    equal = np.flatnonzero(steps == 0) + 1
    if equal.size:
        from ..inputs.sensor_health import row_ranges

        notes.append(f"equal time stamps at data rows {row_ranges(rows[equal])} ({equal.size} "
                     "rows): taken as the logger's resolution (the lags hold still over them)")
    return breaks, notes


def duration_text(seconds: float) -> str:
    """A duration in the largest unit that keeps it above 1 (s, min, h, d).

    Parameters
    ----------
    seconds : float
        The duration [s].

    Returns
    -------
    str
        E.g. ``"2.5 h"``.
    """
    for unit, size in (("d", 86400.0), ("h", 3600.0), ("min", 60.0)):
        if seconds >= size:
            return f"{seconds / size:.3g} {unit}"
    return f"{seconds:.3g} s"


def leave_out_dead_sensors(temperatures: dict[str, NDArray[np.float64]],
                           run_of_row: NDArray[np.intp] | None, names: list[str] | None,
                           data_rows: NDArray[np.intp] | None = None,
                           breaks: NDArray[np.bool_] | None = None
                           ) -> tuple[dict[str, NDArray[np.float64]], list[str]]:
    """(the sensors kept, one note per finding): every sensor judged by
    :func:`~..inputs.sensor_health.judge_sensors` (dead, out of range, stuck, dropping out,
    jumping). A sensor bad on more than
    :data:`~..inputs.sensor_health.LEAVE_OUT_SHARE` of the rows, or
    :data:`~..inputs.sensor_health.LEAVE_OUT_RUN_SHARE` of one run, or jumping, is left out
    of every model and its rows kept; a few bad rows are NaN in the sensor kept (the
    caller's complete-row rule leaves those rows out). ``data_rows`` (N,) number the rows
    in the notes; ``breaks`` (N,) mark rows after a clock jump.

    Parameters
    ----------
    temperatures : dict of str to ndarray, shape (N,)
        Sensor name -> readings [degC].
    run_of_row : ndarray of int, shape (N,), or None
        Run index of each row, or None for one run.
    names : list of str or None
        The runs' names, in order.
    data_rows : ndarray of int, shape (N,), optional
        The rows' numbers in the file (default 1..N).
    breaks : ndarray of bool, shape (N,), optional
        Rows right after a clock jump.

    Returns
    -------
    tuple of (dict of str to ndarray, shape (N,), list of str)
        The sensors kept [degC] (a few bad rows NaN), and the notes.
    """
    from ..inputs.sensor_health import judge_sensors

    health = judge_sensors(temperatures, data_rows, run_of_row, names, breaks)
    return health.kept, health.notes
