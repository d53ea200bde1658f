"""A measured target's failed readings: a reading far from its neighbours, then back.

A thermal log's displacement comes from an instrument that can fail one reading at a time:
a printer re-homing its Z axis that misses the switch (+1720 steps in one reading, then
back), a probe that touches a chip, a capacitive sensor that sees the spindle's coolant.
Such a reading is not the machine's drift and it decides a least-squares fit: eleven of
them, 4.3 mm off in a log that drifts 0.6 mm, leave every model at the constant's figure.

A reading is a **spike** when it lies beyond both the median of the
:data:`SPIKE_HALF_WINDOW` readings before it and that of those after it, on the same side,
by :data:`SPIKE_SIGMAS` times the target's noise (and its resolution). A drift of any speed
lies between the two, a step that stays on one of them: only readings that go and come back
(up to :data:`MAX_SPIKE_ROWS` in a row) are spikes. Each run (and each stretch between
clock breaks) is judged alone, by its own noise, so a reading at a run's first or last
rows, with neighbours on one side only, is never called a spike (a zeroed gauge's morning
ramp is the machine), nor is a run logged in other units (the unit check's to name). A
failed reading jumps: the steps into and out of it are each :data:`SPIKE_ISOLATION` times
every other step near it (a thermal peak on a low-noise gauge rises and falls over steps
alike), and no input (temperature, driver) leaves its own neighbours on its rows.

Pure numpy, no ROS.
"""
from __future__ import annotations

import dataclasses
import warnings

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike, NDArray

from .sensor_health import noise_from_differences, row_ranges, true_stretches

#: A spike lies this many noises (and resolutions) beyond its neighbours on both sides.
SPIKE_SIGMAS = 30.0
#: The most readings in a row one failed reading may span (a homing retried).
MAX_SPIKE_ROWS = 3
#: The readings each side whose median a reading is judged against: a spike of
#: :data:`MAX_SPIKE_ROWS` leaves a majority of each side's readings outside it.
SPIKE_HALF_WINDOW = 2 * MAX_SPIKE_ROWS - 1
#: The steps into and out of a failed reading are each this many times every other step
#: near it.
SPIKE_ISOLATION = 4.0
#: An input leaving its neighbours by this many of its noises on a spike's rows moved with
#: the target: the machine, not a failed reading.
INPUT_SIGMAS = 5.0
#: More spikes than this share of the readings is no failed reading but a signal: refused.
MAX_SPIKE_SHARE = 0.05


@dataclasses.dataclass(frozen=True)
class TargetSpikes:
    """The spikes of a target.

    Attributes
    ----------
    rows : ndarray of bool, shape (N,)
        The spikes.
    offsets : ndarray, shape (S,)
        Each spike's offset from the nearer of its two sides' medians, the values' unit.
    noise : float
        The target's noise (:func:`~.sensor_health.noise_from_differences`), same unit.
    resolution : float
        Its smallest non-zero step, same unit (a quantised target's noise can read 0).
    """

    rows: NDArray[np.bool_]
    offsets: NDArray[np.float64]
    noise: float
    resolution: float = 0.0

    @property
    def count(self) -> int:
        return int(self.rows.sum())

    def text(self, name: str, unit: str, data_rows: ArrayLike | None = None) -> str:
        """One line: the target, how many readings, how far, where, what was done.

        Parameters
        ----------
        name : str
            The target column.
        unit : str
            The unit of the values judged (the offsets, noise and resolution).
        data_rows : array_like of int, shape (N,), optional
            Each reading's data row in the file (default 1..N).

        Returns
        -------
        str
            The note.
        """
        numbers = np.arange(1, self.rows.size + 1) if data_rows is None \
            else np.asarray(data_rows)
        largest = self.offsets[np.argmax(np.abs(self.offsets))]
        scale = f"its noise {self.noise:.2g} {unit}" if self.noise >= self.resolution \
            else f"its resolution {self.resolution:.2g} {unit}"
        return (f"target {name}: {self.count} reading{'s' if self.count > 1 else ''} far from "
                f"the readings either side and back (up to {largest:+.4g} {unit} beyond the "
                f"nearer side's median; {scale}) at data rows "
                f"{row_ranges(numbers[self.rows])} - failed readings (a missed homing or "
                "touch?), those rows left out")


def target_spikes(values: ArrayLike, segment_starts: ArrayLike | None = None,
                  inputs: list[ArrayLike] | None = None) -> TargetSpikes:
    """The readings of ``values`` that lie beyond their neighbours on both sides, alone.

    Parameters
    ----------
    values : array_like, shape (N,)
        The target in time order, any unit (non-finite readings are not judged).
    segment_starts : array_like of bool, shape (N,), optional
        Rows that start a run or follow a clock break: no window reaches across them, and
        each segment's own noise and resolution set its threshold (a run in other units
        is the unit check's to name, not a run of spikes).
    inputs : list of array_like, shape (N,), optional
        The temperatures and drivers on the same rows: a stretch where one of them leaves
        its own neighbours too is the machine doing something, not a failed reading.

    Returns
    -------
    TargetSpikes
        The spikes (their offset from the nearer side's median).
    """
    v = np.asarray(values, dtype=np.float64)
    finite = np.flatnonzero(np.isfinite(v))
    if finite.size < 3:
        return TargetSpikes(np.zeros(v.size, dtype=bool), np.zeros(0), 0.0)
    kept = v[finite]
    starts = np.zeros(v.size, dtype=bool) if segment_starts is None \
        else np.asarray(segment_starts, dtype=bool)
    segment = np.cumsum(starts)[finite]
    drivers = [np.asarray(x, dtype=np.float64)[finite] for x in inputs or []]
    offsets = np.zeros(kept.size)
    for label in np.unique(segment):
        rows = np.flatnonzero(segment == label)
        offsets[rows] = _segment_spikes(kept[rows], [x[rows] for x in drivers])
    spikes = offsets != 0.0
    rows = np.zeros(v.size, dtype=bool)
    rows[finite[spikes]] = True
    noise, resolution = _noise_and_resolution(kept)
    return TargetSpikes(rows, offsets[spikes], noise, resolution)


