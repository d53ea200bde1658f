"""Yaw estimator: yaw of each axis from its pair of parallel scales (Kidani eq. 2.13).

Subscribes ``scales`` (``mt_accuracy_msgs/ScaleBatch``, sensor-data QoS) and
publishes ``yaw/<axis>`` (``mt_accuracy_msgs/YawBatch``, reliable), one yaw per
sample, relative to the first sample received (the zero reference).
"""
from __future__ import annotations

import sys

import numpy as np
import rclpy
from rclpy.node import Node
from rclpy.parameter import Parameter

from mt_accuracy_msgs.msg import ScaleBatch, YawBatch

from ..core.dual_scale import yaw_from_scales
from ..core.errors import InputDataError
from ._common import (RESULT_QOS, SENSOR_QOS, accept, pack_float64, plain_descriptor, refuse,
                      unpack_float64)


class YawEstimator(Node):
    """Turns ScaleBatch messages into YawBatch messages per configured axis."""

    def __init__(self, **kwargs) -> None:
        super().__init__("yaw_estimator", **kwargs)
        self.declare_parameter("axes", ["x"], plain_descriptor(
            "Axes to estimate; channels '<axis>1' and '<axis>2' must be in the batches",
            read_only=True))
        self.declare_parameter("scale_distance_m", [0.24], plain_descriptor(
            "Distance D between the two scales of each axis [m], same order as 'axes'"))
        self.add_on_set_parameters_callback(self._validate)
        self._axes = list(self.get_parameter("axes").value)
        self._distances = [float(d) for d in self.get_parameter("scale_distance_m").value]
        if len(self._distances) != len(self._axes):
            raise ValueError("scale_distance_m needs one value per entry of 'axes'")
        self._reference: dict[str, tuple[float, float]] = {}
        self._yaw_publishers = {axis: self.create_publisher(YawBatch, f"yaw/{axis}", RESULT_QOS)
                            for axis in self._axes}
        self.create_subscription(ScaleBatch, "scales", self._on_batch, SENSOR_QOS)

    def _validate(self, parameters: list[Parameter]):
        for parameter in parameters:
            if parameter.name == "scale_distance_m":
                values = list(parameter.value)
                if len(values) != len(self._axes):
                    return refuse(f"scale_distance_m needs {len(self._axes)} values")
                if any(not np.isfinite(v) or v <= 0.0 for v in values):
                    return refuse("scale_distance_m values must be finite and > 0 [m]")
                self._distances = [float(v) for v in values]
        return accept()

    def _on_batch(self, message: ScaleBatch) -> None:
        channels = list(message.channel_names)
        data = unpack_float64(message.positions).reshape(-1, len(channels))
        for axis, distance in zip(self._axes, self._distances):
            try:
                first = data[:, channels.index(f"{axis}1")]
                second = data[:, channels.index(f"{axis}2")]
            except ValueError:
                continue
            if axis not in self._reference:
                self._reference[axis] = (float(first[0]), float(second[0]))
            try:
                yaw = yaw_from_scales(first, second, distance, reference=self._reference[axis])
            except InputDataError as exc:
                self.get_logger().warning(f"axis {axis}: batch skipped: {exc}")
                continue
            out = YawBatch()
            out.header = message.header
            out.axis = axis
            out.first_sample_index = message.first_sample_index
            out.sample_period = message.sample_period
            out.positions = pack_float64(0.5 * (first + second))
            out.yaw = pack_float64(yaw)
            self._yaw_publishers[axis].publish(out)


def main(args: list[str] | None = None) -> int:
    rclpy.init(args=args if args is not None else sys.argv)
    node = YawEstimator()
    try:
        rclpy.spin(node)
    except KeyboardInterrupt:
        pass
    finally:
        node.destroy_node()
        rclpy.try_shutdown()
    return 0


if __name__ == "__main__":
    sys.exit(main())
