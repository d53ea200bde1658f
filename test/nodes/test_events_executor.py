"""The nodes that spin in rclpy's events executor (``nodes/_common.node_executor``): the
machine, its thermometers, the estimator and the broadcaster, which take a message per
scale batch. They answer parameter requests, and a SIGINT stops them cleanly (exit 0):
the events executor's own ``spin()`` runs in C++ and never lets Python see the signal,
so a node spun by it would hang until killed."""
from __future__ import annotations

from graph_helpers import set_parameter_again_until_answered, spin_until
from mt_accuracy_ros.commands.processes import start_node


def test_events_executor_nodes_answer_parameters_and_stop_on_sigint(rclpy_context):
    import rclpy

    node = rclpy.create_node("events_executor_probe")
    # The machine held (no start stamp): it spins until stopped, as the estimator does.
    encoder = start_node("encoder_publisher", {"scenario": "demo", "start_stamp_ns": -1},
                         quiet=True)
    estimator = start_node("yaw_estimator", quiet=True)
    try:
        assert spin_until(node, lambda: node.count_publishers("/scales") >= 1 and
                          node.count_subscribers("/scales") >= 1, 60.0)
        ok, reason = set_parameter_again_until_answered(node, "yaw_estimator", "tolerance_rad",
                                                        20e-6)
        assert ok, reason
        ok, reason = set_parameter_again_until_answered(node, "yaw_estimator", "tolerance_rad",
                                                        float("nan"))
        assert not ok and "out of range" in reason
        ok, reason = set_parameter_again_until_answered(node, "encoder_publisher",
                                                        "reference_period_s", -1.0)
        assert not ok and "out of range" in reason
    finally:
        # stop(): SIGINT, then SIGKILL (exit -9) if the node has not ended within 30 s.
        codes = {"encoder_publisher": encoder.stop(timeout_s=30.0),
                 "yaw_estimator": estimator.stop(timeout_s=30.0)}
        node.destroy_node()
    assert codes == {"encoder_publisher": 0, "yaw_estimator": 0}