def _noise_and_resolution(values: NDArray[np.float64]) -> tuple[float, float]:
    """(noise from successive differences, smallest non-zero step), the values' unit."""
    steps = np.abs(np.diff(values[np.isfinite(values)]))
    return (noise_from_differences(values),
            float(steps[steps > 0].min()) if np.any(steps > 0) else 0.0)


def _segment_spikes(values: NDArray[np.float64], inputs: list[NDArray[np.float64]]
                    ) -> NDArray[np.float64]:
    """(n,) the offsets of one segment's failed readings (0 elsewhere): beyond both sides'
    medians by its threshold, judged again with those found masked (a failure longer than
    a side's majority), kept only where the stretch steps in and out alone
    (:data:`SPIKE_ISOLATION`) and no input leaves its own neighbours there."""
    noise, resolution = _noise_and_resolution(values)
    threshold = SPIKE_SIGMAS * max(noise, resolution)
    out = np.zeros(values.size)
    if threshold <= 0.0:
        return out
    masked = values.copy()
    for _ in range(MAX_SPIKE_ROWS):
        found = _offsets_beyond_both_sides(masked, threshold)
        new = (found != 0.0) & (out == 0.0)
        if not new.any():
            break
        # The offset from the unmasked neighbours: the first pass's, or this pass's.
        out[new] = found[new]
        masked[new] = np.nan
    for a, b in true_stretches(out != 0.0):
        if not _steps_alone(values, masked, a, b) or any(_moves(x, a, b) for x in inputs):
            out[a:b] = 0.0
    return out


def _steps_alone(values: NDArray[np.float64], masked: NDArray[np.float64], a: int, b: int
                 ) -> bool:
    """Whether the steps into and out of readings [a, b) of ``values`` are each
    :data:`SPIKE_ISOLATION` times every other one-row step within :data:`SPIKE_HALF_WINDOW`
    rows between readings not found failing (``masked``: those NaN): a reading that fails
    jumps; a thermal peak rises and falls over several steps alike."""
    if a < 1 or b >= values.size:
        return False
    into, out_of = abs(values[a] - values[a - 1]), abs(values[b] - values[b - 1])
    steps = np.abs(np.diff(masked))
    near = np.r_[steps[max(0, a - 1 - SPIKE_HALF_WINDOW):a - 1],
                 steps[b:b + SPIKE_HALF_WINDOW]]
    near = near[np.isfinite(near)]
    return near.size == 0 or min(into, out_of) >= SPIKE_ISOLATION * float(near.max())


def _moves(values: NDArray[np.float64], a: int, b: int) -> bool:
    """Whether an input lies beyond the medians of its own :data:`SPIKE_HALF_WINDOW`
    readings on both sides, on one side, on rows [a, b) by more than :data:`INPUT_SIGMAS`
    of its noise (any amount, for a noise-free input such as a spindle's speed)."""
    h = SPIKE_HALF_WINDOW
    if a < h or b + h > values.size:
        return False
    before = np.nanmedian(values[a - h:a])
    after = np.nanmedian(values[b:b + h])
    inside = values[a:b]
    tolerance = INPUT_SIGMAS * noise_from_differences(values)
    # Beyond both medians on one side, as the spike is: a rising input lies between them.
    up = np.minimum(inside - before, inside - after)
    down = np.maximum(inside - before, inside - after)
    return bool(np.any(up > tolerance) or np.any(down < -tolerance))


def _offsets_beyond_both_sides(values: NDArray[np.float64], threshold: float
                               ) -> NDArray[np.float64]:
    """(n,) each reading's offset from the nearer of its two sides' medians (NaN readings
    left out of the medians) when it lies beyond both on one side by more than
    ``threshold``, else 0 (the ends, and NaN readings: 0)."""
    h = SPIKE_HALF_WINDOW
    n = values.size
    out = np.zeros(n)
    if n < 2 * h + 1:
        return out
    # Rows h .. n-h-1, those with h readings on either side: row r's before is
    # values[r-h:r] (window r-h), its after values[r+1:r+1+h] (window r+1).
    windows = sliding_window_view(values, h)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)     # an all-NaN side: no median
        before = np.nanmedian(windows[:n - 2 * h], axis=1)
        after = np.nanmedian(windows[h + 1:], axis=1)
    middle = values[h:n - h]
    up = np.minimum(middle - before, middle - after)
    down = np.maximum(middle - before, middle - after)
    offset = np.where(up > threshold, up, np.where(down < -threshold, down, 0.0))
    out[h:n - h] = np.nan_to_num(offset, nan=0.0)
    return out
