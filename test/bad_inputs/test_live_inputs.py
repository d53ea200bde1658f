"""Bad live input to a real node process: each class is said on ``/diagnostics`` by the
node that receives it, and the node keeps running and compensating.

The node is a ``compensation_broadcaster`` process (the one on the real-time path that
receives the scales, the temperatures and the models); this test is a peer node in
another process that publishes the inputs a CNC and its sensors would and listens to
``/diagnostics``. One broadcaster serves every class (a fresh one per class would cost
a node start each on a loaded host); each class uses sensors of its own, so what one
class sends cannot decide another's outcome.
"""
from __future__ import annotations

import math
import time

import pytest

from mt_accuracy_ros.commands.processes import start_node
from nodes.graph_helpers import scale_batch, set_parameter_again_until_answered, spin_until

#: (class, the input, what the node says on /diagnostics). "refused": the message is
#: counted as refused with that reason; "announced": the node names the problem and
#: goes on without the bad input. " … " stands for the figures of the case (stamps).
CLASSES = [
    ("nan_temperature",
     "a temperature sensor sends NaN instead of a reading",
     "announced: temperature sensor nan_probe: no value (nan) - left out of the model's "
     "inputs"),
    ("dead_thermocouple",
     "a thermocouple breaks and reads -180 degC",
     "announced: temperature sensor open_tc: reads -180 degC, a physically absent value"),
    ("kelvin_as_celsius",
     "a sensor sends kelvin (293.15) where degC is declared",
     "announced: temperature sensor kelvin_probe: reads 293.1 degC, a physically absent "
     "value"),
    ("fahrenheit_as_celsius",
     "a sensor sends degF of a warm day (95) where degC is declared",
     "announced: temperature sensor fahrenheit_probe: reads 95 degC, outside a workshop's"),
    ("frozen_sensor",
     "a sensor repeats the very same value while another one warms by several kelvin",
     "announced: temperature sensor frozen_probe: frozen at 20.5 degC"),
    ("names_and_values_differ",
     "a temperature message names two sensors and carries one value",
     "refused: temperatures: refused: InputDataError: 2 sensor names but 1 temperatures"),
    ("nan_sample_period",
     "a scale batch with a NaN sample period",
     "refused: scales: refused: InputDataError: sample_period nan s: must be finite"),
    ("stamp_out_of_order",
     "a scale batch stamped before the previous one",
     "refused: scales: refused: InputDataError: stamp … not after the last one … out of "
     "order or repeated"),
    ("duplicate_stamp",
     "the same scale batch stamp twice",
     "refused: scales: refused: InputDataError: stamp … not after the last one … out of "
     "order or repeated"),
    ("clock_jump",
     "a scale batch stamped an hour ahead of the stream (the sender's clock jumped)",
     "refused: scales: refused: InputDataError: … beyond the 60 s horizon"),
    ("stopped_input",
     "the temperature source stops while the scales go on",
     "announced: temperatures: nothing for"),
    ("bad_parameter",
     "publish_rate_hz set to 0 at run time",
     "refused: parameters: refused: publish_rate_hz: 0.0 outside [1.0, 20000.0]"),
]

BATCH_SAMPLES = 50
PERIOD_S = 0.001
#: Data time the broadcaster waits for a silent input before it says so [s] (each batch
#: carries 50 ms of data).
INPUT_TIMEOUT_S = 1.0


