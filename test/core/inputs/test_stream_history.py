"""StreamHistory: a forged or corrupt batch index or stamp is refused and leaves the
stream's history alone; a real gap is counted; a genuinely restarted stream is followed
again (issue 29, item 4)."""
from __future__ import annotations

import pytest

from mt_accuracy_ros.core.errors import InputDataError
from mt_accuracy_ros.core.inputs.stream_history import StreamHistory

PERIOD = 1e-3          # 1 kHz
BATCH = 50             # samples per batch: 50 ms


def _stamp(index: int, origin_ns: int = 10**9) -> int:
    return origin_ns + round(index * PERIOD * 1e9)


def test_a_continuous_stream_loses_nothing_and_a_real_gap_is_counted():
    history = StreamHistory(horizon_s=60.0)
    lost = [history.check(i, BATCH, _stamp(i), PERIOD) for i in range(0, 500, BATCH)]
    assert lost == [0] * 10
    # Two batches dropped on the way: 100 samples lost, within the horizon.
    assert history.check(600, BATCH, _stamp(600), PERIOD) == 100
    assert history.check(650, BATCH, _stamp(650), PERIOD) == 0


@pytest.mark.parametrize("index, stamp, why", [
    (2**64 - 1, _stamp(550), "not a running count"),
    (-5, _stamp(550), "not a running count"),
    (550 + 61_000, _stamp(550 + 61_000), "jumps 61000 samples"),   # 61 s of samples
    (550, _stamp(550) + 3600 * 10**9, "from the"),                 # clock an hour ahead
])
def test_forged_batches_are_refused_and_move_nothing(index, stamp, why):
    history = StreamHistory(horizon_s=60.0)
    for i in range(0, 550, BATCH):
        history.check(i, BATCH, _stamp(i), PERIOD)
    with pytest.raises(InputDataError, match=why):
        history.check(index, BATCH, stamp, PERIOD)
    # The genuine stream carries on as if the forgery never came: nothing lost.
    assert history.check(550, BATCH, _stamp(550), PERIOD) == 0
    assert history.restarts == 0


def test_a_stream_that_really_jumped_is_followed_after_three_consistent_batches():
    history = StreamHistory(horizon_s=60.0, resync_batches=3)
    for i in range(0, 500, BATCH):
        history.check(i, BATCH, _stamp(i), PERIOD)
    # The publisher restarted: indices from 0 again, the clock two hours on.
    later = 7200 * 10**9
    for n, i in enumerate((0, BATCH)):
        with pytest.raises(InputDataError, match="refused"):
            history.check(i, BATCH, _stamp(i, later), PERIOD)
    assert history.check(2 * BATCH, BATCH, _stamp(2 * BATCH, later), PERIOD) == 0
    assert history.restarts == 1
    assert history.check(3 * BATCH, BATCH, _stamp(3 * BATCH, later), PERIOD) == 0
    # Alternating forgeries never add up to a restart.
    with pytest.raises(InputDataError):
        history.check(10**9, BATCH, _stamp(10**9, later), PERIOD)
    assert history.check(4 * BATCH, BATCH, _stamp(4 * BATCH, later), PERIOD) == 0
    with pytest.raises(InputDataError):
        history.check(2 * 10**9, BATCH, _stamp(2 * 10**9, later), PERIOD)
    assert history.restarts == 1


def test_the_horizon_must_be_positive():
    with pytest.raises(InputDataError, match="positive"):
        StreamHistory(0.0)
