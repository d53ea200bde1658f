"""Bag player: republish a bag's messages with their recorded timing, and /clock.

Plays bags written by this package's recorder and by rosbag2 (zstd chunks,
bags split over files, with or without ``metadata.yaml``). Publishes the raw
CDR bytes (no decode/re-encode), on the recorded topic names - remap them with
ordinary ROS remapping (``--ros-args -r /old:=/new``). With ``clock`` on it
publishes ``/clock`` (``rosgraph_msgs/Clock``, best effort, keep last 1 - the
QoS ``use_sim_time`` subscribers use) at ``clock_frequency`` and right before
every message, so nodes with ``use_sim_time`` see recorded time.

Services (``std_srvs/Trigger``): ``~/pause``, ``~/resume``, ``~/toggle_paused``.
A type that is not installed is skipped with one warning; a bag whose messages
are not CDR is refused.
"""
from __future__ import annotations

import sys
import threading
import time

import rclpy
from rclpy.executors import ExternalShutdownException, SingleThreadedExecutor
from rclpy.node import Node
from rclpy.qos import DurabilityPolicy, HistoryPolicy, QoSProfile, ReliabilityPolicy
from rosgraph_msgs.msg import Clock
from std_srvs.srv import Trigger

from ..core.errors import BagError
from ..io.bag_reader import bag_info, message_class, read_messages, topics
from ..io.playback import PlaybackClock, playback_policies
from ._common import (MATCH_SETTLE_S, accept, float_descriptor, int_descriptor,
                      nanoseconds_to_stamp, plain_descriptor, refuse)

#: What ``use_sim_time`` subscribers use for /clock.
#: The played topics' publisher history [messages]: the topic's message count within
#: these bounds (a reliable late reader loses nothing of a bag up to the upper one).
MIN_PLAYBACK_DEPTH = 1000
MAX_PLAYBACK_DEPTH = 20000


def _message_counts(bag: str) -> dict[str, int]:
    """Topic -> message count from the bag's summaries ({} for a bag without them: a
    truncated file, whose topics then get the lower depth)."""
    try:
        return {name: int(t["count"]) for name, t in bag_info(bag)["topics"].items()}
    except BagError:
        return {}


CLOCK_QOS = QoSProfile(depth=1, reliability=ReliabilityPolicy.BEST_EFFORT,
                       durability=DurabilityPolicy.VOLATILE, history=HistoryPolicy.KEEP_LAST)