class Feed:
    """The peer: scales and temperatures on a running data clock, /diagnostics heard."""

    def __init__(self, node) -> None:
        from diagnostic_msgs.msg import DiagnosticArray

        from mt_accuracy_msgs.msg import ScaleBatch, TemperatureArray, VolumetricCompensation
        from mt_accuracy_ros.nodes._common import SENSOR_QOS
        from mt_accuracy_ros.nodes.compensation_broadcaster import COMPENSATION_QOS

        self.node = node
        self.diagnostics: list = []
        self.compensation: list = []
        node.create_subscription(DiagnosticArray, "/diagnostics", self.diagnostics.append, 500)
        node.create_subscription(VolumetricCompensation, "compensation",
                                 self.compensation.append, COMPENSATION_QOS)
        self.scales = node.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
        self.temperatures = node.create_publisher(TemperatureArray, "temperatures", SENSOR_QOS)
        self.index = 0
        self.sent_at = 0.0
        #: Statuses before this index are an earlier class's (see :meth:`said`).
        self.since = 0

    @property
    def stamp_ns(self) -> int:
        """The next batch's stamp: 1 s + 50 ms per batch sent."""
        return 10**9 + self.index * BATCH_SAMPLES * int(PERIOD_S * 1e9)

    def batch(self, first_index: int, stamp_ns: int, period: float = PERIOD_S):
        return scale_batch(first_index, stamp_ns, period, BATCH_SAMPLES)

    def temperature(self, readings: dict[str, float], stamp_ns: int, values=None) -> None:
        from mt_accuracy_msgs.msg import TemperatureArray
        from mt_accuracy_ros.io.fields import nanoseconds_to_stamp, pack_float64

        message = TemperatureArray(sensor_names=list(readings))
        message.temperatures = pack_float64(list(readings.values()) if values is None
                                            else values)
        message.header.stamp = nanoseconds_to_stamp(stamp_ns)
        self.temperatures.publish(message)

    def step(self, readings: dict[str, float] | None) -> None:
        """At most one batch per 20 ms of waiting: its temperatures (unless None) stamped
        just before it, then the batch."""
        if time.monotonic() - self.sent_at < 0.02:
            return
        self.sent_at = time.monotonic()
        stamp = self.stamp_ns
        if readings is not None:
            self.temperature(readings, stamp - 1)
        self.scales.publish(self.batch(self.index * BATCH_SAMPLES, stamp))
        self.index += 1

    def said(self, words: str, *, delivery: bool = False) -> bool:
        """The broadcaster said ``words`` since this class began (on its delivery status
        - a counted refusal - with ``delivery``)."""
        parts = words.split(" … ")
        return any(all(part in s.message for part in parts)
                   for array in self.diagnostics[self.since:] for s in array.status
                   if "compensation_broadcaster" in s.name and
                   (not delivery or s.name.endswith(": delivery")))

    def heard(self) -> list[str]:
        """What the broadcaster said since this class began, but its routine reports."""
        return [s.message for array in self.diagnostics[self.since:] for s in array.status
                if "compensation_broadcaster" in s.name and s.message not in
                ("all streams complete", "")][-8:]

    def run_until_said(self, words: str, readings, timeout_s: float = 60.0) -> bool:
        """Stream (``readings(k)`` gives the k-th temperatures) until the node says it."""
        count = {"k": 0}

        def go() -> bool:
            before = self.index
            self.step(readings(count["k"]) if readings is not None else None)
            count["k"] += self.index - before
            return self.said(words)
        return spin_until(self.node, go, timeout_s)


def _warming(k: int) -> float:
    """A sensor that warms 0.1 K per reading: the others move, so a frozen one shows."""
    return 20.0 + 0.1 * k


def _send_bad(feed: Feed, name: str) -> None:
    """Send class ``name``'s bad input until the node says what it should."""
    words = dict((c, o) for c, _, o in CLASSES)[name].split(": ", 1)[1]
    warm = f"warm_{name}"
    sensor_value = {"nan_temperature": ("nan_probe", math.nan),
                    "dead_thermocouple": ("open_tc", -180.0),
                    "kelvin_as_celsius": ("kelvin_probe", 293.15),
                    "fahrenheit_as_celsius": ("fahrenheit_probe", 95.0),
                    "frozen_sensor": ("frozen_probe", 20.5)}
    if name in sensor_value:
        sensor, value = sensor_value[name]
        assert feed.run_until_said(words, lambda k: {warm: _warming(k), sensor: value}), \
            (name, feed.heard())
    elif name == "names_and_values_differ":
        def send(_k):
            feed.temperature({"a_probe": 20.0, "b_probe": 20.0}, feed.stamp_ns - 1,
                             values=[20.0])
            return {warm: _warming(_k)}
        assert feed.run_until_said(words, send), name
    elif name in ("nan_sample_period", "stamp_out_of_order", "duplicate_stamp", "clock_jump"):
        _send_bad_batch(feed, name, words)
    elif name == "stopped_input":
        assert feed.run_until_said(words, None), name
    elif name == "bad_parameter":
        ok, reason = set_parameter_again_until_answered(
            feed.node, "compensation_broadcaster", "publish_rate_hz", 0.0)
        assert not ok and "publish_rate_hz" in reason, reason
        assert spin_until(feed.node, lambda: feed.said(words), 30), name


