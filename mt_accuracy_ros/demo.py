"""The main job on the virtual machine tool: real nodes in separate processes.

The encoder publisher streams dual-scale samples of a simulated X axis, the yaw
estimator turns them into yaw (Kidani eq. 2.13) in another process, and this
process listens like any other ROS tool, compares the estimate with the yaw the
simulator put in, and writes a summary.
"""
from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np


def run_demo(out_dir: str = "demo_output", duration_s: float = 6.0) -> int:
    import rclpy
    from rclpy.node import Node

    from mt_accuracy_msgs.msg import YawBatch

    from .nodes._common import RESULT_QOS, unpack_float64
    from .processes import start_node
    from .sim.scale_pair import YawProfile

    out = Path(out_dir)
    out.mkdir(parents=True, exist_ok=True)
    started = time.monotonic()
    estimator = start_node("yaw_estimator", {"axes": ["x"], "scale_distance_m": [0.24]})
    publisher = start_node("encoder_publisher", {
        "sample_rate_hz": 1000, "batch_period_s": 0.05, "duration_s": duration_s,
        "feed_m_per_s": 0.39, "noise_m": 20e-9})
    positions: list[np.ndarray] = []
    yaws: list[np.ndarray] = []
    indices: list[int] = []
    rclpy.init()
    listener = Node("demo_listener")

    def on_yaw(message: YawBatch) -> None:
        positions.append(unpack_float64(message.positions).copy())
        yaws.append(unpack_float64(message.yaw).copy())
        indices.append(int(message.first_sample_index))

    listener.create_subscription(YawBatch, "yaw/x", on_yaw, RESULT_QOS)
    try:
        deadline = time.monotonic() + duration_s + 20.0
        while time.monotonic() < deadline and publisher.popen.poll() is None:
            rclpy.spin_once(listener, timeout_sec=0.1)
        settle = time.monotonic() + 1.0
        while time.monotonic() < settle:
            rclpy.spin_once(listener, timeout_sec=0.05)
    finally:
        publisher.stop()
        estimator.stop()
        listener.destroy_node()
        rclpy.try_shutdown()

    if not yaws:
        print("demo: no yaw received from the estimator - is the ROS graph working?")
        return 1
    position = np.concatenate(positions)
    yaw = np.concatenate(yaws)
    # The estimator measures relative to its first sample; the simulator's
    # truth is absolute, so compare after removing the same reference.
    truth = YawProfile()(position)
    truth -= YawProfile()(np.array([position[0]]))[0]
    rmse_urad = float(np.sqrt(np.mean((yaw - truth) ** 2)) * 1e6)
    summary = {
        "batches_received": len(yaws),
        "samples_received": int(yaw.size),
        "first_batch_index": min(indices),
        "yaw_peak_to_peak_urad": float(np.ptp(yaw) * 1e6),
        "yaw_rmse_vs_simulator_truth_urad": rmse_urad,
        "wall_time_s": time.monotonic() - started,
    }
    (out / "summary.json").write_text(json.dumps(summary, indent=2))
    print("mt_accuracy_ros demo - virtual machine tool, X axis, dual scales D = 240 mm")
    for key, value in summary.items():
        print(f"  {key:36s} {value:.4g}" if isinstance(value, float) else f"  {key:36s} {value}")
    print(f"  summary written to {out / 'summary.json'}")
    return 0 if rmse_urad < 1.0 else 1
