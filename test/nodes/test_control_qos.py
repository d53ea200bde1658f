"""The CNC takes the real-time compensation best effort (issue 27): a late correction is
worth nothing, so a lost one must never hold the next back."""
from __future__ import annotations

from graph_helpers import spin_until
from mt_accuracy_ros.commands.processes import start_node


def test_the_virtual_cncs_compensation_subscription_is_best_effort(rclpy_context):
    import rclpy
    from rclpy.qos import ReliabilityPolicy

    node = rclpy.create_node("control_qos_probe")
    machine = start_node("encoder_publisher", {"scenario": "demo", "start_stamp_ns": -1,
                                               "compensation_input": "realtime"}, quiet=True)
    try:
        def cnc_subscription():
            return [info for info in node.get_subscriptions_info_by_topic("/compensation")
                    if info.node_name == "encoder_publisher"]

        assert spin_until(node, lambda: bool(cnc_subscription()), 60.0), \
            "the virtual CNC never subscribed to /compensation"
        (info,) = cnc_subscription()
        assert info.qos_profile.reliability == ReliabilityPolicy.BEST_EFFORT
        # The broadcaster's side stays reliable for recorders (a reliable writer matches a
        # best-effort reader).
        from mt_accuracy_ros.nodes._common import COMPENSATION_QOS, CONTROL_QOS

        assert COMPENSATION_QOS.reliability == ReliabilityPolicy.RELIABLE
        assert CONTROL_QOS.depth == 100
    finally:
        machine.stop()
        node.destroy_node()
