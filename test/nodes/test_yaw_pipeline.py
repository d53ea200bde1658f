"""The smallest real end-to-end path: encoder publisher -> yaw estimator, two processes."""
from __future__ import annotations


import numpy as np

from graph_helpers import spin_until
from mt_accuracy_ros.commands.processes import start_node

SCENARIO = """machine: kidani_hmc
seed: 8
duration_s: 6
sample_rate_hz: 2000
program: {type: back_and_forth, axes: [X, Y], feed_m_per_min: 30}
effects: {timing_skew: {skew_s: 2e-6}}
"""


def test_yaw_estimated_in_another_process_equals_the_offline_computation(rclpy_context, tmp_path):
    import rclpy

    from mt_accuracy_msgs.msg import YawBatch
    from mt_accuracy_ros.core.scales.dual_scale import yaw_from_scales
    from mt_accuracy_ros.nodes._common import RESULT_QOS, unpack_float64
    from mt_accuracy_ros.sim.machine_tool import simulate
    from mt_accuracy_ros.sim.scenario import load_scenario

    (tmp_path / "s.yaml").write_text(SCENARIO)
    node = rclpy.create_node("yaw_listener")
    batches: list[YawBatch] = []
    node.create_subscription(YawBatch, "yaw/y", batches.append, RESULT_QOS)
    estimator = start_node("yaw_estimator", {"thermal_correction": False})
    try:
        assert spin_until(node, lambda: node.count_publishers("yaw/y") >= 0 and
                          node.count_subscribers("scales") >= 1)
        publisher = start_node("encoder_publisher", {"batch_period_s": 0.05,
                                                     "scenario": str(tmp_path / "s.yaml"),
                                                     "rate_factor": 3.0, "min_subscribers": 1})
        assert spin_until(node, lambda: publisher.popen.poll() is not None, timeout_s=60)
        # The estimator may still be working through the last batches on a loaded host.
        spin_until(node, lambda: len(batches) >= 120, timeout_s=30)
    finally:
        estimator.stop()
        node.destroy_node()
    assert publisher.popen.returncode == 0
    indices = [b.first_sample_index for b in batches]
    assert indices == list(range(0, 12000, 100))  # every batch, in order, none lost
    yaw = np.concatenate([unpack_float64(b.yaw) for b in batches])
    result = simulate(load_scenario(tmp_path / "s.yaml"))
    first, second = result.channel("y1"), result.channel("y2")
    offline = yaw_from_scales(first, second, 0.60, reference=(first[0], second[0]))
    np.testing.assert_array_equal(yaw, offline)  # same numbers, bit for bit
    assert np.ptp(yaw) > 1e-6
