"""CNC bridge: a real controller's data in, the compensation out (OPC UA).

Connects to a CNC through :mod:`mt_accuracy_ros.io.cnc` (``url``, e.g.
``opc.tcp://cnc:4840``, and a ``node_map`` YAML naming the OPC UA node and
unit of every axis, temperature and compensation input) and, every
``poll_period_s``:

* reads the axis command positions -> ``scales`` (``ScaleBatch``, one sample per
  message, no scale heads: the CNC's commands for the compensation
  broadcaster; sensor-data QoS), stamped with the read time;
* every ``temperature_period_s`` the temperatures -> ``temperatures``
  (``TemperatureArray``, degC);

and writes each ``compensation`` (``VolumetricCompensation``) it receives to
the CNC's compensation nodes (correction, model version, stamp), converting
to the node's unit. A failed read or write is counted and reported on
``/diagnostics``; the node keeps running and tries again next cycle. This
node never imports the simulator: it is the one that runs at a real machine.
"""
from __future__ import annotations

import sys

import numpy as np
from rclpy.node import Node

from mt_accuracy_msgs.msg import ScaleBatch, TemperatureArray, VolumetricCompensation

from ..core.errors import InputDataError
from ..io.cnc import connect, load_node_map
from ._common import (CONTROL_QOS, SENSOR_QOS, float_descriptor, pack_float64,
                      plain_descriptor, run_node, stamp_to_nanoseconds)
from ._health import DeliveryHealth
from ._priority import declare_niceness


class CncBridge(Node):
    """CNC (OPC UA) <-> topics: commands and temperatures in, compensation out."""

    def __init__(self, **kwargs) -> None:
        super().__init__("cnc_bridge", **kwargs)
        self.declare_parameter("url", "opc.tcp://localhost:4840", plain_descriptor(
            "The CNC's server, e.g. opc.tcp://cnc:4840", read_only=True))
        self.declare_parameter("node_map", "", plain_descriptor(
            "YAML naming the node and unit of each axis, temperature and compensation input",
            read_only=True))
        self.declare_parameter("poll_period_s", 0.01, float_descriptor(
            "Time between two reads of the axis positions [s]", 0.001, 10.0, read_only=True))
        self.declare_parameter("temperature_period_s", 0.5, float_descriptor(
            "Time between two published temperature readings [s]", 0.01, 3600.0,
            read_only=True))
        self.declare_parameter("frame_id", "cnc", plain_descriptor("frame_id of the messages"))
        if not str(self.get_parameter("node_map").value):
            raise InputDataError("node_map: give the YAML that maps the CNC's OPC UA nodes")
        node_map = load_node_map(str(self.get_parameter("node_map").value))
        self.cnc = connect(str(self.get_parameter("url").value), node_map)
        self.health = DeliveryHealth(self)
        declare_niceness(self, self.health)
        self._period = float(self.get_parameter("poll_period_s").value)
        self._temperature_every = max(1, int(round(
            float(self.get_parameter("temperature_period_s").value) / self._period)))
        self._index = 0
        self._temperature_sequence = 0
        self.written = 0
        self._scales = self.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
        self._temperatures = self.create_publisher(TemperatureArray, "temperatures", SENSOR_QOS)
        self.create_subscription(VolumetricCompensation, "compensation",
                                 self.health.guard("compensation", self._on_compensation),
                                 CONTROL_QOS)
        poll = self.health.guard("cnc_read", self._poll)  # a failed read: counted, not fatal
        self.create_timer(self._period, lambda: poll(None))

    def _poll(self, _message=None) -> None:
        positions, temperatures = self.cnc.read()  # raises InputDataError: counted
        now = self.get_clock().now()
        frame = str(self.get_parameter("frame_id").value)
        batch = ScaleBatch()
        batch.header.stamp = now.to_msg()
        batch.header.frame_id = frame
        batch.first_sample_index = self._index
        batch.sample_period = self._period
        batch.command_axes = [a.lower() for a in positions]
        batch.command_positions = pack_float64(np.array(list(positions.values()), dtype=float))
        self._scales.publish(batch)
        if self._index % self._temperature_every == 0 and temperatures:
            message = TemperatureArray(sequence=self._temperature_sequence)
            message.header = batch.header
            message.sensor_names = list(temperatures)
            message.temperatures = pack_float64(np.array(list(temperatures.values()), float))
            message.variances = [0.0] * len(temperatures)
            self._temperature_sequence += 1
            self._temperatures.publish(message)
        self._index += 1
        self.health.processed("cnc_read")

    def _on_compensation(self, message: VolumetricCompensation) -> None:
        self.health.sequence("compensation", message.sequence)
        correction = (message.correction.x, message.correction.y, message.correction.z)
        if not np.all(np.isfinite(correction)) or max(abs(c) for c in correction) > 1e-3:
            raise InputDataError(f"correction {correction} m: not finite or beyond 1 mm; "
                                 "not written, the CNC keeps the last one")
        self.cnc.write_compensation(correction, int(message.model_version),
                                    stamp_to_nanoseconds(message.header.stamp))
        self.written += 1
        self.health.processed("compensation")

    def destroy_node(self) -> None:
        self.cnc.close()
        super().destroy_node()


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    return run_node(CncBridge, args)


if __name__ == "__main__":
    sys.exit(main())
