"""Foxglove bridge: the live graph's topics over the Foxglove WebSocket protocol.

Optional: start it beside the graph and open ``ws://<host>:<port>`` in the
Foxglove app (the layout ``share/mt_accuracy_ros/foxglove/mt_accuracy.json``
shows scales and yaw, the systematic profiles, the compensation, the
residual, the temperatures and a 3-D error map).

* Every topic of the graph (or the listed ``topics``) with an installed type
  is relayed as it is: serialized CDR, subscribed raw (never decoded), with
  its ``ros2msg`` schema - the same schema text rosbag2 and our recorder
  store - so Foxglove decodes it like a ROS 2 bag. QoS follows the
  publishers, and topics are rediscovered on a steady-clock timer.
* ``/error_map`` (``foxglove.SceneUpdate``): the latest ``error_map_points``
  compensation points, each a sphere at the command position, its colour
  the size of the model's TCP error, refreshed once a second.

The server is the ``foxglove-sdk`` package's (PyPI); ``port`` 0 picks a free
one (logged).
"""
from __future__ import annotations

import sys
from collections import deque

import numpy as np
from rclpy.clock import Clock, ClockType
from rclpy.node import Node

from mt_accuracy_msgs.msg import VolumetricCompensation

from ..core.errors import BagError
from ..io.msg_definitions import schema_text
from ._common import RESULT_QOS, float_descriptor, int_descriptor, plain_descriptor, run_node
from ._raw_topics import RawTopicFollower

#: Topic of the 3-D error map (a Foxglove scene, not a ROS topic).
ERROR_MAP_TOPIC = "/error_map"


def error_colour(magnitude_m: float, full_scale_m: float) -> tuple[float, float, float, float]:
    """RGBA from blue (no error) to red (``full_scale_m`` or more): the error map's scale."""
    share = float(np.clip(magnitude_m / full_scale_m, 0.0, 1.0)) if full_scale_m > 0 else 0.0
    return (share, 0.2, 1.0 - share, 0.9)


class FoxgloveBridge(Node):
    """Relay the graph to Foxglove; draw the compensation as a 3-D error map."""

    def __init__(self, **kwargs) -> None:
        super().__init__("foxglove_bridge", **kwargs)
        self.declare_parameter("host", "127.0.0.1", plain_descriptor(
            "Address the WebSocket server listens on (0.0.0.0: every interface)",
            read_only=True))
        self.declare_parameter("port", 8765, int_descriptor(
            "WebSocket port (0: any free port, logged)", 0, 65535, read_only=True))
        self.declare_parameter("topics", [""], plain_descriptor(
            "Topics to relay (empty: every topic with an installed type)", read_only=True))
        self.declare_parameter("discovery_period_s", 1.0, float_descriptor(
            "How often to look for new topics [s]", 0.05, 60.0))
        self.declare_parameter("error_map_points", 400, int_descriptor(
            "Compensation points kept in the 3-D error map", 1, 100000, read_only=True))
        self.add_on_set_parameters_callback(self._validate)
        import foxglove

        self._foxglove = foxglove
        self.server = foxglove.start_server(
            name="mt_accuracy_ros", host=str(self.get_parameter("host").value),
            port=int(self.get_parameter("port").value))
        self._channels: dict = {}
        self._points = deque(maxlen=int(self.get_parameter("error_map_points").value))
        from foxglove.channels import SceneUpdateChannel

        self._error_map = SceneUpdateChannel(ERROR_MAP_TOPIC)
        self.create_subscription(VolumetricCompensation, "compensation", self._on_compensation,
                                 RESULT_QOS)
        self._follower = RawTopicFollower(
            self, {t for t in self.get_parameter("topics").value if t},
            float(self.get_parameter("discovery_period_s").value), self._new_topic, "relaying")
        self.create_timer(1.0, self._publish_error_map,
                          clock=Clock(clock_type=ClockType.STEADY_TIME))
        self.get_logger().info(f"Foxglove WebSocket server on "
                               f"ws://{self.get_parameter('host').value}:{self.server.port}")

    def _validate(self, parameters):
        return self._follower.validate(parameters)

    def _new_topic(self, name: str, type_name: str, _offered: list[dict]):
        """A Foxglove channel for the topic (its ros2msg schema); the relay callback."""
        try:
            schema = schema_text(type_name)
        except BagError as exc:
            self.get_logger().warning(f"topic {name}: no schema ({exc}); not relayed")
            return None
        channel = self._foxglove.Channel(
            name, schema=self._foxglove.Schema(name=type_name, encoding="ros2msg",
                                               data=schema.encode()),
            message_encoding="cdr")
        self._channels[name] = channel
        clock = self.get_clock()

        def relay(data: bytes) -> None:
            channel.log(bytes(data), log_time=clock.now().nanoseconds)
        return relay

    def _on_compensation(self, message: VolumetricCompensation) -> None:
        error = (message.error.x, message.error.y, message.error.z)
        if all(np.isfinite(error)):
            self._points.append(((message.command_position.x, message.command_position.y,
                                  message.command_position.z), error))

    def error_map(self) -> list[tuple[tuple[float, float, float], tuple[float, ...]]]:
        """(command position [m], RGBA) of each kept compensation point; full scale is the
        largest error kept."""
        magnitudes = [float(np.linalg.norm(e)) for _, e in self._points]
        full_scale = max(magnitudes, default=0.0)
        return [(p, error_colour(m, full_scale)) for (p, _), m in zip(self._points, magnitudes)]

    def scene_update(self):
        """The error map as a ``foxglove.SceneUpdate`` (one entity of spheres)."""
        from foxglove.messages import (Color, Pose, Quaternion, SceneEntity, SceneUpdate,
                                       SpherePrimitive, Vector3)

        spheres = [SpherePrimitive(
            pose=Pose(position=Vector3(x=p[0], y=p[1], z=p[2]),
                      orientation=Quaternion(x=0.0, y=0.0, z=0.0, w=1.0)),
            size=Vector3(x=0.01, y=0.01, z=0.01), color=Color(r=c[0], g=c[1], b=c[2], a=c[3]))
            for p, c in self.error_map()]
        return SceneUpdate(entities=[SceneEntity(frame_id="machine", id="tcp_error",
                                                 spheres=spheres)])

    def _publish_error_map(self) -> None:
        if self._points:
            self._error_map.log(self.scene_update(), log_time=self.get_clock().now().nanoseconds)

    def destroy_node(self) -> None:
        self.server.stop()
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    return run_node(FoxgloveBridge, args)


if __name__ == "__main__":
    sys.exit(main())
