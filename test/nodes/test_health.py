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
