"""Encoder publisher: the virtual machine tool's dual linear scales, streamed live.

Runs a scenario of the virtual machine tool (:mod:`mt_accuracy_ros.sim`) in
windows and publishes, in real time x ``rate_factor``:

* ``scales`` (``mt_accuracy_msgs/ScaleBatch``, sensor-data QoS): every head of
  every scale pair and the CNC command positions, ``batch_period_s`` per message;
* ``reference/tcp_error`` (``mt_accuracy_msgs/ReferenceMeasurement``, reliable):
  every ``reference_period_s`` the TCP error a reference instrument (laser
  tracker-like, 1 um at k = 2) measures at the current command position. With a
  scenario's ``work_offset`` the instrument was zeroed there at the start (an
  R-test's zero on the part): each reading is the error relative to that one.

Sample i is stamped ``start_stamp_ns + i / sample_rate``. Late timer ticks
publish every batch that fell due - no sample is skipped. The node exits when
the scenario ends.

With ``lockstep`` the machine streams in data time instead of the wall clock's:
the next batch goes out once every participant named in ``lockstep_nodes`` has
handled what it needs (:mod:`._lockstep`), so the run's outcome does not depend
on the host's speed. The controller then judges a correction's age in data time.

The virtual machine is a CNC with an external compensation input
(``compensation_input``): ``table`` interpolates the latched
``compensation_table`` per axis and combines it through the CNC's kinematic
chain; ``realtime`` applies the latest ``compensation`` message at the
controller cycle after a fixed delay (stale ones are counted, not applied);
``hybrid`` takes the tables at the current command plus the real-time rest.
The correction is added to the commanded position, so the axes move by it
(the scale heads read it) and the reference instrument measures the
compensated machine; each reading says what was applied
(``applied_correction``, ``compensation_model_version``). To first order the
machine's error at the shifted command equals its error at the command (the
difference is |correction| x the error's slope, below 1e-10 m here).
"""
from __future__ import annotations

import sys
import time
from concurrent.futures import ThreadPoolExecutor

import numpy as np
from rclpy.node import Node

from mt_accuracy_msgs.msg import ReferenceMeasurement, ScaleBatch

from ..core.compensation.error_model import ErrorModel
from ..core.compensation.five_axis import tool_direction
from ..core.errors import MtAccuracyError
from ..sim.machine_tool import SimulationResult, simulate
from ._cnc_input import MODES, CompensationInput
from ._health import DeliveryHealth
from ._priority import declare_niceness
from ._common import (MATCH_SETTLE_S, RESULT_QOS, SENSOR_QOS, accept, float_descriptor,
                      int_descriptor, nanoseconds_to_stamp, pack_float64, plain_descriptor,
                      refuse, run_node)
from ._lockstep import (PROGRESS_TOPIC, STREAM_TOPIC, LockstepGate, ProgressReporter,
                        check_compensation_delay, lockstep_qos, parse_participants,
                        progress_from_message)
from ._scenario import ScenarioClock, resolve_scenario

#: Simulated seconds generated per window.
WINDOW_S = 2.0
#: The 5-axis reference instrument's tool-direction uncertainty (k = 2) [rad].
ORIENTATION_UNCERTAINTY_RAD = 2e-6


#: Largest ScaleBatch [bytes] the best-effort ``scales`` topic delivered every time
#: (cross-process, Fast DDS, this machine, two runs: 0.48 MB 3 of 3; 0.96-4.8 MB 0 or 1 of 3;
#: `python -m bench.scale_batch_delivery`).
MAX_SCALE_BATCH_BYTES = 450_000


