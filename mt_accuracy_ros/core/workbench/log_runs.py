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
  than the others' (a day logged in mm among days in um; a sensor in degF).
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
    """(R,) the first row of each run."""
    run_of_row = np.asarray(run_of_row)
    return np.concatenate(([0], np.flatnonzero(np.diff(run_of_row) != 0) + 1)).astype(np.intp)


def stitched_time(time_s: NDArray[np.float64], run_of_row: NDArray[np.intp],
                  names: list[str], data_rows: ArrayLike | None = None) -> NDArray[np.float64]:
    """Runs laid end to end (N,) [s]: each starts one of its own median steps after the
    previous run's end, its time relative to its first row. A time that goes back inside
    a run is refused, naming the row."""
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
    ``max_blocks`` contiguous blocks of near-equal rows (None with one run)."""
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
    whose median lies :data:`TEMPERATURE_SLIP_K` from the median of the other runs.
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
            levels = np.array([float(np.nanmedian(values[s])) if np.isfinite(values[s]).any()
                               else np.nan for s in slices])
            for k, level in enumerate(levels):
                others = float(np.nanmedian(np.delete(levels, k)))
                if abs(level - others) >= TEMPERATURE_SLIP_K:
                    return (f"run {names[k]!r}: sensor {sensor} reads {level:.4g} where the "
                            f"other runs read {others:.4g} - mixed units across runs? (degF, "
                            "K); give every run in degC")
    return ""


#: A sensor without a reading in more than this share of the rows is dead: it is left
#: out, not its rows (a few glitches leave their rows out instead).
DEAD_SHARE = 0.2

#: ... or in more than this share of one run (an open thermocouple for a day).
DEAD_RUN_SHARE = 0.5


def leave_out_dead_sensors(temperatures: dict[str, NDArray[np.float64]],
                           run_of_row: NDArray[np.intp] | None, names: list[str] | None
                           ) -> tuple[dict[str, NDArray[np.float64]], list[str]]:
    """(the sensors kept, one note per sensor left out). A sensor with no reading (NaN) in
    more than :data:`DEAD_SHARE` of the rows, or :data:`DEAD_RUN_SHARE` of one run, is
    dead - a broken
    thermocouple - and is left out of every model; its rows stay. A few holes leave
    their rows out instead (the caller's complete-row rule)."""
    kept, notes = {}, []
    for sensor, values in temperatures.items():
        bad = ~np.isfinite(values)
        if not bad.any():
            kept[sensor] = values
            continue
        where = ""
        dead = bad.mean() > DEAD_SHARE
        if run_of_row is not None:
            share = np.bincount(run_of_row, weights=bad, minlength=len(names)) / \
                np.bincount(run_of_row, minlength=len(names))
            runs = [names[k] for k in np.flatnonzero(share > DEAD_RUN_SHARE)]
            dead = dead or bool(runs)
            where = f" (run{'s' if len(runs) > 1 else ''} {', '.join(runs)})" if runs else ""
        if dead:
            notes.append(f"sensor {sensor}: no reading in {int(bad.sum())} of {bad.size} rows"
                         f"{where} - dead, left out of every model (its rows kept)")
        else:
            kept[sensor] = values
    return kept, notes
