"""Encoder publisher: batched synchronous dual-scale samples from the virtual machine tool.

Publishes ``scales`` (``mt_accuracy_msgs/ScaleBatch``, sensor-data QoS): every
``batch_period_s`` one batch of ``sample_rate_hz * batch_period_s`` synchronous
samples of the heads ``<axis>1``, ``<axis>2`` of each axis, with the CNC command
positions.
"""
from __future__ import annotations

import sys
import time

import numpy as np
import rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter

from mt_accuracy_msgs.msg import ScaleBatch

from ..sim.motion import back_and_forth
from ..sim.scale_pair import YawProfile, read_scale_pair
from ._common import (MATCH_SETTLE_S, SENSOR_QOS, accept, float_descriptor, int_descriptor,
                      nanoseconds_to_stamp, pack_float64, plain_descriptor, refuse)


class EncoderPublisher(Node):
    """Streams ScaleBatch messages of a simulated X axis with two parallel scales."""

    def __init__(self, **kwargs) -> None:
        super().__init__("encoder_publisher", **kwargs)
        self.declare_parameter("sample_rate_hz", 1000, int_descriptor(
            "Synchronous sampling rate of all scale heads [Hz]", 100, 20000, read_only=True))
        self.declare_parameter("batch_period_s", 0.05, float_descriptor(
            "Time covered by one ScaleBatch [s]", 0.001, 1.0, read_only=True))
        self.declare_parameter("stroke_m", 0.39, float_descriptor(
            "Axis stroke [m] (Kidani Table 3.1: X 390 mm)", 0.01, 5.0))
        self.declare_parameter("scale_distance_m", 0.24, float_descriptor(
            "Distance between the two scales [m] (Kidani Table 3.1: X 240 mm)", 0.01, 5.0))
        self.declare_parameter("feed_m_per_s", 0.5, float_descriptor(
            "Feed speed of the back-and-forth program [m/s] (max 1.0 = 60 m/min)", 1e-4, 1.0))
        self.declare_parameter("noise_m", 20e-9, float_descriptor(
            "White noise of each head [m]", 0.0, 1e-5))
        self.declare_parameter("seed", 1, int_descriptor("Random seed", 0, 2**31 - 1,
                                                         read_only=True))
        self.declare_parameter("duration_s", 0.0, float_descriptor(
            "Stop after this much simulated time [s]; 0 = run until shut down", 0.0, 1e7,
            read_only=True))
        self.declare_parameter("frame_id", "machine", plain_descriptor(
            "frame_id of the published batches"))
        self.declare_parameter("min_subscribers", 0, int_descriptor(
            "Hold the stream until this many subscriptions match 'scales' (e.g. the "
            "estimator and a recorder), so nobody misses the first sample", 0, 100,
            read_only=True))
        self.add_on_set_parameters_callback(self._validate)

        self._rate = int(self.get_parameter("sample_rate_hz").value)
        self._batch = max(1, int(round(self._rate * self.get_parameter("batch_period_s").value)))
        self._rng = np.random.default_rng(int(self.get_parameter("seed").value))
        self._yaw_profile = YawProfile()
        self._next_index = 0
        self._start_ns: int | None = None
        self._matched_at: float | None = None
        self.finished = False
        self._publisher = self.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
        self._timer = self.create_timer(self._batch / self._rate, self._publish_batch)

    def _validate(self, parameters: list[Parameter]):
        for parameter in parameters:
            if parameter.name in ("stroke_m", "scale_distance_m", "feed_m_per_s") and \
                    not np.isfinite(parameter.value):
                return refuse(f"{parameter.name} must be finite")
        return accept()

    def _publish_batch(self) -> None:
        duration = float(self.get_parameter("duration_s").value)
        if duration > 0.0 and self._next_index / self._rate >= duration:
            self.finished = True
            return
        if self._start_ns is None:
            if self._publisher.get_subscription_count() < \
                    int(self.get_parameter("min_subscribers").value):
                return
            if self._matched_at is None:
                self._matched_at = time.monotonic()
            if time.monotonic() - self._matched_at < (
                    MATCH_SETTLE_S if self.get_parameter("min_subscribers").value else 0.0):
                return
            self._start_ns = self.get_clock().now().nanoseconds
        index = self._next_index + np.arange(self._batch)
        time_s = index / self._rate
        position, _ = back_and_forth(time_s, self.get_parameter("stroke_m").value,
                                     self.get_parameter("feed_m_per_s").value)
        x1, x2 = read_scale_pair(position, self.get_parameter("scale_distance_m").value,
                                 self._yaw_profile, noise_m=self.get_parameter("noise_m").value,
                                 rng=self._rng)
        message = ScaleBatch()
        message.header.stamp = nanoseconds_to_stamp(
            self._start_ns + int(round(self._next_index * 1e9 / self._rate)))
        message.header.frame_id = self.get_parameter("frame_id").value
        message.first_sample_index = int(self._next_index)
        message.sample_period = 1.0 / self._rate
        message.channel_names = ["x1", "x2"]
        message.positions = pack_float64(np.column_stack([x1, x2]).ravel())
        message.command_axes = ["x"]
        message.command_positions = pack_float64(position)
        self._publisher.publish(message)
        self._next_index += self._batch


def main(args: list[str] | None = None) -> int:
    rclpy.init(args=args if args is not None else sys.argv)
    node = EncoderPublisher()
    try:
        while rclpy.ok() and not node.finished:
            rclpy.spin_once(node, timeout_sec=0.1)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
