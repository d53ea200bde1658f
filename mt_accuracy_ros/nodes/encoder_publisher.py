"""Encoder publisher: the virtual machine tool's dual linear scales, streamed live.

Runs a scenario of the virtual machine tool (:mod:`mt_accuracy_ros.sim`) in
windows and publishes, in real time x ``rate_factor``:

* ``scales`` (``mt_accuracy_msgs/ScaleBatch``, sensor-data QoS): every head of
  every scale pair and the CNC command positions, ``batch_period_s`` per message;
* ``reference/tcp_error`` (``mt_accuracy_msgs/ReferenceMeasurement``, reliable):
  every ``reference_period_s`` the TCP error a reference instrument (laser
  tracker-like, 1 um at k = 2) measures at the current command position.

Sample i is stamped ``start_stamp_ns + i / sample_rate``. Late timer ticks
publish every batch that fell due - no sample is skipped. The node exits when
the scenario ends.
"""
from __future__ import annotations

import sys
import time

import numpy as np
from rclpy.node import Node

from mt_accuracy_msgs.msg import ReferenceMeasurement, ScaleBatch

from ..core.errors import MtAccuracyError
from ..sim.machine_tool import SimulationResult, simulate
from ._common import (MATCH_SETTLE_S, RESULT_QOS, SENSOR_QOS, accept, float_descriptor,
                      int_descriptor, nanoseconds_to_stamp, pack_float64, plain_descriptor,
                      refuse, run_node)
from ._scenario import ScenarioClock, resolve_scenario

#: Simulated seconds generated per window.
WINDOW_S = 2.0


