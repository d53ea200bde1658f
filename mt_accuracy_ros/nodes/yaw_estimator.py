"""Yaw and systematic-error estimator, per axis (Kidani chapters 2-4).

Subscribes ``scales`` (``ScaleBatch``) and ``temperatures`` (``TemperatureArray``),
and for every axis whose heads ``<axis>1``/``<axis>2`` are in the batches:

* yaw from the pair (Kidani eq. 2.13) relative to the first sample heard, with the
  relative scale expansion removed (Kidani eq. 3.17, thermocouples ``<axis><i>_s<j>``
  every ``thermocouple_spacing_m``, rises over the first reading) -> ``yaw/<axis>``
  (``YawBatch``, reliable);
* the streaming kNN systematic profile with periodic re-selection of k by
  K-fold CV, and the random sigma (Kidani eqs. 2.22-2.23, 4.10-4.12) ->
  ``systematic/<axis>`` (``SystematicProfile``, reliable) every ``profile_period_s``;
* once ``baseline_after_s`` of data has passed the profile becomes the
  baseline; later profiles carry ``baseline_difference`` and a deterioration
  alarm (|dE| >= ``tolerance_rad``, Kidani eq. 2.1) that also goes to ``/diagnostics``;
* with ``absorb_deterioration``, the alarm's rising edge restarts the profile
  from the samples that follow, so the profile - and the compensation built
  on its change dE (p2 = p1 - delta e, Kidani eq. 3.16) - shows the deteriorated
  guideway after one pass instead of mixing both states for several memory
  horizons.

Bad input (NaN readings, a gap in ``first_sample_index``, stamps going back,
a dead thermocouple) is reported on ``/diagnostics`` and skipped; the node keeps
running.
"""
from __future__ import annotations

import sys

import numpy as np
from diagnostic_msgs.msg import DiagnosticArray, DiagnosticStatus, KeyValue
from rclpy.node import Node

from mt_accuracy_msgs.msg import ScaleBatch, SystematicProfile, TemperatureArray, YawBatch

from ..core.scales.deterioration import detect_deterioration
from ..core.scales.dual_scale import (SQ57_EXPANSION_PER_K, YAW_COMPONENT, ExpansionProfile,
                                      thermal_yaw_error, thermocouple_positions,
                                      yaw_from_scales)
from ..core.inputs.stream_history import StreamHistory
from ..core.errors import InputDataError, MtAccuracyError
from ..core.validation import sample_period
from ..core.kinematics.machine import load_machine
from ..core.scales.streaming import StreamingSystematic
from ._health import DeliveryHealth, LiveSensorWatch
from ._priority import declare_niceness
from ._lockstep import ProgressReporter, report_after
from ._common import (run_node, RESULT_QOS, SENSOR_QOS, accept, float_descriptor, int_descriptor,
                      pack_float64, plain_descriptor, refuse, stamp_to_nanoseconds,
                      unpack_float64)


#: A reading may overshoot the stroke by this fraction of it (overtravel, the scales' own
#: zero) before it is left out of the systematic profile.
STROKE_MARGIN = 0.01


class AxisState:
    """Everything the estimator keeps for one axis."""

    def __init__(self, axis: str, distance: float, stroke: tuple[float, float], params) -> None:
        self.axis = axis
        self.distance = distance
        self.low, self.high = stroke
        self.reference: tuple[float, float] | None = None
        self.streaming = StreamingSystematic(
            self.low, self.high, bin_width_m=params["bin_width_m"], k_lim=params["k_lim"],
            window=params["window"], reselect_every=params["reselect_every"],
            memory_samples=params["memory_samples"], initial_k=min(20, params["k_lim"]))
        self.baseline: np.ndarray | None = None
        self.alarm = False
        #: Readings left out because they lay outside the stroke (said on /diagnostics).
        self.outside_stroke = 0
        #: (what they were made from, the two scales' prepared expansion profiles).
        self.expansion: tuple[tuple, list[ExpansionProfile]] | None = None


