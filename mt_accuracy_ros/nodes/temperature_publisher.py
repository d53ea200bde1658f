"""Temperature publisher: the virtual machine tool's thermocouples, streamed live.

Publishes ``temperatures`` (``mt_accuracy_msgs/TemperatureArray``, sensor-data
QoS, degrees Celsius as ``sensor_msgs/Temperature``) at the scenario's
temperature rate (x ``rate_factor``): the thermocouples every 110 mm on each
scale and the structure sensors. ``dead_sensors`` makes chosen sensors report
NaN (a broken thermocouple) for testing the consumers.

With ``lockstep`` it follows the encoder publisher's progress instead of the wall
clock: every temperature stamped up to the machine's stream position goes out
before the machine streams on (participant ``temperature_publisher:temperatures``).
"""
from __future__ import annotations

import sys
import time

import numpy as np
from rclpy.node import Node

from mt_accuracy_msgs.msg import TemperatureArray

from ..sim.machine_tool import simulate
from ._common import (MATCH_SETTLE_S, SENSOR_QOS, accept, float_descriptor, int_descriptor,
                      nanoseconds_to_stamp, pack_float64, plain_descriptor, refuse, run_node)
from ._lockstep import STREAM_TOPIC, ProgressReporter, lockstep_qos
from ._scenario import ScenarioClock, resolve_scenario


class TemperaturePublisher(Node):
    """Streams the temperatures of one virtual machine."""

    def __init__(self, **kwargs) -> None:
        super().__init__("temperature_publisher", **kwargs)
        self._sequence = 0  # TemperatureArray.sequence
        self.declare_parameter("scenario", "demo", plain_descriptor(
            "Bundled scenario name or path (the same as the encoder publisher's)", read_only=True))
        self.declare_parameter("rate_factor", 1.0, float_descriptor(
            "Sim seconds per wall second", 0.01, 1000.0, read_only=True))
        self.declare_parameter("start_stamp_ns", 0, int_descriptor(
            "Stamp of sim time 0 [ns] (0: now; -1: hold the stream until it is set)",
            -1, 2**63 - 1))
        self.declare_parameter("dead_sensors", [""], plain_descriptor(
            "Sensors that report NaN (fault injection)"))
        self.declare_parameter("frame_id", "", plain_descriptor("frame_id (empty: machine name)"))
        self.declare_parameter("min_subscribers", 0, int_descriptor(
            "Hold the stream until this many subscriptions match 'temperatures'", 0, 100,
            read_only=True))
        self.declare_parameter("lockstep", False, plain_descriptor(
            "Follow the encoder publisher's data time (its position on 'lockstep/stream') "
            "instead of the wall clock", read_only=True))
        self.add_on_set_parameters_callback(self._validate)
        self.scenario = resolve_scenario(str(self.get_parameter("scenario").value))
        result = simulate(self.scenario, start_index=0, stop_index=1)
        self._names = list(result.temperature_names)
        self._time = result.temperature_time_s
        self._values = result.temperatures_c
        self._variance = float(self.scenario.noise["thermocouple_k"]) ** 2
        self._next = 0
        self._scenario_clock: ScenarioClock | None = None   # set at the first tick not held
        self.finished = False
        self._released = False
        self._matched_at: float | None = None
        self._publisher = self.create_publisher(TemperatureArray, "temperatures", SENSOR_QOS)
        self._machine_at_ns: int | None = None   # the machine's stream position (lockstep)
        self._progress: ProgressReporter | None = None
        if self.get_parameter("lockstep").value:
            from mt_accuracy_msgs.msg import DataProgress

            self._progress = ProgressReporter(self)
            self.create_subscription(DataProgress, STREAM_TOPIC, self._on_progress,
                                     lockstep_qos())
        self.create_timer(0.05, self._tick)

    def _on_progress(self, message) -> None:
        if message.node == "encoder_publisher":
            from ._common import stamp_to_nanoseconds

            self._machine_at_ns = max(self._machine_at_ns or 0,
                                      stamp_to_nanoseconds(message.header.stamp))
            self._tick()

    def _validate(self, parameters):
        for parameter in parameters:
            if parameter.name == "start_stamp_ns" and self._scenario_clock is not None and \
                    parameter.value != self.get_parameter("start_stamp_ns").value:
                return refuse("start_stamp_ns cannot change once the stream has started")
            if parameter.name == "dead_sensors":
                unknown = [s for s in parameter.value if s and s not in self._names]
                if unknown:
                    return refuse(f"unknown sensor(s) {', '.join(unknown)}; known: "
                                  f"{', '.join(self._names)}")
        return accept()

    def _tick(self) -> None:
        wanted = int(self.get_parameter("min_subscribers").value)
        if self._scenario_clock is None:
            start = int(self.get_parameter("start_stamp_ns").value)
            if start < 0:
                return   # held until a start stamp is set (the demo sets it when all are up)
            self._scenario_clock = ScenarioClock(start or self.get_clock().now().nanoseconds,
                                                 float(self.get_parameter("rate_factor").value))
        if not self._released:
            if self._publisher.get_subscription_count() < wanted:
                return
            if wanted and self._matched_at is None:
                self._matched_at = time.monotonic()
            if wanted and time.monotonic() - self._matched_at < MATCH_SETTLE_S:
                return
            self._released = True
        if self._progress is not None:
            if self._machine_at_ns is None:
                return
            now_s = (self._machine_at_ns - self._scenario_clock.start_ns) / 1e9
        else:
            now_s = self._scenario_clock.sim_time_s(self.get_clock().now().nanoseconds)
        dead = {s for s in self.get_parameter("dead_sensors").value if s}
        while self._next < self._time.size and self._time[self._next] <= now_s:
            values = self._values[self._next].copy()
            for name in dead:
                if name in self._names:
                    values[self._names.index(name)] = np.nan
            message = TemperatureArray()
            stamp_ns = self._scenario_clock.stamp_ns(self._time[self._next])
            message.header.stamp = nanoseconds_to_stamp(stamp_ns)
            message.header.frame_id = str(self.get_parameter("frame_id").value) or \
                self.scenario.machine.name
            message.sensor_names = self._names
            message.temperatures = pack_float64(values)
            message.variances = pack_float64(np.full(len(self._names), self._variance))
            message.sequence = self._sequence
            self._sequence += 1
            self._publisher.publish(message)
            self._next += 1
        if self._next >= self._time.size:
            self.finished = True
        if self._progress is not None:
            # Every reading stamped before the next one is out, so the machine may run
            # up to that stamp without hearing from this node again: one report per
            # reading instead of one per scale batch. Once the last one is out, nothing
            # will ever hold the machine again.
            self._progress.report(handled_ns=2**62 if self.finished else
                                  self._scenario_clock.stamp_ns(self._time[self._next]) - 1)


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    return run_node(TemperaturePublisher, args, until_finished=True, events=True)


if __name__ == "__main__":
    sys.exit(main())