class EncoderPublisher(Node):
    """Streams the scales (and reference readings) of one virtual machine."""

    def __init__(self, **kwargs) -> None:
        super().__init__("encoder_publisher", **kwargs)
        self._reference_sequence = 0  # ReferenceMeasurement.sequence
        self.declare_parameter("scenario", "demo", plain_descriptor(
            "Bundled scenario name or path to a scenario YAML", read_only=True))
        self.declare_parameter("batch_period_s", 0.05, float_descriptor(
            "Sim time covered by one ScaleBatch [s]", 0.001, 1.0, read_only=True))
        self.declare_parameter("rate_factor", 1.0, float_descriptor(
            "Sim seconds per wall second", 0.01, 1000.0, read_only=True))
        self.declare_parameter("start_stamp_ns", 0, int_descriptor(
            "Stamp of sample 0 [ns] (0: now); give several nodes the same one", 0, 2**63 - 1,
            read_only=True))
        self.declare_parameter("min_subscribers", 0, int_descriptor(
            "Hold the stream until this many subscriptions match 'scales'", 0, 100,
            read_only=True))
        self.declare_parameter("reference_period_s", 0.5, float_descriptor(
            "Sim time between two reference readings [s] (0: none)", 0.0, 3600.0))
        self.declare_parameter("frame_id", "", plain_descriptor(
            "frame_id of the messages (empty: the machine's name)"))
        self.add_on_set_parameters_callback(self._validate)

        self.scenario = resolve_scenario(str(self.get_parameter("scenario").value))
        self._rate = self.scenario.sample_rate_hz
        self._batch = max(1, int(round(self._rate * self.get_parameter("batch_period_s").value)))
        self._next_index = 0
        self._next_reference_s = 0.0
        self._window: SimulationResult | None = None
        self._scenario_clock: ScenarioClock | None = None
        self._matched_at: float | None = None
        self.finished = False
        self._scales = self.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
        self._reference = self.create_publisher(ReferenceMeasurement, "reference/tcp_error",
                                                RESULT_QOS)
        self._axes = list(self.scenario.machine.axis_order)
        self._last_direction: dict[str, int] = {}
        self._rng = np.random.default_rng(np.random.SeedSequence([self.scenario.seed, 0xEEF]))
        self.create_timer(min(self._batch / self._rate, 0.05), self._tick)

    def _validate(self, parameters):
        for parameter in parameters:
            if parameter.name == "reference_period_s" and not (
                    np.isfinite(parameter.value) and parameter.value >= 0):
                return refuse("reference_period_s must be finite and >= 0 [s]")
        return accept()

    def _start(self) -> bool:
        wanted = int(self.get_parameter("min_subscribers").value)
        if self._scales.get_subscription_count() < wanted:
            return False
        if wanted:
            if self._matched_at is None:
                self._matched_at = time.monotonic()
            if time.monotonic() - self._matched_at < MATCH_SETTLE_S:
                return False
        start = int(self.get_parameter("start_stamp_ns").value) or \
            self.get_clock().now().nanoseconds
        self._scenario_clock = ScenarioClock(start, float(self.get_parameter("rate_factor").value))
        return True

    def _window_for(self, index: int) -> SimulationResult:
        window = self._window
        if window is None or not (window.first_index <= index <
                                  window.first_index + window.time_s.size):
            size = int(WINDOW_S * self._rate)
            self._window = simulate(self.scenario, start_index=index, stop_index=index + size)
        return self._window

    def _tick(self) -> None:
        if self.finished:
            return
        if self._scenario_clock is None and not self._start():
            return
        due = int(self._scenario_clock.sim_time_s(self.get_clock().now().nanoseconds) * self._rate)
        total = self.scenario.n_samples
        try:
            while self._next_index + self._batch <= min(due, total):
                self._publish_batch(self._next_index)
                self._next_index += self._batch
        except MtAccuracyError as exc:
            self.get_logger().error(f"simulation failed: {exc}")
            self.finished = True
        if self._next_index + self._batch > total:
            self.finished = True

    def _publish_batch(self, first: int) -> None:
        window = self._window_for(first)
        offset = first - window.first_index
        if offset + self._batch > window.time_s.size:  # batch straddles two windows
            self._window = simulate(self.scenario, start_index=first,
                                    stop_index=first + int(WINDOW_S * self._rate))
            window, offset = self._window, 0
        rows = slice(offset, offset + self._batch)
        frame = str(self.get_parameter("frame_id").value) or self.scenario.machine.name
        message = ScaleBatch()
        message.header.stamp = nanoseconds_to_stamp(self._scenario_clock.stamp_ns(first / self._rate))
        message.header.frame_id = frame
        message.first_sample_index = int(first)
        message.sample_period = 1.0 / self._rate
        message.channel_names = list(window.scale_channels)
        message.positions = pack_float64(window.scale_readings[rows].ravel())
        message.command_axes = [a.lower() for a in self._axes]
        message.command_positions = pack_float64(
            np.column_stack([window.command[a][rows] for a in self._axes]).ravel())
        self._scales.publish(message)
        period = float(self.get_parameter("reference_period_s").value)
        if period > 0:
            end_s = (first + self._batch) / self._rate
            while self._next_reference_s < end_s:
                index = int(round(self._next_reference_s * self._rate)) - window.first_index
                index = min(max(index, offset), offset + self._batch - 1)
                self._publish_reference(window, index, frame)
                self._next_reference_s += period

    def _direction(self, window: SimulationResult, axis: str, index: int) -> int:
        """Sign of the axis' last motion up to ``index`` (what the CNC knows), 0 if none yet."""
        moving = np.flatnonzero(np.abs(window.velocity[axis][:index + 1]) > 1e-9)
        if moving.size:
            self._last_direction[axis] = int(np.sign(window.velocity[axis][moving[-1]]))
        return self._last_direction.get(axis, 0)

    def _publish_reference(self, window: SimulationResult, index: int, frame: str) -> None:
        uncertainty = 1e-6  # k = 2
        error = window.tcp_error(np.array([index]))[0] + \
            self._rng.normal(0.0, uncertainty / 2, 3)
        message = ReferenceMeasurement()
        message.header.stamp = nanoseconds_to_stamp(
            self._scenario_clock.stamp_ns((window.first_index + index) / self._rate))
        message.header.frame_id = frame
        message.instrument = "reference_probe"
        message.command_axes = [a.lower() for a in self._axes]
        message.command_positions = [float(window.command[a][index]) for a in self._axes]
        message.command_velocities = [float(window.velocity[a][index]) for a in self._axes]
        message.command_directions = [int(self._direction(window, a, index)) for a in self._axes]
        message.error.x, message.error.y, message.error.z = (float(v) for v in error)
        message.measured = [True, True, True]
        message.uncertainty = uncertainty
        message.sequence = self._reference_sequence
        self._reference_sequence += 1
        self._reference.publish(message)


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    return run_node(EncoderPublisher, args, until_finished=True)


if __name__ == "__main__":
    sys.exit(main())
