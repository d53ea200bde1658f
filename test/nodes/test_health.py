"""Delivery counters: gaps, refusals, late input, and the status they publish."""
from __future__ import annotations

from graph_helpers import spin_until


def test_counters_and_their_diagnostics(rclpy_context):
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from mt_accuracy_ros.nodes._health import DeliveryHealth

    node = rclpy.create_node("health_under_test")
    health = DeliveryHealth(node, period_s=0.2)
    received = []
    node.create_subscription(DiagnosticArray, "/diagnostics", received.append, 50)
    # Batches of 100 samples: 0, 100, [200 lost], 300; then a restart at 0.
    assert [health.sequence("scales", i, 100) for i in (0, 100, 300)] == [0, 0, 100]
    health.sequence("scales", 0, 100)
    # Messages with sequence 0, 1, 4: two lost.
    assert [health.sequence("model_check", i) for i in (0, 1, 4)] == [0, 0, 2]
    health.late("temperatures", 3)

    def handler(message):
        if message == "bad":
            raise ZeroDivisionError("division by zero")
        health.processed("temperatures")

    guarded = health.guard("temperatures", handler)
    for message in ("good", "bad", "good"):
        guarded(message)  # never raises
    counts = health.counts
    assert counts["scales"]["lost"] == 100 and counts["scales"]["out_of_order"] == 1
    assert counts["model_check"]["lost"] == 2
    assert counts["temperatures"]["processed"] == 2
    assert counts["temperatures"]["refused"] == 1 and counts["temperatures"]["late"] == 3
    assert "ZeroDivisionError" in health.last_reason["temperatures"]

    def has_counters():
        for array in received:
            for status in array.status:
                values = {v.key: v.value for v in status.values}
                if values.get("scales.lost") == "100" and values.get("temperatures.late") == "3":
                    return status
        return None

    assert spin_until(node, lambda: has_counters() is not None, 10)
    status = has_counters()
    assert status.name == "/health_under_test: delivery" and status.level == b"\x01"  # WARN
    assert any("refused: ZeroDivisionError" in s.message for a in received for s in a.status)
    node.destroy_node()


def test_every_warning_is_repeated_with_each_status_until_the_end(rclpy_context):
    """A WARN (a lockstep participant left out, a dead sensor) went out once: a listener
    that missed that moment - the main job's summary - never heard it. Each warning is now
    sent with every status as warning.<n>, in order."""
    import rclpy
    from diagnostic_msgs.msg import DiagnosticArray

    from mt_accuracy_ros.nodes._health import DeliveryHealth, warnings_of

    node = rclpy.create_node("warner_under_test")
    health = DeliveryHealth(node, period_s=0.2)
    left_out = ("lockstep: model_monitor held the stream 121 s of wall time (reference "
                "reading not handled); streaming on without it - the run is no longer "
                "host-independent")
    health.warn(left_out)
    health.warn("temperature sensor bed: no value (nan) - left out of the model's inputs")
    health.warn(left_out)                  # said again: still one warning
    received = []
    node.create_subscription(DiagnosticArray, "/diagnostics", received.append, 50)

    def periodic():
        for array in received:
            for status in array.status:
                values = {v.key: v.value for v in status.values}
                if status.message == "all streams complete" and warnings_of(values):
                    return values
        return None

    # Subscribed after the WARNs went out: the periodic statuses still carry them.
    assert spin_until(node, lambda: periodic() is not None, 10)
    assert warnings_of(periodic()) == [
        left_out, "temperature sensor bed: no value (nan) - left out of the model's inputs"]
    # The main job's summary takes them from the statuses it hears, once each.
    from mt_accuracy_ros.commands.demo import hear_warnings, warning_lines

    heard: dict[str, list[str]] = {}
    for array in received:
        for status in array.status:
            hear_warnings(heard, status.name, {v.key: v.value for v in status.values})
    assert warning_lines(heard) == [
        f"warner_under_test: {left_out}",
        "warner_under_test: temperature sensor bed: no value (nan) - left out of the model's "
        "inputs"]
    node.destroy_node()


def test_a_live_sensor_that_dies_or_freezes_is_named_and_left_out():
    """The live judge uses the offline rules (core/inputs/sensor_health.py): NaN, a dead
    thermocouple's -180 degC, degF/kelvin slips and a sensor frozen while another warms."""
    import math

    from mt_accuracy_ros.core.inputs.sensor_health import STUCK_MIN_ROWS
    from mt_accuracy_ros.nodes._health import LiveSensorWatch

    watch = LiveSensorWatch()
    good, bad = watch.judge({"bed": math.nan, "column": -180.0, "spindle": 95.0,
                             "ambient": 293.15, "y1": 20.0})
    assert good == {"y1": 20.0}
    assert {name: kind for name, (kind, _) in bad.items()} == {
        "bed": "dropout", "column": "dead", "spindle": "out_of_range", "ambient": "dead"}
    assert bad["column"][1].startswith("reads -180 degC, a physically absent value")
    # y1 repeats 20.0 bit for bit while the column warms by 0.1 K a reading.
    for k in range(STUCK_MIN_ROWS):
        good, bad = watch.judge({"y1": 20.0, "column": 20.0 + 0.1 * k})
    assert "y1" not in good and bad["y1"][0] == "stuck", bad
    assert bad["y1"][1].startswith("frozen at 20 degC for")
    # A sensor at rest while nothing else moves is not frozen: a cold machine is still.
    quiet = LiveSensorWatch()
    for _ in range(STUCK_MIN_ROWS + 5):
        good, bad = quiet.judge({"a": 20.0, "b": 20.01})
    assert bad == {} and good == {"a": 20.0, "b": 20.01}
