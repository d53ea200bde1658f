"""Is a batch's sample index and stamp plausible for the stream it claims to continue?

A batch of a sampled stream (scales at a fixed period) carries the index of its first
sample and the stamp of that sample. Both come from the network. A forged or corrupt
batch (index 2**64 - 1, a stamp a year ahead) must not move the stream's history: the
lost-sample counter would become nonsense, the data time would jump by millennia, and
every genuine batch after it would look late or out of order.

:class:`StreamHistory` accepts a batch when its index jump and its stamp both agree
with the stream's history within a horizon [s]. A batch that does not is refused (the
caller counts it) and leaves the history alone. A stream that genuinely jumped (a
restarted publisher, a clock step) is followed again once ``resync_batches``
consecutive batches continue from the new position, each within the horizon of the
previous one.
"""
from __future__ import annotations

from ..errors import InputDataError

#: Indices above this cannot be a running count (and would overflow int64 arithmetic).
MAX_INDEX = 2 ** 62


class StreamHistory:
    """Plausibility of (first index, sample count, stamp, period) batches of one stream.

    Parameters
    ----------
    horizon_s : float
        Largest gap [s] a batch may open in the stream (index jump x period), and the
        largest disagreement between its stamp and the one its index predicts.
    resync_batches : int
        Consecutive mutually consistent batches after which a jumped stream is followed.
    """

    def __init__(self, horizon_s: float, resync_batches: int = 3) -> None:
        if not horizon_s > 0:
            raise InputDataError(f"horizon must be positive, got {horizon_s}")
        self.horizon_s = float(horizon_s)
        self.resync_batches = int(resync_batches)
        self._last: tuple[int, int, int] | None = None     # (first index, count, stamp ns)
        self._pending: list[tuple[int, int, int]] = []      # a new position being confirmed
        self.restarts = 0

    def _problem(self, last: tuple[int, int, int], index: int, stamp_ns: int,
                 period_s: float) -> str:
        first, count, stamp = last
        jump = index - (first + count)
        if jump * period_s > self.horizon_s:
            return (f"first_sample_index {index} jumps {jump} samples ({jump * period_s:.3g} s) "
                    f"ahead, beyond the {self.horizon_s:g} s horizon")
        predicted = stamp + round((index - first) * period_s * 1e9)
        if abs(stamp_ns - predicted) > self.horizon_s * 1e9:
            return (f"stamp {stamp_ns} ns is {(stamp_ns - predicted) * 1e-9:.3g} s from the "
                    f"{predicted} ns its index predicts, beyond the {self.horizon_s:g} s horizon")
        return ""

    def check(self, index: int, count: int, stamp_ns: int, period_s: float) -> int:
        """Accept the batch (return the samples lost before it, >= 0, or -1 when it goes
        back: out of order) or raise :class:`InputDataError` saying why it is refused.

        Parameters
        ----------
        index : int
            The batch's first sample index (a running count).
        count : int
            Samples in the batch.
        stamp_ns : int
            Stamp of its first sample [ns].
        period_s : float
            Sample period [s].

        Returns
        -------
        int
            Samples lost since the last accepted batch (>= 0), 0 for the first batch or a
            resynchronisation, -1 for a batch that goes back.

        Raises
        ------
        InputDataError
            An index outside 0 ... 2**62, or an index jump or stamp beyond the horizon (the
            history is left alone).
        """
        index, count, stamp_ns = int(index), int(count), int(stamp_ns)
        if not 0 <= index <= MAX_INDEX:
            raise InputDataError(f"first_sample_index {index} is not a running count "
                                 f"(0 ... 2**62)")
        if self._last is None:
            self._last = (index, count, stamp_ns)
            return 0
        problem = self._problem(self._last, index, stamp_ns, period_s)
        if not problem:
            self._pending = []
            lost = index - (self._last[0] + self._last[1])
            self._last = (index, count, stamp_ns)
            return max(lost, -1)
        # Implausible against the history: is it the start or continuation of a new one?
        if self._pending and not self._problem(self._pending[-1], index, stamp_ns, period_s):
            self._pending.append((index, count, stamp_ns))
        else:
            self._pending = [(index, count, stamp_ns)]
        if len(self._pending) >= self.resync_batches:
            self._last, self._pending = self._pending[-1], []
            self.restarts += 1
            return 0
        raise InputDataError(f"{problem}: refused (forged or corrupt? the stream is "
                             f"followed from a new position after {self.resync_batches} "
                             "consistent batches)")