class EncoderPublisher(Node):
    """Streams the scales (and reference readings) of one virtual machine."""

    def __init__(self, **kwargs) -> None:
        super().__init__("encoder_publisher", **kwargs)
        self._reference_sequence = 0  # ReferenceMeasurement.sequence
        self.declare_parameter("scenario", "demo", plain_descriptor(
            "Bundled scenario name or path to a scenario YAML", read_only=True))
        # 10 ms: the latency sweep (docs/benchmarks.md) gives p99 stamp-to-applied <= 20 ms
        # at 20 kHz x 6 heads there; 5 ms costs more CPU than it saves latency on 2 cores.
        self.declare_parameter("batch_period_s", 0.01, float_descriptor(
            "Sim time covered by one ScaleBatch [s]", 0.001, 1.0, read_only=True))
        self.declare_parameter("rate_factor", 1.0, float_descriptor(
            "Sim seconds per wall second", 0.01, 1000.0, read_only=True))
        self.declare_parameter("start_stamp_ns", 0, int_descriptor(
            "Stamp of sample 0 [ns] (0: now; -1: hold the stream until it is set); give "
            "several nodes the same one", -1, 2**63 - 1))
        self.declare_parameter("min_subscribers", 0, int_descriptor(
            "Hold the stream until this many subscriptions match 'scales'", 0, 100,
            read_only=True))
        self.declare_parameter("reference_period_s", 0.5, float_descriptor(
            "Sim time between two reference readings [s] (0: none)", 0.0, 3600.0))
        self.declare_parameter("frame_id", "", plain_descriptor(
            "frame_id of the messages (empty: the machine's name)"))
        self.declare_parameter("compensation_input", "off", plain_descriptor(
            "How the CNC takes the compensation: off, table (compensation_table), realtime "
            "(compensation) or hybrid (tables + the real-time rest)", read_only=True))
        self.declare_parameter("controller_cycle_s", 0.001, float_descriptor(
            "CNC interpolation cycle: the real-time offset changes at its ticks [s]",
            1e-5, 1.0, read_only=True))
        self.declare_parameter("compensation_delay_s", 0.02, float_descriptor(
            "Fixed delay from a correction's stamp to its application [s]", 0.0, 10.0,
            read_only=True))
        self.declare_parameter("max_correction_m", 1e-3, float_descriptor(
            "The controller's correction limit [m]: a real-time correction or a translational "
            "table value beyond it is refused and counted, whatever the model says",
            1e-9, 0.1, read_only=True))
        self.declare_parameter("max_compensation_age_s", 0.25, float_descriptor(
            "A correction arriving later than this after its stamp is stale [s]", 1e-3, 60.0,
            read_only=True))
        self.declare_parameter("lockstep", False, plain_descriptor(
            "Stream in data time, each batch once every lockstep_nodes participant has caught "
            "up (host-independent runs), instead of in real time x rate_factor",
            read_only=True))
        self.declare_parameter("lockstep_nodes", [""], plain_descriptor(
            "Lockstep participants as node:stream (stream: scales, compensation, reference, "
            "temperatures or checks)", read_only=True))
        self.declare_parameter("lockstep_lead_s", 0.02, float_descriptor(
            "How far a 'scales' participant may trail the stream in a lockstep run [s of data]",
            0.0, 10.0, read_only=True))
        self.declare_parameter("lockstep_timeout_s", 120.0, float_descriptor(
            "Wall seconds a silent participant may hold the stream before it is left out "
            "(WARN on /diagnostics)", 1.0, 3600.0, read_only=True))
        self.add_on_set_parameters_callback(self._validate)

        self.scenario = resolve_scenario(str(self.get_parameter("scenario").value))
        self._rate = self.scenario.sample_rate_hz
        self._batch = max(1, int(round(self._rate * self.get_parameter("batch_period_s").value)))
        machine = self.scenario.machine
        linear = [a for a in machine.axis_order if not machine.axes[a].is_rotary]
        batch_bytes = 8 * self._batch * (2 * len(linear) + len(machine.axis_order))
        if batch_bytes > MAX_SCALE_BATCH_BYTES:
            # Best effort drops what it cannot deliver whole without a word: measured,
            # larger batches arrive intermittently or never (docs/reliability.md).
            raise MtAccuracyError(
                f"batch_period_s {self.get_parameter('batch_period_s').value:g} s at "
                f"{self._rate:g} Hz makes {self._batch}-sample batches of {batch_bytes / 1e6:.2f}"
                f" MB; the best-effort 'scales' topic delivers batches up to "
                f"{MAX_SCALE_BATCH_BYTES / 1e6:.2f} MB: lower batch_period_s")
        self._next_index = 0
        self._next_reference_s = 0.0
        self._window: SimulationResult | None = None
        #: (3,) the machine's error where the reference instrument was zeroed [m].
        self._instrument_zero: np.ndarray | None = None
        self._pool = ThreadPoolExecutor(max_workers=1, thread_name_prefix="simulate")
        # The window thread must not hold the GIL for the default 5 ms while a batch or a
        # compensation is due: hand it over every 0.5 ms.
        sys.setswitchinterval(0.0005)
        self._ahead: tuple | None = None   # (first index, future) of the next window
        self._scenario_clock: ScenarioClock | None = None
        self._matched_at: float | None = None
        self.finished = False
        self._scales = self.create_publisher(ScaleBatch, "scales", SENSOR_QOS)
        self._reference = self.create_publisher(ReferenceMeasurement, "reference/tcp_error",
                                                RESULT_QOS)
        self._axes = list(self.scenario.machine.axis_order)
        self._last_direction: dict[str, int] = {}
        self._rng = np.random.default_rng(np.random.SeedSequence([self.scenario.seed, 0xEEF]))
        mode = str(self.get_parameter("compensation_input").value)
        if mode not in MODES:
            raise MtAccuracyError(f"compensation_input {mode!r}: one of {', '.join(MODES)}")
        self.health = DeliveryHealth(self)
        declare_niceness(self, self.health)
        self.compensation = CompensationInput(
            self, mode, self.scenario.machine, self.health, now_stamp_ns=self._now_stamp_ns,
            cycle_s=float(self.get_parameter("controller_cycle_s").value),
            delay_s=float(self.get_parameter("compensation_delay_s").value),
            max_age_s=float(self.get_parameter("max_compensation_age_s").value),
            max_correction_m=float(self.get_parameter("max_correction_m").value))
        # Where a unit move of each linear axis takes the TCP (+-unit vectors): the
        # axes realise a TCP correction c by moving c . direction each.
        model = ErrorModel(self.scenario.machine)
        self._kinematics = model.kinematics
        middle = {a: np.array([0.5 * sum(self.scenario.machine.axes[a].stroke)])
                  for a in self._axes}
        self._axis_directions = {
            a: model.axis_direction(a, middle)[0] for a in self._axes
            if not self.scenario.machine.axes[a].is_rotary}
        self._last_reference_ns: int | None = None
        #: ((window's first index, tables' revision), the window, the tables' correction
        #: (W, 3) [m] at its commands).
        self._tables_at: tuple[tuple[int, int], SimulationResult, np.ndarray] | None = None
        self.compensation.known_table_correction = self._known_table_correction
        self._lockstep: LockstepGate | None = None
        self._waiting: tuple[str, float] | None = None   # (participant, since [monotonic s])
        if self.get_parameter("lockstep").value:
            self._start_lockstep()
        # Ticks several times per batch: a batch goes out within a quarter of its period
        # (at most 5 ms) after its last sample is due - its latency, not the tick's.
        self.create_timer(min(self._batch / self._rate / 4, 0.005), self._tick)

    def _start_lockstep(self) -> None:
        from mt_accuracy_msgs.msg import DataProgress

        try:
            participants = parse_participants(list(self.get_parameter("lockstep_nodes").value))
            check_compensation_delay(float(self.get_parameter("compensation_delay_s").value),
                                     self._batch / self._rate, participants)
        except ValueError as exc:
            raise MtAccuracyError(str(exc)) from exc
        self._lockstep = LockstepGate(
            participants, lead_ns=int(round(float(self.get_parameter("lockstep_lead_s").value)
                                            * 1e9)),
            compensation_delay_ns=int(round(float(
                self.get_parameter("compensation_delay_s").value) * 1e9)))
        # The stream's position, for what follows it (the temperature source).
        self._progress = ProgressReporter(self, topic=STREAM_TOPIC)
        self.create_subscription(DataProgress, PROGRESS_TOPIC, self._on_progress,
                                 lockstep_qos())

    def _on_progress(self, message) -> None:
        if message.node in self._lockstep.participants:
            self._lockstep.update(message.node, progress_from_message(message))
            self._tick()

    def _data_stamp_ns(self, index: int) -> int:
        return self._scenario_clock.start_ns + int(round(index / self._rate * 1e9))

    def _validate(self, parameters):
        for parameter in parameters:
            if parameter.name == "start_stamp_ns" and self._scenario_clock is not None and \
                    parameter.value != self.get_parameter("start_stamp_ns").value:
                return refuse("start_stamp_ns cannot change once the stream has started")
            if parameter.name == "reference_period_s" and not (
                    np.isfinite(parameter.value) and parameter.value >= 0):
                return refuse("reference_period_s must be finite and >= 0 [s]")
        return accept()

    def _start(self) -> bool:
        if int(self.get_parameter("start_stamp_ns").value) < 0:
            return False   # held until a start stamp is set (the demo sets it when all are up)
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
        if self._lockstep is not None:
            self._progress.report(handled_ns=start)   # the stream's position: its start
        return True

    def destroy_node(self) -> None:
        self._pool.shutdown(wait=False, cancel_futures=True)
        super().destroy_node()

    def _now_stamp_ns(self) -> int | None:
        """The controller's time in the stamps' time base (sim time), None before start."""
        if self._scenario_clock is None:
            return None
        if self._lockstep is not None:
            # Data time: where the stream is. A correction is as late as the data it missed.
            return self._data_stamp_ns(self._next_index)
        clock = self._scenario_clock
        return clock.stamp_ns(clock.sim_time_s(self.get_clock().now().nanoseconds))

    def _simulate(self, first: int) -> SimulationResult:
        """The window starting at sample ``first``: computed ahead in a worker thread.

        A window takes tens of ms at 20 kHz; computed in the timer callback it would
        hold every batch (and every compensation downstream) back once per window.
        The next window is started as soon as one is taken (numpy releases the GIL).
        """
        size = int(WINDOW_S * self._rate)
        ahead = self._ahead
        if ahead is not None and ahead[0] == first:
            window = ahead[1].result()
        else:
            window = simulate(self.scenario, start_index=first, stop_index=first + size)
        if self.scenario.work_offset and self._instrument_zero is None and first == 0:
            # The instrument is zeroed at the work offset before the program starts:
            # every reading is then relative to the error it had there.
            self._instrument_zero = window.error_at(self.scenario.work_offset, 0)
        following = first + size
        self._ahead = None
        if following < self.scenario.n_samples:
            self._ahead = (following, self._pool.submit(
                simulate, self.scenario, start_index=following, stop_index=following + size))
        return window

    def _window_for(self, index: int) -> SimulationResult:
        window = self._window
        if window is None or not (window.first_index <= index <
                                  window.first_index + window.time_s.size):
            self._window = self._simulate(index)
        return self._window

    def _tick(self) -> None:
        if self.finished:
            return
        if self._scenario_clock is None and not self._start():
            return
        if self._lockstep is not None:
            self._tick_lockstep()
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
        self._finish_at_the_end()

    def _finish_at_the_end(self) -> None:
        if self._next_index + self._batch > self.scenario.n_samples:
            if self._lockstep is not None and not self.finished:
                # The stream's end: what follows the stream publishes everything before it.
                self._progress.report(handled_ns=self._data_stamp_ns(self._next_index))
            self.finished = True
            if self.compensation.mode != "off":
                self.compensation.publish_status()  # the whole run's figures, once more

    def _tick_lockstep(self) -> None:
        """Every batch the participants are ready for (at most 0.1 s of wall time: the
        reports that open the next ones must get their turn)."""
        total = self.scenario.n_samples
        until = time.monotonic() + 0.1
        try:
            while self._next_index + self._batch <= total and time.monotonic() < until:
                start = self._data_stamp_ns(self._next_index)
                waiting = self._lockstep.waiting_for(
                    start, self._data_stamp_ns(self._next_index + self._batch),
                    self._last_reference_ns, self._scenario_clock.start_ns)
                if waiting is None:
                    waiting = self._corrections_in_flight(start)
                if waiting is not None:
                    self._hold(*waiting)
                    return
                self._waiting = None
                self._publish_batch(self._next_index)
                self._next_index += self._batch
                self._report_position()
        except MtAccuracyError as exc:
            self.get_logger().error(f"simulation failed: {exc}")
            self.finished = True
        self._finish_at_the_end()

    def _report_position(self) -> None:
        """Say the stream's position (on ``lockstep/stream``) when a participant following
        it (the temperature source) has not yet published what lies before it: right after
        the batch that reaches it, but not after every batch - each report costs its
        subscribers a callback, and there is one batch every 10 ms of data."""
        position = self._data_stamp_ns(self._next_index)
        if self._lockstep.stream_awaited(position):
            self._progress.report(handled_ns=position)

    def _corrections_in_flight(self, start_ns: int) -> tuple[str, str] | None:
        """The broadcaster says it has computed this batch's corrections: wait (at most
        1 s of wall time - they travel best effort) until they have reached the input."""
        if self.compensation.mode not in ("realtime", "hybrid") or \
                "compensation" not in self._lockstep.participants.values():
            return None
        needed = start_ns - self.compensation.offset.delay_ns
        if needed <= self._scenario_clock.start_ns or self.compensation.newest_stamp_ns >= needed:
            return None
        if self._waiting is not None and self._waiting[0] == "corrections" and \
                time.monotonic() - self._waiting[1] > 1.0:
            return None
        return "corrections", "computed, not yet received"

    def _hold(self, node: str, what: str) -> None:
        """Wait for ``node``; leave it out (WARN) once it has been silent too long."""
        now = time.monotonic()
        if self._waiting is None or self._waiting[0] != node:
            self._waiting = (node, now)
            return
        waited = now - self._waiting[1]
        if waited > float(self.get_parameter("lockstep_timeout_s").value):
            reason = (f"lockstep: {node} held the stream {waited:.0f} s of wall time ({what}); "
                      "streaming on without it - the run is no longer host-independent")
            self._lockstep.leave_out(node, reason)
            self.health.warn(reason)
            self._waiting = None

    def _publish_batch(self, first: int) -> None:
        window = self._window_for(first)
        offset = first - window.first_index
        if offset + self._batch > window.time_s.size:  # batch straddles two windows
            self._window = self._simulate(first)
            window, offset = self._window, 0
        rows = slice(offset, offset + self._batch)
        frame = str(self.get_parameter("frame_id").value) or self.scenario.machine.name
        stamps = self._scenario_clock.start_ns + np.round(
            (first + np.arange(self._batch)) / self._rate * 1e9).astype(np.int64)
        tables = self._table_correction(window)
        applied, rotary_applied, versions = self.compensation.corrections_with_rotary(
            stamps, {a: window.command[a][rows] for a in self._axes},
            table_correction=None if tables is None else tables[rows])
        readings = window.scale_readings[rows]
        if np.any(applied):
            readings = readings.copy()
            for k, axis in enumerate(window.scale_axes):
                shift = applied @ self._axis_directions[axis]
                readings[:, 2 * k] += shift
                readings[:, 2 * k + 1] += shift
        message = ScaleBatch()
        message.header.stamp = nanoseconds_to_stamp(int(stamps[0]))
        message.header.frame_id = frame
        message.first_sample_index = int(first)
        message.sample_period = 1.0 / self._rate
        message.channel_names = list(window.scale_channels)
        message.positions = pack_float64(readings.ravel())
        message.command_axes = [a.lower() for a in self._axes]
        message.command_positions = pack_float64(
            np.column_stack([window.command[a][rows] for a in self._axes]).ravel())
        message.encoder_names = [a.lower() for a in window.encoder_axes]
        encoders = window.encoder_readings[rows]
        if np.any(rotary_applied):
            encoders = encoders + rotary_applied  # the CNC turned the axes by the correction
        message.encoder_angles = pack_float64(encoders.ravel())
        self._scales.publish(message)
        period = float(self.get_parameter("reference_period_s").value)
        if period > 0:
            end_s = (first + self._batch) / self._rate
            while self._next_reference_s < end_s:
                index = int(round(self._next_reference_s * self._rate)) - window.first_index
                index = min(max(index, offset), offset + self._batch - 1)
                self._publish_reference(window, index, frame, applied[index - offset],
                                        rotary_applied[index - offset],
                                        int(versions[index - offset]))
                self._next_reference_s += period

    def _table_correction(self, window: SimulationResult) -> np.ndarray | None:
        """The tables' correction (W, 3) [m] at every command of ``window``, or None when
        the CNC takes no tables. Computed once per window and tables' revision: one
        array operation instead of one chain evaluation per 10-sample batch (the same
        values: the chain evaluates each sample on its own)."""
        tables = self.compensation.tables
        if self.compensation.mode not in ("table", "hybrid"):
            return None
        key = (window.first_index, tables.revision)
        if self._tables_at is None or self._tables_at[0] != key:
            self._tables_at = (key, window, tables.correction({a: window.command[a]
                                                               for a in self._axes}))
        return self._tables_at[2]

    def _known_table_correction(self, stamp_ns: int, command: dict[str, np.ndarray]
                                ) -> np.ndarray | None:
        """The tables' correction (3,) [m] at a real-time correction's command, from the
        window's (:meth:`_table_correction`) when that command is the window's at the
        stamp, value for value, and the tables have not changed since; else None."""
        cached = self._tables_at
        if cached is None or self._scenario_clock is None or \
                cached[0][1] != self.compensation.tables.revision:
            return None
        _, window, correction = cached
        index = int(round((stamp_ns - self._scenario_clock.start_ns) * self._rate / 1e9)) \
            - window.first_index
        if not 0 <= index < correction.shape[0] or \
                any(window.command[a][index] != command[a][0] for a in self._axes):
            return None
        return correction[index]

    def _direction(self, window: SimulationResult, axis: str, index: int) -> int:
        """Sign of the axis' last motion up to ``index`` (what the CNC knows), 0 if none yet."""
        moving = np.flatnonzero(np.abs(window.velocity[axis][:index + 1]) > 1e-9)
        if moving.size:
            self._last_direction[axis] = int(np.sign(window.velocity[axis][moving[-1]]))
        return self._last_direction.get(axis, 0)

    def _publish_reference(self, window: SimulationResult, index: int, frame: str,
                           applied: np.ndarray, rotary_applied: np.ndarray, version: int) -> None:
        uncertainty = 1e-6  # k = 2
        # The compensated machine: the TCP lands where its error puts it plus the
        # correction the CNC added to the command (and where turning the rotary axes by
        # their correction took the tool).
        rows = np.array([index])
        position, orientation = window.tcp_error(rows, with_orientation=True)
        shift, turn = np.zeros((1, 3)), np.zeros((1, 3))
        if np.any(rotary_applied):
            shift, turn = window.rotary_turn(rows, rotary_applied[None, :])
        # What the compensation did to the TCP: the linear correction and the shift the
        # rotary turn caused (the controller knows both through its nominal kinematics).
        applied = applied + shift[0]
        error = position[0] + applied + self._rng.normal(0.0, uncertainty / 2, 3)
        if self._instrument_zero is not None:
            error = error - self._instrument_zero
        message = ReferenceMeasurement()
        if window.encoder_axes:
            # A two-sphere R-test: the tool's direction as well as its tip; the rotation
            # about the tool axis is invisible to it (and irrelevant to a cutting tool).
            axis = tool_direction(self._kinematics, {a: window.command[a][rows]
                                                     for a in self._axes})[0]
            seen = orientation[0] + turn[0] + self._rng.normal(
                0.0, ORIENTATION_UNCERTAINTY_RAD / 2, 3)
            direction = seen - axis * (seen @ axis)
            turned = turn[0] - axis * (turn[0] @ axis)
            message.applied_orientation_correction.x, message.applied_orientation_correction.y, \
                message.applied_orientation_correction.z = (float(v) for v in turned)
            message.orientation_error.x, message.orientation_error.y, \
                message.orientation_error.z = (float(v) for v in direction)
            message.orientation_measured = True
            message.orientation_uncertainty = ORIENTATION_UNCERTAINTY_RAD
            message.applied_rotary_correction = [float(v) for v in rotary_applied]
        stamp_ns = self._scenario_clock.stamp_ns((window.first_index + index) / self._rate)
        self._last_reference_ns = stamp_ns
        message.header.stamp = nanoseconds_to_stamp(stamp_ns)
        message.header.frame_id = frame
        message.instrument = "r_test_two_sphere" if window.encoder_axes else "reference_probe"
        message.command_axes = [a.lower() for a in self._axes]
        message.command_positions = [float(window.command[a][index]) for a in self._axes]
        message.command_velocities = [float(window.velocity[a][index]) for a in self._axes]
        message.command_directions = [int(self._direction(window, a, index)) for a in self._axes]
        message.error.x, message.error.y, message.error.z = (float(v) for v in error)
        message.measured = [True, True, True]
        message.uncertainty = uncertainty
        message.applied_correction.x, message.applied_correction.y, \
            message.applied_correction.z = (float(v) for v in applied)
        message.compensation_model_version = int(version)
        message.sequence = self._reference_sequence
        self._reference_sequence += 1
        self._reference.publish(message)


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    return run_node(EncoderPublisher, args, until_finished=True, events=True)


if __name__ == "__main__":
    sys.exit(main())