def _send_bad_batch(feed: Feed, name: str, words: str) -> None:
    """A bad scale batch after good ones, until the node refuses it with ``words``."""
    def bad() -> None:
        last = feed.index - 1       # the last good batch sent
        stamp = 10**9 + last * BATCH_SAMPLES * int(PERIOD_S * 1e9)
        if name == "nan_sample_period":
            feed.scales.publish(feed.batch(feed.index * BATCH_SAMPLES, feed.stamp_ns,
                                           math.nan))
        elif name == "stamp_out_of_order":
            feed.scales.publish(feed.batch(last * BATCH_SAMPLES, stamp - 50_000_000))
        elif name == "duplicate_stamp":
            feed.scales.publish(feed.batch(last * BATCH_SAMPLES, stamp))
        else:
            feed.scales.publish(feed.batch(feed.index * BATCH_SAMPLES,
                                           feed.stamp_ns + 3600 * 10**9))

    sent = {"at": 0.0}

    def go() -> bool:
        feed.step({f"warm_{name}": 20.0 + 0.001 * feed.index})
        if time.monotonic() - sent["at"] > 0.5:   # the bad one between good ones
            sent["at"] = time.monotonic()
            bad()
        return feed.said(words)
    assert spin_until(feed.node, go, 60), (name, feed.heard())


@pytest.fixture(scope="module")
def broadcaster_feed():
    """One broadcaster process and its peer for every class (a context of their own)."""
    import rclpy

    rclpy.init()
    node = rclpy.create_node("live_input_peer")
    feed = Feed(node)
    broadcaster = start_node("compensation_broadcaster", {
        "input_delay_s": 0.0, "input_timeout_s": INPUT_TIMEOUT_S}, quiet=True)
    try:
        assert spin_until(node, lambda: feed.scales.get_subscription_count() > 0
                          and feed.temperatures.get_subscription_count() > 0
                          and node.count_publishers("compensation") > 0, 60)
        assert spin_until(node, lambda: feed.step({"warm_start": 20.0 + 0.001 * feed.index})
                          or len(feed.compensation) > 5, 60), "no compensation at the start"
        yield feed, broadcaster
    finally:
        broadcaster.stop()
        node.destroy_node()
        rclpy.try_shutdown()


@pytest.mark.parametrize("name, description, expected", CLASSES,
                         ids=[c[0] for c in CLASSES])
def test_bad_live_input_is_said_and_the_node_keeps_compensating(broadcaster_feed, name,
                                                                description, expected):
    feed, broadcaster = broadcaster_feed
    feed.since = len(feed.diagnostics)
    _send_bad(feed, name)
    kind, words = expected.split(": ", 1)
    # A refusal is counted on the node's delivery status, with its reason; an
    # announcement names the sensor or input and what the node does without it.
    assert feed.said(words, delivery=kind == "refused"), name
    assert broadcaster.popen.poll() is None, f"{name}: the broadcaster died"
    # Still compensating after it: good data gives corrections.
    count = len(feed.compensation)
    assert spin_until(feed.node, lambda: feed.step({f"warm_{name}_after": 20.0 + 0.001 *
                                                    feed.index})
                      or len(feed.compensation) > count + 3, 60), f"{name}: no compensation"
