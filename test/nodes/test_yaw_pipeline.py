"""The smallest real end-to-end path: encoder publisher -> yaw estimator, two processes."""
from __future__ import annotations

import time

import numpy as np

from mt_accuracy_ros.processes import start_node


def test_yaw_estimated_in_another_process_matches_the_simulated_yaw(rclpy_context):
    import rclpy

    from mt_accuracy_msgs.msg import YawBatch
    from mt_accuracy_ros.nodes._common import RESULT_QOS, unpack_float64
    from mt_accuracy_ros.sim.scale_pair import YawProfile

    estimator = start_node("yaw_estimator", {"axes": ["x"], "scale_distance_m": [0.24]})
    publisher = start_node("encoder_publisher", {"sample_rate_hz": 1000, "batch_period_s": 0.05,
                                                 "duration_s": 3.0, "noise_m": 0.0})
    node = rclpy.create_node("yaw_listener")
    batches: list[YawBatch] = []
    node.create_subscription(YawBatch, "yaw/x", batches.append, RESULT_QOS)
    try:
        # A timeout against a hung graph, not a speed requirement.
        deadline = time.monotonic() + 30
        while time.monotonic() < deadline and publisher.popen.poll() is None:
            rclpy.spin_once(node, timeout_sec=0.1)
        for _ in range(10):
            rclpy.spin_once(node, timeout_sec=0.05)
    finally:
        assert publisher.stop() == 0
        estimator.stop()
        node.destroy_node()
    assert len(batches) >= 20
    indices = [b.first_sample_index for b in batches]
    assert indices == sorted(indices)
    # Consecutive batches, no gap once the estimator is up.
    assert np.all(np.diff(indices) == 50)
    position = np.concatenate([unpack_float64(b.positions) for b in batches])
    yaw = np.concatenate([unpack_float64(b.yaw) for b in batches])
    # The estimator's zero reference is the first sample it heard, which the
    # listener may not have heard: compare changes relative to our first sample.
    truth = YawProfile()(position)
    error = (yaw - yaw[0]) - (truth - truth[0])
    # Without noise only the 10 nm quantisation of the heads remains: each
    # yaw carries <= 2 * 5 nm / 0.24 m, a difference of two yaws twice that.
    assert np.max(np.abs(error)) < 2 * 2 * 5e-9 / 0.24 + 1e-12
    assert np.ptp(yaw) > 3e-6
