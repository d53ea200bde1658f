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
clock breaks) is judged alone, so a reading at a run's first or last rows, with neighbours
on one side only, is never called a spike: a zeroed gauge's morning ramp is the machine.

Pure numpy, no ROS.
"""
from __future__ import annotations

import dataclasses

import numpy as np
from numpy.lib.stride_tricks import sliding_window_view
from numpy.typing import ArrayLike, NDArray

from .sensor_health import noise_from_differences, row_ranges

#: A spike lies this many noises (and resolutions) beyond its neighbours on both sides.
SPIKE_SIGMAS = 30.0
#: The most readings in a row one failed reading may span (a homing retried).
MAX_SPIKE_ROWS = 3
#: The readings each side whose median a reading is judged against: a spike of
#: :data:`MAX_SPIKE_ROWS` leaves a majority of each side's readings outside it.
SPIKE_HALF_WINDOW = 2 * MAX_SPIKE_ROWS - 1
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
        """One line: the target, how many readings, how far, where, what was done."""
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


def target_spikes(values: ArrayLike, segment_starts: ArrayLike | None = None
                  ) -> TargetSpikes:
    """The readings of ``values`` that lie beyond their neighbours on both sides.

    Parameters
    ----------
    values : array_like, shape (N,)
        The target in time order, any unit (non-finite readings are not judged).
    segment_starts : array_like of bool, shape (N,), optional
        Rows that start a run or follow a clock break: no window reaches across them.

    Returns
    -------
    TargetSpikes
        The spikes (their offset from the nearer side's median).
    """
    v = np.asarray(values, dtype=np.float64)
    none = TargetSpikes(np.zeros(v.size, dtype=bool), np.zeros(0), 0.0)
    finite = np.flatnonzero(np.isfinite(v))
    if finite.size < 3:
        return none
    kept = v[finite]
    noise = noise_from_differences(kept)
    steps = np.abs(np.diff(kept))
    resolution = float(steps[steps > 0].min()) if np.any(steps > 0) else 0.0
    threshold = SPIKE_SIGMAS * max(noise, resolution)
    if threshold <= 0.0:
        return none
    starts = np.zeros(v.size, dtype=bool) if segment_starts is None \
        else np.asarray(segment_starts, dtype=bool)
    segment = np.cumsum(starts)[finite]
    offsets = np.zeros(kept.size)
    for label in np.unique(segment):
        rows = np.flatnonzero(segment == label)
        offsets[rows] = _offsets_beyond_both_sides(kept[rows], threshold)
    spikes = offsets != 0.0
    rows = np.zeros(v.size, dtype=bool)
    rows[finite[spikes]] = True
    return TargetSpikes(rows, offsets[spikes], noise, resolution)


def _offsets_beyond_both_sides(values: NDArray[np.float64], threshold: float
                               ) -> NDArray[np.float64]:
    """(n,) each reading's offset from the nearer of its two sides' medians when it lies
    beyond both on one side by more than ``threshold``, else 0 (the ends: 0)."""
    h = SPIKE_HALF_WINDOW
    n = values.size
    out = np.zeros(n)
    if n < 2 * h + 1:
        return out
    # Rows h .. n-h-1, those with h readings on either side: row r's before is
    # values[r-h:r] (window r-h), its after values[r+1:r+1+h] (window r+1).
    windows = sliding_window_view(values, h)
    before = np.median(windows[:n - 2 * h], axis=1)
    after = np.median(windows[h + 1:], axis=1)
    middle = values[h:n - h]
    up = np.minimum(middle - before, middle - after)
    down = np.maximum(middle - before, middle - after)
    offset = np.where(up > threshold, up, np.where(down < -threshold, down, 0.0))
    out[h:n - h] = offset
    return out
