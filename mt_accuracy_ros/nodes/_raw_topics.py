"""Follow the graph's topics and subscribe to each raw (CDR, never decoded).

What the recorder and the Foxglove bridge share: discovery on a steady-clock
timer (with ``use_sim_time`` a ROS-time timer would not fire before the first
``/clock``), one warning per topic that cannot be followed (several types, a
type not installed), and a subscription whose QoS matches every publisher.
"""
from __future__ import annotations

from rclpy.clock import Clock, ClockType

from ..core.errors import BagError
from ..io.bag_reader import message_class
from ._common import accept, matching_subscription_qos, refuse

#: Range of the discovery period [s] both nodes accept.
DISCOVERY_PERIOD_RANGE_S = (0.05, 60.0)


class RawTopicFollower:
    """Subscribe raw to every new topic (or the ``wanted`` ones) as it appears.

    ``on_new(name, type_name, offered_qos)`` is called once per topic and
    returns the raw-message callback (or None to skip the topic); ``verb``
    words the log ("recording", "relaying").
    """

    def __init__(self, node, wanted: set[str], period_s: float, on_new, verb: str) -> None:
        self._node = node
        self._wanted = wanted
        self._on_new = on_new
        self._verb = verb
        self.subscriptions: dict = {}
        self._warned: set[str] = set()
        self.discover()
        self._timer = node.create_timer(period_s, self.discover,
                                        clock=Clock(clock_type=ClockType.STEADY_TIME))

    def set_period(self, seconds: float) -> str | None:
        """Change the discovery period; the reason it is refused, or None."""
        low, high = DISCOVERY_PERIOD_RANGE_S
        if not low <= float(seconds) <= high:
            return f"discovery_period_s must be within [{low}, {high}] s"
        self._timer.timer_period_ns = int(float(seconds) * 1e9)
        return None

    def validate(self, parameters):
        """The owning node's parameter callback: ``discovery_period_s`` changes the timer."""
        for parameter in parameters:
            if parameter.name == "discovery_period_s":
                reason = self.set_period(parameter.value)
                if reason:
                    return refuse(reason)
        return accept()

    def discover(self) -> None:
        node = self._node
        if not node.context.ok():
            return  # shutting down (SIGINT/SIGTERM): nothing new to follow
        try:
            found = node.get_topic_names_and_types()
        except RuntimeError:
            if node.context.ok():
                raise
            return  # the context went down between the check and the call
        for name, types in found:
            if name in self.subscriptions or (self._wanted and name not in self._wanted):
                continue
            if len(types) != 1:
                self._warn_once(name, f"topic {name} has several types {types}; skipped")
                continue
            try:
                cls = message_class(types[0])
            except BagError:
                self._warn_once(name, f"topic {name}: type {types[0]} is not installed; skipped")
                continue
            matched = matching_subscription_qos(node, name)
            if matched is None:
                continue
            qos, offered = matched
            callback = self._on_new(name, types[0], offered)
            if callback is None:
                continue
            self.subscriptions[name] = node.create_subscription(cls, name, callback, qos,
                                                                raw=True)
            node.get_logger().info(f"{self._verb} {name} [{types[0]}]")

    def _warn_once(self, topic: str, text: str) -> None:
        if topic not in self._warned:
            self._warned.add(topic)
            self._node.get_logger().warning(text)
