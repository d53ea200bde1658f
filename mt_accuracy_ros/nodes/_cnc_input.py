"""A controller's compensation input on ROS topics: what a CNC node takes and applies.

Glue between the broadcaster's topics and
:mod:`mt_accuracy_ros.core.compensation.controller`: ``compensation``
(``VolumetricCompensation``) feeds the real-time offset, ``compensation_table``
(``CompensationTable``, latched) the tables. Malformed messages are counted
refusals (``<node>: delivery``); what the input did - corrections applied,
stale, the stamp-to-applied latency - goes out once a second as
``<node>: compensation`` on ``/diagnostics``.
"""
from __future__ import annotations

from collections.abc import Callable

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.clock import Clock, ClockType

from mt_accuracy_msgs.msg import CompensationTable, VolumetricCompensation

from ..core.compensation.controller import (MAX_CORRECTION_M, RealtimeOffset,
                                            TableCompensation)
from ..core.errors import InputDataError
from ..core.kinematics.machine import MachineDescription
from ._common import CONTROL_QOS, TABLE_QOS, stamp_to_nanoseconds, unpack_float64

#: How a controller can take the compensation. ``hybrid``: the tables for the
#: position-dependent part, evaluated at the current command every cycle (no
#: latency however fast the axes move), plus the real-time offset for the rest
#: (thermal drift and the like: slow, so its latency costs nothing) - each
#: real-time correction minus what the tables give at the command position it
#: was computed for (the message carries it).
MODES = ("off", "table", "realtime", "hybrid")