class YawEstimator(Node):
    """ScaleBatch + TemperatureArray -> YawBatch, SystematicProfile, diagnostics."""

    def __init__(self, **kwargs) -> None:
        super().__init__("yaw_estimator", **kwargs)
        self.declare_parameter("machine", "kidani_hmc", plain_descriptor(
            "Machine description (bundled name or path): strokes and scale distances",
            read_only=True))
        self.declare_parameter("axes", [""], plain_descriptor(
            "Axes to estimate (empty: every pair in the batches)", read_only=True))
        self.declare_parameter("thermal_correction", True, plain_descriptor(
            "Remove the relative scale expansion (Kidani eq. 3.17)"))
        self.declare_parameter("thermocouple_spacing_m", 0.11, float_descriptor(
            "Spacing of the thermocouples on each scale [m]", 0.001, 10.0, read_only=True))
        self.declare_parameter("expansion_per_k", SQ57_EXPANSION_PER_K, float_descriptor(
            "Scale expansion coefficient C [1/K]", 0.0, 1e-4))
        self.declare_parameter("bin_width_m", 0.5e-3, float_descriptor(
            "Position resolution of the streaming summary [m]", 1e-6, 0.1, read_only=True))
        self.declare_parameter("k_lim", 100, int_descriptor("Largest k tried by CV", 1, 1000,
                                                            read_only=True))
        self.declare_parameter("window", 20000, int_descriptor(
            "Raw samples kept for re-selecting k", 1000, 10_000_000, read_only=True))
        self.declare_parameter("reselect_every", 5000, int_descriptor(
            "Samples between re-selections of k", 100, 10_000_000, read_only=True))
        self.declare_parameter("memory_s", 20.0, float_descriptor(
            "Forgetting horizon of the profile [s of data] (0: never forget)", 0.0, 1e7,
            read_only=True))
        self.declare_parameter("profile_period_s", 1.0, float_descriptor(
            "Data time between two published profiles [s]", 0.01, 3600.0))
        self.declare_parameter("profile_points", 100, int_descriptor(
            "Query positions of a published profile", 2, 10000))
        self.declare_parameter("baseline_after_s", 40.0, float_descriptor(
            "Data time after which the profile becomes the baseline [s] (0: no baseline)",
            0.0, 1e7))
        self.declare_parameter("tolerance_rad", 10e-6, float_descriptor(
            "Deterioration tolerance dE_TOL on the yaw [rad]", 1e-9, 1.0))
        self.declare_parameter("absorb_deterioration", True, plain_descriptor(
            "On a deterioration alarm restart the profile from the samples that follow"))
        self.declare_parameter("input_delay_s", 0.5, float_descriptor(
            "Use temperatures stamped this much before the batch (deterministic replay) [s]",
            0.0, 60.0, read_only=True))
        self.declare_parameter("stream_horizon_s", 60.0, float_descriptor(
            "Largest gap a scale batch may open in its stream, and the largest disagreement "
            "of its stamp with the one its sample index predicts [s]; a batch beyond it is "
            "refused (forged or corrupt) until 3 consistent batches confirm a new position",
            0.001, 86400.0, read_only=True))
        self.declare_parameter("lockstep", False, plain_descriptor(
            "Report on 'lockstep' how far the scales are handled (a lockstep run)",
            read_only=True))
        self.add_on_set_parameters_callback(self._validate)

        self.machine = load_machine(str(self.get_parameter("machine").value))
        self._wanted = [a.upper() for a in self.get_parameter("axes").value if a]
        self._axes: dict[str, AxisState] = {}
        self._yaw_publishers: dict = {}
        self._profile_publishers: dict = {}
        self._temperature_reference: dict[str, float] = {}
        self._rises: dict[str, float] = {}
        # Each sensor judged by the live rules (dead, frozen, implausible): left out, named.
        self._sensor_watch = LiveSensorWatch()
        self._sensors_left_out: dict[str, str] = {}
        self._last_index: int | None = None
        self._last_stamp = -1
        self._history = StreamHistory(float(self.get_parameter("stream_horizon_s").value))
        self._data_time_s = 0.0
        self._sample_period = 0.0
        self._next_profile_s = 0.0
        self._problems: list[tuple[int, str]] = []
        self._pending_temperatures: list = []
        self._temperatures_applied_until = -1  # data time [ns]
        self._diagnostics = self.create_publisher(DiagnosticArray, "/diagnostics", 10)
        self.health = DeliveryHealth(self)
        declare_niceness(self, self.health)
        self._profile_sequence: dict[str, int] = {}  # per systematic/<axis> topic
        # Publishers up front, so that recorders and listeners match before data flows.
        for axis in self._wanted or [a for a in self.machine.axis_order
                                     if a in self.machine.scale_distance_m]:
            self._create_publishers(axis)
        reporter = ProgressReporter(self) if self.get_parameter("lockstep").value else None
        self.create_subscription(ScaleBatch, "scales", report_after(
            reporter, self.health.guard("scales", self._on_batch)), SENSOR_QOS)
        self.create_subscription(TemperatureArray, "temperatures",
                                 self.health.guard("temperatures", self._on_temperatures),
                                 SENSOR_QOS)

    # ---------------------------------------------------------------- parameters
    def _validate(self, parameters):
        for parameter in parameters:
            if parameter.name in ("expansion_per_k", "tolerance_rad", "profile_period_s") and \
                    not np.isfinite(parameter.value):
                self.health.refused("parameters", f"{parameter.name} must be finite")
                return refuse(f"{parameter.name} must be finite")
        return accept()

    def _axis(self, axis: str) -> AxisState | None:
        if axis in self._axes:
            return self._axes[axis]
        if self._wanted and axis not in self._wanted:
            return None
        if axis not in self.machine.axes:
            self._report(DiagnosticStatus.WARN, f"axis {axis} is not an axis of "
                                                f"{self.machine.name}; ignored")
            self._axes[axis] = None
            return None
        rate = 1.0 / self._sample_period if self._sample_period else 1000.0
        memory_s = float(self.get_parameter("memory_s").value)
        params = {"bin_width_m": float(self.get_parameter("bin_width_m").value),
                  "k_lim": int(self.get_parameter("k_lim").value),
                  "window": int(self.get_parameter("window").value),
                  "reselect_every": int(self.get_parameter("reselect_every").value),
                  "memory_samples": memory_s * rate if memory_s > 0 else np.inf}
        distance = float(self.machine.scale_distance_m.get(axis, 0.5))
        state = AxisState(axis, distance, self.machine.axes[axis].stroke, params)
        self._axes[axis] = state
        self._create_publishers(axis)
        return state

    def _create_publishers(self, axis: str) -> None:
        if axis in self._yaw_publishers:
            return
        self._yaw_publishers[axis] = self.create_publisher(YawBatch, f"yaw/{axis.lower()}",
                                                           RESULT_QOS)
        self._profile_publishers[axis] = self.create_publisher(
            SystematicProfile, f"systematic/{axis.lower()}", RESULT_QOS)

    # ---------------------------------------------------------------- inputs
    def _on_temperatures(self, message: TemperatureArray) -> None:
        values = unpack_float64(message.temperatures).copy()
        names = list(message.sensor_names)
        if len(values) != len(names):
            raise InputDataError("temperature message: names and values differ in length")
        self.health.sequence("temperatures", message.sequence)
        self.health.processed("temperatures")
        # Applied in data time (see _apply_temperatures), not on arrival.
        if stamp_to_nanoseconds(message.header.stamp) <= self._temperatures_applied_until:
            self.health.late("temperatures")
        self._pending_temperatures.append((stamp_to_nanoseconds(message.header.stamp), names,
                                           values))
        self._pending_temperatures.sort(key=lambda item: item[0])

    def _apply_temperatures(self, batch_stamp_ns: int) -> None:
        limit = batch_stamp_ns - int(float(self.get_parameter("input_delay_s").value) * 1e9)
        self._temperatures_applied_until = max(self._temperatures_applied_until, limit)
        while self._pending_temperatures and self._pending_temperatures[0][0] <= limit:
            _, names, values = self._pending_temperatures.pop(0)
            self._use_temperatures(names, values)

    def _use_temperatures(self, names, values) -> None:
        good, bad = self._sensor_watch.judge(dict(zip(names, (float(v) for v in values))))
        for name, value in good.items():
            self._temperature_reference.setdefault(name, value)
            self._rises[name] = value - self._temperature_reference[name]
        # Said once per sensor and kind of trouble; its last valid value is used meanwhile.
        for name, (kind, why) in bad.items():
            if self._sensors_left_out.get(name) != kind:
                self._report(DiagnosticStatus.WARN, f"no valid reading from {name} "
                                                    f"(temperature sensor: {why}) - left out; "
                                                    "its last valid value is used")
        self._sensors_left_out = {name: kind for name, (kind, _) in bad.items()}

    def _on_batch(self, message: ScaleBatch) -> None:
        channels = list(message.channel_names)
        data = unpack_float64(message.positions)
        if not channels or data.size % len(channels):
            raise InputDataError("scale batch: positions do not fill n_samples x n_channels")
        sample_period(message.sample_period)
        data = data.reshape(-1, len(channels))
        stamp = stamp_to_nanoseconds(message.header.stamp)
        if stamp <= self._last_stamp:
            # Counted as refused by the guard, and said on /diagnostics with the reason.
            raise InputDataError(f"stamp went back or repeated ({stamp} after "
                                 f"{self._last_stamp} ns); batch skipped")
        restarts = self._history.restarts
        self._history.check(message.first_sample_index, data.shape[0], stamp,
                            float(message.sample_period))
        restarted = self._history.restarts != restarts
        if self._last_index is not None and message.first_sample_index != self._last_index \
                and not restarted:
            lost = int(message.first_sample_index) - self._last_index
            self._report(DiagnosticStatus.WARN, f"{lost} samples lost before index "
                                                f"{message.first_sample_index}")
        self.health.sequence("scales", message.first_sample_index, data.shape[0],
                             restart=restarted)
        self.health.processed("scales", data.shape[0])
        self._last_stamp = stamp
        self._apply_temperatures(stamp)
        self._last_index = int(message.first_sample_index) + data.shape[0]
        self._sample_period = float(message.sample_period)
        self._data_time_s = self._last_index * self._sample_period
        for axis in sorted({c[:-1].upper() for c in channels if c[-1:] in "12"}):
            try:
                first = data[:, channels.index(f"{axis.lower()}1")]
                second = data[:, channels.index(f"{axis.lower()}2")]
            except ValueError:
                continue
            state = self._axis(axis)
            if state is None:
                continue
            self._process(state, message, first, second)
        if self._data_time_s >= self._next_profile_s:
            self._next_profile_s = self._data_time_s + float(
                self.get_parameter("profile_period_s").value)
            for state in self._axes.values():
                if state is not None:
                    self._publish_profile(state, message)
            self._publish_diagnostics()

    def _process(self, state: AxisState, message: ScaleBatch, first, second) -> None:
        good = np.isfinite(first) & np.isfinite(second)
        if not good.all():
            self._report(DiagnosticStatus.WARN, f"axis {state.axis}: {int((~good).sum())} "
                                                "non-finite readings dropped")
        if state.reference is None:
            if not good.any():
                return
            index = int(np.argmax(good))
            state.reference = (float(first[index]), float(second[index]))
        try:
            raw = np.full(first.shape, np.nan)
            raw[good] = yaw_from_scales(first[good], second[good], state.distance,
                                        reference=state.reference)
        except InputDataError as exc:
            self._report(DiagnosticStatus.ERROR, f"axis {state.axis}: {exc}")
            return
        correction = self._thermal_term(state, first)
        yaw = raw - correction if correction is not None else raw
        positions = 0.5 * (first + second)
        inside = good & self._within_stroke(state, positions, good)
        state.streaming.add(positions[inside], yaw[inside])
        out = YawBatch()
        out.header = message.header
        out.axis = state.axis.lower()
        out.first_sample_index = message.first_sample_index
        out.sample_period = message.sample_period
        out.positions = pack_float64(positions)
        out.yaw = pack_float64(yaw)
        out.thermal_correction = pack_float64(correction if correction is not None
                                              else np.zeros(0))
        self._yaw_publishers[state.axis].publish(out)

    def _within_stroke(self, state: AxisState, positions, good) -> np.ndarray:
        """(n,) which readings lie on the axis' stroke (within 1 % of it): the others are
        left out of the systematic profile, counted and said with the likely cause."""
        margin = STROKE_MARGIN * (state.high - state.low)
        inside = (positions >= state.low - margin) & (positions <= state.high + margin)
        outside = good & ~inside
        if outside.any():
            state.outside_stroke += int(outside.sum())
            read = positions[outside]
            in_mm = bool(np.all((read / 1e3 >= state.low - margin) &
                                (read / 1e3 <= state.high + margin)))
            why = "the scales read in mm, not m?" if in_mm else \
                "another machine's stroke, or a scale fault?"
            self._report(DiagnosticStatus.WARN,
                         f"axis {state.axis}: {int(outside.sum())} readings at "
                         f"{read.min():.4g}..{read.max():.4g} m lie outside the stroke "
                         f"{state.low:.4g}..{state.high:.4g} m and are left out of the "
                         f"systematic profile ({why})")
        return inside

    def _thermal_term(self, state: AxisState, first) -> np.ndarray | None:
        if not self.get_parameter("thermal_correction").value:
            return None
        length = state.high - state.low
        positions = thermocouple_positions(
            length, float(self.get_parameter("thermocouple_spacing_m").value))
        rises = []
        for i in (1, 2):
            names = [f"{state.axis.lower()}{i}_s{j}" for j in range(positions.size)]
            if not all(n in self._rises for n in names):
                return None  # no (complete) thermocouple data yet
            rises.append(np.array([self._rises[n] for n in names]))
        travel = np.clip(np.nan_to_num(first - state.low), 0.0, length)
        c = float(self.get_parameter("expansion_per_k").value)
        # The rises change with each temperature reading (2 Hz), the batches come at
        # 100 Hz: each scale's profile is integrated once per reading (the same numbers).
        key = (c, positions.tobytes(), rises[0].tobytes(), rises[1].tobytes())
        if state.expansion is None or state.expansion[0] != key:
            state.expansion = (key, [ExpansionProfile(positions, rise, c) for rise in rises])
        dl1, dl2 = (profile(travel) for profile in state.expansion[1])
        return thermal_yaw_error(travel, dl1, dl2, state.distance)

    # ---------------------------------------------------------------- outputs
    def _publish_profile(self, state: AxisState, message: ScaleBatch) -> None:
        try:
            points = int(self.get_parameter("profile_points").value)
            query = np.linspace(state.low, state.high, points)
            profile = state.streaming.profile(query)
        except MtAccuracyError:
            return
        out = SystematicProfile()
        out.header = message.header
        out.axis = state.axis.lower()
        out.error_name = f"E{YAW_COMPONENT.get(state.axis, 'C')}{state.axis}"
        out.unit = "rad"
        out.positions = pack_float64(profile.positions)
        out.systematic = pack_float64(profile.systematic)
        out.random_sigma = pack_float64(np.nan_to_num(profile.random_sigma))
        out.k = int(profile.k)
        out.cv_rmse = float(profile.cv_rmse)
        out.sample_count = int(profile.sample_count)
        tolerance = float(self.get_parameter("tolerance_rad").value)
        out.tolerance = tolerance
        after = float(self.get_parameter("baseline_after_s").value)
        if state.baseline is None and after > 0 and self._data_time_s >= after:
            state.baseline = profile.systematic.copy()
            self.get_logger().info(
                f"axis {state.axis}: baseline taken at {self._data_time_s:.1f} s")
        if state.baseline is not None:
            report = detect_deterioration(query, state.baseline, profile.systematic, tolerance)
            out.baseline_difference = pack_float64(report.change)
            out.deterioration = bool(report.deteriorated)
            if report.deteriorated and not state.alarm:
                ranges = ", ".join(f"{a * 1e3:.0f}..{b * 1e3:.0f} mm"
                                   for a, b in report.flagged_ranges())
                self.get_logger().warning(
                    f"axis {state.axis}: yaw deteriorated by up to "
                    f"{report.max_abs_change * 1e6:.1f} urad over {ranges}")
                if self.get_parameter("absorb_deterioration").value:
                    state.streaming.forget()
                    self.get_logger().info(f"axis {state.axis}: profile restarted at "
                                           f"{self._data_time_s:.1f} s to absorb the change")
            state.alarm = bool(report.deteriorated)
        out.sequence = self._profile_sequence.get(state.axis, 0)
        self._profile_sequence[state.axis] = out.sequence + 1
        self._profile_publishers[state.axis].publish(out)

    def _report(self, level: int, text: str) -> None:
        self._problems.append((level, text))
        if len(self._problems) > 50:
            self._problems = self._problems[-50:]

    def _publish_diagnostics(self) -> None:
        statuses = []
        for axis, state in sorted((a, s) for a, s in self._axes.items() if s is not None):
            level = DiagnosticStatus.ERROR if state.alarm else DiagnosticStatus.OK
            status = DiagnosticStatus(
                level=level, name=f"{self.get_fully_qualified_name()}: axis {axis}",
                hardware_id=self.machine.name,
                message="yaw deterioration beyond tolerance" if state.alarm else "ok")
            status.values = [KeyValue(key="samples", value=str(state.streaming.sample_count)),
                             KeyValue(key="k", value=str(state.streaming.k)),
                             KeyValue(key="baseline", value=str(state.baseline is not None)),
                             KeyValue(key="outside_stroke", value=str(state.outside_stroke))]
            statuses.append(status)
        worst = max((level for level, _ in self._problems), default=DiagnosticStatus.OK)
        statuses.append(DiagnosticStatus(
            level=worst, name=f"{self.get_fully_qualified_name()}: input",
            hardware_id=self.machine.name,
            message="; ".join(text for _, text in self._problems[-3:]) or "ok"))
        self._problems.clear()
        array = DiagnosticArray(status=statuses)
        array.header.stamp = self.get_clock().now().to_msg()
        self._diagnostics.publish(array)


def main(args: list[str] | None = None) -> int:
    """Entry point (console_scripts)."""
    return run_node(YawEstimator, args, events=True)


if __name__ == "__main__":
    sys.exit(main())