class BagPlayer(Node):
    """Publish one bag's messages on their topics in recorded time."""

    def __init__(self, **kwargs) -> None:
        super().__init__("bag_player", **kwargs)
        self.declare_parameter("bag", "", plain_descriptor(
            "Bag directory or .mcap file to play", read_only=True))
        self.declare_parameter("topics", [""], plain_descriptor(
            "Topics to play (empty: all)", read_only=True))
        self.declare_parameter("rate", 1.0, float_descriptor(
            "Playback speed factor", 0.01, 1000.0, read_only=True))
        self.declare_parameter("start_offset", 0.0, float_descriptor(
            "Skip this much bag time from the first message [s]", 0.0, 1e9, read_only=True))
        self.declare_parameter("loop", False, plain_descriptor("Play again when the bag ends"))
        self.declare_parameter("clock", True, plain_descriptor("Publish /clock", read_only=True))
        self.declare_parameter("clock_frequency", 100.0, float_descriptor(
            "/clock messages per second of wall time while waiting [Hz]", 1.0, 10000.0,
            read_only=True))
        self.declare_parameter("start_paused", False, plain_descriptor(
            "Wait for ~/resume before playing", read_only=True))
        self.declare_parameter("wait_for_subscribers_s", 0.0, float_descriptor(
            "Wait up to this long for subscribers on every played topic [s]", 0.0, 60.0,
            read_only=True))
        self.declare_parameter("min_subscribers", 1, int_descriptor(
            "Subscribers every played topic must have before playing (with "
            "wait_for_subscribers_s)", 1, 100, read_only=True))
        self.add_on_set_parameters_callback(self._validate)

        self.bag = str(self.get_parameter("bag").value)
        if not self.bag:
            raise BagError("parameter 'bag' is required (a bag directory or .mcap file)")
        wanted = [t for t in self.get_parameter("topics").value if t]
        available = topics(self.bag)
        counts = _message_counts(self.bag)
        self._topic_publishers: dict = {}
        self._skipped: set[str] = set()
        for name, info in sorted(available.items()):
            if wanted and name not in wanted:
                continue
            if info.encoding != "cdr":
                raise BagError(f"{self.bag}: topic {name} has message encoding "
                               f"{info.encoding!r}; only 'cdr' (ROS 2) can be played")
            try:
                cls = message_class(info.type)
            except BagError:
                self.get_logger().warning(
                    f"skipping topic {name}: type {info.type} is not installed")
                self._skipped.add(name)
                continue
            reliability, durability = playback_policies(info.offered_qos)
            # A history as deep as the topic's messages (bounded): a reliable subscriber
            # that falls behind a fast replay gets every message instead of the writer
            # overwriting those it has not acknowledged yet.
            depth = int(min(max(MIN_PLAYBACK_DEPTH, counts.get(name, 0)), MAX_PLAYBACK_DEPTH))
            qos = QoSProfile(
                depth=depth, history=HistoryPolicy.KEEP_LAST,
                reliability=ReliabilityPolicy.RELIABLE if reliability == "reliable"
                else ReliabilityPolicy.BEST_EFFORT,
                durability=DurabilityPolicy.TRANSIENT_LOCAL if durability == "transient_local"
                else DurabilityPolicy.VOLATILE)
            self._topic_publishers[name] = self.create_publisher(cls, name, qos)
        missing = sorted(set(wanted) - set(available))
        if missing:
            self.get_logger().warning(f"topics not in the bag: {', '.join(missing)}")
        if not self._topic_publishers:
            # Playing nothing is not success: say why, exit 2.
            reasons = [f"types not installed on {', '.join(sorted(self._skipped))}"
                       if self._skipped else "",
                       f"topics not in the bag: {', '.join(missing)}" if missing else "",
                       "the bag has no topics" if not available else ""]
            raise BagError(f"{self.bag}: nothing to play ({'; '.join(r for r in reasons if r)})")
        self._clock_publisher = (self.create_publisher(Clock, "/clock", CLOCK_QOS)
                                 if self.get_parameter("clock").value else None)
        self._pause_requested = bool(self.get_parameter("start_paused").value)
        self._clock: PlaybackClock | None = None
        self._lock = threading.Lock()
        self.create_service(Trigger, "~/pause", self._on_pause)
        self.create_service(Trigger, "~/resume", self._on_resume)
        self.create_service(Trigger, "~/toggle_paused", self._on_toggle)
        self.published = 0
        self.finished = threading.Event()
        self.error: Exception | None = None
        self._thread = threading.Thread(target=self._run, daemon=True)

    # -- parameters and services --------------------------------------------------------
    def _validate(self, parameters):
        for parameter in parameters:
            if parameter.name == "loop" and not isinstance(parameter.value, bool):
                return refuse("loop must be a bool")
        return accept()

    def _set_paused(self, paused: bool) -> bool:
        with self._lock:
            if self._clock is None:
                changed = self._pause_requested != paused
                self._pause_requested = paused
                return changed
            return self._clock.pause() if paused else self._clock.resume()

    def _is_paused(self) -> bool:
        with self._lock:
            return self._clock.paused if self._clock else self._pause_requested

    def _on_pause(self, _request, response):
        response.success = self._set_paused(True)
        response.message = "paused" if response.success else "already paused"
        return response

    def _on_resume(self, _request, response):
        response.success = self._set_paused(False)
        response.message = "resumed" if response.success else "was not paused"
        return response

    def _on_toggle(self, _request, response):
        response.success = self._set_paused(not self._is_paused())
        response.message = "paused" if self._is_paused() else "resumed"
        return response

    # -- playback -------------------------------------------------------------------------
    def start(self) -> None:
        """Start playing in a background thread."""
        self._thread.start()

    def _wait_for_subscribers(self) -> None:
        deadline = time.monotonic() + float(self.get_parameter("wait_for_subscribers_s").value)
        waited = False
        wanted = int(self.get_parameter("min_subscribers").value)
        while time.monotonic() < deadline and not all(
                p.get_subscription_count() >= wanted for p in self._topic_publishers.values()):
            waited = True
            time.sleep(0.02)
        if waited or self.get_parameter("wait_for_subscribers_s").value > 0:
            time.sleep(MATCH_SETTLE_S)

    def _publish_clock(self, bag_ns: int) -> None:
        if self._clock_publisher is not None:
            self._clock_publisher.publish(Clock(clock=nanoseconds_to_stamp(max(0, bag_ns))))

    def _run(self) -> None:
        try:
            self._wait_for_subscribers()
            while rclpy.ok():
                self._play_once()
                if not self.get_parameter("loop").value:
                    break
        except Exception as exc:  # reported by main(); the thread must not die silently
            self.error = exc
        finally:
            self.finished.set()

    def _play_once(self) -> None:
        offset_ns = int(float(self.get_parameter("start_offset").value) * 1e9)
        rate = float(self.get_parameter("rate").value)
        tick_ns = int(1e9 / float(self.get_parameter("clock_frequency").value))
        names = list(self._topic_publishers)
        if not names:
            return
        start_ns = None
        for message in read_messages(self.bag, names):
            if start_ns is None:
                start_ns = message.log_time_ns + offset_ns
                with self._lock:
                    paused = self._pause_requested if self._clock is None else self._clock.paused
                    self._clock = PlaybackClock(start_ns, rate)
                    if paused:
                        self._clock.pause()
            if message.log_time_ns < start_ns:
                continue
            while rclpy.ok():
                with self._lock:
                    wait = self._clock.wait_ns(message.log_time_ns)
                    paused = self._clock.paused
                    now_bag = self._clock.bag_now_ns()
                if wait <= 0 and not paused:
                    break
                self._publish_clock(now_bag)
                time.sleep(min(tick_ns, max(wait, 0) if not paused else tick_ns) / 1e9)
            if not rclpy.ok():
                return
            self._publish_clock(message.log_time_ns)
            self._topic_publishers[message.topic].publish(message.data)
            self.published += 1


def main(args: list[str] | None = None) -> int:
    rclpy.init(args=args if args is not None else sys.argv)
    try:
        node = BagPlayer()
    except BagError as exc:
        print(f"bag_player: {exc}", file=sys.stderr)
        rclpy.try_shutdown()
        return 2
    executor = SingleThreadedExecutor()
    executor.add_node(node)
    node.start()
    code = 0
    try:
        while rclpy.ok() and not node.finished.is_set():
            executor.spin_once(timeout_sec=0.05)
        # Let subscribers drain the last messages before the publishers go.
        for _ in range(25):
            executor.spin_once(timeout_sec=0.02)
        if node.error is not None:
            print(f"bag_player: {node.error}", file=sys.stderr)
            code = 2
        else:
            node.get_logger().info(f"played {node.published} messages from {node.bag}")
    except (KeyboardInterrupt, ExternalShutdownException):
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return code


if __name__ == "__main__":
    sys.exit(main())
