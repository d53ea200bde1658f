"""Timing of bag playback, ROS-free: bag time <-> wall time with rate and pause.

The player publishes a message recorded at bag time ``t_bag`` when the wall
clock reaches ``wall_start + (t_bag - bag_start) / rate`` (plus every pause).
Keeping this arithmetic out of the node makes it testable to the nanosecond.
"""
from __future__ import annotations

import time
from dataclasses import dataclass, field

from ..core.errors import ParameterError


@dataclass
class PlaybackClock:
    """Map bag time to wall time for one playback.

    Parameters
    ----------
    bag_start_ns : int
        Bag time at which playback starts (first message + start offset) [ns].
    rate : float
        Playback speed factor (> 0); 2.0 plays twice as fast as recorded.
    now_ns : callable
        Monotonic wall clock [ns]; injectable for tests.
    """

    bag_start_ns: int
    rate: float = 1.0
    now_ns: object = time.monotonic_ns
    _wall_start_ns: int = field(default=0, init=False)
    _paused_at_ns: int | None = field(default=None, init=False)

    def __post_init__(self) -> None:
        if not (self.rate > 0.0) or self.rate != self.rate or self.rate == float("inf"):
            raise ParameterError(f"playback rate must be finite and > 0, got {self.rate}")
        self._wall_start_ns = self.now_ns()

    @property
    def paused(self) -> bool:
        return self._paused_at_ns is not None

    def pause(self) -> bool:
        """Freeze bag time; returns False if already paused."""
        if self.paused:
            return False
        self._paused_at_ns = self.now_ns()
        return True

    def resume(self) -> bool:
        """Continue from where bag time froze; returns False if not paused."""
        if not self.paused:
            return False
        self._wall_start_ns += self.now_ns() - self._paused_at_ns
        self._paused_at_ns = None
        return True

    def bag_now_ns(self) -> int:
        """Current bag time [ns] (frozen while paused)."""
        wall = self._paused_at_ns if self.paused else self.now_ns()
        return self.bag_start_ns + int(round((wall - self._wall_start_ns) * self.rate))

    def wait_ns(self, bag_time_ns: int) -> int:
        """Wall nanoseconds until ``bag_time_ns`` is due (<= 0: due now)."""
        return int(round((bag_time_ns - self.bag_now_ns()) / self.rate))


def qos_policy_name(value, kind: str) -> str:
    """A recorded QoS policy as a name, whether the bag wrote names or rmw enums.

    Bags of rosbag2 before version 9 store rmw enum integers
    (reliability 1 = reliable, 2 = best effort; durability 1 = transient
    local, 2 = volatile); version 9 stores the names.
    """
    if isinstance(value, str):
        return value.lower()
    table = {"reliability": {1: "reliable", 2: "best_effort"},
             "durability": {1: "transient_local", 2: "volatile"}}[kind]
    return table.get(int(value), "system_default")


def playback_policies(offered: tuple[dict, ...] | list[dict]) -> tuple[str, str]:
    """(reliability, durability) to republish with, like rosbag2's player.

    Reliable only if every recorded publisher offered reliable; transient
    local only if every one offered it; otherwise the permissive choice.
    """
    reliabilities = {qos_policy_name(q.get("reliability", 1), "reliability") for q in offered}
    durabilities = {qos_policy_name(q.get("durability", 2), "durability") for q in offered}
    reliability = "reliable" if reliabilities <= {"reliable"} else "best_effort"
    durability = "transient_local" if offered and durabilities == {"transient_local"} \
        else "volatile"
    return reliability, durability
