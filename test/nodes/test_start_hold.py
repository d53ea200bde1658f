"""The virtual machine's streams held until a start stamp is set (start_stamp_ns = -1):
how the demo starts the machine only once every node is up, so that no node meets
a backlog of data whose corrections are stale on arrival."""
from __future__ import annotations

import time

from graph_helpers import set_parameter_again_until_answered, spin_for, spin_until
from mt_accuracy_ros.commands.processes import start_node


def test_streams_wait_for_the_start_stamp_and_begin_at_sample_zero(rclpy_context):
    import rclpy
    from mt_accuracy_msgs.msg import ScaleBatch, TemperatureArray

    from mt_accuracy_ros.nodes._common import SENSOR_QOS, stamp_to_nanoseconds

    node = rclpy.create_node("start_hold_listener")
    batches, temperatures = [], []
    node.create_subscription(ScaleBatch, "scales", batches.append, SENSOR_QOS)
    node.create_subscription(TemperatureArray, "temperatures", temperatures.append, SENSOR_QOS)
    machine = {"scenario": "demo", "start_stamp_ns": -1, "rate_factor": 1.0}
    encoder = start_node("encoder_publisher", {**machine, "batch_period_s": 0.05,
                                               "min_subscribers": 1}, quiet=True)
    thermometers = start_node("temperature_publisher", {**machine, "min_subscribers": 1},
                              quiet=True)
    try:
        # Both publishers up and matched, and still nothing: they hold.
        assert spin_until(node, lambda: node.count_publishers("/scales") >= 1 and
                          node.count_publishers("/temperatures") >= 1, 60.0)
        spin_for(node, 3.0)
        assert batches == [] and temperatures == []
        start = time.time_ns() + 1_000_000_000
        for name in ("encoder_publisher", "temperature_publisher"):
            ok, reason = set_parameter_again_until_answered(node, name, "start_stamp_ns", start)
            assert ok, reason
        assert spin_until(node, lambda: len(batches) >= 5 and temperatures, 60.0)
        # Sample 0 at the stamp set, temperatures on the same time base.
        assert batches[0].first_sample_index == 0
        assert stamp_to_nanoseconds(batches[0].header.stamp) == start
        assert stamp_to_nanoseconds(temperatures[0].header.stamp) == start
        # Once started, the time base cannot move (the same value again is harmless).
        ok, reason = set_parameter_again_until_answered(node, "encoder_publisher",
                                                        "start_stamp_ns", start + 10**9)
        assert not ok and "cannot change" in reason
        ok, _ = set_parameter_again_until_answered(node, "encoder_publisher", "start_stamp_ns",
                                                   start)
        assert ok
    finally:
        encoder.stop()
        thermometers.stop()
        node.destroy_node()