class CompensationInput:
    """Subscribes what ``mode`` needs and answers: which correction was live when?

    Parameters
    ----------
    node : rclpy Node
    mode : str
        ``off``, ``table`` or ``realtime`` (see :data:`MODES`).
    machine : MachineDescription
        The controller's nominal machine (tables are combined through it).
    health : DeliveryHealth
        Counts refusals per stream.
    now_stamp_ns : callable
        The controller's time in the stamps' time base [ns] (``None`` before it runs).
    cycle_s, delay_s, max_age_s : float
        See :class:`~mt_accuracy_ros.core.compensation.controller.RealtimeOffset`.
    """

    def __init__(self, node, mode: str, machine: MachineDescription, health, *,
                 now_stamp_ns: Callable[[], int | None], cycle_s: float, delay_s: float,
                 max_age_s: float, max_correction_m: float = MAX_CORRECTION_M) -> None:
        if mode not in MODES:
            raise InputDataError(f"compensation_input {mode!r}: one of {', '.join(MODES)}")
        self.node = node
        self.mode = mode
        self.health = health
        self.machine = machine
        self._now = now_stamp_ns
        self.rotary_axes = [a for a in machine.axis_order if machine.axes[a].is_rotary]
        self.offset = RealtimeOffset(cycle_s, delay_s, max_age_s,
                                     rotary_axes=len(self.rotary_axes),
                                     max_correction_m=max_correction_m)
        self.tables = TableCompensation(machine, max_correction_m=max_correction_m)
        self._reported = (0, 0)
        self.newest_stamp_ns = -1
        #: Where the node already has the tables' correction at a command (a virtual CNC
        #: computes it for its whole window): ``(stamp [ns], axis -> (1,) command) ->
        #: (3,) [m]`` at the tables' current revision, or None when it has not.
        self.known_table_correction: Callable[[int, dict[str, np.ndarray]],
                                              np.ndarray | None] | None = None
        self._publisher = node.create_publisher(DiagnosticArray, "/diagnostics", 10)
        if mode in ("realtime", "hybrid"):
            node.create_subscription(VolumetricCompensation, "compensation",
                                     health.guard("compensation", self._on_compensation),
                                     CONTROL_QOS)
        if mode in ("table", "hybrid"):
            node.create_subscription(CompensationTable, "compensation_table",
                                     health.guard("compensation_table", self._on_table),
                                     TABLE_QOS)
        if mode != "off":
            node.create_timer(1.0, self.publish_status,
                              clock=Clock(clock_type=ClockType.STEADY_TIME))

    # ------------------------------------------------------------ inputs
    def _on_compensation(self, message: VolumetricCompensation) -> None:
        #: The newest correction stamp that reached this input, whatever became of it [ns].
        self.newest_stamp_ns = max(self.newest_stamp_ns,
                                   stamp_to_nanoseconds(message.header.stamp))
        arrival = self._now()
        if arrival is None:
            raise InputDataError("compensation before the controller runs: not applied")
        self.health.sequence("compensation", message.sequence)
        rotary = self.rotary_axes
        if len(message.rotary_positions) != len(rotary) or \
                len(message.rotary_corrections) not in (0, len(rotary)):
            raise InputDataError(
                f"unknown axis: compensation for {len(message.rotary_positions)} rotary axes, "
                f"the machine has {len(rotary)} ({', '.join(rotary) or 'none'}); the last "
                "valid compensation stays")
        correction = np.array([message.correction.x, message.correction.y, message.correction.z])
        if self.mode == "hybrid":
            # The broadcaster names linear axes X, Y, Z by their letter.
            position = {"X": message.command_position.x, "Y": message.command_position.y,
                        "Z": message.command_position.z}
            position.update(zip(rotary, message.rotary_positions))
            command = {a: np.array([position.get(a, 0.0)]) for a in self.machine.axis_order}
            known = None if self.known_table_correction is None else \
                self.known_table_correction(stamp_to_nanoseconds(message.header.stamp), command)
            correction = correction - (known if known is not None
                                       else self.tables.correction(command)[0])
        reason = self.offset.offer(stamp_to_nanoseconds(message.header.stamp), arrival,
                                   correction, int(message.model_version),
                                   rotary_rad=np.asarray(message.rotary_corrections, float))
        if reason is None:
            self.health.processed("compensation")
        elif not reason.startswith("stale"):
            raise InputDataError(reason)
        # Stale ones are counted by the offset and reported in the 1 Hz status: at
        # 100 Hz a log line each would drown the log when the graph falls behind.

    def _on_table(self, message: CompensationTable) -> None:
        self.health.sequence("compensation_table", message.sequence)
        reason = self.tables.offer(message.axis, list(message.columns),
                                   unpack_float64(message.values), list(message.squareness_names),
                                   np.asarray(message.squareness, dtype=np.float64),
                                   int(message.model_version))
        if reason is not None:
            raise InputDataError(f"{reason}; axis {message.axis!r} keeps its last valid table")
        self.health.processed("compensation_table")

    # ------------------------------------------------------------ output
    def corrections(self, stamps_ns: np.ndarray, positions: dict[str, np.ndarray]
                    ) -> tuple[np.ndarray, np.ndarray]:
        """Correction (N, 3) [m] added to the command at each sample and its model version."""
        applied, _, versions = self.corrections_with_rotary(stamps_ns, positions)
        return applied, versions

    def corrections_with_rotary(self, stamps_ns: np.ndarray, positions: dict[str, np.ndarray],
                                table_correction: np.ndarray | None = None
                                ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """TCP correction (N, 3) [m], rotary-axis corrections (N, R) [rad], model version (N,).

        The rotary part (the tool's direction, from the real-time input) is
        added to the rotary commands; the tables carry position only.

        Parameters
        ----------
        stamps_ns : ndarray of int, shape (N,)
            The samples' controller times [ns].
        positions : dict of str to ndarray, shape (N,)
            Axis commands [m] (rotary [rad]) at those samples.
        table_correction : ndarray, shape (N, 3), optional
            What ``self.tables.correction(positions)`` gives [m], when the caller
            computed it at once for a longer stretch of commands (at the tables'
            current :attr:`~TableCompensation.revision`); None: computed here.
        """
        n = np.size(stamps_ns)
        rotary = np.zeros((n, len(self.rotary_axes)))
        if self.mode in ("realtime", "hybrid"):
            values, versions = self.offset.at_with_rotary(stamps_ns)
            # Memory stays bounded on a long run: older corrections are superseded.
            self.offset.forget_before(int(np.min(stamps_ns)) - 2 * self.offset.max_age_ns)
            applied, rotary = values[:, :3], values[:, 3:]
            if self.mode == "hybrid":
                applied = self._table_part(positions, table_correction) + applied
            return applied, rotary, versions
        if self.mode == "table":
            return (self._table_part(positions, table_correction), rotary,
                    np.full(n, self.tables.version, dtype=np.int64))
        return np.zeros((n, 3)), rotary, np.zeros(n, dtype=np.int64)

    def _table_part(self, positions: dict[str, np.ndarray],
                    table_correction: np.ndarray | None) -> np.ndarray:
        """The tables' correction (N, 3) [m] at ``positions``: the caller's, if it has it."""
        if table_correction is not None:
            return table_correction
        return self.tables.correction(positions)

    def publish_status(self) -> None:
        stats = self.offset.statistics
        p50, p99, worst = stats.latency_percentiles()
        table_refusals = sum(self.tables.refusals.values())
        news = (stats.stale - self._reported[0], stats.refused + table_refusals
                - self._reported[1])
        self._reported = (stats.stale, stats.refused + table_refusals)
        level = DiagnosticStatus.WARN if any(news) else DiagnosticStatus.OK
        text = (f"{news[0]} stale and {news[1]} refused since the last report; the last valid "
                "compensation stays" if any(news) else f"{self.mode} compensation applied")
        values = [("mode", self.mode), ("applied", stats.applied), ("stale", stats.stale),
                  ("refused", stats.refused + table_refusals),
                  ("latency_p50_ms", f"{p50 * 1e3:.2f}"), ("latency_p99_ms", f"{p99 * 1e3:.2f}"),
                  ("latency_max_ms", f"{worst * 1e3:.2f}"),
                  ("first_stale_stamp_ns", stats.first_stale_ns),
                  ("last_stale_stamp_ns", stats.last_stale_ns),
                  ("worst_stale_age_ms", f"{stats.worst_stale_age_s * 1e3:.1f}"),
                  ("table_version", self.tables.version),
                  ("tables", ",".join(sorted(self.tables.tables)))]
        values += [(f"reason.{k}", n) for k, n in sorted({**stats.reasons,
                                                          **self.tables.refusals}.items())]
        status = DiagnosticStatus(level=level, name=f"{self.node.get_fully_qualified_name()}: "
                                  "compensation", message=text, hardware_id=self.machine.name,
                                  values=[KeyValue(key=k, value=str(v)) for k, v in values])
        array = DiagnosticArray(status=[status])
        array.header.stamp = self.node.get_clock().now().to_msg()
        self._publisher.publish(array)
