"""Playback timing (ROS-free): bag time <-> wall time, rate, pause; QoS adaptation."""
from __future__ import annotations

import pytest

from mt_accuracy_ros.core.errors import ParameterError
from mt_accuracy_ros.io.playback import PlaybackClock, playback_policies


class FakeWall:
    def __init__(self) -> None:
        self.t = 1_000

    def __call__(self) -> int:
        return self.t


@pytest.mark.parametrize("rate", [0.5, 1.0, 2.0, 10.0])
def test_rate_scales_wall_time(rate):
    wall = FakeWall()
    clock = PlaybackClock(bag_start_ns=5_000_000_000, rate=rate, now_ns=wall)
    assert clock.wait_ns(6_000_000_000) == round(1e9 / rate)
    wall.t += 250_000_000
    assert clock.bag_now_ns() == 5_000_000_000 + round(250_000_000 * rate)


def test_pause_freezes_bag_time_and_resume_continues():
    wall = FakeWall()
    clock = PlaybackClock(bag_start_ns=0, rate=1.0, now_ns=wall)
    wall.t += 100
    assert clock.pause() and not clock.pause()
    wall.t += 10_000
    assert clock.bag_now_ns() == 100
    assert clock.resume() and not clock.resume()
    wall.t += 50
    assert clock.bag_now_ns() == 150


@pytest.mark.parametrize("rate", [0.0, -1.0, float("nan"), float("inf")])
def test_bad_rate_is_refused(rate):
    with pytest.raises(ParameterError, match="rate"):
        PlaybackClock(bag_start_ns=0, rate=rate)


@pytest.mark.parametrize("offered, expected", [
    ([{"reliability": "reliable", "durability": "transient_local"}],
     ("reliable", "transient_local")),
    ([{"reliability": "reliable"}, {"reliability": "best_effort"}], ("best_effort", "volatile")),
    # rosbag2 bags before version 9 store rmw enums: 1 reliable / transient local.
    ([{"reliability": 1, "durability": 1}], ("reliable", "transient_local")),
    ([{"reliability": 2, "durability": 2}], ("best_effort", "volatile")),
    ([], ("reliable", "volatile")),
])
def test_playback_qos_follows_the_recorded_publishers(offered, expected):
    assert playback_policies(offered) == expected
